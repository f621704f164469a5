"""The classic illumination model (`phong`, `illuminate`, area-light estimators) against hand-computed values
and closed-form irradiance (DESIGN.md §3: Kd·I·max(N·L,0)/att + Ks·I·max(R·V,0)^n/att, ambient Ka·Ia,
area lights Kd·E/π)."""

import math

import numpy as np
import pytest
from conftest import call_illuminate, compile_dict, material_row
from naive import polygon_irradiance, sphere_irradiance, unit

from lumos.kernels.illumination import phong

N_UP = (0.0, 0.0, 1.0)
L_34 = (0.0, 0.6, 0.8)  # N·L = 0.8 exactly (a 3-4-5 triangle)


# ------------------------------------------------------------------------------------------------ phong


@pytest.mark.nojit
def test_phong_diffuse_only_by_hand():
    mat = material_row(kd=(0.5, 0.25, 1.0))
    # Kd·Id·(N·L) = (0.5, 0.25, 1.0) · 2 · 0.8
    assert phong(N_UP, L_34, N_UP, mat, (2.0, 2.0, 2.0), (0.0, 0.0, 0.0), 1.0) == pytest.approx((0.8, 0.4, 1.6))
    # the weight w (1/att) scales the whole term
    assert phong(N_UP, L_34, N_UP, mat, (2.0, 2.0, 2.0), (0.0, 0.0, 0.0), 0.25) == pytest.approx((0.2, 0.1, 0.4))


@pytest.mark.nojit
def test_phong_specular_by_hand():
    mat = material_row(ks=0.5, shininess=2.0)
    # R = 2(N·L)N − L = 2·0.8·(0,0,1) − (0,0.6,0.8) = (0, −0.6, 0.8); with V = N: R·V = 0.8, (R·V)² = 0.64
    assert phong(N_UP, L_34, N_UP, mat, (0.0, 0.0, 0.0), (1.0, 2.0, 3.0), 1.0) == pytest.approx((0.32, 0.64, 0.96))
    # looking straight down R: R·V = 1, the full Ks·Is
    assert phong(N_UP, L_34, (0.0, -0.6, 0.8), mat, (0.0,) * 3, (1.0, 2.0, 3.0), 1.0) == pytest.approx((0.5, 1.0, 1.5))
    # V = (0, 1, 0) on the far side of R: R·V = −0.6 < 0, no highlight
    assert phong(N_UP, L_34, (0.0, 1.0, 0.0), mat, (0.0,) * 3, (1.0, 2.0, 3.0), 1.0) == (0.0, 0.0, 0.0)


@pytest.mark.nojit
def test_phong_light_below_the_horizon_gives_nothing():
    mat = material_row(kd=1.0, ks=1.0, shininess=1.0)
    below = (0.0, 0.6, -0.8)  # N·L = −0.8; its "R" = (0, −0.6, −0.8) would still meet V = R
    assert phong(N_UP, below, (0.0, -0.6, -0.8), mat, (1.0,) * 3, (1.0,) * 3, 1.0) == (0.0, 0.0, 0.0)
    grazing = (0.0, 1.0, 0.0)  # N·L = 0 exactly
    assert phong(N_UP, grazing, (0.0, -1.0, 0.0), mat, (1.0,) * 3, (1.0,) * 3, 1.0) == (0.0, 0.0, 0.0)


def test_phong_matches_formula_on_random_inputs(rng):
    for _ in range(200):
        n, L, V = unit(rng.normal(size=3)), unit(rng.normal(size=3)), unit(rng.normal(size=3))
        kd, ks, Id, Is = rng.random(3), rng.random(3), rng.random(3) * 3, rng.random(3) * 3
        shininess, w = float(rng.uniform(0.5, 60)), float(rng.uniform(0.1, 2))
        mat = material_row(kd=kd, ks=ks, shininess=shininess)
        got = phong(tuple(n), tuple(L), tuple(V), mat, tuple(Id), tuple(Is), w)
        nl = n @ L
        R = 2 * nl * n - L
        want = (kd * Id * nl + ks * Is * max(R @ V, 0.0) ** shininess) * w if nl > 0 else np.zeros(3)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)


