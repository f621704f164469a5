"""Tessellation of the canonical shapes (`compile.tessellate`): vertices on the analytic surface, exact normals,
watertight and outward closed meshes whose volume and area converge to the closed forms, counter-clockwise
winding (also under a mirror), uvs equal to the ray tracer's, planar groups."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumos.compile.tessellate import Tessellation, tessellate_plane, tessellate_shape
from lumos.kernels.layout import (
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CYLINDER,
    SHAPE_DISK,
    SHAPE_PLANE,
    SHAPE_RECT,
    SHAPE_SPHERE,
)

ALL_KINDS = [SHAPE_SPHERE, SHAPE_BOX, SHAPE_CYLINDER, SHAPE_CONE, SHAPE_DISK, SHAPE_RECT]
CLOSED_KINDS = [SHAPE_SPHERE, SHAPE_BOX, SHAPE_CYLINDER, SHAPE_CONE]


def _rotation(axis, degrees) -> np.ndarray:
    """Rodrigues' rotation matrix."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    a = math.radians(degrees)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx


def _affine(linear, origin) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = linear
    m[:3, 3] = origin
    return m


# translate · rotate · non-uniform scale, and the same after a mirror in canonical x
SKEWED = _affine(_rotation([1, 2, -0.5], 37) @ np.diag([1.5, 0.7, 2.2]), [0.3, -1.2, 4.0])
MIRRORED = SKEWED @ np.diag([-1.0, 1.0, 1.0, 1.0])
SIMILAR = _affine(1.7 * _rotation([-0.3, 1, 0.2], 71), [2.0, 0.5, -3.0])  # rotation + uniform scale
MATRICES = {"skewed": SKEWED, "mirrored": MIRRORED}


def _canonical(t: Tessellation, m: np.ndarray):
    """Vertices mapped back to canonical space, and the unit canonical normals (transpose of the linear part)."""
    linear = m[:3, :3]
    points = (t.vertices - m[:3, 3]) @ np.linalg.inv(linear).T
    normals = t.normals @ linear  # row form of linear.T @ n: undoes the inverse transpose
    return points, normals / np.linalg.norm(normals, axis=1, keepdims=True)


def _gradient(kind, p, n_unit, u):
    """Analytic outward normal (unnormalised) of the canonical shape at p. Which part a rim or corner vertex
    belongs to is read from the normal it carries; `test_vertices_on_surface` checks it lies on that part."""
    x, y, z = p
    if kind == SHAPE_SPHERE:
        return np.array(p)
    if kind == SHAPE_BOX:
        axis = int(np.argmax(np.abs(n_unit)))
        g = np.zeros(3)
        g[axis] = 1.0 if p[axis] > 0.5 else -1.0
        return g
    if kind in (SHAPE_DISK, SHAPE_RECT):
        return np.array([0.0, 0.0, 1.0])
    if abs(n_unit[2]) > 0.99:  # a cap
        return np.array([0.0, 0.0, 1.0 if z > 0.5 else -1.0])
    if kind == SHAPE_CYLINDER:
        return np.array([x, y, 0.0])
    if math.hypot(x, y) < 1e-12:  # the cone's apex: the slant normal at the segment's middle angle
        phi = 2 * math.pi * (u - 0.5)
        return np.array([math.cos(phi), math.sin(phi), 1.0])
    return np.array([x, y, 1.0 - z])


def _on_surface(kind, p, n_unit) -> bool:
    x, y, z = p
    r = math.hypot(x, y)
    eps = 1e-9
    inside = lambda lo, c, hi: lo - eps <= c <= hi + eps  # noqa: E731
    if kind == SHAPE_SPHERE:
        return abs(np.linalg.norm(p) - 1.0) < eps
    if kind == SHAPE_BOX:
        axis = int(np.argmax(np.abs(n_unit)))
        face = 1.0 if n_unit[axis] > 0 else 0.0
        return abs(p[axis] - face) < eps and all(inside(0, c, 1) for c in p)
    if kind == SHAPE_DISK:
        return abs(z) < eps and r <= 1 + eps
    if kind == SHAPE_RECT:
        return abs(z) < eps and inside(0, x, 1) and inside(0, y, 1)
    if abs(n_unit[2]) > 0.99:  # a cap of a cylinder (z = 0 or 1) or cone (z = 0), facing away from the body
        face = 1.0 if n_unit[2] > 0 else 0.0
        return abs(z - face) < eps and r <= 1 + eps and (kind == SHAPE_CYLINDER or face == 0.0)
    rim = 1.0 if kind == SHAPE_CYLINDER else 1.0 - z
    return abs(r - rim) < eps and inside(0, z, 1)


