"""Face and vertex normals of a triangle mesh, with a choice of weighting and a crease angle.

    normals, areas = face_normals(vertices, faces)
    vertices2, faces2, normals2, source = vertex_normals(vertices, faces, weighting="angle", crease_angle=60.0)
    uvs2 = uvs[source]          # carry any per-vertex attribute over to the split vertices

Interpolated shading is only as good as its vertex normals. Averaging the normals of the faces around a vertex
gives an unrepresentative normal where the faces are uneven (a long thin triangle counts as much as a big one)
or where the surface has a real edge (a cube's corner becomes a blurry diagonal). `weighting` fixes the first:
"angle" weights each face by its corner angle at the vertex (Thürmer & Wüthrich 1998, "Computing vertex normals
from polygonal facets"), which does not depend on how the surface around the vertex was tessellated; "area" and
"average" are the classic alternatives. `crease_angle` fixes the second: faces whose normals differ by more than
it do not share a normal, and the vertex is split so each side of the crease keeps its own.

Everything is vectorized NumPy: bincounts over flat corner arrays and sorts, no loop over faces.
"""

from __future__ import annotations

import numpy as np

#: Weightings `vertex_normals` accepts.
WEIGHTINGS = ("average", "area", "angle")
#: Slack on cosine comparisons, so faces of one plane count as "within 0 degrees" of each other.
_COS_SLACK = 1e-12
#: Corner pairs compared at once when splitting vertices at creases (bounds memory at high valences).
_PAIR_CHUNK = 1 << 23
#: Normal of a vertex that no valid face touches.
_FALLBACK_NORMAL = (0.0, 0.0, 1.0)
#: Distinct vertices closer than this fraction of the mesh's bounding-box diagonal are one position for the
#: normals (`weld_ids`): a file that repeats a vertex along a seam (the Utah teapot's patch borders) means one
#: surface, not two.
WELD_TOLERANCE = 1e-6
#: Across welded vertices (the file gave them as distinct) faces share a normal only within this angle, even
#: when the crease angle is wider: a seam of a smooth surface is nearly flat, while a cube given with a vertex per
#: face corner is meant faceted.
WELD_CREASE = 60.0


