"""Spot lights (`type: spot`): a point light limited to a cone, with glTF KHR_lights_punctual's falloff s²,
s = clamp((cosθ − cos angle)/(cos inner_angle − cos angle), 0, 1), cosθ = dot(axis, −L).

Closed forms (a 90° spot is a point light on its lit side; a row of pixels on a plane below a spot follows
I·(N·L)·s²/att exactly; a hard-edged spot leaves only the ambient term outside its cone), the direct light of
a spot-lit diffuse floor agreeing across raycast, whitted, raster (flat, Gouraud, Phong), path and radiosity,
whitted's and raster's shadows, the path tracer's light-selection power, explain, info and the scene errors.
"""

import math

import numpy as np
import pytest

import lumos
from lumos.api import scene_info
from lumos.compile import compile_scene, spot_cos
from lumos.methods import compile_for
from lumos.compile.emitters import spot_solid_angle
from lumos.errors import LumosError
from lumos.tools.explain import format_text
from lumos.kernels import layout as L
from lumos.kernels.illumination import spot_falloff


def falloff(cos_theta, angle, inner):
    """The twin of `spot_falloff`, from the angles in degrees (shared_formats item 2)."""
    co, ci = math.cos(math.radians(angle)), math.cos(math.radians(inner))
    if ci - co < 1e-9:
        return np.where(cos_theta >= co, 1.0, 0.0)
    return np.clip((cos_theta - co) / (ci - co), 0.0, 1.0) ** 2


def _unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v)


# ------------------------------------------------------------------------------------------- the falloff

def test_falloff_helper_matches_the_formula_and_steps_when_the_cones_coincide():
    rng = np.random.default_rng(1)
    for angle, inner in ((45.0, 0.0), (30.0, 20.0), (90.0, 60.0), (10.0, 9.999)):
        for c in rng.uniform(-1.0, 1.0, 200):
            want = float(falloff(c, angle, inner))
            assert spot_falloff(c, spot_cos(angle), spot_cos(inner)) == pytest.approx(want, abs=1e-12)
    co = spot_cos(30.0)
    assert spot_falloff(co, co, co) == 1.0 and spot_falloff(co - 1e-12, co, co) == 0.0
    assert spot_cos(90.0) == 0.0  # exactly: a 90° spot lights the whole half-space a point light would


@pytest.mark.parametrize("angle,inner", [(45.0, 0.0), (30.0, 20.0), (60.0, 60.0), (90.0, 90.0), (90.0, 0.0)])
def test_spot_power_is_its_falloff_integrated_over_the_sphere(angle, inner):
    """Ω = ∫ falloff dω = 2π ∫ f(c) dc, by the midpoint rule on the kernel's own falloff."""
    co, ci = spot_cos(angle), spot_cos(inner)
    n = 200_000
    c = -1.0 + (np.arange(n) + 0.5) * (2.0 / n)
    numeric = 2.0 * math.pi * sum(spot_falloff(x, co, ci) for x in c) * (2.0 / n)
    assert spot_solid_angle(co, ci) == pytest.approx(numeric, rel=2e-4, abs=1e-4)
    if angle == inner == 90.0:
        assert spot_solid_angle(co, ci) == pytest.approx(2.0 * math.pi)


def test_path_picks_a_spot_by_its_power_against_a_point_light():
    """Light selection is proportional to power: a spot carries Ω/(4π) of a point light of the same I."""
    scene = {"lights": [{"type": "point", "position": [0, 3, 0], "intensity": 2.0},
                        {"type": "spot", "position": [1, 3, 0], "direction": [0, -1, 0], "intensity": 2.0,
                         "angle": 40, "inner_angle": 25}],
             "objects": [{"type": "sphere", "radius": 1.0}]}
    s = lumos.load_scene(scene)
    from lumos.api import resolve_settings

    em = compile_for(s, resolve_settings(s, {"method": "path"})).emitters
    pmf = em.emit_pmf[em.light_emit]
    omega = spot_solid_angle(spot_cos(40.0), spot_cos(25.0))
    assert pmf[1] / pmf[0] == pytest.approx(omega / (4.0 * math.pi), rel=1e-12)


# ------------------------------------------------------------------------------------------ closed forms