# ------------------------------------------------------------------------------------------- illuminate


def _illuminate(scene, p, n=N_UP, V=N_UP, pixel=0, sample=0, seed=0, arrays=None):
    """`illuminate` at p for the material of the scene's first object (row 0), no shadow rays."""
    if arrays is None:
        arrays = compile_dict(scene).arrays
    stack = np.empty(64, np.int64)
    rgb, rays = call_illuminate(arrays, tuple(map(float, p)), tuple(map(float, n)), tuple(map(float, V)), 0, seed,
                                pixel, sample, False, stack)
    assert rays == 0
    return np.array(rgb)


def _scene(material, lights, ambient=0.0):
    # a far-away object only carries the material (row 0)
    return {"ambient": ambient, "lights": lights,
            "objects": [{"type": "sphere", "center": [0, -100, 0], "radius": 0.1, "material": material}]}


@pytest.mark.nojit
def test_point_light_with_attenuation_by_hand():
    # light at distance 5 along (0, 0.6, 0.8); att = 1 + 0.5·5 + 0.2·25 = 8.5
    scene = _scene({"kd": 0.5}, [{"type": "point", "position": [1.0, 3.0 + 2.0, 4.0 - 1.0], "intensity": 2.0,
                                  "attenuation": [1.0, 0.5, 0.2]}])
    got = _illuminate(scene, (1.0, 2.0, -1.0))
    np.testing.assert_allclose(got, [0.5 * 2.0 * 0.8 / 8.5] * 3, rtol=1e-12)
    # with the default attenuation [1, 0, 0] there is no fall-off
    scene["lights"][0].pop("attenuation")
    np.testing.assert_allclose(_illuminate(scene, (1.0, 2.0, -1.0)), [0.8] * 3, rtol=1e-12)


@pytest.mark.nojit
def test_directional_light_uses_minus_direction():
    scene = _scene({"kd": [0.5, 1.0, 0.25]}, [{"type": "directional", "direction": [0.0, -3.0, -4.0],
                                                "intensity": 2.0}])
    # L = −normalize(direction) = (0, 0.6, 0.8); no attenuation however far
    np.testing.assert_allclose(_illuminate(scene, (50.0, -20.0, 7.0)), [0.8, 1.6, 0.4], rtol=1e-12)
    scene["lights"][0]["direction"] = [0.0, 3.0, 4.0]  # now shining from below: nothing
    np.testing.assert_allclose(_illuminate(scene, (0.0, 0.0, 0.0)), [0.0, 0.0, 0.0], atol=0)


@pytest.mark.nojit
def test_ambient_and_lights_behind_the_surface():
    scene = _scene({"ka": [0.1, 0.2, 0.3], "kd": 1.0, "ks": 1.0}, [
        {"type": "point", "position": [0.0, 0.0, -2.0], "intensity": 5.0},  # behind: N·L < 0
        {"type": "directional", "direction": [1.0, 0.0, 0.0], "intensity": 5.0},  # N·L = 0
    ], ambient=[1.0, 0.5, 2.0])
    np.testing.assert_allclose(_illuminate(scene, (0.0, 0.0, 0.0)), [0.1, 0.1, 0.6], rtol=1e-12)


@pytest.mark.nojit
def test_separate_diffuse_and_specular_intensities():
    # Id = (1, 0, 0), Is = (0, 0, 1); N·L = 0.8 and, with V = N, R·V = 0.8 (shininess 1)
    light = {"type": "directional", "direction": [0.0, -0.6, -0.8], "intensity": 9.0,
             "diffuse": [1.0, 0.0, 0.0], "specular": [0.0, 0.0, 1.0]}
    scene = _scene({"kd": 1.0, "ks": 1.0, "shininess": 1.0}, [light])
    np.testing.assert_allclose(_illuminate(scene, (0.0, 0.0, 0.0)), [0.8, 0.0, 0.8], rtol=1e-12)
    # only `diffuse` given: the specular part keeps `intensity`
    del light["specular"]
    np.testing.assert_allclose(_illuminate(scene, (0.0, 0.0, 0.0)), [0.8 + 9 * 0.8, 9 * 0.8, 9 * 0.8], rtol=1e-12)


