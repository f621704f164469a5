"""lumos.mesh: vertex normals, triangulation, T-junction repair and subdivision, against closed forms and naive twins.

Geometry with known answers: the normals of a sphere are radial, a cube's corners are its diagonals (or its axes
once split at the crease), a triangulation covers its polygon exactly once, Loop subdivision keeps the Euler
characteristic and rounds an icosahedron. Where there is no closed form, a slow per-corner or per-vertex
Python twin is the reference.
"""

from __future__ import annotations


import numpy as np
import pytest
import trimesh

from lumos.mesh import (face_normals, weld_ids, repair_t_junctions, subdivide, triangulate, triangulate_polygon,
                        vertex_normals)

WEIGHTINGS = ("average", "area", "angle")


# ---------------------------------------------------------------------------------------------------- helpers

def _grid(n, height=None):
    """An n x n grid of unit squares in the xy plane, each split into two triangles; z = height(x, y)."""
    xs, ys = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="ij")
    zs = np.zeros_like(xs) if height is None else height(xs, ys)
    vertices = np.stack([xs.ravel(), ys.ravel(), zs.ravel()], axis=1)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
    idx = lambda i, j: i * (n + 1) + j  # noqa: E731
    faces = np.r_[np.stack([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], 1),
                  np.stack([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)], 1)]
    return vertices, faces


def _quad_grid(n, x0=0.0, step=1.0, rows=None):
    """Quads of an n-column grid of squares of side `step` starting at x = x0 (rows = n unless given)."""
    rows = n if rows is None else rows
    xs, ys = np.meshgrid(x0 + step * np.arange(n + 1), step * np.arange(rows + 1), indexing="ij")
    vertices = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(rows), indexing="ij"))
    idx = lambda i, j: i * (rows + 1) + j  # noqa: E731
    return vertices, np.stack([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)], axis=1)


def _signed_areas(points_2d, triangles):
    p = points_2d[triangles]
    return 0.5 * ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                  - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))