def _row_scene(light, ambient=0.0, ka=0.0, kd=0.8, ks=0.0, objects=()):
    """A top-down orthographic view of the plane y = 0 whose middle pixel row (of 3) sees the points (x, 0, 0),
    x at the pixel centres of a row 8 units wide."""
    width, height = 201, 3
    return {
        "camera": {"type": "orthographic", "position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
                   "size": 8.0 * height / width},
        "render": {"width": width, "height": height, "antialias": "none", "spp": 1},
        "ambient": ambient,
        "lights": [light],
        "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0],
                     "material": {"ka": ka, "kd": kd, "ks": ks, "shininess": 10}}, *objects],
    }


def _row_x(width=201):
    return ((2.0 * (np.arange(width) + 0.5) / width) - 1.0) * 4.0


def test_a_row_of_pixels_below_a_tilted_spot_follows_the_formula():
    """E·kd/π on a diffuse plane: kd·I·(N·L)·s²(cosθ)/att(d), with the spot's cosθ = dot(axis, −L) — not N·L —
    because the axis is tilted; the row crosses the full cone, the falloff band and the dark outside."""
    pos, axis = np.array([0.3, 2.0, 0.0]), _unit([0.35, -1.0, 0.0])
    light = {"type": "spot", "position": pos.tolist(), "direction": axis.tolist(), "intensity": 3.0,
             "attenuation": [0.5, 0.0, 1.0], "angle": 40.0, "inner_angle": 15.0}
    img = lumos.render(_row_scene(light), method="raycast").array.astype(np.float64)
    x = _row_x()
    p = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1)
    to = pos - p
    d = np.linalg.norm(to, axis=1)
    Ldir = to / d[:, None]
    cos_spot = -(Ldir @ axis)
    want = 0.8 * 3.0 * Ldir[:, 1] * falloff(cos_spot, 40.0, 15.0) / (0.5 + d * d)
    got = img[1, :, 0]
    assert np.allclose(got, want, rtol=1e-5, atol=1e-7), np.abs(got - want).max()
    band = (cos_spot < math.cos(math.radians(15.0))) & (cos_spot > math.cos(math.radians(40.0)))
    assert band.sum() > 10 and 10 < (want > 0).sum() < len(x) - 10


def test_a_90_degree_spot_is_a_point_light():
    """angle 90 and inner_angle 90: the half-space the spot faces, lit exactly as by a point light (diffuse and
    specular terms, every surface below the light)."""
    point = {"type": "point", "position": [0.5, 3.0, 1.0], "intensity": [1.0, 0.8, 0.6], "attenuation": [1, 0.1, 0.02]}
    spot = dict(point, type="spot", direction=[0, -1, 0], angle=90, inner_angle=90)
    base = {"camera": {"position": [0, 2, 5], "look_at": [0, 0.5, 0], "fov": 50},
            "render": {"width": 64, "height": 48}, "ambient": 0.05,
            "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"ka": 0.3, "kd": 0.6}},
                        {"type": "sphere", "center": [0, 0.8, 0], "radius": 0.8,
                         "material": {"ka": 0.2, "kd": [0.7, 0.2, 0.2], "ks": 0.5, "shininess": 30}}]}
    a = lumos.render(dict(base, lights=[point]), method="raycast").array
    b = lumos.render(dict(base, lights=[spot]), method="raycast").array
    assert a.max() > 0.3
    assert np.abs(a - b).max() <= 1e-6


HARD = {"type": "spot", "position": [0.0, 2.0, 0.0], "direction": [0, -1, 0], "intensity": 2.0, "angle": 30.0,
        "inner_angle": 30.0}


@pytest.mark.parametrize("method,extra", [("raycast", {}), ("whitted", {}), ("raster", {"shading": "phong"}),
                                          ("raster", {"shading": "flat"}), ("raster", {"shading": "gouraud"})])
