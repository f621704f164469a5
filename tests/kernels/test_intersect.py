"""Ray–primitive intersection and surface normals/UVs against world-space closed forms (`naive.hit_*`).

The kernels intersect canonical shapes through `object_from_world`; the naive twins solve each shape in world
space from the object's own parameters (an ellipsoid from the SVD of its transform, a parallelepiped from its
faces, a cylinder from its axis…). Hits, misses, tangent rays, origins inside, the open interval
t_min < t < t_max, transformed shapes, normals (unit, analytic) and UVs are all compared.
"""

import numpy as np
import pytest
from conftest import compile_dict, surfaces
from naive import (
    hit_cone,
    hit_cylinder,
    hit_disk,
    hit_object,
    hit_rect,
    transform_matrix,
    unit,
)

from lumos import config
from lumos.kernels import layout as L
from lumos.kernels.intersect import intersect_shape, intersect_triangle, triangle_setup
from lumos.kernels.surface import face_forward, offset_origin

MAT = {"kd": 0.5}

# name -> (scene dict, naive (o, d, t_min, t_max) -> (t, n), UVs documented in [0, 1]?)
SPHERE = {"type": "sphere", "center": [0.3, -0.5, 1.2], "radius": 0.9, "material": MAT}
BOX = {"type": "box", "min": [-1.0, -0.5, 0.2], "max": [0.7, 1.3, 1.0], "material": MAT}
CYL = {"type": "cylinder", "base": [0.2, -0.4, 0.1], "top": [-0.5, 0.9, 0.6], "radius": 0.6, "material": MAT}
CONE = {"type": "cone", "base": [0.1, 0.3, -0.2], "top": [0.8, -0.6, 1.1], "radius": 0.7, "material": MAT}
DISK = {"type": "disk", "center": [0.2, 0.1, -0.3], "normal": [0.3, 1.0, -0.4], "radius": 1.1, "material": MAT}
PLANE = {"type": "plane", "point": [0.0, -0.7, 0.2], "normal": [0.2, 1.0, 0.1], "material": MAT}
TRI = {"type": "triangle", "vertices": [[-1.0, -0.75, 0.25], [1.25, -0.5, 0.5], [0.0, 1.5, -0.25]], "material": MAT}
RECT = {"corner": [-0.6, -0.4, 0.3], "edge_u": [1.2, 0.2, 0.0], "edge_v": [0.0, 0.3, 1.0]}


def _naive_obj(obj):
    return lambda o, d, t_min=0.0, t_max=np.inf: hit_object(obj, o, d, t_min, t_max)


def _naive_rect(o, d, t_min=0.0, t_max=np.inf):
    return hit_rect(o, d, RECT["corner"], RECT["edge_u"], RECT["edge_v"], t_min, t_max)


CASES = {
    "sphere": ({"objects": [SPHERE]}, _naive_obj(SPHERE), True),
    "box": ({"objects": [BOX]}, _naive_obj(BOX), True),
    "cylinder_capped": ({"objects": [CYL]}, _naive_obj(CYL), True),
    "cylinder_open": ({"objects": [{**CYL, "capped": False}]}, _naive_obj({**CYL, "capped": False}), True),
    "cone_capped": ({"objects": [CONE]}, _naive_obj(CONE), True),
    "cone_open": ({"objects": [{**CONE, "capped": False}]}, _naive_obj({**CONE, "capped": False}), True),
    "disk": ({"objects": [DISK]}, _naive_obj(DISK), True),
    "plane": ({"objects": [PLANE]}, _naive_obj(PLANE), False),
    "rect": ({"lights": [{"type": "area", "shape": "rect", **RECT}]}, _naive_rect, True),
    "triangle": ({"objects": [TRI]}, _naive_obj(TRI), True),
}


def kernel_hits(arrays, o, d, t_min=0.0, t_max=config.T_FAR):
    """Kernel intersection of each ray with the scene's single primitive: (t (n,), inf on a miss; part (n,))."""
    o = np.atleast_2d(o)
    d = np.atleast_2d(d)
    t_min = np.broadcast_to(np.asarray(t_min, dtype=np.float64), len(o))
    t_max = np.broadcast_to(np.asarray(t_max, dtype=np.float64), len(o))
    t_out = np.full(len(o), np.inf)
    part_out = np.zeros(len(o), int)
    tri = arrays.tri_verts.shape[0] > 0
    if not tri:
        kind = int(arrays.shape_info[0, L.INFO_KIND])
        capped = int(arrays.shape_info[0, L.INFO_FLAGS]) & L.FLAG_CAPPED
        xform = arrays.shape_xform[0]
    for i in range(len(o)):
        oi = tuple(float(x) for x in o[i])
        di = tuple(float(x) for x in d[i])
        if tri:
            t, b1, b2 = intersect_triangle(oi, triangle_setup(di), arrays.tri_verts, 0, float(t_max[i]))
            part = 0
            if t <= t_min[i]:
                t = -1.0
        else:
            t, part = intersect_shape(kind, capped, xform, oi, di, float(t_min[i]), float(t_max[i]))
        if t != -1.0:
            t_out[i], part_out[i] = t, part
    return t_out, part_out


