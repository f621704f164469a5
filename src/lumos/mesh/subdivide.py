"""Subdivision of triangle meshes: midpoint (finer, same shape) and Loop (finer and smoother).

    vertices, faces, uvs = subdivide(vertices, faces, scheme="loop", levels=2, uvs=uvs)

Interpolated shading cannot hide a polygonal silhouette: the outline of a coarse sphere stays a polygon however
its normals are interpolated. Loop subdivision (Loop 1987, "Smooth subdivision surfaces based on triangles",
MSc thesis, University of Utah) converges to a smooth surface, so each level makes the silhouette rounder;
midpoint subdivision keeps the shape and only makes the mesh finer (smaller triangles for Gouraud shading to
interpolate over, so highlights are not lost inside large faces).

Each level splits every triangle (v0, v1, v2) into four through new points on its edges, keeping its winding:
(v0, e01, e20), (v1, e12, e01), (v2, e20, e12), (e01, e12, e20). Old vertices keep their indices; the point on
edge i follows as vertex n + i. Edges are found by sorting vertex-pair keys, so a level is a few sorts and
bincounts. UV seams (vertices split for texture coordinates) are boundaries to Loop subdivision: weld the
positions first if the surface must stay smooth across them.
"""

from __future__ import annotations

import numpy as np

#: Schemes `subdivide` accepts.
SCHEMES = ("midpoint", "loop")


def subdivide(vertices, faces, scheme: str = "loop", levels: int = 1, uvs=None):
    """Subdivide a triangle mesh `levels` times.

    vertices: float (n, 3) positions.
    faces:    int (m, 3) vertex indices.
    scheme:   "midpoint" (new points at edge midpoints, old vertices stay) or "loop" (Loop 1987: new edge
              points 3/8 (a + b) + 1/8 (c + d), old vertices (1 - n beta) v + beta * sum of neighbours with
              Warren's beta = 3 / (8 n) for n > 3 and 3/16 for n = 3; boundary edges take their midpoint and
              boundary vertices 3/4 v + 1/8 (their two boundary neighbours)).
    levels:   number of times to subdivide (0 returns copies).
    uvs:      optional float (n, 2) texture coordinates: edge points get the average of the edge's two ends
              (linear interpolation) in both schemes, old vertices keep theirs.

    Returns (vertices float64 (n', 3), faces int64 (4^levels m, 3), uvs float64 (n', 2) or None). The four
    children of face f are faces 4f .. 4f + 3 at each level.
    """
    if scheme not in SCHEMES:
        raise ValueError(f"unknown subdivision scheme {scheme!r} (expected one of {', '.join(SCHEMES)})")
    if int(levels) != levels or levels < 0:
        raise ValueError(f"levels must be a non-negative integer, got {levels!r}")
    vertices = np.array(vertices, dtype=np.float64)
    faces = np.array(faces, dtype=np.int64).reshape(-1, 3) if np.size(faces) else np.zeros((0, 3), np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), got {vertices.shape}")
    if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise ValueError(f"faces index vertices outside [0, {len(vertices)})")
    if uvs is not None:
        uvs = np.array(uvs, dtype=np.float64)
        if uvs.shape != (len(vertices), 2):
            raise ValueError(f"uvs must have shape ({len(vertices)}, 2), got {uvs.shape}")

    for _ in range(int(levels)):
        vertices, faces, uvs = _subdivide_once(vertices, faces, uvs, scheme == "loop")
    return vertices, faces, uvs


def _subdivide_once(vertices, faces, uvs, loop: bool):
    """One level: edge points, (Loop only) moved old vertices, four children per face."""
    n = len(vertices)
    edges, edge_of_side, side_count = _edges(faces, n)             # (e, 2), (m, 3), (e,)
    a, b = vertices[edges[:, 0]], vertices[edges[:, 1]]
    edge_points = 0.5 * (a + b)
    old_points = vertices
    if loop:
        edge_points, old_points = _loop_points(vertices, faces, edges, edge_of_side, side_count)

    e01, e12, e20 = (n + edge_of_side[:, k] for k in range(3))
    v0, v1, v2 = faces.T
    children = np.stack([np.stack([v0, e01, e20], 1), np.stack([v1, e12, e01], 1),
                         np.stack([v2, e20, e12], 1), np.stack([e01, e12, e20], 1)], axis=1)
    new_uvs = None if uvs is None else np.concatenate([uvs, 0.5 * (uvs[edges[:, 0]] + uvs[edges[:, 1]])])
    return np.concatenate([old_points, edge_points]), children.reshape(-1, 3), new_uvs


def _edges(faces: np.ndarray, n: int):
    """Unique undirected edges (e, 2) sorted, the edge of each face side k = (f[k], f[k+1]) (m, 3), and how
    many face sides each edge has (1 on a boundary, 2 inside a manifold)."""
    start, end = faces, np.roll(faces, -1, axis=1)
    keys = (np.minimum(start, end) * n + np.maximum(start, end)).ravel()
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    new = np.r_[True, sorted_keys[1:] != sorted_keys[:-1]]
    edge_of_sorted = np.cumsum(new) - 1
    edge_of_side = np.empty(len(keys), dtype=np.int64)
    edge_of_side[order] = edge_of_sorted
    unique_keys = sorted_keys[new]
    edges = np.stack([unique_keys // n, unique_keys % n], axis=1)
    side_count = np.bincount(edge_of_side, minlength=len(edges))
    return edges, edge_of_side.reshape(-1, 3), side_count


def _loop_points(vertices, faces, edges, edge_of_side, side_count):
    """Loop's edge points (e, 3) and new positions of the old vertices (n, 3)."""
    n = len(vertices)
    a, b = vertices[edges[:, 0]], vertices[edges[:, 1]]

    # Edge points: 3/8 (a + b) + 1/8 (c + d) inside, the midpoint on boundaries (and non-manifold edges).
    opposite = vertices[np.roll(faces, -2, axis=1)].reshape(-1, 3)   # vertex facing side k is f[k + 2]
    opposite_sum = _sum_rows(edge_of_side.ravel(), opposite, len(edges))
    interior = side_count == 2
    edge_points = 0.5 * (a + b)
    edge_points[interior] = 0.375 * (a + b)[interior] + 0.125 * opposite_sum[interior]

    # Old vertices: valence n and neighbour sum over all edges; boundary vertices over boundary edges only.
    ends = edges.ravel()
    others = vertices[edges[:, ::-1].ravel()]
    valence = np.bincount(ends, minlength=n)
    neighbour_sum = _sum_rows(ends, others, n)
    boundary = np.repeat(side_count != 2, 2)
    boundary_valence = np.bincount(ends[boundary], minlength=n)
    boundary_sum = _sum_rows(ends[boundary], others[boundary], n)

    beta = np.where(valence > 3, 3.0 / (8.0 * np.maximum(valence, 1)), 3.0 / 16.0)
    moved = (1.0 - valence * beta)[:, None] * vertices + beta[:, None] * neighbour_sum
    moved[valence == 0] = vertices[valence == 0]                       # vertices no face uses stay
    on_boundary = boundary_valence > 0
    moved[on_boundary] = vertices[on_boundary]                         # corners, non-manifold: stay
    curve = boundary_valence == 2
    moved[curve] = 0.75 * vertices[curve] + 0.125 * boundary_sum[curve]
    return edge_points, moved


def _sum_rows(index: np.ndarray, values: np.ndarray, size: int) -> np.ndarray:
    """Sum rows of `values` (k, 3) into `size` bins by `index` (k,)."""
    return np.stack([np.bincount(index, values[:, c], minlength=size) for c in range(3)], axis=1)