def test_outside_a_hard_edged_spot_only_the_ambient_term_is_left(method, extra):
    """Per-pixel lighting (raycast, whitted, raster Phong) lights the cone's disk exactly; flat and Gouraud light
    polygons or vertices, so their edge is blurred by one cell of the tessellated plane (kept out of the test)."""
    img = lumos.render(_row_scene(HARD, ambient=0.2, ka=0.5, ks=0.3), method=method, **extra).array
    x = _row_x()
    edge = 2.0 * math.tan(math.radians(30.0))
    per_pixel = extra.get("shading", "phong") == "phong"
    margin = 0.05 if per_pixel else 0.5
    outside, inside = np.abs(x) > edge + margin, np.abs(x) < edge - margin
    assert np.all(img[1, outside] == np.float32(0.5 * 0.2))
    assert np.all(img[1, inside, 0] > 0.1 + 0.5)


# -------------------------------------------------------------------------------------- naive twins

TWIN_SCENE = {  # spheres, a box and a floor under a soft tilted spot, a hard-edged spot and a point light
    "camera": {"position": [1.0, 3.0, 7.0], "look_at": [0.2, 0.3, 0.0], "fov": 50.0},
    "ambient": 0.1,
    "lights": [
        {"type": "spot", "position": [-2.0, 4.0, 2.0], "direction": [0.5, -1.0, -0.4], "angle": 35.0,
         "inner_angle": 12.0, "intensity": [14.0, 12.0, 10.0], "attenuation": [0.2, 0.0, 1.0]},
        {"type": "spot", "position": [2.5, 3.0, 1.5], "direction": [-0.6, -1.0, -0.3], "angle": 20.0,
         "inner_angle": 20.0, "diffuse": [0.1, 0.3, 0.6], "specular": 0.8},
        {"type": "point", "position": [0.0, 5.0, -4.0], "intensity": 0.2},
    ],
    "objects": [
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"ka": 0.3, "kd": 0.6}},
        {"type": "sphere", "center": [-0.5, 0.8, 0.0], "radius": 0.8,
         "material": {"ka": 0.2, "kd": [0.7, 0.3, 0.2], "ks": 0.6, "shininess": 40}},
        {"type": "box", "min": [0.6, 0.0, -1.2], "max": [1.6, 1.0, -0.2], "material": {"ka": 0.2, "kd": 0.5}},
    ],
}


def test_raycast_matches_the_naive_twin_with_spot_lights():
    from naive import render_classic

    w, h = 160, 120
    img = lumos.render(TWIN_SCENE, method="raycast", width=w, height=h, antialias="none").array
    want, _, _ = render_classic(TWIN_SCENE, w, h)
    err = np.abs(img - want).max(axis=2)
    assert (err <= 2e-3).mean() >= 0.99 and np.median(err) < 1e-5, (np.median(err), err.max())
    lit_by_spots = want.max(axis=2) > 0.5
    assert 0.05 < lit_by_spots.mean() < 0.8


def test_whitted_matches_the_naive_twin_with_spot_shadows():
    from naive import render_whitted

    w, h = 160, 120
    img = lumos.render(TWIN_SCENE, method="whitted", width=w, height=h, antialias="none", max_depth=0).array
    want = render_whitted(TWIN_SCENE, w, h, max_depth=0)
    err = np.abs(img - want).max(axis=2)
    assert (err <= 3e-3).mean() >= 0.98 and np.median(err) < 1e-4, (np.median(err), err.max())
    cast = lumos.render(TWIN_SCENE, method="raycast", width=w, height=h, antialias="none").array
    assert (np.abs(cast - want).max(axis=2) > 0.05).mean() > 0.02  # the spots' shadows are in the picture


# --------------------------------------------------------------------------------- across the methods

FLOOR = {  # a spot-lit diffuse floor (nothing else: no shadows, no light between surfaces)
    "camera": {"position": [0, 4, 4], "look_at": [0, 0, 0], "fov": 40},
    "lights": [{"type": "spot", "position": [0.3, 2.5, 0.2], "direction": [0.2, -1.0, -0.1], "intensity": 4.0,
                "attenuation": [0, 0, 1], "angle": 35.0, "inner_angle": 15.0}],
    "objects": [{"type": "rect", "corner": [-10, 0, -10], "edge_u": [0, 0, 20], "edge_v": [20, 0, 0],
                 "material": {"kd": 0.7}}],
}
W, H = 48, 36


