"""`lumos.render(method="whitted")`: optics closed forms, shadow transmittance, and agreement with an independent
implementation of DESIGN.md §3 "Recursion" (`naive.render_whitted`: NumPy ray queues, per-object analytic
intersection, the classic model with shadow rays, Snell/Schlick written from the formulas).

The done criterion is `test_matches_independent_implementation`: whitted on scenes of spheres, boxes and planes
(mirror, glass with and without Fresnel, a glass box, diffuse spheres, a floor, a point light with attenuation
and a directional light, max_depth 5) agrees with the twin to within 3e-3 on at least 98 % of the pixels.
"""

import math

import numba
import numpy as np
import pytest
from naive import camera_rays, hit_object, render_whitted

import lumos
import lumos.api
from lumos.kernels.optics import reflect, refract, schlick

needs_whitted = pytest.mark.skipif("whitted" not in lumos.api.METHODS, reason="method whitted not registered yet")


def whitted(scene, **settings):
    """`lumos.render(scene, method="whitted", antialias="none", ...)` (one ray through each pixel centre)."""
    settings.setdefault("method", "whitted")
    settings.setdefault("antialias", "none")
    return lumos.render(scene, **settings)


def _frame(rng):
    """A random orthonormal frame (n, t1, t2)."""
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q[:, 0], q[:, 1], q[:, 2]


def _tuple(v):
    return tuple(float(x) for x in v)


# ------------------------------------------------------------------------------------- optics closed forms


def test_snell_law_for_random_angles(rng):
    for _ in range(200):
        n, t1, _ = _frame(rng)
        theta1 = rng.uniform(0.0, 0.5 * math.pi)
        eta = rng.uniform(0.4, 2.5)  # n1 / n2
        d = math.sin(theta1) * t1 - math.cos(theta1) * n
        ok, t = refract(_tuple(d), _tuple(n), eta)
        t = np.array(t)
        assert np.linalg.norm(t) == pytest.approx(1.0, abs=1e-12)
        if eta * math.sin(theta1) > 1.0 + 1e-9:
            assert not ok
            np.testing.assert_allclose(t, d - 2.0 * (d @ n) * n, atol=1e-12)
            continue
        if eta * math.sin(theta1) > 1.0 - 1e-9:
            continue  # at the critical angle; either answer is right
        assert ok
        sin2 = np.linalg.norm(np.cross(t, n))
        assert eta * math.sin(theta1) == pytest.approx(sin2, abs=1e-10)  # n1 sin θ1 = n2 sin θ2
        assert t @ n < 0.0  # goes on through the surface
        assert abs(np.linalg.det(np.stack([d, n, t]))) < 1e-12  # in the plane of incidence
        assert t @ t1 >= -1e-12  # on the far side of the normal from d's origin, as d


def test_total_internal_reflection_at_the_critical_angle():
    theta_c = math.asin(1.0 / 1.5)  # leaving glass (η = 1.5) into air
    n = np.array([0.0, 1.0, 0.0])
    for theta, want_ok in ((theta_c - 1e-6, True), (theta_c + 1e-6, False)):
        d = np.array([math.sin(theta), -math.cos(theta), 0.0])
        ok, t = refract(_tuple(d), _tuple(n), 1.5)
        assert ok == want_ok
        if ok:
            assert abs(t[1]) < 5e-3 and t[1] < 0.0  # just below: refracts, grazing the surface
        else:
            np.testing.assert_allclose(t, [d[0], -d[1], 0.0], atol=1e-15)  # just above: the mirror direction


def test_reflect_preserves_the_angle(rng):
    for _ in range(100):
        n, t1, _ = _frame(rng)
        theta = rng.uniform(0.0, 0.5 * math.pi)
        d = math.sin(theta) * t1 - math.cos(theta) * n
        r = np.array(reflect(_tuple(d), _tuple(n)))
        assert np.linalg.norm(r) == pytest.approx(1.0, abs=1e-12)
        assert r @ n == pytest.approx(-(d @ n), abs=1e-12)  # angle of reflection = angle of incidence
        np.testing.assert_allclose(r - (r @ n) * n, d - (d @ n) * n, atol=1e-12)  # same tangential part