def _shoelace(points_2d):
    x, y = points_2d[:, 0], points_2d[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def _inside(points_2d, polygon_2d):
    """Even-odd point-in-polygon test, points (q, 2)."""
    x, y = points_2d[:, 0:1], points_2d[:, 1:2]
    a, b = polygon_2d, np.roll(polygon_2d, -1, axis=0)
    crosses = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (crosses & (x < x_at)).sum(axis=1) % 2 == 1


def _naive_corner_normals(vertices, faces, weighting, crease_angle):
    """Per-corner normal by definition: a Python loop over corners and the faces around each vertex."""
    normals, areas = face_normals(vertices, faces)
    cos_crease = np.cos(np.radians(crease_angle))
    around = {}
    for f, face in enumerate(faces):
        for k, v in enumerate(face):
            e1 = vertices[face[(k + 1) % 3]] - vertices[v]
            e2 = vertices[face[(k + 2) % 3]] - vertices[v]
            angle = np.arctan2(np.linalg.norm(np.cross(e1, e2)), e1 @ e2)
            weight = {"average": 1.0, "area": areas[f], "angle": angle}[weighting] * (areas[f] > 0)
            around.setdefault(v, []).append((f, weight))
    result = np.zeros((len(faces), 3, 3))
    for f, face in enumerate(faces):
        for k, v in enumerate(face):
            total = sum(w * normals[g] for g, w in around[v]
                        if areas[f] == 0 or normals[f] @ normals[g] >= cos_crease - 1e-12)
            result[f, k] = total / np.linalg.norm(total)
    return result


def _naive_loop(vertices, faces):
    """One level of Loop subdivision by the textbook rules, with dicts and loops."""
    sides = {}
    for f in faces:
        for k in range(3):
            a, b, c = f[k], f[(k + 1) % 3], f[(k + 2) % 3]
            sides.setdefault((min(a, b), max(a, b)), []).append(c)
    neighbours = {v: set() for v in range(len(vertices))}
    boundary = {v: set() for v in range(len(vertices))}
    for (a, b), opposite in sides.items():
        neighbours[a].add(b), neighbours[b].add(a)
        if len(opposite) == 1:
            boundary[a].add(b), boundary[b].add(a)
    moved = vertices.copy()
    for v in range(len(vertices)):
        if boundary[v]:
            if len(boundary[v]) == 2:
                moved[v] = 0.75 * vertices[v] + 0.125 * sum(vertices[u] for u in boundary[v])
        elif neighbours[v]:
            n = len(neighbours[v])
            beta = 3.0 / (8.0 * n) if n > 3 else 3.0 / 16.0
            moved[v] = (1 - n * beta) * vertices[v] + beta * sum(vertices[u] for u in neighbours[v])
    edge_point = {}
    for (a, b), opposite in sides.items():
        if len(opposite) == 2:
            edge_point[a, b] = 0.375 * (vertices[a] + vertices[b]) + 0.125 * (vertices[opposite[0]]
                                                                             + vertices[opposite[1]])
        else:
            edge_point[a, b] = 0.5 * (vertices[a] + vertices[b])
    return moved, edge_point


# ---------------------------------------------------------------------------------------------------- normals

def test_face_normals_units_areas_and_degenerate_faces():
    vertices = np.array([[0, 0, 0], [2, 0, 0], [0, 3, 0], [4, 0, 0]], dtype=float)
    normals, areas = face_normals(vertices, [[0, 1, 2], [0, 2, 1], [0, 1, 3]])
    np.testing.assert_allclose(normals, [[0, 0, 1], [0, 0, -1], [0, 0, 0]])
    np.testing.assert_allclose(areas, [3.0, 3.0, 0.0])


@pytest.mark.parametrize("weighting", WEIGHTINGS)
def test_vertex_normals_of_a_sphere_are_radial(weighting):
    sphere = trimesh.creation.icosphere(subdivisions=4)
    vertices, faces = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    vertices2, faces2, normals, source = vertex_normals(vertices, faces, weighting)
    radial = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    assert np.abs(normals - radial).max() < 1e-2
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert vertices2 is vertices and faces2 is faces
    np.testing.assert_array_equal(source, np.arange(len(vertices)))


def test_angle_weighting_gives_cube_diagonals():
    box = trimesh.creation.box()
    vertices, faces = np.asarray(box.vertices), np.asarray(box.faces)
    _, _, normals, _ = vertex_normals(vertices, faces, "angle", crease_angle=180.0)
    np.testing.assert_allclose(normals, np.sign(vertices) / np.sqrt(3.0), atol=1e-12)
    # Area weighting depends on how each square was cut in two: some corners are not diagonals.
    _, _, by_area, _ = vertex_normals(vertices, faces, "area", crease_angle=180.0)
    assert np.abs(by_area - np.sign(vertices) / np.sqrt(3.0)).max() > 0.1


def test_cube_with_crease_splits_into_face_normals():
    box = trimesh.creation.box()
    vertices, faces = np.asarray(box.vertices), np.asarray(box.faces)
    vertices2, faces2, normals, source = vertex_normals(vertices, faces, "angle", crease_angle=60.0)
    assert len(vertices2) == 24
    assert np.all(np.sort(np.abs(normals), axis=1) == [0.0, 0.0, 1.0])      # axis normals
    face_n, _ = face_normals(vertices2, faces2)
    np.testing.assert_allclose(normals[faces2], np.repeat(face_n[:, None], 3, axis=1), atol=1e-12)
    np.testing.assert_array_equal(vertices2, vertices[source])
    np.testing.assert_array_equal(vertices2[faces2], vertices[faces])        # same triangles, same winding
    np.testing.assert_array_equal(np.bincount(source), np.full(8, 3))


def test_smooth_sphere_with_crease_is_not_split():
    sphere = trimesh.creation.uv_sphere(count=[24, 24])
    vertices, faces = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    vertices2, faces2, normals, source = vertex_normals(vertices, faces, "angle", crease_angle=60.0)
    _, _, smooth, _ = vertex_normals(vertices, faces, "angle")
    assert len(vertices2) == len(vertices)
    np.testing.assert_array_equal(faces2, faces)
    np.testing.assert_allclose(normals, smooth)


@pytest.mark.parametrize("weighting", WEIGHTINGS)
def test_creased_normals_match_naive_twin(weighting):
    # A coarse cylinder (sharp rim, smooth side) with jittered vertices and one degenerate face.
    cylinder = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=7)
    rng = np.random.default_rng(3)
    vertices = np.asarray(cylinder.vertices) + rng.normal(0.0, 0.02, (len(cylinder.vertices), 3))
    faces = np.r_[np.asarray(cylinder.faces), [[0, 0, 1]]]
    vertices2, faces2, normals, source = vertex_normals(vertices, faces, weighting, crease_angle=50.0)
    np.testing.assert_allclose(normals[faces2], _naive_corner_normals(vertices, faces, weighting, 50.0),
                               atol=1e-12)
    np.testing.assert_array_equal(vertices2[faces2], vertices[faces])
    assert len(vertices2) > len(vertices)                                    # the rims split
    # No vertex is duplicated needlessly: split copies of one vertex have different normals.
    for v in np.flatnonzero(np.bincount(source) > 1):
        copies = normals[source == v]
        gaps = np.linalg.norm(copies[:, None] - copies[None], axis=2) + np.eye(len(copies))
        assert gaps.min() > 1e-9