def _face_normals(t: Tessellation) -> np.ndarray:
    v = t.vertices[t.faces]
    return np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])


def _merged_faces(t: Tessellation) -> np.ndarray:
    """Faces re-indexed after merging vertices at the same position (seam, pole and apex duplicates)."""
    scale = max(1.0, np.abs(t.vertices).max())
    _, index = np.unique(np.round(t.vertices / scale, 9), axis=0, return_inverse=True)
    return index.reshape(-1)[t.faces]


def _volume(t: Tessellation) -> float:
    v = t.vertices[t.faces]
    return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)


def _area(t: Tessellation) -> float:
    return float(0.5 * np.linalg.norm(_face_normals(t), axis=1).sum())


# -------------------------------------------------------------------------------------------------- tests


@pytest.mark.parametrize("name", MATRICES)
@pytest.mark.parametrize("kind", ALL_KINDS)
def test_types_and_shapes(kind, name):
    t = tessellate_shape(kind, MATRICES[name], 12)
    n, m = len(t.vertices), len(t.faces)
    assert t.vertices.shape == (n, 3) and t.normals.shape == (n, 3) and t.uvs.shape == (n, 2)
    assert t.faces.shape == (m, 3) and t.groups.shape == (m,)
    assert t.vertices.dtype == t.normals.dtype == t.uvs.dtype == np.float64
    assert t.faces.dtype == t.groups.dtype == np.int64
    assert t.faces.min() == 0 and t.faces.max() == n - 1  # every vertex used, no index out of range
    # groups numbered 0.. without gaps
    np.testing.assert_array_equal(np.unique(t.groups), np.arange(t.groups.max() + 1))


def test_counts():
    s = tessellate_shape(SHAPE_SPHERE, np.eye(4), 16)  # 8 rings: 7 interior rings of 17, 2 × 16 pole vertices
    assert len(s.vertices) == 7 * 17 + 2 * 16
    assert len(s.faces) == 6 * 16 * 2 + 2 * 16 and s.groups.max() + 1 == 6 * 16 + 2 * 16
    b = tessellate_shape(SHAPE_BOX, np.eye(4), 3)
    assert (len(b.vertices), len(b.faces)) == (24, 12)
    assert sorted(np.bincount(b.groups)) == [2] * 6  # six groups of two triangles
    r = tessellate_shape(SHAPE_RECT, np.eye(4), 3)
    assert (len(r.vertices), len(r.faces), r.groups.max()) == (4, 2, 0)
    d = tessellate_shape(SHAPE_DISK, np.eye(4), 10)
    assert (len(d.vertices), len(d.faces)) == (11, 10)  # a fan around the centre
    c = tessellate_shape(SHAPE_CONE, np.eye(4), 10, capped=False)
    apex = np.isclose(c.vertices[:, 2], 1.0)
    assert apex.sum() == 10  # one apex vertex per segment
    assert len(tessellate_shape(SHAPE_CYLINDER, np.eye(4), 10, capped=False).faces) == 20


@pytest.mark.parametrize("name", MATRICES)
@pytest.mark.parametrize("kind", ALL_KINDS)
def test_vertices_on_surface(kind, name):
    m = MATRICES[name]
    t = tessellate_shape(kind, m, 9)
    points, normals = _canonical(t, m)
    bad = [i for i, (p, n) in enumerate(zip(points, normals)) if not _on_surface(kind, p, n)]
    assert not bad, f"{len(bad)} vertices off the surface, e.g. canonical {points[bad[0]]}"


@pytest.mark.parametrize("name", MATRICES)
@pytest.mark.parametrize("kind", ALL_KINDS)
def test_normals_exact_and_unit(kind, name):
    m = MATRICES[name]
    t = tessellate_shape(kind, m, 11)
    np.testing.assert_allclose(np.linalg.norm(t.normals, axis=1), 1.0, atol=1e-12)
    points, normals = _canonical(t, m)
    inv_t = np.linalg.inv(m[:3, :3]).T
    expected = np.array([inv_t @ _gradient(kind, p, n, uv[0]) for p, n, uv in zip(points, normals, t.uvs)])
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    np.testing.assert_allclose(t.normals, expected, atol=1e-9)