@pytest.mark.parametrize("theta1_deg", [10.0, 35.0, 60.0, 80.0])
def test_glass_slab_shifts_a_ray_sideways(theta1_deg):
    thickness, ior = 0.7, 1.5
    theta1 = math.radians(theta1_deg)
    theta2 = math.asin(math.sin(theta1) / ior)
    n = np.array([0.0, 1.0, 0.0])  # both faces (y = 0 and y = −thickness) face up, towards the incoming ray
    d = np.array([math.sin(theta1), -math.cos(theta1), 0.0])
    p0 = np.array([0.3, 0.0, -0.2])
    ok, inside = refract(_tuple(d), _tuple(n), 1.0 / ior)
    assert ok
    inside = np.array(inside)
    p1 = p0 + inside * (thickness / -inside[1])  # the bottom face
    ok, out = refract(_tuple(inside), _tuple(n), ior)
    assert ok
    np.testing.assert_allclose(out, d, atol=1e-12)  # direction unchanged
    shift = np.linalg.norm(np.cross(p1 - p0, d))  # distance between the incoming and outgoing lines
    assert shift == pytest.approx(thickness * math.sin(theta1 - theta2) / math.cos(theta2), rel=1e-10)


def test_schlick_closed_forms():
    for eta in (1.0 / 1.5, 1.5, 1.0 / 2.4, 1.33):
        r0 = ((1.0 - eta) / (1.0 + eta)) ** 2
        assert schlick(1.0, eta, 1.0) == pytest.approx(r0, abs=1e-15)  # normal incidence
    assert schlick(1.0, 1.0 / 1.5, 1.0) == pytest.approx(0.04)
    assert schlick(0.0, 1.0 / 1.5, math.sqrt(1.0 - (1.0 / 1.5) ** 2)) == pytest.approx(1.0)  # grazing
    assert schlick(1e-4, 1.0 / 1.5, 0.75) > 0.999
    # monotone in the angle of incidence (entering glass)
    eta = 1.0 / 1.5
    cos_i = np.cos(np.linspace(0.0, 0.5 * math.pi, 50))
    cos_t = np.sqrt(1.0 - eta * eta * (1.0 - cos_i**2))
    F = np.array([schlick(ci, eta, ct) for ci, ct in zip(cos_i, cos_t)])
    assert (np.diff(F) > 0.0).all() and F[0] == pytest.approx(0.04) and F[-1] == pytest.approx(1.0)
    # leaving the denser medium the cosine on the thinner (air) side is used: the same F as the reverse path
    for ci, ct in zip(cos_i[1:-1], cos_t[1:-1]):
        leaving = schlick(ct, 1.0 / eta, ci)  # inside glass at angle θt, out into air at θi
        assert leaving == pytest.approx(schlick(ci, eta, ct), abs=1e-14)
        assert leaving == pytest.approx(0.04 + 0.96 * (1.0 - ci) ** 5, abs=1e-14)


# ------------------------------------------------------------------------------- shadows through glass

AMBIENT = np.array([0.2, 0.15, 0.1])
FLOOR_KD = 0.7


def _shadow_scene(blockers):
    """A floor y = 0 lit from straight above; the centre pixel of an odd-sized image looks at the origin, which
    the blockers hang over. Its direct light at max_depth 0 is FLOOR_KD (N·L = 1, att = 1) times the shadow
    transmittance."""
    return {
        "camera": {"position": [0.0, 2.0, 6.0], "look_at": [0.0, 0.0, 0.0], "fov": 30.0},
        "ambient": AMBIENT.tolist(),
        "lights": [{"type": "point", "position": [0.0, 6.0, 0.0], "intensity": 1.0}],
        "objects": [{"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0],
                     "material": {"ka": 1.0, "kd": FLOOR_KD}}] + blockers,
    }


def _glass(kt):
    return {"kt": kt, "ior": 1.5}