def _blocks(a, k=6):
    return a.reshape(a.shape[0] // k, k, a.shape[1] // k, k, -1).mean(axis=(1, 3))


@pytest.fixture(scope="module")
def floor_raycast():
    return lumos.render(FLOOR, method="raycast", width=W, height=H, antialias="none").array.astype(np.float64)


def test_the_floor_is_lit_as_the_cone_says(floor_raycast):
    lit = floor_raycast.max(axis=2) > 0
    assert 0.05 < lit.mean() < 0.7  # the cone's ellipse, not the whole floor


@pytest.mark.parametrize("method,extra", [("whitted", {"max_depth": 0}), ("raster", {"shading": "phong"}),
                                          ("raster", {"shading": "phong", "shadows": True})])
def test_whitted_and_raster_phong_see_the_floor_as_raycast(floor_raycast, method, extra):
    img = lumos.render(FLOOR, method=method, width=W, height=H, antialias="none", **extra).array
    assert np.allclose(img, floor_raycast, rtol=1e-4, atol=1e-5), np.abs(img - floor_raycast).max()


def test_the_term_aovs_of_raster_hold_the_spot_light(floor_raycast):
    img = lumos.render(FLOOR, method="raster", shading="phong", width=W, height=H, antialias="none",
                       aov=["diffuse", "ambient", "specular"])
    assert np.allclose(img.aovs["diffuse"], floor_raycast, rtol=1e-4, atol=1e-5)
    assert not img.aovs["ambient"].any() and not img.aovs["specular"].any()


def test_path_direct_light_agrees_with_raycast():
    """max_depth 0 with one delta light: path's next-event estimate is the classic diffuse term (DESIGN.md §3
    units: E = π·I·falloff·cosθ/att, times kd/π), the pixel jitter the only noise: block means to 0.3%."""
    p = lumos.render(FLOOR, method="path", width=W, height=H, spp=64, max_depth=0, seed=2).array.astype(np.float64)
    r = lumos.render(FLOOR, method="raycast", width=W, height=H, spp=64).array.astype(np.float64)
    bp, br = _blocks(p), _blocks(r)
    lit = br > 0.1 * br.max()
    assert lit.sum() > 10
    assert np.abs(bp[lit] - br[lit]).max() < 0.003 * br.max()
    assert abs(bp[lit].sum() / br[lit].sum() - 1.0) < 0.001


def test_radiosity_first_bounce_agrees_with_raycast():
    """radiosity shoots a spot's light analytically onto its patches; on a lone floor nothing bounces back, so
    the solution is the direct light, averaged over patches (block means within 2% where it is bright)."""
    scene = dict(FLOOR, objects=[dict(FLOOR["objects"][0], corner=[-3, 0, -3], edge_u=[0, 0, 6], edge_v=[6, 0, 0])])
    rad = lumos.render(scene, method="radiosity", width=W, height=H, spp=4,
                       radiosity={"patch_size": 0.1}).array.astype(np.float64)
    r = lumos.render(scene, method="raycast", width=W, height=H, spp=4).array.astype(np.float64)
    bp, br = _blocks(rad), _blocks(r)
    lit = br > 0.3 * br.max()
    assert lit.sum() > 5
    rel = np.abs(bp[lit] - br[lit]) / br[lit]
    assert np.median(rel) < 0.01 and rel.max() < 0.02, (np.median(rel), rel.max())
    assert abs(bp[lit].sum() / br[lit].sum() - 1.0) < 0.01


# -------------------------------------------------------------------------------------------- shadows

def test_whitted_and_raster_shadows_from_a_spot():
    """A ball between a spot and the floor: where the segment to the light crosses it the floor keeps only its
    ambient term (whitted; raster with shadows), elsewhere it is raycast's (which casts no shadow rays)."""
    pos, center, radius = np.array([0.0, 2.5, 0.0]), np.array([0.6, 1.5, 0.0]), 0.25
    light = {"type": "spot", "position": pos.tolist(), "direction": [0, -1, 0], "intensity": 2.0, "angle": 60.0,
             "inner_angle": 30.0}
    ball = {"type": "sphere", "center": center.tolist(), "radius": radius, "material": {"kd": 0.5}}
    scene = _row_scene(light, ambient=0.2, ka=0.5, objects=[ball])
    x = _row_x()
    p = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1)
    # distance from the ball's centre to each segment p -> light
    seg = pos - p
    t = np.clip(((center - p) * seg).sum(axis=1) / (seg * seg).sum(axis=1), 0.0, 1.0)
    gap = np.linalg.norm(p + t[:, None] * seg - center, axis=1)
    floor = np.abs(x - center[0]) > radius + 0.05  # not under the ball as the top-down camera sees it
    shadowed = floor & (gap < radius - 0.02)
    open_ = floor & (gap > radius + 0.02)
    assert shadowed.sum() > 10
    ray = lumos.render(scene, method="raycast").array[1]
    assert np.all(ray[shadowed, 0] > 0.2)  # raycast: lit there
    for method, extra in (("whitted", {}), ("raster", {"shading": "phong", "shadows": True})):
        img = lumos.render(scene, method=method, **extra).array[1]
        assert np.all(img[shadowed] == np.float32(0.1)), method
        assert np.allclose(img[open_], ray[open_], rtol=1e-4, atol=1e-6), method