def random_rays(rng, n, lo=(-2.0, -2.0, -1.5), hi=(2.0, 2.0, 2.5)):
    """Origins spread around (and inside) the shapes; half the rays aimed at points near them, half random."""
    lo, hi = np.array(lo), np.array(hi)
    o = lo + (hi - lo) * rng.random((n, 3))
    target = -1.0 + 2.0 * rng.random((n, 3))
    target[:, 2] += 0.5
    d = np.where(np.arange(n)[:, None] % 2 == 0, target - o, rng.normal(size=(n, 3)))
    d *= rng.uniform(0.3, 3.0, size=(n, 1))  # directions need not be unit length
    return o, d


def _assert_same_hits(t_kernel, t_naive, rtol=1e-9):
    hit_k, hit_n = np.isfinite(t_kernel), np.isfinite(t_naive)
    assert np.array_equal(hit_k, hit_n), np.flatnonzero(hit_k != hit_n)
    np.testing.assert_allclose(t_kernel[hit_k], t_naive[hit_n], rtol=rtol, atol=1e-12)


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.nojit
def test_random_rays_match_closed_form(name, rng):
    scene, naive, _ = CASES[name]
    arrays = compile_dict(scene).arrays
    o, d = random_rays(rng, 300)
    t_kernel, _ = kernel_hits(arrays, o, d)
    t_naive, _ = naive(o, d)
    assert 0.1 < np.isfinite(t_naive).mean() < 0.95  # a real mix of hits and misses
    _assert_same_hits(t_kernel, t_naive)


@pytest.mark.parametrize("name", list(CASES))
def test_t_min_t_max_are_an_open_interval(name, rng):
    scene, naive, _ = CASES[name]
    arrays = compile_dict(scene).arrays
    o, d = random_rays(rng, 200)
    t_star, _ = naive(o, d)
    keep = np.isfinite(t_star)
    o, d, t_star = o[keep], d[keep], t_star[keep]
    # just below the nearest hit: nothing; just above it: the next surface along the ray, if any
    below, _ = kernel_hits(arrays, o, d, 0.0, t_star * (1 - 1e-7))
    assert not np.isfinite(below).any()
    for t_min in (t_star * (1 + 1e-7), 0.5 * t_star):
        t_k, _ = kernel_hits(arrays, o, d, t_min)
        t_n = np.array([naive(o[i : i + 1], d[i : i + 1], t_min[i])[0][0] for i in range(len(o))])
        _assert_same_hits(t_k, t_n)