SHADOW_CASES = {
    "one sphere": ([{"type": "sphere", "center": [0.0, 3.0, 0.0], "radius": 0.6, "material": _glass(0.5)}],
                   0.5),
    "two spheres": ([{"type": "sphere", "center": [0.0, 2.0, 0.0], "radius": 0.6, "material": _glass(0.5)},
                     {"type": "sphere", "center": [0.0, 3.5, 0.0], "radius": 0.6, "material": _glass(0.5)}],
                    0.25),
    "coloured": ([{"type": "sphere", "center": [0.0, 3.0, 0.0], "radius": 0.6,
                   "material": _glass([0.8, 0.4, 0.2])}], np.array([0.8, 0.4, 0.2])),
    "glass box and disk": ([{"type": "box", "min": [-0.5, 1.5, -0.5], "max": [0.5, 2.5, 0.5],
                             "material": _glass(0.5)},
                            {"type": "disk", "center": [0.0, 4.0, 0.0], "normal": [0.3, 1.0, 0.0], "radius": 0.8,
                             "material": _glass([0.9, 0.6, 0.5])}], 0.5 * np.array([0.9, 0.6, 0.5])),
    "opaque": ([{"type": "sphere", "center": [0.0, 3.0, 0.0], "radius": 0.6, "material": {"kd": 0.5}}], 0.0),
    "opaque behind glass": ([{"type": "sphere", "center": [0.0, 2.0, 0.0], "radius": 0.6, "material": _glass(0.5)},
                             {"type": "sphere", "center": [0.0, 3.5, 0.0], "radius": 0.6,
                              "material": {"kd": 0.5, "kt": [0.0, 0.0, 0.0]}}], 0.0),
}