# ---------------------------------------------------------------------------------- explain, info, errors

def test_explain_names_the_spot_and_its_falloff():
    scene = _row_scene(HARD, ambient=0.2, ka=0.5)
    for method in ("raycast", "whitted"):
        img = lumos.render(scene, method=method).array
        inside = lumos.explain(scene, 100, 1, method=method)
        outside = lumos.explain(scene, 5, 1, method=method)
        assert np.allclose(inside["value"], img[1, 100], atol=1e-5)
        text_in, text_out = format_text(inside), format_text(outside)
        assert "(spot): N·L" in text_in and "spot falloff 1.0000" in text_in, text_in
        assert "(spot): outside its cone" in text_out, text_out


def test_info_counts_spot_lights(capsys, tmp_path):
    import yaml

    from lumos import cli

    scene = _row_scene(HARD)
    scene["lights"].append(dict(HARD, position=[1, 2, 0]))
    assert scene_info(lumos.load_scene(scene))["lights"] == {"spot": 2}
    path = tmp_path / "spots.yaml"
    path.write_text(yaml.safe_dump(scene))
    assert cli.main(["info", str(path)]) == 0
    assert "2 (spot 2)" in capsys.readouterr().out


@pytest.mark.parametrize("change,message", [
    ({"angle": 30, "inner_angle": 40}, "lights[0]: inner_angle (40) must not exceed angle (30)"),
    ({"angle": 95}, "lights[0].angle: must be at most 90, got 95"),
    ({"angle": 0}, "lights[0].angle: must be greater than 0, got 0"),
    ({"inner_angle": -5}, "lights[0].inner_angle: must be at least 0, got -5"),
    ({"direction": [0, 0, 0]}, "lights[0].direction: must not be the zero vector"),
    ({"attenuation": [0, 0, 0]}, "lights[0]: attenuation [c, l, q] must not be all zero"),
    ({"type": "spott"}, "unknown light type 'spott' (did you mean 'spot'?"),
])
def test_scene_errors_are_one_line(change, message):
    light = dict(HARD, **change)
    with pytest.raises(LumosError) as err:
        lumos.load_scene({"lights": [light]})
    text = str(err.value)
    assert message in text and "\n" not in text, text


def test_a_spot_without_direction_is_an_error_and_defaults_are_the_agreed_ones():
    with pytest.raises(LumosError, match=r"lights\[0\]: missing required key 'direction'"):
        lumos.load_scene({"lights": [{"type": "spot", "position": [0, 1, 0]}]})
    light = lumos.load_scene({"lights": [{"type": "spot", "position": [0, 1, 0], "direction": [0, -2, 0]}]}).lights[0]
    assert (light.angle, light.inner_angle, light.attenuation) == (45.0, 0.0, (1.0, 0.0, 0.0))
    arrays = compile_scene(lumos.load_scene({"lights": [dict(HARD, direction=[0, -2, 0])],
                                             "objects": [{"type": "sphere"}]})).arrays
    assert arrays.light_kind[0] == L.LIGHT_SPOT
    assert np.allclose(arrays.light_vecs[0, L.LV_DIRECTION], [0, -1, 0])
    assert arrays.light_scalars[0, L.LS_COS_OUTER] == arrays.light_scalars[0, L.LS_COS_INNER] == spot_cos(30.0)
