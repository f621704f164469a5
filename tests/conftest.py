"""Shared fixtures for the kernel tests: compile a scene dict, trace arrays of rays, a seeded NumPy generator.

Scenes stay small: a handful of objects, or a few hundred triangles for the BVH tests. Kernels are Numba
dispatchers; every call here passes the same argument types (float64 arrays and tuples, Python ints), so each
kernel is compiled once and then loaded from NUMBA_CACHE_DIR.
"""

from __future__ import annotations


import numpy as np
import pytest
from helpers import DATA, RADIANCE

import lumos
from lumos.compile import compile_scene
from lumos.kernels import layout as L
from lumos.radiosity.solution import Solution


def run_cli(capsys, *argv):
    """(exit code, stdout, stderr) of `lumos ARGV...` run in-process."""
    from lumos import cli

    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def compile_dict(scene: dict):
    """`CompiledScene` of a scene dict (load + validate + flatten + BVH)."""
    return compile_scene(lumos.load_scene(scene))


def trace(arrays, origins, directions, t_max=1e30):
    """Closest hits of rays through `kernels.batch.trace_closest`: (t (n,), -1 on a miss; ref (n,); b (n, 2))."""
    from lumos.kernels.batch import trace_closest

    o = np.ascontiguousarray(np.atleast_2d(origins), dtype=np.float64)
    d = np.ascontiguousarray(np.atleast_2d(directions), dtype=np.float64)
    n = len(o)
    t = np.empty(n)
    ref = np.empty(n, np.int64)
    b = np.empty((n, 2))
    trace_closest(arrays, o, d, float(t_max), t, ref, b)
    return t, ref, b


def trace_any(arrays, origins, directions, t_max):
    from lumos.kernels.batch import trace_any as _trace_any

    o = np.ascontiguousarray(np.atleast_2d(origins), dtype=np.float64)
    d = np.ascontiguousarray(np.atleast_2d(directions), dtype=np.float64)
    hit = np.zeros(len(o), bool)
    _trace_any(arrays, o, d, np.ascontiguousarray(t_max, dtype=np.float64), hit)
    return hit


def geometry(arrays):
    """What `closest_hit` / `any_hit` take: the traversal view of `SceneArrays`."""
    from lumos.kernels.views import geometry_of

    return geometry_of(arrays)


def call_illuminate(arrays, p, n, V, mat_id, seed, pixel, sample, shadows, stack):
    """`illuminate(...)` on the lighting and traversal views of `arrays`."""
    from lumos.kernels.illumination import illuminate
    from lumos.kernels.views import lighting_of, surfaces_of

    stack_t = np.empty(len(stack))
    return illuminate(lighting_of(arrays), geometry(arrays), surfaces_of(arrays), p, n, n, V, mat_id, seed, pixel,
                      sample, shadows, stack, stack_t, 0.0)


def surfaces(arrays, origins, directions):
    """Per ray: the kernels' closest hit (`traverse.closest_hit`) and the surface there (`surface.surface_at`).

    Returns a list of None (miss) or dicts with t, ref, part, p, n_geo, n_sh, u, v, material, object, light.
    """
    from lumos.kernels.surface import surface_at
    from lumos.kernels.traverse import closest_hit
    from lumos.kernels.views import surfaces_of

    stack = np.empty(64, np.int64)
    stack_t = np.empty(64)
    geo = geometry(arrays)
    surf = surfaces_of(arrays)
    out = []
    for o, d in zip(np.atleast_2d(origins), np.atleast_2d(directions)):
        o = tuple(float(x) for x in o)
        d = tuple(float(x) for x in d)
        t, ref, b1, b2, part = closest_hit(geo, o, d, 0.0, 1e30, stack, stack_t, 0.0)
        if t < 0.0:
            out.append(None)
            continue
        p, n_geo, n_sh, u, v, mat, obj, light = surface_at(surf, o, d, t, ref, b1, b2, part, 0.0)
        out.append(dict(t=t, ref=int(ref), part=int(part), p=np.array(p), n_geo=np.array(n_geo),
                        n_sh=np.array(n_sh), u=u, v=v, material=int(mat), object=int(obj), light=int(light)))
    return out


def material_row(ka=0.0, kd=0.0, ks=0.0, shininess=1.0) -> np.ndarray:
    """One row of `SceneArrays.materials` (float64 (MAT_SIZE,)), for calling `phong` directly."""
    row = np.zeros(L.MAT_SIZE)
    row[L.MAT_KA : L.MAT_KA + 3] = ka
    row[L.MAT_KD : L.MAT_KD + 3] = kd
    row[L.MAT_KS : L.MAT_KS + 3] = ks
    row[L.MAT_SHININESS] = shininess
    row[L.MAT_IOR] = 1.0
    return row


def render(scene: dict, **settings):
    """`lumos.render(scene, method="raycast", ...)`."""
    settings.setdefault("method", "raycast")
    return lumos.render(scene, **settings)


@pytest.fixture
def rng():
    return np.random.default_rng(20240607)


@pytest.fixture
def solution() -> Solution:
    """Two unit quads (a floor facing +y and a wall facing −x, apart), each split into two display triangles."""
    corners = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0],  # floor, CCW about +y
                        [2, 0, 0], [2, 1, 0], [2, 1, 1], [2, 0, 1]], dtype=np.float64)  # wall, CCW about −x
    normals = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    return Solution(
        element_vertices=corners,
        element_polys=np.array([[0, 1, 2, 3], [4, 5, 6, 7]], np.int32),
        element_normal=normals,
        element_area=np.array([1.0, 1.0]),
        element_reflectance=np.array([[0.7, 0.6, 0.5], [0.2, 0.8, 0.3]]),
        element_emission=np.array([[0.0, 0.0, 0.0], [1.5, 1.5, 1.5]]),
        element_radiance=np.array([[0.25, 1.0 / 3.0, 2.5], [1.5, 1.9, 1.6]]),
        element_object=np.array([0, 3], np.int32),
        element_material=np.array([1, 0], np.int32),
        element_patch=np.array([0, 1], np.int32),
        element_optics=np.array([[0.0] * 9, [0.5, 0.5, 0.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]]),
        element_twin=np.array([-1, -1], np.int32),
        vertices=corners + 0.0,
        vertex_normal=np.repeat(normals, 4, axis=0),
        vertex_radiance=RADIANCE.copy(),
        faces=np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]], np.int32),
        face_element=np.array([0, 0, 1, 1], np.int32),
        settings={"solver": "progressive", "max_area": 0.25, "tolerance": 1e-3, "hemicube": [64, 64],
                  "nested": {"on": True, "none": None, "name": "Ünïcode"}},
        stats={"patches": 2, "elements": 2, "solve_s": 0.0123456789, "iterations": np.int64(7),
               "residual": np.float64(1e-17)},
        scene_digest="3f786850e387550fdab836ed7e6dc881de23001b",
    )


@pytest.fixture
def scene_file(tmp_path):
    """The preview's tests: a copy of tests/data/preview/ball.yaml in a folder of its own (Save writes beside it)."""
    path = tmp_path / "scenes" / "ball.yaml"
    path.parent.mkdir()
    path.write_text((DATA / "preview" / "ball.yaml").read_text())
    return path