def _split_along_a_seam(mesh):
    """The mesh with the vertices of its faces left of x = 0 repeated: a seam of unshared vertices, as a file with
    patches (the Utah teapot) or uv seams gives them."""
    v, f = np.array(mesh.vertices, float), np.array(mesh.faces)
    left = v[f].mean(axis=1)[:, 0] < 0
    used = np.unique(f[left])
    remap = np.arange(len(v))
    remap[used] = len(v) + np.arange(len(used))
    f[left] = remap[f[left]]
    return np.concatenate([v, v[used]]), f


def test_welding_removes_seams_and_keeps_a_faceted_cube_faceted():
    """Repeated positions share normals (the seam of a split sphere shades as the sphere does), within the smaller
    of the crease angle and WELD_CREASE (a cube given with a vertex per face corner stays faceted); the first n
    output vertices are the input ones and `source` carries attributes over; without repeats nothing changes."""
    v, f = _split_along_a_seam(trimesh.creation.uv_sphere(count=[16, 16]))
    assert np.all(weld_ids(v)[len(v) - 10:] < len(v) - 10)  # the copies weld to the originals
    v2, f2, n2, source = vertex_normals(v, f)
    radial = v2 / np.linalg.norm(v2, axis=1, keepdims=True)
    err = np.degrees(np.arccos(np.clip(np.einsum("ijk,ijk->ij", n2[f2], radial[f2]), -1, 1))).max()
    _, f3, n3, _ = vertex_normals(v, f, weld=False)
    err3 = np.degrees(np.arccos(np.clip(np.einsum("ijk,ijk->ij", n3[f3], radial[f3]), -1, 1))).max()
    assert err < 1.0 < 5.0 < err3  # 0.4° against 5.6° along the seam unwelded
    assert np.array_equal(v2[:len(v)], v) and np.array_equal(v2, v[source])
    box = trimesh.creation.box()
    cv, cf = box.vertices[box.faces].reshape(-1, 3), np.arange(36).reshape(-1, 3)
    _, cf2, cn2, _ = vertex_normals(cv, cf)
    fn, _ = face_normals(cv, cf)
    np.testing.assert_allclose(cn2[cf2], np.repeat(fn[:, None], 3, axis=1), atol=1e-12)
    sphere = trimesh.creation.icosphere(subdivisions=2)
    out = vertex_normals(sphere.vertices, sphere.faces)
    ref = vertex_normals(sphere.vertices, sphere.faces, weld=False)
    assert all(np.array_equal(a, b) for a, b in zip(out, ref))


def test_vertex_without_faces_and_bad_arguments():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]], dtype=float)
    _, _, normals, _ = vertex_normals(vertices, [[0, 2, 1]])
    np.testing.assert_allclose(normals, [[0, 0, -1]] * 3 + [[0, 0, 1]])
    with pytest.raises(ValueError, match="weighting"):
        vertex_normals(vertices, [[0, 1, 2]], weighting="median")
    with pytest.raises(ValueError, match="crease_angle"):
        vertex_normals(vertices, [[0, 1, 2]], crease_angle=200)


@pytest.mark.slow
def test_vertex_normals_of_a_million_triangles():
    # the benchmark mesh (1.3M triangles): vectorised code must cope (how fast is BENCHMARKS.md's business)
    sphere = trimesh.creation.icosphere(subdivisions=8)
    vertices, faces = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    assert len(faces) > 1_300_000
    _, _, normals, _ = vertex_normals(vertices, faces, "angle")
    vertices2, _, _, _ = vertex_normals(vertices, faces, "angle", crease_angle=30.0)
    assert len(vertices2) == len(vertices)
    assert np.abs(normals - vertices / np.linalg.norm(vertices, axis=1, keepdims=True)).max() < 1e-3


# ---------------------------------------------------------------------------------------------------- triangulate

def _star(k=10, r_in=0.4):
    angles = np.linspace(0, 2 * np.pi, k, endpoint=False)
    radii = np.where(np.arange(k) % 2 == 0, 1.0, r_in)
    return np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)


L_SHAPE = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
COMB = np.array([[0, 0], [5, 0], [5, 3], [4, 3], [4, 1], [3, 1], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3],
                 [0, 3]], dtype=float)


