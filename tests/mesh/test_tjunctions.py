"""lumos.mesh.tjunctions: T-junction repair inserts each vertex lying on an edge into that edge, in order, and
leaves a crack-free mesh once triangulated."""

from __future__ import annotations

import numpy as np

from lumos.mesh import repair_t_junctions, triangulate

# ---------------------------------------------------------------------------------------------------- helpers

def _quad_grid(n, x0=0.0, step=1.0, rows=None):
    """Quads of an n-column grid of squares of side `step` starting at x = x0 (rows = n unless given)."""
    rows = n if rows is None else rows
    xs, ys = np.meshgrid(x0 + step * np.arange(n + 1), step * np.arange(rows + 1), indexing="ij")
    vertices = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(rows), indexing="ij"))
    idx = lambda i, j: i * (rows + 1) + j  # noqa: E731
    return vertices, np.stack([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)], axis=1)


# ---------------------------------------------------------------------------------------------------- T-junctions

def test_t_junction_vertex_is_inserted_in_order():
    # A big square [0, 2]^2 and, on its right, two unit squares whose shared corner (2, 1) halves its side.
    vertices = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [2, 1, 0], [3, 0, 0], [3, 1, 0],
                         [3, 2, 0]], dtype=float)
    polygons = [[0, 1, 2, 3], [1, 5, 6, 4], [4, 6, 7, 2]]
    repaired = repair_t_junctions(vertices, polygons)
    np.testing.assert_array_equal(repaired[0], [0, 1, 4, 2, 3])
    np.testing.assert_array_equal(repaired[1], polygons[1])
    np.testing.assert_array_equal(repaired[2], polygons[2])
    assert all(p.dtype == np.int64 for p in repaired)


def test_several_t_junctions_on_one_edge_in_order_and_tolerance():
    # A big square whose top side (walked from (3, 3) to (0, 3)) meets three small squares from above, and
    # a vertex just off the side: inside the tolerance it is inserted, outside it is not.
    def build(offset):
        vertices = np.array([[0, 0, 0], [3, 0, 0], [3, 3, 0], [0, 3, 0],
                             [1, 3, 0], [2, 3 + offset, 0], [0, 4, 0], [1, 4, 0], [2, 4, 0], [3, 4, 0]],
                            dtype=float)
        return vertices, [[0, 1, 2, 3], [3, 4, 7, 6], [4, 5, 8, 7], [5, 2, 9, 8]]

    vertices, polygons = build(0.0)
    np.testing.assert_array_equal(repair_t_junctions(vertices, polygons)[0], [0, 1, 2, 5, 4, 3])
    vertices, polygons = build(1e-9)
    np.testing.assert_array_equal(repair_t_junctions(vertices, polygons)[0], [0, 1, 2, 5, 4, 3])
    vertices, polygons = build(1e-3)
    np.testing.assert_array_equal(repair_t_junctions(vertices, polygons)[0], [0, 1, 2, 4, 3])


def test_a_polygon_never_gets_its_own_vertex():
    # A pinched polygon whose corner 3 = (2, 0) touches its own bottom side, beside a square below that
    # side which does get the vertex.
    vertices = np.array([[0, 0, 0], [4, 0, 0], [4, 2, 0], [2, 0, 0], [0, 2, 0], [0, -4, 0], [4, -4, 0]], float)
    polygons = [[0, 1, 2, 3, 4], [0, 5, 6, 1]]
    repaired = repair_t_junctions(vertices, polygons)
    np.testing.assert_array_equal(repaired[0], polygons[0])
    np.testing.assert_array_equal(repaired[1], [0, 5, 6, 1, 3])


def test_mesh_without_t_junctions_is_unchanged():
    vertices, quads = _quad_grid(30)
    repaired = repair_t_junctions(vertices, quads)
    assert len(repaired) == len(quads)
    assert all(np.array_equal(r, q) for r, q in zip(repaired, quads))


def test_coarse_beside_fine_grid_at_scale():
    # 60 x 100 unit squares on the left, 240 x 200 half-size squares on the right (54k polygons), the two grids
    # not welded: every coarse square along the seam gets the fine vertex in the middle of its right side.
    # The fine vertices at the coarse corners are twins of those corners (at the ends of the coarse edges),
    # and no coarse vertex lies inside a fine edge, so nothing else changes.
    rows = 100
    coarse_v, coarse_q = _quad_grid(60, rows=rows)
    fine_v, fine_q = _quad_grid(240, x0=60.0, step=0.5, rows=2 * rows)
    vertices = np.r_[coarse_v, fine_v]
    polygons = list(coarse_q) + list(fine_q + len(coarse_v))
    repaired = repair_t_junctions(vertices, polygons)
    changed = [i for i, (r, p) in enumerate(zip(repaired, polygons)) if not np.array_equal(r, p)]
    assert len(changed) == rows
    for i in changed:
        quad, new = polygons[i], repaired[i]
        assert len(new) == 5 and vertices[quad[1], 0] == 60.0
        inserted = vertices[new[2]]
        np.testing.assert_array_equal(inserted, 0.5 * (vertices[quad[1]] + vertices[quad[2]]))
        np.testing.assert_array_equal(np.delete(new, 2), quad)


def test_t_junction_repair_then_triangulate_is_crack_free():
    # After repair and triangulation, every edge inside the mesh is shared by exactly two triangles: the
    # big square's right side (1, 2) is gone, replaced by (1, 4) and (4, 2), which the small squares share.
    vertices = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [2, 1, 0], [3, 0, 0], [3, 1, 0],
                         [3, 2, 0]], dtype=float)
    faces, _ = triangulate(vertices, repair_t_junctions(vertices, [[0, 1, 2, 3], [1, 5, 6, 4], [4, 6, 7, 2]]))
    edges = np.sort(np.r_[faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    outline = {(0, 1), (1, 5), (5, 6), (6, 7), (2, 7), (2, 3), (0, 3)}
    assert {tuple(e) for e in unique[counts == 1]} == outline and np.all(counts <= 2)
