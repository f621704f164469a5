"""lumos.mesh.triangulate: a triangulation covers its polygon exactly once (concave, collinear and degenerate
polygons, fans of convex ones, vertices inserted into edges)."""

from __future__ import annotations

import numpy as np
import pytest

from lumos.mesh import face_normals, triangulate, triangulate_polygon

# ---------------------------------------------------------------------------------------------------- helpers

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