@pytest.mark.parametrize("polygon_2d", [L_SHAPE, _star(), COMB, L_SHAPE[::-1]], ids=["L", "star", "comb", "L-cw"])
def test_concave_polygon_is_covered_exactly_once(polygon_2d):
    # Put the polygon in a tilted plane, so the projection through the Newell normal is exercised.
    rotation, _ = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))
    points = np.c_[polygon_2d, np.zeros(len(polygon_2d))] @ rotation.T + [0.3, -2.0, 1.0]
    triangles = triangulate_polygon(points)
    assert triangles.shape == (len(points) - 2, 3) and triangles.dtype == np.int64

    areas = _signed_areas(polygon_2d, triangles)
    polygon_area = _shoelace(polygon_2d)
    assert np.all(np.sign(areas) == np.sign(polygon_area))                   # the polygon's winding
    assert np.all(np.abs(areas) > 1e-9)                                     # no slivers
    assert np.sum(areas) == pytest.approx(polygon_area, rel=1e-12)
    # Every triangle lies inside: with the areas adding up, they cannot overlap.
    bary = np.random.default_rng(2).dirichlet(np.ones(3), size=50)
    samples = np.einsum("sk,tkc->tsc", bary, polygon_2d[triangles]).reshape(-1, 2)
    assert _inside(samples, polygon_2d).all()
    # In 3D too the triangles' normals follow the polygon's.
    normals, _ = face_normals(points, triangles)
    assert np.allclose(normals, normals[0]) and np.sign(polygon_area) * normals[0] @ rotation[:, 2] > 0.99


def test_collinear_and_degenerate_polygons():
    # A square with a vertex in the middle of each side: 6 triangles, none of them flat.
    square = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2], [0, 1]], dtype=float)
    triangles = triangulate_polygon(np.c_[square, np.zeros(8)])
    areas = _signed_areas(square, triangles)
    assert len(triangles) == 6 and np.all(areas > 1e-9) and np.sum(areas) == pytest.approx(4.0)
    # Through `triangulate` too, and a triangle with two vertices on one side, where every fan has a sliver.
    for points, ring in ((np.c_[square, np.zeros(8)], np.arange(8)),
                         (np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [0, 3, 0]], float), np.arange(5))):
        faces, _ = triangulate(points, [ring])
        areas = _signed_areas(points[:, :2], faces)
        assert len(faces) == len(ring) - 2 and np.all(areas > 1e-9)
        assert np.sum(areas) == pytest.approx(_shoelace(points[:, :2]))
    # All points on a line: no plane, so a fan of the right size.
    line = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)]
    np.testing.assert_array_equal(triangulate_polygon(line), [[0, 1, 2], [0, 2, 3], [0, 3, 4]])


def test_triangulate_fans_convex_polygons_and_maps_faces_to_polygons():
    angles = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    hexagon = np.c_[np.cos(angles), np.sin(angles), np.zeros(6)]
    vertices = np.r_[hexagon, np.c_[L_SHAPE, np.ones(6)], [[5, 5, 5]]]
    polygons = [np.arange(6), [0, 1, 12], np.arange(6, 12), [1, 2, 3, 4]]
    faces, face_polygon = triangulate(vertices, polygons)
    np.testing.assert_array_equal(face_polygon, [0, 0, 0, 0, 1, 2, 2, 2, 2, 3, 3])
    np.testing.assert_array_equal(faces[:4], [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])  # the fan
    np.testing.assert_array_equal(faces[4], [0, 1, 12])                                      # passed through
    for p, polygon in enumerate(polygons):
        assert np.isin(faces[face_polygon == p], polygon).all()
    l_faces = faces[face_polygon == 2]
    assert np.sum(_signed_areas(vertices[:, :2], l_faces)) == pytest.approx(3.0)
    assert np.all(_signed_areas(vertices[:, :2], l_faces) > 0)


def test_triangulate_uses_a_vertex_inserted_into_an_edge():
    # The big quad of a repaired T-junction: corner 2 is the midpoint of the side from 1 to 3.
    vertices = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [2, 2, 0], [0, 2, 0]], dtype=float)
    faces, _ = triangulate(vertices, [[0, 1, 2, 3, 4]])
    areas = _signed_areas(vertices[:, :2], faces)
    assert np.all(areas > 1e-9) and np.sum(areas) == pytest.approx(4.0)
    assert 2 in faces


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


# ---------------------------------------------------------------------------------------------------- subdivide

