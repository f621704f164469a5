"""lumos.mesh.subdivide: midpoint and Loop subdivision against closed forms and a naive twin.

Loop subdivision keeps the Euler characteristic and rounds an icosahedron; where there is no closed form, a slow
per-vertex Python twin is the reference.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from lumos.mesh import face_normals, subdivide

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