@pytest.mark.nojit
def test_lights_add_up():
    lights = [{"type": "point", "position": [0.0, 3.0, 4.0], "intensity": 1.0},
              {"type": "directional", "direction": [0.0, 0.0, -1.0], "intensity": [0.5, 0.25, 0.0]}]
    scene = _scene({"kd": 1.0, "ka": 0.5}, lights, ambient=0.2)
    np.testing.assert_allclose(_illuminate(scene, (0.0, 0.0, 0.0)), [0.1 + 0.8 + 0.5, 0.1 + 0.8 + 0.25, 0.1 + 0.8])


# ------------------------------------------------------------------------------------------ area lights


def _mean_over_pixels(scene, p, n, pixels=64):
    arrays = compile_dict(scene).arrays
    return np.mean([_illuminate(None, p, n, arrays=arrays, pixel=k) for k in range(pixels)], axis=0)


@pytest.mark.parametrize("shape", ["rect", "disk"])
def test_small_far_area_light_equals_point_light(shape):
    # a 0.2-wide emitter 20 away, tilted by 30°, seen from a tilted surface: like a point light of intensity
    # Le·A·cosθ'/π with 1/d² fall-off
    Le, center = 40.0, np.array([3.0, 1.0, 20.0])
    light_n = np.array([0.0, -math.sin(math.radians(30)), -math.cos(math.radians(30))])
    if shape == "rect":
        eu = np.array([0.2, 0.0, 0.0])
        ev = np.cross(light_n, eu)  # cross(eu, ev) ∥ light_n
        ev = 0.2 * ev / np.linalg.norm(ev)
        if np.cross(eu, ev) @ light_n < 0:
            ev = -ev
        light = {"type": "area", "shape": "rect", "corner": (center - 0.5 * eu - 0.5 * ev).tolist(),
                 "edge_u": eu.tolist(), "edge_v": ev.tolist(), "radiance": Le, "samples": 4}
        area = 0.04
    else:
        light = {"type": "area", "shape": "disk", "center": center.tolist(), "normal": light_n.tolist(),
                 "radius": 0.1, "radiance": Le, "samples": 4}
        area = math.pi * 0.01
    p, n = np.zeros(3), unit([0.3, 0.1, 1.0])
    to = center - p
    d = np.linalg.norm(to)
    cos_light = -(light_n @ to) / d
    intensity = Le * area * cos_light / math.pi
    expect = 0.7 * intensity * (n @ to / d) / d**2  # Kd·I·cosθ/d²
    got = _mean_over_pixels(_scene({"kd": 0.7}, [light]), p, n, pixels=8)
    np.testing.assert_allclose(got, [expect] * 3, rtol=0.01)
    # and the same number from a point light of that intensity with quadratic attenuation
    point = {"type": "point", "position": center.tolist(), "intensity": intensity, "attenuation": [0, 0, 1]}
    np.testing.assert_allclose(_illuminate(_scene({"kd": 0.7}, [point]), p, n), [expect] * 3, rtol=1e-12)


def test_large_near_rect_light_matches_lambert_polygon_formula():
    corner, eu, ev = np.array([-1.0, -0.5, 1.0]), np.array([2.0, 0.0, 0.0]), np.array([0.0, 1.5, 0.3])
    # emits towards −z-ish: cross(eu, ev) must point down at the receiver
    eu, ev = ev, eu
    light = {"type": "area", "shape": "rect", "corner": corner.tolist(), "edge_u": eu.tolist(),
             "edge_v": ev.tolist(), "radiance": 3.0, "samples": 64}
    assert np.cross(eu, ev)[2] < 0
    p, n = np.array([0.2, 0.1, 0.0]), unit([0.2, -0.1, 1.0])
    E = polygon_irradiance(p, n, [corner, corner + eu, corner + eu + ev, corner + ev], 3.0)
    got = _mean_over_pixels(_scene({"kd": 0.6}, [light]), p, n, pixels=16)
    np.testing.assert_allclose(got, [0.6 * E / math.pi] * 3, rtol=0.01)