def test_cone_apex_normals_are_slant_normals_at_mid_angles():
    t = tessellate_shape(SHAPE_CONE, np.eye(4), 8, capped=False)
    apex = np.flatnonzero(np.isclose(t.vertices[:, 2], 1.0))
    phi = np.sort(np.arctan2(t.normals[apex, 1], t.normals[apex, 0]))
    np.testing.assert_allclose(phi, 2 * np.pi * ((np.arange(8) + 0.5) / 8 - 0.5), atol=1e-12)
    np.testing.assert_allclose(t.normals[apex, 2], math.sqrt(0.5), atol=1e-12)


@pytest.mark.parametrize("name", MATRICES)
@pytest.mark.parametrize("kind", ALL_KINDS)
def test_winding_counter_clockwise_from_normal_side(kind, name):
    t = tessellate_shape(kind, MATRICES[name], 7)
    g = _face_normals(t)
    for corner in range(3):
        assert np.all(np.einsum("ij,ij->i", g, t.normals[t.faces[:, corner]]) > 0.0)


@pytest.mark.parametrize("name", MATRICES)
@pytest.mark.parametrize("kind", CLOSED_KINDS)
def test_closed_shapes_watertight(kind, name):
    t = tessellate_shape(kind, MATRICES[name], 10)
    faces = _merged_faces(t)
    assert np.all((faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2]))
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)
    # consistently oriented: each directed edge once (the neighbour runs it the other way)
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)


def test_open_shapes_have_a_boundary():
    t = tessellate_shape(SHAPE_CYLINDER, np.eye(4), 10, capped=False)
    faces = _merged_faces(t)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert (counts == 1).sum() == 20  # the two rims


CANONICAL_VOLUME = {SHAPE_SPHERE: 4 * math.pi / 3, SHAPE_BOX: 1.0, SHAPE_CYLINDER: math.pi, SHAPE_CONE: math.pi / 3}
CANONICAL_AREA = {
    SHAPE_SPHERE: 4 * math.pi,
    SHAPE_BOX: 6.0,
    SHAPE_CYLINDER: 4 * math.pi,  # side 2π + two caps
    SHAPE_CONE: math.pi * math.sqrt(2) + math.pi,  # slant π·r·√2 + base
}


@pytest.mark.parametrize("name", MATRICES)
@pytest.mark.parametrize("kind", CLOSED_KINDS)
def test_volume_positive_and_converging(kind, name):
    m = MATRICES[name]
    exact = CANONICAL_VOLUME[kind] * abs(np.linalg.det(m[:3, :3]))
    volumes = [_volume(tessellate_shape(kind, m, s)) for s in (8, 32, 128)]
    assert all(v > 0 for v in volumes)
    errors = [abs(v - exact) / exact for v in volumes]
    if kind == SHAPE_BOX:
        assert max(errors) < 1e-12
    else:
        assert errors[0] > errors[1] > errors[2] and errors[2] < 2e-3


@pytest.mark.parametrize("kind", CLOSED_KINDS)
def test_area_converges(kind):
    scale = 1.7  # SIMILAR scales uniformly, so areas scale by its square
    exact = CANONICAL_AREA[kind] * scale**2
    errors = [abs(_area(tessellate_shape(kind, SIMILAR, s)) - exact) / exact for s in (8, 64, 256)]
    assert errors[2] < 0.01
    if kind == SHAPE_BOX:
        assert max(errors) < 1e-12
    else:
        assert errors[0] > errors[1] > errors[2]


@pytest.mark.parametrize("kind", ALL_KINDS)
def test_uvs_match_ray_tracer(kind):
    from lumos.kernels.surface import _canonical_normal_uv

    m = SKEWED
    t = tessellate_shape(kind, m, 8)
    points, normals = _canonical(t, m)
    checked = 0
    for p, n, uv in zip(points, normals, t.uvs):
        part = 0
        if kind == SHAPE_BOX:
            axis = int(np.argmax(np.abs(n)))
            part = 2 * axis + (1 if n[axis] > 0 else 0)
        elif kind in (SHAPE_CYLINDER, SHAPE_CONE) and abs(n[2]) > 0.99:
            part = 2 if n[2] > 0 else 1
        curved_part = kind == SHAPE_SPHERE or (kind in (SHAPE_CYLINDER, SHAPE_CONE) and part == 0)
        if curved_part:
            if min(uv[0], 1.0 - uv[0]) < 1e-9:
                continue  # a seam duplicate: u = 0 and u = 1 are the same points
            if (kind == SHAPE_SPHERE and abs(abs(p[1]) - 1) < 1e-9) or (kind == SHAPE_CONE and abs(p[2] - 1) < 1e-9):
                continue  # a pole or apex duplicate, at its segment's middle u
        n_kernel, u, v = _canonical_normal_uv(kind, part, tuple(float(c) for c in p), True)
        assert (u, v) == pytest.approx(tuple(uv), abs=1e-9)
        n_kernel = np.asarray(n_kernel) / np.linalg.norm(n_kernel)
        np.testing.assert_allclose(n, n_kernel, atol=1e-9)
        checked += 1
    assert checked >= min(len(points), 8) * 0.5