@needs_whitted
@pytest.mark.parametrize("case", list(SHADOW_CASES))
def test_shadow_transmittance_through_glass(case):
    blockers, transmittance = SHADOW_CASES[case]
    scene = _shadow_scene(blockers)
    W, H = 9, 7
    img = whitted(scene, width=W, height=H, max_depth=0).array
    o, d = camera_rays(scene["camera"], W, H)
    centre = (H // 2) * W + W // 2
    p = o[centre] + d[centre] * hit_object(scene["objects"][0], o[centre:centre + 1], d[centre:centre + 1])[0][0]
    np.testing.assert_allclose(p, 0.0, atol=1e-12)  # the centre pixel looks at the origin
    want = AMBIENT + FLOOR_KD * np.broadcast_to(transmittance, (3,))
    np.testing.assert_allclose(img[H // 2, W // 2], want, rtol=1e-5, atol=1e-6)
    # and the whole little image is the twin's
    np.testing.assert_allclose(img, render_whitted(scene, W, H, max_depth=0), atol=1e-5)


def test_one_pass_transmittance_matches_the_ordered_walk(rng):
    """`traverse.transmittance` multiplies what each primitive lets through, in traversal order, in one pass; the
    walk (`illumination.walk_transmittance`) goes hit by hit along the ray. On random rays through glass and
    opaque spheres, boxes, capped cylinders and cones, disks, triangles, a plane and an area light's rect (which
    lets everything through), one sphere moving, from outside and from inside solids, they agree; an open glass
    cylinder is left to the walk."""
    from conftest import compile_dict

    from lumos import config
    from lumos.kernels.illumination import walk_transmittance
    from lumos.kernels.traverse import transmittance
    from lumos.kernels.views import geometry_of, lighting_of, surfaces_of

    glass = [{"kt": [0.9, 0.7, 0.5], "ior": 1.5}, {"kt": 0.6, "ior": 1.3}, {"kt": [0.5, 0.8, 0.9], "ior": 1.0}]
    opaque = {"kd": 0.5}
    objects = [{"type": "plane", "point": [0, -3, 0], "normal": [0, 1, 0.2], "material": glass[1]}]
    for i in range(14):
        c = rng.uniform(-3, 3, 3)
        mat = opaque if i % 5 == 4 else glass[i % 3]
        kind = ["sphere", "box", "cylinder", "cone", "disk", "triangle"][i % 6]
        if kind == "sphere":
            obj = {"type": "sphere", "center": c.tolist(), "radius": float(rng.uniform(0.3, 1.0))}
            if i == 7:
                obj["motion"] = [0.3, 0.0, -0.2]
        elif kind == "box":
            obj = {"type": "box", "min": (c - 0.6).tolist(), "max": (c + rng.uniform(0.2, 0.8, 3)).tolist()}
        elif kind in ("cylinder", "cone"):
            obj = {"type": kind, "base": c.tolist(), "top": (c + rng.normal(size=3)).tolist(), "radius": 0.5,
                   "capped": True}
        elif kind == "disk":
            obj = {"type": "disk", "center": c.tolist(), "normal": rng.normal(size=3).tolist(), "radius": 0.8}
        else:
            obj = {"type": "triangle", "vertices": (c + rng.uniform(-1, 1, (3, 3))).tolist()}
        objects.append(dict(obj, material=mat))
    light = {"type": "area", "shape": "rect", "corner": [-1, 0, -1], "edge_u": [2, 0, 0.3], "edge_v": [0, 1.5, 1]}
    arrays = compile_dict({"lights": [light], "objects": objects}).arrays
    geo, surf, lit = geometry_of(arrays), surfaces_of(arrays), lighting_of(arrays)
    stack, stack_t = np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK)
    seen = []
    for _ in range(3000):
        o = tuple(rng.uniform(-4, 4, 3))
        d = rng.normal(size=3)
        d = tuple(d / np.linalg.norm(d))
        dist, time = float(rng.uniform(0.5, 9.0)), float(rng.uniform(0, 1))
        fast, settled = transmittance(geo, surf.tri_info, lit.materials, o, d, dist, stack, time)
        assert settled
        slow, _ = walk_transmittance(geo, surf, lit, o, d, dist, stack, stack_t, time)
        np.testing.assert_allclose(fast, slow, rtol=1e-9, atol=1e-12)
        seen.append(round(max(fast), 6))
    # blocked, clear, and many products in between (through one glass, two, three...)
    assert seen.count(0.0) > 20 and seen.count(1.0) > 100 and len(set(seen)) >= 8
    assert sum(0.0 < x < 1.0 for x in seen) > 300
    # an open glass cylinder can be crossed twice: only the walk knows
    arrays = compile_dict({"objects": [{"type": "cylinder", "base": [0, 0, 0], "top": [0, 2, 0], "radius": 1,
                                        "capped": False, "material": glass[1]}]}).arrays
    geo, surf, lit = geometry_of(arrays), surfaces_of(arrays), lighting_of(arrays)
    o, d = (-3.0, 1.0, 0.0), (1.0, 0.0, 0.0)
    _, settled = transmittance(geo, surf.tri_info, lit.materials, o, d, 6.0, stack, 0.0)
    assert not settled
    slow, _ = walk_transmittance(geo, surf, lit, o, d, 6.0, stack, stack_t, 0.0)
    np.testing.assert_allclose(slow, 0.36, rtol=1e-12)


# ------------------------------------------------------------------------------------ the done criterion

DONE_CAMERAS = {
    "perspective": {"position": [0.8, 2.2, 7.0], "look_at": [0.1, -0.1, 0.0], "up": [0.0, 1.0, 0.05],
                    "fov": 50.0},
    "orthographic": {"type": "orthographic", "position": [3.0, 4.0, 6.0], "look_at": [0.0, -0.3, 0.0],
                     "size": 6.0},
}


def done_scene(camera, fresnel, mirror_floor=False):
    return {
        "camera": camera,
        "ambient": [0.1, 0.11, 0.13],
        "background": [0.15, 0.2, 0.35],
        "lights": [
            {"type": "point", "position": [4.0, 6.0, 5.0], "intensity": [1.3, 1.2, 1.1],
             "attenuation": [1.0, 0.02, 0.005]},
            {"type": "directional", "direction": [-0.3, -1.0, -0.5], "intensity": [0.5, 0.45, 0.4]},
        ],
        "materials": {
            "mirror": {"ka": 0.02, "kd": 0.05, "ks": 0.6, "shininess": 80, "kr": 0.85},
            "glass": {"ka": 0.0, "ks": 0.8, "shininess": 150, "kr": 0.1, "kt": 0.85, "ior": 1.5,
                      "fresnel": fresnel},
            "tinted": {"ks": 0.5, "shininess": 60, "kr": 0.05, "kt": [0.6, 0.85, 0.7], "ior": 1.4,
                       "fresnel": fresnel},
            "red": {"ka": [0.4, 0.1, 0.1], "kd": [0.7, 0.15, 0.1], "ks": 0.4, "shininess": 30},
            "blue": {"ka": 0.1, "kd": [0.1, 0.25, 0.8], "ks": [0.3, 0.3, 0.6], "shininess": 8},
            "floor": {"ka": 0.3, "kd": [0.6, 0.6, 0.5], "kr": 0.3 if mirror_floor else 0.0},
            "wall": {"ka": 0.2, "kd": [0.5, 0.45, 0.3]},
        },
        "objects": [
            {"type": "plane", "point": [0.0, -1.0, 0.0], "normal": [0.0, 1.0, 0.0], "material": "floor"},
            {"type": "plane", "point": [0.0, 0.0, -5.0], "normal": [0.1, 0.0, 1.0], "material": "wall"},
            {"type": "sphere", "center": [-1.6, 0.0, -0.8], "radius": 1.0, "material": "mirror"},
            {"type": "sphere", "center": [0.6, -0.15, 1.2], "radius": 0.8, "material": "glass"},
            # lifted off the floor: a face on the floor plane would make "inside the box" a coin toss
            {"type": "box", "min": [1.4, -0.8, -1.6], "max": [2.4, 0.5, -0.6], "material": "tinted"},
            {"type": "sphere", "center": [0.3, -0.55, -1.8], "radius": 0.45, "material": "red"},
            {"type": "sphere", "center": [-0.4, -0.7, 2.4], "radius": 0.3, "material": "blue"},
            {"type": "box", "min": [-3.2, -1.0, -3.5], "max": [-2.4, 0.8, -2.7], "material": "red"},
        ],
    }


@needs_whitted
@pytest.mark.parametrize("cam, fresnel, mirror_floor", [("perspective", False, False), ("perspective", True, True),
                                                        ("orthographic", False, True), ("orthographic", True, False)])
def test_matches_independent_implementation(cam, fresnel, mirror_floor):
    scene = done_scene(DONE_CAMERAS[cam], fresnel, mirror_floor)
    W, H = 160, 120
    img = whitted(scene, width=W, height=H, max_depth=5).array
    want = render_whitted(scene, W, H, max_depth=5)
    err = np.abs(img - want).max(axis=2)
    close = err <= 3e-3
    assert close.mean() >= 0.98, (f"only {close.mean():.4f} of the pixels agree to 3e-3 "
                                  f"(median error {np.median(err):.2e}, worst {err.max():.3f})")
    assert np.median(err) < 1e-4  # not just close on most pixels: the same numbers, up to ray offsets
    # the scene is not trivial: recursion changes the picture a lot, and there are bright and dark parts
    local = render_whitted(scene, W, H, max_depth=0)
    assert (np.abs(want - local).max(axis=2) > 0.05).mean() > 0.1
    assert want.std() > 0.1 and (want.max(axis=2) > 1.0).any()


@needs_whitted
def test_nested_dielectrics_match_the_twin():
    # a water sphere inside a glass box and a glass sphere overlapping it: each ray's ordered list of media
    # decides n1 and n2 (entering the water from the glass: 1.5 → 1.33)
    scene = {
        "camera": {"position": [0.3, 1.2, 4.5], "look_at": [0.0, 0.0, 0.0], "fov": 40.0},
        "ambient": 0.1,
        "background": [0.3, 0.35, 0.5],
        "lights": [{"type": "point", "position": [3.0, 5.0, 4.0], "intensity": 1.0}],
        "objects": [
            {"type": "plane", "point": [0.0, -1.2, 0.0], "normal": [0.0, 1.0, 0.0],
             "material": {"ka": 0.5, "kd": 0.6}},
            {"type": "sphere", "center": [1.5, 1.0, -6.0], "radius": 2.0, "material": {"kd": [0.9, 0.2, 0.1]}},
            {"type": "box", "min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0],
             "material": {"kt": 0.9, "kr": 0.05, "ior": 1.5}},
            {"type": "sphere", "center": [0.1, 0.0, 0.2], "radius": 0.6, "material": {"kt": 0.9, "ior": 1.33}},
            {"type": "sphere", "center": [1.1, 0.7, 0.3], "radius": 0.5,
             "material": {"kt": [0.9, 0.8, 0.6], "ior": 1.7, "fresnel": True}},
        ],
    }
    W, H = 96, 72
    img = whitted(scene, width=W, height=H, max_depth=6).array
    want = render_whitted(scene, W, H, max_depth=6)
    close = (np.abs(img - want) <= 3e-3).all(axis=2)
    # (media lists matter here: leaving every solid into air instead changes ~13 % of the pixels)
    assert close.mean() >= 0.98, f"only {close.mean():.4f} of the pixels agree to 3e-3"


# ---------------------------------------------------------------------------------------- anti-aliasing


def _edges_scene():
    """Flat-coloured (ambient-only) spheres and a box on a plane under a directional light, seen from above: a
    few sharp edges (outlines and shadow borders) between flat regions, which a corner-and-subdivide sampler
    should find and a ray per pixel aliases."""
    return {
        "camera": {"position": [0.0, 4.0, 4.0], "look_at": [0.0, 0.0, 0.0], "fov": 40.0},
        "ambient": 1.0,
        "lights": [{"type": "directional", "direction": [0.3, -1.0, -0.2], "intensity": 0.6}],
        "objects": [
            {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0], "material": {"ka": 0.1, "kd": 0.5}},
            {"type": "sphere", "center": [-0.9, 0.5, 0.2], "radius": 0.5, "material": {"ka": 0.9}},
            {"type": "sphere", "center": [0.7, 0.6, -0.5], "radius": 0.6, "material": {"ka": [0.9, 0.5, 0.2]}},
            {"type": "box", "min": [0.3, 0.0, 0.8], "max": [0.9, 0.5, 1.3], "material": {"ka": [0.2, 0.4, 0.9]}},
        ],
    }


def _primary_rays(img):
    """Primary rays the render traced: `stats["primary_rays"]` where reported, else the samples AOV's sum."""
    if "primary_rays" in img.stats:
        return img.stats["primary_rays"]
    return float(np.asarray(img.aovs["samples"], dtype=np.float64).sum())


@needs_whitted
def test_adaptive_antialiasing_beats_one_ray_per_pixel_for_fewer_rays():
    scene = _edges_scene()
    W, H = 80, 60
    reference = whitted(scene, width=W, height=H, antialias="supersample", spp=256, seed=1).array
    one = whitted(scene, width=W, height=H).array
    adaptive = whitted(scene, width=W, height=H, antialias="adaptive", aov=["samples"])
    rmse = lambda img: float(np.sqrt(((img - reference) ** 2).mean()))  # noqa: E731
    assert rmse(adaptive.array) <= 0.6 * rmse(one), (rmse(adaptive.array), rmse(one))
    assert _primary_rays(adaptive) <= 0.4 * 16 * W * H
    # where it spends them: about one ray per pixel on flat regions, more along edges
    samples = np.asarray(adaptive.aovs["samples"], dtype=np.float64).reshape(H, W)
    pad = np.pad(reference.max(axis=2), 1, mode="edge")
    windows = np.stack([pad[y:y + H, x:x + W] for y in range(3) for x in range(3)])
    flat = (windows.max(axis=0) - windows.min(axis=0)) < 0.005
    edge = np.abs(one - reference).max(axis=2) > 0.1
    assert flat.sum() > 0.3 * W * H and edge.sum() > 30
    if "primary_rays" in adaptive.stats:
        assert adaptive.stats["primary_rays"] == samples.sum()
    assert 1.0 <= np.median(samples[flat]) <= 2.0 and samples[flat].mean() < 4.0
    assert samples[edge].mean() > 1.5 * samples[flat].mean()


# ---------------------------------------------------------------------------------------- depth of field


SQUARE, BOARD_X = 0.4, -0.3  # the checkerboard's squares and its centre's x; it spans BOARD_X ± 2·SQUARE


def _dof_scene(aperture):
    """A flat 'checkerboard' of white squares (triangles) on the plane of focus z = −5, seen head-on, and a
    sphere close to the lens (z = −1.5). Ambient-only and Lambert shading under a light along the view axis:
    the colour at a point does not depend on where the eye is."""
    squares = []
    for i in range(4):
        for j in range(4):
            if (i + j) % 2:
                continue
            x0, y0 = BOARD_X - 2 * SQUARE + SQUARE * i, -2 * SQUARE + SQUARE * j
            a, b = [x0, y0, -5.0], [x0 + SQUARE, y0, -5.0]
            c, d = [x0 + SQUARE, y0 + SQUARE, -5.0], [x0, y0 + SQUARE, -5.0]
            squares += [{"type": "triangle", "vertices": [a, b, c], "material": "white"},
                        {"type": "triangle", "vertices": [a, c, d], "material": "white"}]
    return {
        "camera": {"position": [0.0, 0.0, 0.0], "look_at": [0.0, 0.0, -1.0], "fov": 40.0,
                   "aperture": aperture, "focus_distance": 5.0},
        "ambient": 0.5,
        "lights": [{"type": "directional", "direction": [0.0, 0.0, -1.0], "intensity": 0.5}],
        "materials": {"white": {"ka": 1.0, "kd": 1.0}},
        "objects": squares + [{"type": "sphere", "center": [0.55, 0.05, -1.5], "radius": 0.12,
                               "material": {"ka": 1.0, "kd": 0.8}}],
    }


@needs_whitted
def test_depth_of_field_blurs_only_off_the_focus_plane():
    W, H = 64, 48
    kw = dict(width=W, height=H, antialias="supersample", spp=64, seed=2)
    pinhole = whitted(_dof_scene(0.0), **kw).array.max(axis=2)
    lens = whitted(_dof_scene(0.2), **kw).array.max(axis=2)
    # image columns: the checkerboard's (at z = −5) and the sphere's (at z = −1.5, x = 0.55 ± 0.12), with margins
    cols = (np.arange(W) + 0.5) / W * 2.0 - 1.0  # sx
    half_w = math.tan(math.radians(20.0)) * W / H  # x / depth at sx = 1
    board = np.abs(cols * half_w * 5.0 - BOARD_X) < 2 * SQUARE + 0.05 * 5.0 * half_w
    right = cols * half_w * 1.5 > 0.55 - 0.25  # the sphere and its blur (circle of confusion ≈ 0.14 there)
    assert not (board & right).any()
    diff = np.abs(lens - pinhole)
    assert (pinhole[:, board] > 0.9).sum() > 100 and (pinhole[:, board] < 0.01).sum() > 100  # an edged pattern
    assert diff[:, board].max() < 0.02  # in focus: sharp, edges included
    assert diff[:, right].max() > 0.3 and diff[:, right].sum() > 20.0  # out of focus: blurred
    assert lens[:, right].sum() == pytest.approx(pinhole[:, right].sum(), rel=0.1)  # the light is only spread


# ------------------------------------------------------------------------------------------- determinism


@needs_whitted
@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two Numba threads")
def test_deterministic_across_threads():
    scene = done_scene(DONE_CAMERAS["perspective"], fresnel=True, mirror_floor=True)
    kw = dict(width=40, height=30, antialias="adaptive", max_depth=5, aov=["samples"])
    a = whitted(scene, threads=1, **kw)
    b = whitted(scene, threads=2, **kw)
    assert np.array_equal(a.array, b.array)
    assert np.array_equal(a.aovs["samples"], b.aovs["samples"])


# ------------------------------------------------------------------------------------------------ depth


@needs_whitted
def test_max_depth_zero_shows_only_the_local_term():
    scene = done_scene(DONE_CAMERAS["perspective"], fresnel=False, mirror_floor=True)
    W, H = 80, 60
    flat = whitted(scene, width=W, height=H, max_depth=0, aov=["object_id"])
    local = render_whitted(scene, W, H, max_depth=0)
    close = (np.abs(flat.array - local) <= 1e-3).all(axis=2)
    assert close.mean() >= 0.99
    mirror = flat.aovs["object_id"] == 2
    assert mirror.sum() > 150
    assert close[mirror].mean() > 0.99  # the mirror sphere: its local term only, no reflection
    deeper = whitted(scene, width=W, height=H, max_depth=1).array
    assert (np.abs(deeper - flat.array)[mirror].max(axis=1) > 0.05).mean() > 0.5  # reflections appear at depth 1


def _mirror_corridor(kr, camera_type="orthographic"):
    """Two parallel mirrors z = 0 and z = 2 facing each other, an eye half-way looking straight at one: every
    bounce sees ka·Ia (no lights), weighted by kr^k."""
    camera = {"position": [0.0, 0.0, 1.0], "look_at": [0.0, 0.0, 0.0], "fov": 30.0, "size": 1.0}
    if camera_type == "orthographic":
        camera["type"] = "orthographic"
    mirror = {"ka": 1.0, "kr": kr}
    return {
        "camera": camera,
        "ambient": [0.1, 0.2, 0.3],
        "background": [5.0, 5.0, 5.0],
        "objects": [{"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "material": mirror},
                    {"type": "plane", "point": [0.0, 0.0, 2.0], "normal": [0.0, 0.0, -1.0], "material": mirror}],
    }


@needs_whitted
@pytest.mark.parametrize("max_depth", [0, 3, 40])
def test_mirror_facing_a_mirror_terminates(max_depth):
    W, H = 5, 3
    scene = _mirror_corridor(1.0)
    img = whitted(scene, width=W, height=H, max_depth=max_depth)
    assert np.isfinite(img.array).all()
    # lossless mirrors: exactly max_depth + 1 hits, each adding ka·Ia; no ray escapes to the background
    np.testing.assert_allclose(img.array, np.broadcast_to(np.multiply(max_depth + 1, [0.1, 0.2, 0.3]), (H, W, 3)),
                               rtol=1e-5)
    assert img.stats["rays"] == W * H * (max_depth + 1)
    # lossy mirrors (kr 0.5): the bounces stop where the path weight 0.5^k drops below 1e-3 (k = 10)
    lossy = whitted(_mirror_corridor(0.5, "perspective"), width=W, height=H, max_depth=max_depth).array
    k = min(max_depth, 9)
    want = (1.0 - 0.5 ** (k + 1)) / 0.5 * np.array([0.1, 0.2, 0.3])
    np.testing.assert_allclose(lossy, np.broadcast_to(want, (H, W, 3)), rtol=1e-5)
    np.testing.assert_allclose(render_whitted(_mirror_corridor(0.5, "perspective"), W, H, max_depth), lossy,
                               rtol=1e-5)


def test_motion_blur_converges_to_the_time_average():
    # a sphere moving along x during the shutter interval, seen head-on by an orthographic camera; with an
    # ambient-only material each pixel's value is the fraction of the shutter time the sphere covers it
    W, H = 48, 16
    scene = {
        "camera": {"type": "orthographic", "position": [0.0, 0.0, 5.0], "look_at": [0.0, 0.0, 0.0], "size": 2.0,
                   "shutter": [0.0, 1.0]},
        "ambient": 1.0,
        "objects": [{"type": "sphere", "center": [-1.5, 0.0, 0.0], "radius": 0.5, "motion": [3.0, 0.0, 0.0],
                     "material": {"ka": 1.0}}],
    }
    # exact: at pixel (x, y) the ray meets the sphere at time τ when |px − (−1.5 + 3τ)| ≤ √(r² − py²)
    xs = (np.arange(W) + 0.5) / W * 2.0 * (W / H) - (W / H)
    ys = 1.0 - (np.arange(H) + 0.5) / H * 2.0
    half = np.sqrt(np.maximum(0.25 - ys[:, None] ** 2, 0.0))
    lo = np.clip((xs[None, :] - half + 1.5) / 3.0, 0.0, 1.0)
    hi = np.clip((xs[None, :] + half + 1.5) / 3.0, 0.0, 1.0)
    exact = np.where(half > 0, hi - lo, 0.0)
    errors = {}
    for spp in (4, 64):
        # one ray through each pixel centre per sample would not do: supersample jitters the position too,
        # so compare the rows' sums (the jitter in y only blurs across rows of equal width here)
        img = lumos.render(scene, method="whitted", width=W, height=H, spp=spp, antialias="supersample").array
        errors[spp] = np.abs(img[..., 0].mean(axis=0) - exact.mean(axis=0)).mean()
    assert errors[64] < 0.02
    assert errors[64] < errors[4]
    # a closed shutter freezes the sphere at its start
    scene["camera"]["shutter"] = [0.0, 0.0]
    still = lumos.render(scene, method="whitted", width=W, height=H, antialias="none").array[..., 0]
    assert still[H // 2, : W // 4].max() == 1.0 and still[:, W // 2:].max() == 0.0