@pytest.mark.nojit
def test_sphere_light_on_axis_irradiance():
    Le, r, dist = 2.0, 0.5, 3.0
    light = {"type": "area", "shape": "sphere", "center": [0.0, 0.0, dist], "radius": r, "radiance": Le,
             "samples": 16}
    got = _mean_over_pixels(_scene({"kd": 0.8}, [light]), (0.0, 0.0, 0.0), N_UP, pixels=32)
    # E = π·Le·(r/d)², so Kd·E/π = Kd·Le·(r/d)²
    np.testing.assert_allclose(got, [0.8 * Le * (r / dist) ** 2] * 3, rtol=0.005)


def test_sphere_light_off_axis_irradiance():
    center, r, Le = np.array([1.0, -0.5, 2.5]), 0.6, 1.5
    light = {"type": "area", "shape": "sphere", "center": center.tolist(), "radius": r, "radiance": Le,
             "samples": 16}
    p, n = np.array([0.1, 0.2, 0.0]), unit([-0.2, 0.3, 1.0])
    got = _mean_over_pixels(_scene({"kd": 1.0}, [light]), p, n, pixels=32)
    np.testing.assert_allclose(got, [sphere_irradiance(p, n, center, r, Le) / math.pi] * 3, rtol=0.01)


@pytest.mark.parametrize("shape", ["rect", "disk"])
@pytest.mark.nojit
def test_one_sided_area_light_emits_nothing_behind(shape):
    if shape == "rect":
        light = {"type": "area", "shape": "rect", "corner": [-0.5, -0.5, 2.0], "edge_u": [1.0, 0.0, 0.0],
                 "edge_v": [0.0, 1.0, 0.0], "radiance": 5.0, "samples": 16}  # emits towards +z
    else:
        light = {"type": "area", "shape": "disk", "center": [0.0, 0.0, 2.0], "normal": [0.0, 0.0, 1.0],
                 "radius": 0.5, "radiance": 5.0, "samples": 16}
    scene = _scene({"kd": 1.0, "ks": 1.0}, [light])
    below = _mean_over_pixels(scene, (0.0, 0.0, 0.0), N_UP, pixels=4)  # behind the emitter, facing it
    assert (below == 0.0).all()
    above = _mean_over_pixels(scene, (0.0, 0.0, 4.0), (0.0, 0.0, -1.0), pixels=4)  # in front, facing it
    assert (above > 0.05).all()


def test_area_light_estimate_uses_its_own_random_stream():
    light = {"type": "area", "shape": "rect", "corner": [-1.0, -1.0, 1.0], "edge_u": [0.0, 2.0, 0.0],
             "edge_v": [2.0, 0.0, 0.0], "radiance": 1.0, "samples": 3}
    arrays = compile_dict(_scene({"kd": 1.0}, [light])).arrays
    a = _illuminate(None, (0.0, 0.0, 0.0), arrays=arrays, pixel=5, sample=2, seed=1)
    assert np.array_equal(a, _illuminate(None, (0.0, 0.0, 0.0), arrays=arrays, pixel=5, sample=2, seed=1))
    others = [_illuminate(None, (0.0, 0.0, 0.0), arrays=arrays, pixel=6, sample=2, seed=1),
              _illuminate(None, (0.0, 0.0, 0.0), arrays=arrays, pixel=5, sample=3, seed=1),
              _illuminate(None, (0.0, 0.0, 0.0), arrays=arrays, pixel=5, sample=2, seed=2)]
    assert all(not np.array_equal(a, b) for b in others)