def face_normals(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """Unit normal and area of each triangle.

    vertices: float (n, 3) positions; faces: int (m, 3) vertex indices, counter-clockwise seen from outside.
    Returns normals float64 (m, 3), unit length along (v1 - v0) x (v2 - v0), and areas float64 (m,).
    A degenerate face (zero area) gets the normal (0, 0, 0) and area 0.
    """
    vertices, faces = _check_mesh(vertices, faces)
    cross = _face_cross(vertices, faces)
    return _normalize_cross(cross)


def weld_ids(vertices, tolerance: float = WELD_TOLERANCE) -> np.ndarray:
    """int64 (n,): for each vertex, the index of the first vertex at (nearly) the same position, positions
    snapped to a grid of `tolerance` × the bounding-box diagonal (as trimesh's merge does: two points either
    side of a grid line stay apart, which a file's repeated vertices, written with the same digits, never are)."""
    vertices = np.asarray(vertices, dtype=np.float64)
    if len(vertices) == 0:
        return np.zeros(0, dtype=np.int64)
    finite = np.all(np.isfinite(vertices), axis=1)
    span = np.ptp(vertices[finite], axis=0) if finite.any() else np.zeros(3)
    step = max(float(np.linalg.norm(span)) * tolerance, 1e-300)
    keys = np.where(finite[:, None], np.round(vertices / step), np.nan)
    keys[~finite] = np.arange((~finite).sum())[:, None] + 0.5  # never weld a non-finite vertex
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return first[inverse.ravel()].astype(np.int64)


def vertex_normals(vertices, faces, weighting: str = "angle", crease_angle: float = 180.0, weld: bool = True):
    """Per-vertex unit normals averaged from the faces around each vertex, split at creases.

    vertices:     float (n, 3) positions.
    faces:        int (m, 3) vertex indices.
    weighting:    "average" (each face counts 1), "area" (face area) or "angle" (the face's corner angle at
                  the vertex, Thürmer & Wüthrich 1998).
    crease_angle: degrees in [0, 180]. Faces around a vertex whose normals differ by more than this do not
                  share that vertex's normal: each corner averages only the faces within the crease angle of
                  its own face, and corners that end up with different normals get different vertices.
                  180 shares everything (no splitting).
    weld:         distinct vertices at the same position (`weld_ids`) share normals too, as if the file had
                  shared them; a mesh that repeats positions is then split at the smaller of the crease angle
                  and WELD_CREASE (60°), so the seams of a smooth surface given with repeated vertices vanish
                  and a cube given with a vertex per face corner stays faceted. A mesh with no repeated
                  positions is not affected.

    Returns (vertices2 float64 (n2, 3), faces2 int64 (m, 3), normals2 float64 (n2, 3), source int64 (n2,)):
    the first n output vertices are the input vertices in order, split copies follow; `source[i]` is the input
    vertex output vertex i was copied from, so `attribute[source]` carries UVs or colours over. With crease
    180 the inputs come back unchanged and `source` is `arange(n)`. A vertex that no non-degenerate face
    touches gets the normal (0, 0, 1).
    """
    if weighting not in WEIGHTINGS:
        raise ValueError(f"unknown normal weighting {weighting!r} (expected one of {', '.join(WEIGHTINGS)})")
    crease = float(crease_angle)
    if not 0.0 <= crease <= 180.0:
        raise ValueError(f"crease_angle must be in [0, 180] degrees, got {crease_angle!r}")
    vertices, faces = _check_mesh(vertices, faces)
    n = len(vertices)
    if weld and len(faces):
        ids = weld_ids(vertices)
        if np.any(ids[faces] != faces):
            return _welded_normals(vertices, faces, ids, weighting, min(crease, WELD_CREASE))

    # Stage 1: face normals and the weight of each face at each of its three corners.
    cross = _face_cross(vertices, faces)
    normals_f, areas = _normalize_cross(cross)
    weights = _corner_weights(vertices, faces, areas, weighting)          # (m, 3)

    # Stage 2: the shared normal of every vertex (all faces around it).
    corner_vertex = faces.ravel()
    corner_face = np.repeat(np.arange(len(faces)), 3)
    sums = _accumulate(corner_vertex, weights.ravel()[:, None] * normals_f[corner_face], n)
    normals_v = _normalize_rows(sums)
    if crease >= 180.0 or len(faces) == 0:
        return vertices, faces, normals_v, np.arange(n, dtype=np.int64)

    # Stage 3: vertices where some faces lie beyond the crease. If every face normal is within half the crease
    # angle of the shared normal, every pair is within the crease angle and the shared normal stands.
    cos_half = np.cos(np.radians(crease / 2.0))
    valid_face = areas > 0.0
    dots = np.einsum("ij,ij->i", normals_f[corner_face], normals_v[corner_vertex])
    beyond = valid_face[corner_face] & (dots < cos_half - _COS_SLACK)
    beyond |= valid_face[corner_face] & (np.linalg.norm(sums, axis=1)[corner_vertex] == 0.0)
    creased_vertex = np.zeros(n, dtype=bool)
    creased_vertex[corner_vertex[beyond]] = True
    if not creased_vertex.any():
        return vertices, faces, normals_v, np.arange(n, dtype=np.int64)

    # Stage 4: at creased vertices, each corner averages the faces within the crease angle of its own face.
    corner_id = np.flatnonzero(creased_vertex[corner_vertex])
    corner_normals, rep, leader = _creased_corner_normals(corner_id, corner_vertex, corner_face, normals_f,
                                                          valid_face, weights.ravel(), np.cos(np.radians(crease)))

    # Stage 5: one output vertex per distinct (vertex, normal); the first keeps the input index.
    return _split_vertices(vertices, faces, normals_v, corner_id, corner_vertex[corner_id], corner_normals,
                           rep, leader)


def _welded_normals(vertices, faces, ids, weighting, crease):
    """`vertex_normals` over the mesh with repeated positions merged (`ids`), handed back in the input's
    vertices: each input vertex keeps its index with the normal of its first corner, and a copy follows for
    each other normal its corners took."""
    n = len(vertices)
    _, faces_w, normals_w, _ = vertex_normals(vertices, ids[faces], weighting, crease, weld=False)
    corner_v, corner_o = faces.ravel(), faces_w.ravel()
    pairs, first, pair_of = np.unique(corner_v * (len(normals_w) + 1) + corner_o, return_index=True,
                                      return_inverse=True)
    pair_v, pair_o = corner_v[first], corner_o[first]
    lead = np.r_[True, pair_v[1:] != pair_v[:-1]]  # pairs are sorted by vertex: the first of each keeps it
    index = np.where(lead, pair_v, 0)
    index[~lead] = n + np.arange((~lead).sum())
    normals2 = np.empty((n + (~lead).sum(), 3))
    normals2[:n] = _FALLBACK_NORMAL  # a vertex no face uses
    normals2[index] = normals_w[pair_o]
    source = np.r_[np.arange(n, dtype=np.int64), pair_v[~lead]]
    return vertices[source], index[pair_of.ravel()].reshape(-1, 3), normals2, source


def _check_mesh(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """Validate and convert to float64 (n, 3) and int64 (m, 3)."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), got {vertices.shape}")
    if faces.size == 0:
        faces = faces.reshape(0, 3)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"faces must have shape (m, 3), got {faces.shape}")
    if not np.issubdtype(faces.dtype, np.integer):
        raise ValueError(f"faces must be integer vertex indices, got dtype {faces.dtype}")
    faces = faces.astype(np.int64, copy=False)
    if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise ValueError(f"faces index vertices outside [0, {len(vertices)})")
    return vertices, faces


def _face_cross(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(v1 - v0) x (v2 - v0) of each face: twice the vector area."""
    v0 = vertices[faces[:, 0]]
    return np.cross(vertices[faces[:, 1]] - v0, vertices[faces[:, 2]] - v0)


def _normalize_cross(cross: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals and areas from face cross products; zero for degenerate faces."""
    length = np.linalg.norm(cross, axis=1)
    ok = length > 0.0
    normals = np.zeros_like(cross)
    normals[ok] = cross[ok] / length[ok, None]
    return normals, 0.5 * length * ok


def _corner_weights(vertices, faces, areas, weighting: str) -> np.ndarray:
    """Weight (m, 3) of each face at each of its corners; zero for degenerate faces."""
    valid = areas > 0.0
    if weighting == "average":
        return np.repeat(valid[:, None].astype(np.float64), 3, axis=1)
    if weighting == "area":
        return np.repeat(areas[:, None], 3, axis=1)
    # Corner angle atan2(|e1 x e2|, e1 . e2); |e1 x e2| = 2 * area at every corner of the triangle.
    p0, p1, p2 = (vertices[faces[:, k]] for k in range(3))
    e01, e12, e20 = p1 - p0, p2 - p1, p0 - p2
    dots = -np.stack([np.einsum("ij,ij->i", e01, e20), np.einsum("ij,ij->i", e12, e01),
                      np.einsum("ij,ij->i", e20, e12)], axis=1)
    angles = np.arctan2(np.repeat(2.0 * areas[:, None], 3, axis=1), dots)
    return angles * valid[:, None]


def _accumulate(index: np.ndarray, values: np.ndarray, size: int) -> np.ndarray:
    """Sum rows of `values` (k, 3) into `size` bins by `index` (k,)."""
    return np.stack([np.bincount(index, values[:, c], minlength=size) for c in range(3)], axis=1)


def _normalize_rows(sums: np.ndarray) -> np.ndarray:
    """Unit rows; zero rows become the fallback normal."""
    length = np.linalg.norm(sums, axis=1)
    ok = length > 0.0
    normals = np.empty_like(sums)
    normals[ok] = sums[ok] / length[ok, None]
    normals[~ok] = _FALLBACK_NORMAL
    return normals


def _creased_corner_normals(corner_id, corner_vertex, corner_face, normals_f, valid_face, corner_weight,
                            cos_crease: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normals of the corners `corner_id` (k,), averaging only faces within the crease angle, and their sharing.

    Corners are grouped by vertex; within a group every pair (c, d) is compared and d's weighted face normal
    is added to c when the two face normals are within the crease. Groups of equal size are batched, so the
    comparison is one Gram matrix per vertex and the sum one matrix product. A corner of a degenerate face
    takes all faces (the shared normal).

    Returns (normals (k, 3), rep (k,), leader (k,)), all in the order of `corner_id`: corners that average the
    same set of faces have the same normal, and rep[i] is the position of the first such corner of the
    vertex; leader[i] is True where that first corner is the first corner of its vertex.
    """
    order = np.argsort(corner_vertex[corner_id], kind="stable")
    corners = corner_id[order]                                    # sorted by vertex
    vertex_of = corner_vertex[corners]
    starts = np.flatnonzero(np.r_[True, vertex_of[1:] != vertex_of[:-1]])
    sizes = np.diff(np.r_[starts, len(corners)])
    normal_of = normals_f[corner_face[corners]]                   # per sorted corner: its face's normal,
    weighted = corner_weight[corners, None] * normal_of          # its weighted normal,
    valid = valid_face[corner_face[corners]]                     # and whether its face is not degenerate
    sums = np.zeros((len(corners), 3))
    rep_sorted = np.empty(len(corners), dtype=np.int64)

    for size in np.unique(sizes):
        group_starts = starts[sizes == size]
        batch = max(1, _PAIR_CHUNK // (size * size * 8))         # bounds the (groups, size, size) arrays
        for lo in range(0, len(group_starts), batch):
            index = group_starts[lo:lo + batch, None] + np.arange(size)          # (g, size) sorted corners
            normals_g, valid_g = normal_of[index], valid[index]
            gram = np.matmul(normals_g, normals_g.transpose(0, 2, 1))
            close = ((gram >= cos_crease - _COS_SLACK) | ~valid_g[:, :, None]) & valid_g[:, None, :]
            sums[index] = np.matmul(close.astype(np.float64), weighted[index])
            # Corners with identical rows of `close` share a normal: the first such corner represents them.
            packed = np.packbits(close, axis=2)
            packed = np.pad(packed, ((0, 0), (0, 0), (0, -packed.shape[2] % 8))).view(np.uint64)
            same = (packed[:, :, None, :] == packed[:, None, :, :]).all(axis=3)
            rep_sorted[index] = group_starts[lo:lo + batch, None] + np.argmax(same, axis=2)

    # Back from sorted order to the order of corner_id (order[j] is where sorted corner j came from).
    normals = np.empty_like(sums)
    normals[order] = _normalize_rows(sums)
    rep = np.empty_like(rep_sorted)
    rep[order] = order[rep_sorted]
    leader = np.zeros(len(corners), dtype=bool)
    leader[order] = np.isin(rep_sorted, starts)
    return normals, rep, leader


def _split_vertices(vertices, faces, normals_v, corner_id, vertex_of, corner_normals, rep, leader):
    """One vertex per distinct (vertex, normal) among the creased corners; a vertex's first keeps its index."""
    n = len(vertices)
    is_rep = rep == np.arange(len(rep))
    new_rep = is_rep & ~leader                                    # representatives that need a new vertex
    index_of = np.where(leader, vertex_of, 0)
    index_of[new_rep] = n + np.arange(new_rep.sum())
    source = np.r_[np.arange(n, dtype=np.int64), vertex_of[new_rep]]
    normals2 = np.concatenate([normals_v, corner_normals[new_rep]])
    leaders = is_rep & leader
    normals2[vertex_of[leaders]] = corner_normals[leaders]
    faces2 = faces.ravel().copy()
    faces2[corner_id] = index_of[rep]
    return vertices[source], faces2.reshape(-1, 3), normals2, source