@pytest.mark.nojit
def test_sphere_interval_endpoints_are_excluded():
    arrays = compile_dict({"objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1.0}]}).arrays
    o, d = (0.0, 0.0, 5.0), (0.0, 0.0, -1.0)  # roots exactly 4 and 6
    assert kernel_hits(arrays, o, d)[0][0] == 4.0
    assert not np.isfinite(kernel_hits(arrays, o, d, 0.0, 4.0)[0][0])
    assert kernel_hits(arrays, o, d, 4.0, 10.0)[0][0] == 6.0
    assert not np.isfinite(kernel_hits(arrays, o, d, 4.0, 6.0)[0][0])
    assert kernel_hits(arrays, o, d, 3.0, 4.5)[0][0] == 4.0


# ------------------------------------------------------------------------------------- normals and UVs


@pytest.mark.parametrize("name", list(CASES))
def test_normals_unit_and_analytic_uvs_in_range(name, rng):
    scene, naive, has_uv = CASES[name]
    arrays = compile_dict(scene).arrays
    o, d = random_rays(rng, 250)
    t_naive, n_naive = naive(o, d)
    hits = surfaces(arrays, o, d)
    n_hit = 0
    for i, h in enumerate(hits):
        assert (h is None) == (not np.isfinite(t_naive[i]))
        if h is None:
            continue
        n_hit += 1
        assert h["t"] == pytest.approx(t_naive[i], rel=1e-9)
        assert np.linalg.norm(h["n_geo"]) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(h["n_geo"], n_naive[i], atol=1e-9)
        np.testing.assert_allclose(h["p"], o[i] + t_naive[i] * d[i], rtol=1e-9, atol=1e-9)
        if has_uv:
            assert -1e-12 <= h["u"] <= 1 + 1e-12 and -1e-12 <= h["v"] <= 1 + 1e-12
    assert n_hit > 20, n_hit


@pytest.mark.nojit
def test_sphere_normal_is_radial_and_uv_follows_latitude():
    c, r = np.array([0.3, -0.5, 1.2]), 0.9
    # uv is computed where the material reads it (a texture here); elsewhere it is left at (0, 0)
    textured = {"materials": {"checks": {"texture": {"type": "checker"}}}, "objects": [dict(SPHERE, material="checks")]}
    arrays = compile_dict(textured).arrays
    plain = compile_dict({"objects": [SPHERE]}).arrays
    (untextured,) = surfaces(plain, [c + [0, 3, 0]], [[0, -1.0, 0]])
    assert untextured["u"] == 0.0 and untextured["v"] == 0.0
    # straight down onto the north pole, and onto the south pole from below
    (top, bottom) = surfaces(arrays, [c + [0, 3, 0], c - [0, 3, 0]], [[0, -1.0, 0], [0, 1.0, 0]])
    np.testing.assert_allclose(top["n_geo"], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(bottom["n_geo"], [0, -1, 0], atol=1e-12)
    assert top["v"] == pytest.approx(1.0) and bottom["v"] == pytest.approx(0.0)
    assert top["t"] == pytest.approx(3 - r) and bottom["t"] == pytest.approx(3 - r)


@pytest.mark.nojit
def test_box_normals_are_face_axes():
    lo, hi = np.array(BOX["min"]), np.array(BOX["max"])
    mid = 0.5 * (lo + hi)
    arrays = compile_dict({"objects": [BOX]}).arrays
    for axis in range(3):
        for sign in (-1.0, 1.0):
            o = mid.copy()
            o[axis] += sign * 5.0
            d = np.zeros(3)
            d[axis] = -sign
            (h,) = surfaces(arrays, [o], [d])
            expect = np.zeros(3)
            expect[axis] = sign
            np.testing.assert_allclose(h["n_geo"], expect, atol=1e-12)
            face = hi[axis] if sign > 0 else lo[axis]
            assert h["t"] == pytest.approx(5.0 - abs(face - mid[axis]), rel=1e-12)
            assert 0 <= h["u"] <= 1 and 0 <= h["v"] <= 1


# --------------------------------------------------------------------------------------- tangent rays


@pytest.mark.nojit
def test_tangent_rays_sphere():
    arrays = compile_dict({"objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1.0}]}).arrays
    t, _ = kernel_hits(arrays, [[1.0, 0.0, 5.0], [1.0 + 2**-30, 0.0, 5.0], [1.0 - 2**-30, 0, 5.0]],
                       [[0.0, 0.0, -1.0]] * 3)
    assert t[0] == 5.0  # the discriminant is exactly 0: touching counts
    assert not np.isfinite(t[1])
    assert abs(t[2] - 5.0) < 1e-4


@pytest.mark.nojit
def test_grazing_rays_box():
    arrays = compile_dict({"objects": [{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1]}]}).arrays
    o = [[-1.0, 0.5, 1.0], [-1.0, 1.0, 1.0], [-1.0, 1.0, 0.5], [-1.0, 0.5, 1.0 + 1e-12], [-1.0, 0.5, 1.0 - 1e-12]]
    d = [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    t, _ = kernel_hits(arrays, o, d)
    # in the plane of a face, along an edge, touching an edge from outside: closed box, all hit at t = 1
    assert list(t[:3]) == [1.0, 1.0, 1.0]
    assert not np.isfinite(t[3]) and t[4] == 1.0
    _assert_same_hits(t, _naive_obj({"type": "box", "min": [0, 0, 0], "max": [1, 1, 1]})(o, d)[0])


@pytest.mark.nojit
def test_tangent_rays_cylinder_cone_disk_rect():
    cyl = {"type": "cylinder", "base": [0, 0, 0], "top": [0, 0, 1], "radius": 1.0, "capped": False}
    cone = {"type": "cone", "base": [0, 0, 0], "top": [0, 0, 1], "radius": 1.0, "capped": False}
    disk = {"type": "disk", "center": [0, 0, 0], "normal": [0, 0, 1], "radius": 1.0}
    cases = [
        (cyl, [1.0, -5.0, 0.5], [0.0, 1.0, 0.0], 5.0),  # touches the side along x = 1
        (cyl, [1.0 + 1e-9, -5.0, 0.5], [0.0, 1.0, 0.0], None),
        (cone, [0.5, -3.0, 0.5], [0.0, 1.0, 0.0], 3.0),  # touches the side where the radius is 0.5
        (cone, [0.5 + 1e-9, -3.0, 0.5], [0.0, 1.0, 0.0], None),
        (disk, [1.0, 0.0, 2.0], [0.0, 0.0, -1.0], 2.0),  # exactly on the rim
        (disk, [0.6, 0.8, 2.0], [0.0, 0.0, -1.0], 2.0),  # on the rim (0.36 + 0.64 = 1 in binary)
        (disk, [1.0 + 1e-9, 0.0, 2.0], [0.0, 0.0, -1.0], None),
        (disk, [-3.0, 0.0, 0.0], [1.0, 0.0, 0.0], None),  # in the disk's plane: parallel, no hit
    ]
    for obj, o, d, expect in cases:
        arrays = compile_dict({"objects": [obj]}).arrays
        t, _ = kernel_hits(arrays, o, d)
        assert (t[0] == pytest.approx(expect, rel=1e-12)) if expect is not None else not np.isfinite(t[0]), (obj, o)
    rect = {"lights": [{"type": "area", "shape": "rect", "corner": [0, 0, 0], "edge_u": [1, 0, 0],
                        "edge_v": [0, 1, 0]}]}
    arrays = compile_dict(rect).arrays
    t, _ = kernel_hits(arrays, [[1.0, 1.0, 1.0], [0.5, 0.0, 1.0], [1.0 + 1e-9, 0.5, 1.0]], [[0, 0, -1.0]] * 3)
    assert t[0] == 1.0 and t[1] == 1.0 and not np.isfinite(t[2])  # corner and edge count


@pytest.mark.nojit
def test_cone_ray_parallel_to_a_generator():
    # a·t² + 2b·t + c = 0 degenerates to a linear equation (a = 0) for rays parallel to the slant; such a ray
    # still crosses the opposite side once
    cone = {"type": "cone", "base": [0, 0, 0], "top": [0, 0, 1], "radius": 1.0, "capped": False}
    arrays = compile_dict({"objects": [cone]}).arrays
    o, d = [[-2.0, 0.0, 1.5]], [[1.0, 0.0, -1.0]]
    t, _ = kernel_hits(arrays, o, d)
    assert t[0] == pytest.approx(1.25, rel=1e-12)
    assert hit_cone(o, d, [0, 0, 0], [0, 0, 1], 1.0, False)[0][0] == pytest.approx(1.25)


# -------------------------------------------------------------------------------- origins inside shapes


@pytest.mark.parametrize("name", ["sphere", "box", "cylinder_capped", "cone_capped"])
def test_rays_from_inside_hit_the_far_side(name, rng):
    scene, naive, _ = CASES[name]
    obj = scene["objects"][0]
    inside = {
        "sphere": lambda: np.array(obj["center"]) + 0.5 * obj["radius"] * unit(rng.normal(size=3)),
        "box": lambda: np.array(obj["min"]) + (np.array(obj["max"]) - np.array(obj["min"])) * rng.uniform(
            0.05, 0.95, 3),
        "cylinder_capped": lambda: np.array(obj["base"]) + rng.uniform(0.1, 0.9) * (
            np.array(obj["top"]) - np.array(obj["base"])),
        "cone_capped": lambda: np.array(obj["base"]) + rng.uniform(0.1, 0.5) * (
            np.array(obj["top"]) - np.array(obj["base"])),
    }[name]
    o = np.array([inside() for _ in range(100)])
    d = rng.normal(size=(100, 3))
    arrays = compile_dict(scene).arrays
    t_kernel, _ = kernel_hits(arrays, o, d)
    t_naive, n_naive = naive(o, d)
    assert np.isfinite(t_kernel).all()
    _assert_same_hits(t_kernel, t_naive)
    assert ((n_naive * d).sum(axis=1) > 0).all()  # leaving through the far side
    for h, di in zip(surfaces(arrays, o, d), d):
        assert h["n_geo"] @ di > 0  # the outward normal there points along the ray


# ------------------------------------------------------------------------------------ transformed shapes


TRANSFORM = {"translate": [0.3, -0.2, 0.5], "rotate": [25.0, -40.0, 70.0], "scale": [1.5, 0.6, 0.9]}


@pytest.mark.parametrize(
    "obj",
    [
        {"type": "sphere", "center": [0.2, 0.1, -0.3], "radius": 0.8, "transform": TRANSFORM},
        {"type": "box", "min": [-0.6, -0.4, -0.5], "max": [0.7, 0.5, 0.4], "transform": TRANSFORM},
        {"type": "plane", "point": [0.1, -0.2, 0.3], "normal": [0.3, 1.0, -0.2], "transform": TRANSFORM},
        {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0,
         "transform": {"matrix": [[1.2, 0.5, 0.0, 0.1], [0.0, 0.7, 0.3, -0.2], [0.2, 0.0, 1.1, 0.3], [0, 0, 0, 1]]}},
    ],
    ids=["ellipsoid", "parallelepiped", "plane", "sheared_ellipsoid"],
)
def test_transformed_shapes_match_world_space_geometry(obj, rng):
    arrays = compile_dict({"objects": [{**obj, "material": MAT}]}).arrays
    o, d = random_rays(rng, 300)
    t_naive, n_naive = hit_object(obj, o, d)
    assert 0.15 < np.isfinite(t_naive).mean() < 0.95
    _assert_same_hits(kernel_hits(arrays, o, d)[0], t_naive)
    # normals: the inverse transpose of the placement (ellipsoid: the quadric's gradient, from the SVD)
    for i, h in enumerate(surfaces(arrays, o[:120], d[:120])):
        if h is not None:
            np.testing.assert_allclose(h["n_geo"], n_naive[i], atol=1e-9)


@pytest.mark.parametrize("kind", ["cylinder", "cone", "disk"])
def test_rigidly_placed_shapes_match(kind, rng):
    # rotate + translate + uniform scale keeps them a cylinder/cone/disk: place the parameters by hand
    tr = {"translate": [0.2, -0.3, 0.4], "rotate": [30.0, 45.0, -60.0], "scale": 0.8}
    m = transform_matrix(tr["translate"], tr["rotate"], tr["scale"])
    place = lambda p: m[:3, :3] @ np.asarray(p, dtype=float) + m[:3, 3]  # noqa: E731
    obj = {"cylinder": CYL, "cone": CONE, "disk": DISK}[kind]
    arrays = compile_dict({"objects": [{**obj, "transform": tr}]}).arrays
    o, d = random_rays(rng, 300)
    if kind == "disk":
        t_naive, n_naive = hit_disk(o, d, place(obj["center"]), m[:3, :3] @ np.asarray(obj["normal"], dtype=float),
                                    0.8 * obj["radius"])
    else:
        fn = hit_cylinder if kind == "cylinder" else hit_cone
        t_naive, n_naive = fn(o, d, place(obj["base"]), place(obj["top"]), 0.8 * obj["radius"], True)
    assert np.isfinite(t_naive).mean() > 0.1
    _assert_same_hits(kernel_hits(arrays, o, d)[0], t_naive)
    for i, h in enumerate(surfaces(arrays, o[:100], d[:100])):
        if h is not None:
            np.testing.assert_allclose(h["n_geo"], n_naive[i], atol=1e-9)


# --------------------------------------------------------------------------- spawning rays off a surface


@pytest.mark.parametrize("name", ["sphere", "box", "cylinder_capped", "disk", "triangle"])
def test_no_self_intersection_after_offset(name, rng):
    scene, _, _ = CASES[name]
    arrays = compile_dict(scene).arrays
    o, d = random_rays(rng, 300)
    count = 0
    for (oi, di), h in zip(zip(o, d), surfaces(arrays, o, d)):
        if h is None:
            continue
        n = np.array(face_forward(tuple(h["n_geo"]), tuple(di)))
        assert n @ di <= 0.0
        # a reflected ray leaves on the viewer's side; from the offset origin it must not see the same surface
        # nearby (convex shapes: not at all; open shapes may be hit again far away)
        refl = di - 2.0 * (di @ n) * n
        origin = offset_origin(tuple(h["p"]), tuple(n), tuple(refl), config.RAY_EPSILON)
        t, _ = kernel_hits(arrays, origin, refl)
        assert not (t[0] < 1e-3 * np.linalg.norm(h["p"] - oi) / np.linalg.norm(refl)), (name, t[0])
        count += 1
    assert count > 30