def test_midpoint_subdivision_of_one_triangle():
    vertices = np.array([[0, 0, 0], [2, 0, 0], [0, 1, 1]], dtype=float)
    uvs = np.array([[0, 0], [1, 0], [0, 1]], dtype=float)
    v, f, u = subdivide(vertices, [[0, 1, 2]], "midpoint", uvs=uvs)
    assert f.shape == (4, 3) and len(v) == 6
    normals, areas = face_normals(v, f)
    _, (area,) = face_normals(vertices, [[0, 1, 2]])
    assert areas.sum() == pytest.approx(area) and np.allclose(areas, area / 4)
    assert np.allclose(normals, face_normals(vertices, [[0, 1, 2]])[0])      # orientation kept
    np.testing.assert_array_equal(v[:3], vertices)
    # Texture coordinates are the same affine function of position before and after.
    fit = np.linalg.lstsq(np.c_[vertices, np.ones(3)], uvs, rcond=None)[0]
    np.testing.assert_allclose(np.c_[v, np.ones(6)] @ fit, u, atol=1e-12)


@pytest.mark.parametrize("levels", [1, 2, 3])
def test_loop_subdivision_of_an_icosahedron(levels):
    ico = trimesh.creation.icosahedron()
    v, f, _ = subdivide(ico.vertices, ico.faces, "loop", levels)
    mv, mf, _ = subdivide(ico.vertices, ico.faces, "midpoint", levels)
    edges = np.unique(np.sort(np.r_[f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]], axis=1), axis=0)
    assert len(f) == 20 * 4**levels
    assert len(v) - len(edges) + len(f) == 2                                 # Euler characteristic
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    spread = lambda x: np.ptp(np.linalg.norm(x, axis=1)) / np.linalg.norm(x, axis=1).mean()  # noqa: E731
    assert spread(v) < 0.5 * spread(mv)                                      # rounder than the midpoints


def _loop_cases():
    grid = _grid(5, lambda x, y: np.sin(x) * np.cos(0.7 * y))                # open: boundary rules, valence 6
    box = trimesh.creation.box()                                            # valence 4 and 5
    jitter = np.random.default_rng(4).normal(0.0, 0.05, (4, 3))
    tetrahedron = (np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) + jitter,   # valence 3
                   np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]))
    ico = trimesh.creation.icosahedron()                                    # valence 5
    return {"grid": grid, "box": (np.asarray(box.vertices), np.asarray(box.faces)), "tetrahedron": tetrahedron,
            "icosahedron": (np.asarray(ico.vertices), np.asarray(ico.faces))}


@pytest.mark.parametrize("case", ["grid", "box", "tetrahedron", "icosahedron"])
def test_loop_matches_naive_twin(case):
    vertices, faces = _loop_cases()[case]
    v, f, _ = subdivide(vertices, faces, "loop")
    moved, edge_point = _naive_loop(vertices, faces)
    np.testing.assert_allclose(v[:len(vertices)], moved, atol=1e-12)
    sides = np.sort(np.r_[faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1)
    for e, (a, b) in enumerate(np.unique(sides, axis=0)):
        np.testing.assert_allclose(v[len(vertices) + e], edge_point[a, b], atol=1e-12)


def test_loop_keeps_a_tilted_plane_planar_and_carries_uvs():
    vertices, faces = _grid(6)
    uvs = vertices[:, :2] / 6.0
    vertices = vertices @ np.array([[1, 0, 0.3], [0, 1, -0.2], [0, 0, 1]]) + [0, 0, 1]   # z = 0.3x - 0.2y + 1
    v, f, u = subdivide(vertices, faces, "loop", levels=2, uvs=uvs)
    np.testing.assert_allclose(v[:, 2], 0.3 * v[:, 0] - 0.2 * v[:, 1] + 1, atol=1e-12)
    assert len(u) == len(v) and len(f) == 16 * len(faces)
    # The first level's edge points carry the mean of their ends' uvs; old vertices keep theirs.
    _, _, u1 = subdivide(vertices, faces, "loop", levels=1, uvs=uvs)
    np.testing.assert_array_equal(u[:len(uvs)], uvs)
    np.testing.assert_array_equal(u[:len(u1)], u1)
    assert np.all((u >= 0) & (u <= 1))
    normals, _ = face_normals(v, f)
    assert np.allclose(normals, normals[0]) and normals[0][2] > 0           # orientation kept


def test_subdivide_levels_and_errors():
    ico = trimesh.creation.icosahedron()
    v, f, u = subdivide(ico.vertices, ico.faces, "loop", levels=5)
    assert len(f) == 20 * 4**5 and len(v) == 10 * 4**5 + 2 and u is None
    v0, f0, _ = subdivide(ico.vertices, ico.faces, levels=0)
    np.testing.assert_array_equal(v0, ico.vertices)
    with pytest.raises(ValueError, match="scheme"):
        subdivide(ico.vertices, ico.faces, "catmull-clark")
    with pytest.raises(ValueError, match="levels"):
        subdivide(ico.vertices, ico.faces, levels=-1)
