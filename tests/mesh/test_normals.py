"""lumos.mesh.normals: face and vertex normals, creases and welding, against closed forms and a naive twin.

Geometry with known answers: the normals of a sphere are radial, a cube's corners are its diagonals (or its axes
once split at the crease). Where there is no closed form, a slow per-corner Python twin is the reference.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from lumos.mesh import face_normals, vertex_normals, weld_ids

WEIGHTINGS = ("average", "area", "angle")


# ---------------------------------------------------------------------------------------------------- helpers

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
