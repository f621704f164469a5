"""T-junction repair: insert vertices that lie inside a neighbour's edge into that edge.

    polygons = repair_t_junctions(vertices, polygons)          # list of int64 index arrays
    faces, face_polygon = triangulate(vertices, polygons)     # then split into triangles as usual

A T-junction is a vertex of one polygon lying in the interior of an edge of a neighbouring polygon that does
not have it as a vertex (two small quads beside the half of a big one). Interpolated shading then computes the
colour at that point twice, once from the vertex's own colour and once by interpolating along the big edge,
and the two disagree: a visible seam. The cure is to insert the shared vertex into the edge of the neighbouring
polygon (a triangle may so become a quadrilateral), after which both sides use the same vertex.

Candidate (edge, vertex) pairs come from a uniform grid: the vertices are sorted by cell, and each edge looks
only at the cells around points sampled along it, so the cost grows with the mesh, not with its square.
"""

from __future__ import annotations

import numpy as np

#: Smallest grid cell, relative to the mesh extent (at most 2^20 cells along an axis keeps keys in int64).
_MIN_CELL = 2.0**-20
#: Corner offsets of the 2 x 2 x 2 block of cells around a sample point.
_BLOCK = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=np.int64)


def repair_t_junctions(vertices, polygons, tolerance: float = 1e-7) -> list[np.ndarray]:
    """Insert every vertex that lies inside another polygon's edge into that edge.

    vertices:  float (n, 3) positions.
    polygons:  a sequence of int vertex-index arrays (any length >= 3), or an int (p, k) array.
    tolerance: how far from an edge's line a vertex may be and still lie on it, relative to the diagonal of
               the bounding box of the vertices the polygons use. A vertex must also be farther than that from
               both ends of the edge.

    Returns a list of p int64 arrays: each polygon with the vertices found on its edges inserted, in order along
    each edge. Vertices the polygon already has are never inserted, and vertices no polygon uses are ignored.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), got {vertices.shape}")
    if not tolerance >= 0.0:
        raise ValueError(f"tolerance must be >= 0, got {tolerance!r}")
    polygons = [np.array(p, dtype=np.int64).ravel() for p in polygons]       # copies: the result is new
    if not polygons:
        return []
    sizes = np.array([len(p) for p in polygons], dtype=np.int64)
    if sizes.min() < 3:
        bad = int(np.argmin(sizes))
        raise ValueError(f"polygon {bad} has {sizes[bad]} vertices (at least 3 are needed)")
    corners = np.concatenate(polygons)                           # vertex at each polygon corner
    if corners.min() < 0 or corners.max() >= len(vertices):
        raise ValueError(f"polygons index vertices outside [0, {len(vertices)})")
    polygon_of = np.repeat(np.arange(len(polygons)), sizes)
    first = np.cumsum(sizes) - sizes
    position = np.arange(len(corners)) - first[polygon_of]
    next_corner = first[polygon_of] + (position + 1) % sizes[polygon_of]

    used = _unique(corners)
    diag = float(np.linalg.norm(np.ptp(vertices[used], axis=0)))
    tol = tolerance * diag
    if diag == 0.0:
        return polygons

    # Stage 1: the undirected edges, and which vertices lie inside them.
    lo_v = np.minimum(corners, corners[next_corner])
    hi_v = np.maximum(corners, corners[next_corner])
    edge_key, edge_of_corner = np.unique(lo_v * len(vertices) + hi_v, return_inverse=True)
    edges = np.stack([edge_key // len(vertices), edge_key % len(vertices)], axis=1)
    edge_id, vertex_id, t = _vertices_on_edges(vertices, edges, used, tol)
    if len(edge_id) == 0:
        return polygons

    # Stage 2: each hit goes to every polygon side along that edge, unless the polygon already has the vertex.
    side_order = np.argsort(edge_of_corner, kind="stable")
    side_start = np.searchsorted(edge_of_corner[side_order], edge_id, side="left")
    side_count = np.searchsorted(edge_of_corner[side_order], edge_id, side="right") - side_start
    hit = np.repeat(np.arange(len(edge_id)), side_count)
    side = side_order[_expand(side_start, side_count)]                # corner that starts the polygon side
    membership = _unique(polygon_of * len(vertices) + corners)
    key = polygon_of[side] * len(vertices) + vertex_id[hit]
    found = np.searchsorted(membership, key)
    keep = membership[np.minimum(found, len(membership) - 1)] != key
    side, hit = side[keep], hit[keep]
    along = np.where(corners[side] == edges[edge_id[hit], 0], t[hit], 1.0 - t[hit])  # t from the side's start

    # Drop repeats: two vertices at one place on one side (an unwelded mesh) are inserted once.
    order = np.lexsort((along, side))
    side, hit, along = side[order], hit[order], along[order]
    length = np.linalg.norm(vertices[corners[next_corner[side]]] - vertices[corners[side]], axis=1)
    repeat = np.r_[False, (side[1:] == side[:-1]) & ((along[1:] - along[:-1]) * length[1:] <= tol)]
    side, hit, along = side[~repeat], hit[~repeat], along[~repeat]

    # Stage 3: each polygon's corners and inserted vertices, sorted by side then by position along it.
    all_side = np.r_[np.arange(len(corners)), side]
    all_along = np.r_[np.full(len(corners), -1.0), along]
    all_vertex = np.r_[corners, vertex_id[hit]]
    order = np.lexsort((all_along, all_side))
    new_sizes = sizes + np.bincount(polygon_of[side], minlength=len(polygons))
    return np.split(all_vertex[order], np.cumsum(new_sizes)[:-1])


def _vertices_on_edges(vertices, edges, candidates, tol: float):
    """Pairs (edge_id, vertex_id, t) with vertex `candidates[...]` within `tol` of the inside of the edge.

    t in (0, 1) is the position along the edge from edges[:, 0]; the vertex is farther than `tol` from both
    ends. Edges are sampled every half cell; a vertex within `tol` of the edge is within a quarter cell plus
    `tol` (at most half a cell) of a sample, so it lies in the 2 x 2 x 2 block of cells around that sample.
    """
    a, b = vertices[edges[:, 0]], vertices[edges[:, 1]]
    length = np.linalg.norm(b - a, axis=1)
    real = np.flatnonzero(length > 2.0 * tol)                    # an edge shorter than that has no inside
    if len(real) == 0:
        return (np.zeros(0, dtype=np.int64),) * 2 + (np.zeros(0),)
    # Cells about one typical edge long; never so small that cell keys overflow, never under 4 tol.
    points = vertices[candidates]
    extent = float(np.ptp(points, axis=0).max())
    cell = max(float(np.median(length[real])), 4.0 * tol, extent * _MIN_CELL)
    origin = points.min(axis=0) - cell
    dims = np.floor((points.max(axis=0) - origin) / cell).astype(np.int64) + 2

    def cell_key(ijk):
        return ijk[..., 0] + dims[0] * (ijk[..., 1] + dims[1] * ijk[..., 2])

    vertex_cell = cell_key(np.floor((points - origin) / cell).astype(np.int64))
    by_cell = np.argsort(vertex_cell, kind="stable")
    sorted_cells = vertex_cell[by_cell]

    # Samples along each edge, at most half a cell apart, and the block of cells around each.
    n_samples = np.ceil(2.0 * length[real] / cell).astype(np.int64) + 1
    sample_edge = np.repeat(real, n_samples)
    step = np.arange(len(sample_edge)) - np.repeat(np.cumsum(n_samples) - n_samples, n_samples)
    s = step / np.repeat(n_samples - 1, n_samples)
    samples = a[sample_edge] + s[:, None] * (b - a)[sample_edge]
    reach = 0.25 * cell + tol
    low = np.floor((samples - reach - origin) / cell).astype(np.int64)
    high = np.floor((samples + reach - origin) / cell).astype(np.int64)
    block = np.minimum(low[:, None, :] + _BLOCK[None], high[:, None, :])            # (samples, 8, 3)
    pair_edge = np.repeat(sample_edge, 8)
    pair_cell = cell_key(block).ravel()
    n_cells = int(dims[0]) * int(dims[1]) * int(dims[2])
    if n_cells * len(edges) < 2**62:
        pair_key = _unique(pair_edge * n_cells + pair_cell)
        pair_edge, pair_cell = pair_key // n_cells, pair_key % n_cells
    else:
        pair_edge, pair_cell = np.unique(np.stack([pair_edge, pair_cell], axis=1), axis=0).T

    # Candidate pairs: every vertex in every cell near the edge; then the exact distance test.
    start = np.searchsorted(sorted_cells, pair_cell, side="left")
    count = np.searchsorted(sorted_cells, pair_cell, side="right") - start
    edge_id = np.repeat(pair_edge, count)
    vertex_id = candidates[by_cell[_expand(start, count)]]
    pairs = _unique(edge_id * len(vertices) + vertex_id)
    edge_id, vertex_id = pairs // len(vertices), pairs % len(vertices)

    direction = (b - a)[edge_id]
    offset = vertices[vertex_id] - a[edge_id]
    t = np.einsum("ij,ij->i", offset, direction) / length[edge_id] ** 2
    distance = np.linalg.norm(offset - t[:, None] * direction, axis=1)
    inside = (distance <= tol) & (t * length[edge_id] > tol) & ((1.0 - t) * length[edge_id] > tol)
    inside &= (vertex_id != edges[edge_id, 0]) & (vertex_id != edges[edge_id, 1])
    return edge_id[inside], vertex_id[inside], t[inside]


def _unique(keys: np.ndarray) -> np.ndarray:
    """Sorted distinct values of an int array (by sorting: NumPy 2's hashing np.unique is far slower here)."""
    keys = np.sort(keys)
    return keys[np.r_[True, keys[1:] != keys[:-1]]]


def _expand(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Concatenated ranges start[i] .. start[i] + count[i] - 1."""
    offset = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    return np.repeat(start, count) + offset