@pytest.mark.parametrize("name", MATRICES)
@pytest.mark.parametrize("kind", ALL_KINDS)
def test_groups_planar(kind, name):
    t = tessellate_shape(kind, MATRICES[name], 10)
    g = _face_normals(t)
    for group in np.unique(t.groups):
        tris = np.flatnonzero(t.groups == group)
        n = g[tris[0]] / np.linalg.norm(g[tris[0]])
        offsets = (t.vertices[t.faces[tris]].reshape(-1, 3) - t.vertices[t.faces[tris[0], 0]]) @ n
        assert np.abs(offsets).max() < 1e-9, f"group {group} is not planar"


def test_groups_of_quads_and_fans():
    s = tessellate_shape(SHAPE_SPHERE, np.eye(4), 12)
    sizes = np.bincount(s.groups)
    assert (sizes == 2).sum() == 12 * 4 and (sizes == 1).sum() == 2 * 12  # quads, then pole triangles
    c = tessellate_shape(SHAPE_CYLINDER, np.eye(4), 12)
    assert sorted(np.bincount(c.groups)) == [2] * 12 + [12, 12]  # side quads, two cap fans


def test_plane_patch():
    m = SKEWED
    center = np.array([1.0, 2.0, -0.5])
    t = tessellate_plane(m, center, 3.0, 4)
    linear, origin = m[:3, :3], m[:3, 3]
    normal = np.linalg.inv(linear).T @ [0.0, 0.0, 1.0]
    normal /= np.linalg.norm(normal)
    points, _ = _canonical(t, m)
    np.testing.assert_allclose(points[:, 2], 0.0, atol=1e-12)  # on the plane
    np.testing.assert_allclose(t.uvs, points[:, :2], atol=1e-12)  # canonical (x, y)
    np.testing.assert_allclose(t.normals, np.tile(normal, (len(t.normals), 1)), atol=1e-12)
    projected = center - np.dot(center - origin, normal) * normal
    np.testing.assert_allclose(t.vertices.mean(axis=0), projected, atol=1e-12)  # centred on the projection
    # a square of side 6 split into 4 × 4 quads of two triangles, one group each
    assert len(t.vertices) == 25 and len(t.faces) == 32
    assert sorted(np.bincount(t.groups)) == [2] * 16
    np.testing.assert_allclose(_area(t), 36.0, rtol=1e-12)
    # sides along the world image of the canonical x axis and the in-plane direction perpendicular to it
    t1 = linear[:, 0] / np.linalg.norm(linear[:, 0])
    t2 = np.cross(normal, t1)
    offsets = t.vertices - projected
    np.testing.assert_allclose(np.abs(offsets @ t1).max(), 3.0, rtol=1e-12)
    np.testing.assert_allclose(np.abs(offsets @ t2).max(), 3.0, rtol=1e-12)
    assert np.all(_face_normals(t) @ normal > 0)  # counter-clockwise seen from the normal side


def test_plane_patch_under_mirror():
    t = tessellate_plane(MIRRORED, [0.0, 0.0, 0.0], 1.0, 3)
    assert np.all(np.einsum("ij,ij->i", _face_normals(t), t.normals[t.faces[:, 0]]) > 0)
    points, _ = _canonical(t, MIRRORED)
    np.testing.assert_allclose(t.uvs, points[:, :2], atol=1e-12)


def test_errors():
    with pytest.raises(ValueError):
        tessellate_shape(99, np.eye(4), 8)
    with pytest.raises(ValueError):
        tessellate_shape(SHAPE_SPHERE, np.eye(4), 2)
    with pytest.raises(ValueError):
        tessellate_shape(SHAPE_PLANE, np.eye(4), 8)  # unbounded: tessellate_plane
    with pytest.raises(ValueError):
        tessellate_plane(np.eye(4), [0, 0, 0], 1.0, 0)
    with pytest.raises(ValueError):
        tessellate_plane(np.eye(4), [0, 0, 0], -1.0, 4)
