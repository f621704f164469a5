"""Method path: closed forms (the furnace, a form factor, the depth series), agreement with whitted on direct
light, determinism, and the film's guards.

Expected values are exact; the tolerances are statistical: each test compares a mean with its standard error
(from the variance AOV), so a wrong factor of a few per cent fails while noise does not.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers import DATA, EXAMPLES, ROOT

import lumos
from lumos.errors import LumosError, LumosWarning


def path(scene, **settings):
    settings.setdefault("method", "path")
    return lumos.render(scene, **settings)


def _mean_and_error(img, mask=None):
    """Mean radiance per channel over the masked pixels and its standard error (from the variance AOV)."""
    arr = img.array.reshape(-1, 3).astype(np.float64)
    var = img.aovs["variance"].reshape(-1, 3).astype(np.float64)
    if mask is not None:
        arr, var = arr[mask.ravel()], var[mask.ravel()]
    return arr.mean(axis=0), np.sqrt(var.sum(axis=0)) / len(arr)


# ------------------------------------------------------------------------------------------------ furnace

def furnace(albedo, emission, enclosure="sphere"):
    """The camera inside a closed, emitting, diffusely reflecting enclosure: every pixel sees Le/(1 − ρ)."""
    material = {"kd": albedo, "emission": emission}
    if enclosure == "sphere":  # an ellipsoid: area-sampled as an emitter, seen from inside
        shape = {"type": "sphere", "radius": 1.0, "material": material,
                 "transform": {"scale": [2.0, 1.5, 1.8], "rotate": [10, 20, 0]}}
    elif enclosure == "round sphere":  # uniform scale: sampled by the cone it subtends, which is none from inside
        shape = {"type": "sphere", "radius": 2.0, "material": material}
    else:
        shape = {"type": "box", "min": [-2, -1.5, -1.8], "max": [2, 1.6, 1.9], "material": material}
    return {"camera": {"position": [0, 0, 0.5], "look_at": [0, 0, -1], "fov": 100},
            "objects": [shape]}


@pytest.mark.parametrize("enclosure", ["sphere", "round sphere", "box"])
@pytest.mark.parametrize("albedo", [0.5, 0.8])
def test_furnace(enclosure, albedo):
    """Pbrt's and Mitsuba's classic check, with roulette on and unbounded depth: L = Le/(1 − ρ), to 1%."""
    le = 0.3
    img = path(furnace(albedo, le, enclosure), width=24, height=16, spp=64, aov=["variance"], seed=1)
    mean, err = _mean_and_error(img)
    want = le / (1.0 - albedo)
    assert np.all(np.abs(mean - want) < max(4 * err.max(), 1e-4)), (mean, err, want)
    assert np.all(np.abs(mean - want) < 0.01 * want)


@pytest.mark.parametrize("max_depth", [0, 1, 3])
def test_max_depth_counts_bounces_after_the_first_hit(max_depth):
    """Emission is gathered at vertices 0 … D+1 (light sampling at 0 … D): inside the furnace the image is the
    partial sum Le·Σ_{k=0}^{D+1} ρ^k, which is what Mitsuba renders at its max_depth D + 2."""
    rho, le = 0.6, 1.0
    img = path(furnace(rho, le, "box"), width=16, height=12, spp=64, max_depth=max_depth, aov=["variance"])
    mean, err = _mean_and_error(img)
    want = le * sum(rho**k for k in range(max_depth + 2))
    assert np.all(np.abs(mean - want) < max(4 * err.max(), 1e-6)), (mean, want)


def test_ambient_is_ignored():
    """Global illumination replaces the ambient term: ka and the scene's ambient light nothing."""
    scene = {"ambient": 1.0, "objects": [{"type": "sphere", "material": {"ka": 1.0, "kd": 0.5}}]}
    assert path(scene, width=8, height=8, spp=4).array.max() == 0.0


# ------------------------------------------------------------------------------------ analytic form factor

def test_parallel_squares_form_factor():
    """An emitting unit square 1 above a Lambertian unit square of albedo ρ: the receiver's mean radiance is
    ρ·F·Le with F = 0.19982 (parallel unit squares at distance 1). An orthographic camera looks at the receiver
    through the gap between the squares, along a slope that passes under the emitter."""
    rho, le = 0.7, 2.0
    scene = {
        "camera": {"type": "orthographic", "position": [-4.0, 2.0, 0.0], "look_at": [0.0, 0.0, 0.0],
                   "size": 1.2},
        "lights": [{"type": "area", "shape": "rect", "corner": [-0.5, 1.0, -0.5], "edge_u": [1, 0, 0],
                    "edge_v": [0, 0, 1], "radiance": le}],  # emits down: along edge_u × edge_v
        "objects": [{"type": "mesh", "vertices": [[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]],
                     "faces": [[0, 1, 2], [0, 2, 3]], "material": {"kd": rho}}],
    }
    # pixel centres, so that every pixel counted lies wholly on the receiver
    img = path(scene, width=96, height=96, spp=64, max_depth=0, antialias="none", aov=["object_id", "variance"])
    receiver = img.aovs["object_id"] == 0
    assert receiver.sum() > 1000
    mean, err = _mean_and_error(img, receiver)
    want = rho * 0.19982 * le
    assert np.all(np.abs(mean - want) < 4 * err + 1e-4 * want), (mean, err, want)
    assert np.all(np.abs(mean - want) < 0.01 * want)


# ------------------------------------------------------------------------- direct light across methods

DIRECT_SCENE = {  # lights placed so that none shadows another onto what the camera sees (in path, area lights
    # are surfaces that cast shadows; whitted's shadow rays pass through them)
    "camera": {"position": [0, 2.2, 6.5], "look_at": [0, 0.6, 0], "fov": 42},
    "materials": {"floor": {"kd": [0.7, 0.7, 0.7]}, "red": {"kd": [0.7, 0.25, 0.2]}, "blue": {"kd": [0.2, 0.3, 0.75]}},
    "lights": [
        {"type": "point", "position": [2.0, 3.5, 2.0], "intensity": [6.0, 5.5, 5.0], "attenuation": [0, 0, 1]},
        {"type": "directional", "direction": [1.0, -0.25, 0.1], "intensity": 0.5},
        {"type": "area", "shape": "rect", "corner": [1.2, 4.0, -1.0], "edge_u": [1.0, 0, 0], "edge_v": [0, 0, 1.2],
         "radiance": 8.0, "samples": 16},
        {"type": "area", "shape": "sphere", "center": [-1.8, 3.2, -1.0], "radius": 0.35, "radiance": 12.0,
         "samples": 16},
    ],
    "objects": [
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": "floor"},
        {"type": "sphere", "center": [-0.6, 0.8, 0.2], "radius": 0.8, "material": "red"},
        {"type": "box", "min": [0.5, 0.0, -0.6], "max": [1.6, 1.1, 0.5], "material": "blue",
         "transform": {"rotate": [0, 25, 0]}},
    ],
}


def _block_means(a, k=8):
    h, w = a.shape[0] // k * k, a.shape[1] // k * k
    return a[:h, :w].reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))


@pytest.mark.slow
def test_direct_light_agrees_with_whitted():
    """max_depth 0 on a diffuse scene with point, directional, rect and sphere lights: path's direct light is
    whitted's (DESIGN.md §3 units), a z-test on every 8×8 block and every channel."""
    w, h = 64, 48
    p = path(DIRECT_SCENE, width=w, height=h, spp=256, max_depth=0, aov=["variance"], seed=3)
    runs = [lumos.render(DIRECT_SCENE, method="whitted", width=w, height=h, spp=64, max_depth=0, seed=s).array
            for s in (1, 2)]
    wt = 0.5 * (runs[0] + runs[1])
    var_w = 0.25 * (runs[0] - runs[1]) ** 2  # the variance of the mean of the two whitted renders, per pixel
    var_p = p.aovs["variance"]
    k = 8
    diff = _block_means(p.array - wt, k)
    se = np.sqrt(_block_means(var_p + var_w, k) / (k * k))
    z = np.abs(diff) / np.maximum(se, 1e-6)
    assert z.max() < 5.0, (z.max(), np.unravel_index(z.argmax(), z.shape))
    lit = wt.max(axis=2) < 2.0  # the surfaces, not the lights seen directly (a few bright edge pixels)
    rel = np.abs(p.array[lit].mean(axis=0) - wt[lit].mean(axis=0)) / wt[lit].mean(axis=0)
    assert rel.max() < 0.01


# ------------------------------------------------------------------------------------- determinism

SMALL_BOX = {  # a closed box, the camera inside
    "camera": {"position": [0, 0, 0.9], "look_at": [0, 0, 0], "fov": 75},
    "lights": [{"type": "area", "shape": "rect", "corner": [-0.3, 0.99, -0.3], "edge_u": [0.6, 0, 0],
                "edge_v": [0, 0, 0.6], "radiance": 8.0}],
    "objects": [
        {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "material": {"kd": 0.7}},
        {"type": "sphere", "center": [-0.4, -0.6, 0.0], "radius": 0.4, "material": {"kd": 0.3, "ks": 0.5,
                                                                                     "shininess": 40}},
        {"type": "sphere", "center": [0.45, -0.6, 0.3], "radius": 0.35, "material": {"kt": 1.0, "ior": 1.5}},
        {"type": "sphere", "center": [0.3, 0.3, -0.5], "radius": 0.3, "material": {"kr": 0.9}},
    ],
}


def test_same_image_for_any_thread_count_and_pass_split(monkeypatch):
    import numba

    from lumos.methods import path as path_method

    settings = dict(width=20, height=14, spp=12, aov=["variance", "albedo", "normal", "depth"], seed=7)
    one = path(SMALL_BOX, threads=1, **settings)
    if numba.config.NUMBA_NUM_THREADS > 1:
        two = path(SMALL_BOX, threads=2, **settings)
        np.testing.assert_array_equal(one.array, two.array)
    monkeypatch.setattr(path_method, "PASS_SECONDS", 1e-9)  # one sample per pass
    split = path(SMALL_BOX, **settings)
    assert split.stats["passes"] == 12
    np.testing.assert_array_equal(one.array, split.array)
    for name in settings["aov"]:
        np.testing.assert_array_equal(one.aovs[name], split.aovs[name])
    other_seed = path(SMALL_BOX, **{**settings, "seed": 8})
    assert not np.array_equal(one.array, other_seed.array)


def test_blocks_of_samples_are_added_in_block_order_whatever_the_passes(monkeypatch):
    """Samples are summed in blocks (SAMPLE_BLOCK) from zero, the blocks added in order: passes that cut through
    blocks, or one sample each, give the same bits; the blocks change only the rounding of the sums."""
    from lumos.methods import path as path_method

    settings = dict(width=12, height=8, spp=11, seed=3, aov=["variance", "albedo", "depth"])
    plain = path(SMALL_BOX, **settings)  # one block of 1024
    monkeypatch.setattr(path_method, "SAMPLE_BLOCK", 4)
    blocks = path(SMALL_BOX, **settings)
    monkeypatch.setattr(path_method, "PASS_SECONDS", 1e-9)
    split = path(SMALL_BOX, **settings)
    assert split.stats["passes"] == 11
    for name in settings["aov"]:
        np.testing.assert_array_equal(blocks.aovs[name], split.aovs[name])
    np.testing.assert_array_equal(blocks.array, split.array)
    np.testing.assert_allclose(blocks.array, plain.array, rtol=1e-6, atol=1e-7)


def test_image_is_the_same_whatever_aovs_are_asked_for():
    """The kernel stores squares, guides and the direct light only for the AOVs that read them: the image and the
    AOVs asked for are those of a render that keeps everything."""
    settings = dict(width=20, height=14, spp=6, seed=5)
    plain = path(SMALL_BOX, **settings)
    every = path(SMALL_BOX, aov=["variance", "albedo", "normal", "direct", "indirect"], **settings)
    np.testing.assert_array_equal(plain.array, every.array)
    assert every.aovs["variance"].max() > 0.0 and every.aovs["direct"].max() > 0.0
    assert np.abs(every.aovs["albedo"]).max() > 0.0 and np.abs(every.aovs["normal"]).max() > 0.0
    for name in ("variance", "direct"):
        alone = path(SMALL_BOX, aov=[name], **settings)
        np.testing.assert_array_equal(alone.aovs[name], every.aovs[name])


def test_variance_aov_is_the_variance_of_the_mean():
    """Across renders with other seeds, the pixels' spread matches the variance AOV on average with independent
    samples, and stays below it with the stratified Sobol points (the AOV is then an upper bound)."""
    settings = dict(width=12, height=10, spp=16, aov=["variance"])
    for sampler, low, high in (("independent", 0.6, 1.6), ("sobol", 0.05, 1.0)):
        imgs = [path(SMALL_BOX, seed=s, sampler=sampler, **settings) for s in range(12)]
        stack = np.stack([im.array for im in imgs])
        spread = stack.var(axis=0, ddof=1).mean()
        predicted = np.mean([im.aovs["variance"] for im in imgs])
        assert low < spread / predicted < high, (sampler, spread / predicted)


def test_sobol_points_lower_the_error_without_bias():
    """The same box with both samplers: the same mean (both unbiased), and a smaller error per pixel with the
    Sobol points, against a converged render."""
    settings = dict(width=16, height=12, max_depth=2)
    ref = path(SMALL_BOX, spp=4096, **settings).array
    errors = {}
    for sampler in ("independent", "sobol"):
        runs = np.stack([path(SMALL_BOX, spp=16, seed=s, sampler=sampler, **settings).array for s in range(8)])
        errors[sampler] = np.sqrt(np.mean((runs - ref) ** 2))
        means = runs.mean(axis=(1, 2, 3))
        bias = means.mean() - ref.mean()
        assert abs(bias) < 4 * means.std(ddof=1) / np.sqrt(len(means)) + 1e-3 * ref.mean(), (sampler, bias)
    assert errors["sobol"] < 0.8 * errors["independent"], errors


# ---------------------------------------------------------------------------------------- guards

def test_nan_prone_scenes_leave_the_film_finite():
    """A light of vanishing area, a surface seen edge-on, glass of ior 1, a needle-sharp lobe, a mirror inside
    glass: the film stays finite, and dropped samples are counted."""
    scene = {
        "camera": {"position": [0, 0.0, 4], "look_at": [0, 0, 0], "fov": 60},
        "lights": [{"type": "area", "shape": "rect", "corner": [0, 1.5, 0], "edge_u": [1e-8, 0, 0],
                    "edge_v": [0, 0, 1e-8], "radiance": 1e6},
                   {"type": "point", "position": [0, 0, 0], "intensity": 1.0}],
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"kd": 0.5}},  # edge-on
            {"type": "sphere", "center": [-1, 0.5, 0], "radius": 0.5, "material": {"kt": 1.0, "ior": 1.0}},
            {"type": "sphere", "center": [1, 0.5, 0], "radius": 0.5, "material": {"ks": 1.0, "shininess": 1e6}},
            {"type": "sphere", "center": [0, 0.5, -1], "radius": 0.5, "material": {"kt": 0.5, "kr": 0.5,
                                                                                    "ior": 1.5}},
            {"type": "disk", "center": [0, 1.0, 1], "normal": [0, 0, 1], "radius": 0.3,
             "material": {"emission": 1e-300}},
        ],
    }
    img = path(scene, width=24, height=24, spp=8, aov=["variance", "albedo", "normal"])
    assert np.all(np.isfinite(img.array))
    for name in ("variance", "albedo", "normal"):
        assert np.all(np.isfinite(img.aovs[name]))
    assert img.stats["discarded_samples"] >= 0


def test_material_that_creates_energy_is_scaled_with_a_warning():
    scene = {"materials": {"hot": {"kd": 0.8, "ks": 0.5}},
             "objects": [{"type": "sphere", "material": "hot"}]}
    with pytest.warns(LumosWarning, match="material 'hot'.*1.3.*create energy"):
        path(scene, width=4, height=4, spp=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        path({"objects": [{"type": "sphere", "material": {"kd": 0.5, "ks": 0.5}}]}, width=4, height=4, spp=1)


def test_path_only_settings_are_refused_elsewhere():
    scene = {"objects": [{"type": "sphere"}]}
    for key, value in (("time_limit", 1.0), ("denoise", True), ("sampling", "light")):
        with pytest.raises(LumosError, match=f"render.{key}: .*path feature"):
            lumos.render(scene, method="whitted", **{key: value})
    with pytest.raises(LumosError, match="variance.*path"):
        lumos.render(scene, method="raycast", aov=["variance"])
    with pytest.raises(LumosError, match="adaptive.*whitted"):
        path(scene, antialias="adaptive")


def test_time_limit_stops_after_the_pass_that_crosses_it():
    img = path(SMALL_BOX, width=64, height=48, spp=1 << 20, time_limit=0.5)
    assert img.stats["stopped"] == "time limit"
    assert 1 <= img.stats["spp"] < 1 << 20
    assert img.stats["render_s"] < 5.0
    assert np.all(np.isfinite(img.array)) and img.array.mean() > 0


def test_gaussian_filter_keeps_the_mean():
    """Filter importance sampling: every sample weighs 1, so a flat field stays flat and the furnace holds."""
    img = path(furnace(0.5, 0.3, "box"), width=16, height=12, spp=32, filter="gaussian", aov=["variance"])
    mean, err = _mean_and_error(img)
    assert np.all(np.abs(mean - 0.6) < 4 * err.max() + 1e-6)


# --------------------------------------------------------------------------- one- and two-sided emitters

def _panel_scene(emitter: str, two_sided: bool, material=None) -> dict:
    """A floor and a ceiling, and between them a 1×1 emitting panel facing down (cross(edge_u, edge_v) = −y):
    an emissive rect object or a rect area light of the same radiance."""
    panel = {"corner": [-0.5, 1.0, -0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1], "two_sided": two_sided}
    scene = {"camera": {"position": [0, 0.4, 3], "look_at": [0, 0.5, 0], "fov": 50},
             "render": {"width": 48, "height": 36, "method": "path", "spp": 64, "max_depth": 3},
             "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"kd": 0.5}},
                         {"type": "plane", "point": [0, 2, 0], "normal": [0, -1, 0], "material": {"kd": 0.5}}],
             "lights": []}
    if emitter == "object":
        scene["objects"].append({"type": "rect", **panel, "material": {"kd": 0, "emission": [4, 4, 4]}})
    else:
        scene["lights"].append({"type": "area", "shape": "rect", **panel, "radiance": [4, 4, 4],
                                **({} if material is None else {"material": material})})
    return scene


@pytest.mark.parametrize("two_sided", [False, True])
def test_an_emissive_object_lights_as_the_area_light_it_stands_for(two_sided):
    """The same panel as an emissive rect object and as a rect area light, one-sided and two-sided: the same image
    within noise (block z-test), so emission found by BSDF rays, light sampling of emissive primitives and their
    MIS all honour the side. One-sided, the ceiling above the panel gets only what the floor reflects back."""
    a = lumos.render(_panel_scene("object", two_sided), aov=["variance"], seed=1)
    b = lumos.render(_panel_scene("light", two_sided), aov=["variance"], seed=2)
    pa, pb = _blocks(a.array.astype(np.float64), 4), _blocks(b.array.astype(np.float64), 4)
    va = _blocks(a.aovs["variance"].astype(np.float64), 4) / 16
    vb = _blocks(b.aovs["variance"].astype(np.float64), 4) / 16
    z = (pa - pb) / np.sqrt(va + vb + 1e-12)
    assert np.abs(z).max() < 5.0, np.abs(z).max()
    assert abs(z.mean()) < 0.2, z.mean()
    ceiling = a.array[:4].mean()
    other = lumos.render(_panel_scene("object", not two_sided), seed=1).array[:4].mean()
    assert (ceiling > 3 * other) if two_sided else (other > 3 * ceiling), (ceiling, other)


def test_an_area_light_with_a_material_reflects():
    """A rect light given a white material adds the light it reflects (the floor's, sent back down): the floor is
    brighter than under the same light without one, and the light seen from below is brighter than its radiance."""
    bare = lumos.render(_panel_scene("light", False), spp=128, seed=3, aov=["variance"])
    white = lumos.render(_panel_scene("light", False, {"kd": 0.8}), spp=128, seed=3, aov=["variance"])
    floor = np.zeros(bare.array.shape[:2], bool)
    floor[-6:] = True
    (m0, e0), (m1, e1) = _mean_and_error(bare, floor), _mean_and_error(white, floor)
    assert np.all(m1 - m0 > 5 * np.hypot(e0, e1)), (m0, m1, e0, e1)
    lamp = bare.array.max(axis=2) >= 3.99  # pixels wholly on the panel
    assert lamp.any() and np.all(white.array[lamp] > 4.0)
    np.testing.assert_allclose(bare.array[lamp], 4.0, rtol=1e-6)


# ------------------------------------------------------------------------------------------- Mitsuba 3

MITSUBA_REF = DATA / "cornell_mitsuba"
CORNELL = EXAMPLES / "path" / "cornell.yaml"


def _blocks(a, k=8):
    h, w = a.shape[:2]
    return a.reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))


@pytest.mark.slow
@pytest.mark.parametrize("ref, max_depth", [("ref_depth8_256.npy", 6), ("ref_depthinf_256.npy", -1)])
def test_cornell_box_matches_mitsuba(ref, max_depth):
    """examples/path/cornell.yaml against Mitsuba 3's own converged render of `mi.cornell_box()` (16,384 spp,
    stored in tests/data/cornell_mitsuba; see its README): a z-test on every 8×8 block and channel, and the
    block mean relative error (the issue's bar is 1% at 1024 spp; here 128 spp, so 1.5%)."""
    reference = np.load(MITSUBA_REF / ref).astype(np.float64)
    img = lumos.render(CORNELL, spp=128, max_depth=max_depth, aov=["variance"], seed=5)
    ours = _blocks(img.array.astype(np.float64))
    theirs = _blocks(reference)
    se = np.sqrt(_blocks(img.aovs["variance"].astype(np.float64)) / 64 + (0.0015 / 8) ** 2)
    z = (ours - theirs) / se
    assert np.abs(z).max() < 5.5, np.abs(z).max()
    assert abs(z.mean()) < 0.15, z.mean()  # no bias across the image
    lit = theirs > 1e-3
    assert np.mean(np.abs(ours - theirs)[lit] / theirs[lit]) < 0.015


@pytest.mark.slow
def test_a_lamp_that_reflects_matches_mitsubas_own_cornell_box():
    """Mitsuba's `mi.cornell_box()` as it is, its lamp with the white BSDF (tests/data/cornell_mitsuba,
    ref_lamp_depthinf_256.npy, 8,192 spp): the area light given `material: white` reflects as Mitsuba's does, to
    within noise on every 8×8 block; the black lamp of cornell.yaml is measurably darker than that reference (the
    1% the test would miss without reflecting lamps)."""
    reference = np.load(MITSUBA_REF / "ref_lamp_depthinf_256.npy").astype(np.float64)
    scene = lumos.load_scene(CORNELL)
    lamp = scene.lights[0].model_copy(update={"material": "white"})
    scene = scene.model_copy(update={"lights": [lamp]})
    img = lumos.render(scene, spp=128, max_depth=-1, aov=["variance"], seed=5)
    ours = _blocks(img.array.astype(np.float64))
    theirs = _blocks(reference)
    se = np.sqrt(_blocks(img.aovs["variance"].astype(np.float64)) / 64 + (0.0021 / 8) ** 2)
    z = (ours - theirs) / se
    assert np.abs(z).max() < 5.5, np.abs(z).max()
    assert abs(z.mean()) < 0.15, z.mean()
    black = _blocks(np.load(MITSUBA_REF / "ref_depthinf_256.npy").astype(np.float64))
    lit = theirs > 1e-3
    assert np.mean(ours[lit]) > 1.004 * np.mean(black[lit])  # brighter than the black lamp's box, by its reflection


@pytest.mark.slow
def test_cornell_box_agrees_with_a_live_mitsuba():
    """Where Mitsuba 3 is installed: both renderers on the same box at 64×64, same means within noise."""
    mi = pytest.importorskip("mitsuba")
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from peers_path import mitsuba_scene_dict  # noqa: E402

    mi.set_variant("scalar_rgb")
    their = np.asarray(mi.render(mi.load_dict(mitsuba_scene_dict(spp=64, max_depth=8, width=64, height=64)),
                                 seed=3), np.float64)
    ours = lumos.render(CORNELL, width=64, height=64, spp=256, aov=["variance"])
    diff = ours.array.mean(axis=(0, 1)) - their.mean(axis=(0, 1))
    se = np.sqrt(ours.aovs["variance"].mean(axis=(0, 1)) / (64 * 64) + their.var(axis=(0, 1)) / (64 * 64) / 4)
    assert np.all(np.abs(diff) < 5 * se + 1e-4), (diff, se)


def _sphere_scenes(material, bsdf, spp_lumos, spp_mitsuba, size=64, depth=6):
    """A sphere of lumos `material` / Mitsuba `bsdf` on a grey floor under a square lamp: (lumos scene dict, Mitsuba
    scene dict), the same scene."""
    import mitsuba as mi

    T = mi.ScalarTransform4f
    theirs = {
        "type": "scene", "integrator": {"type": "path", "max_depth": depth},
        "sensor": {"type": "perspective", "fov": 40, "fov_axis": "y",
                   "to_world": T().look_at(origin=[0, 1, 4], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp_mitsuba}},
        "ball": {"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "bsdf": bsdf},
        "floor": {"type": "rectangle", "to_world": T().translate([0, -1, 0]).rotate([1, 0, 0], -90).scale(10),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}}},
        "lamp": {"type": "rectangle", "to_world": T().translate([0, 3, 0]).rotate([1, 0, 0], 90).scale(0.5),
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}},
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 10.0}}}}
    ours = {"camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
            "render": {"width": size, "height": size, "method": "path", "spp": spp_lumos, "max_depth": depth - 2},
            "lights": [{"type": "area", "shape": "rect", "corner": [-0.5, 3, -0.5], "edge_u": [1, 0, 0],
                        "edge_v": [0, 0, 1], "radiance": 10}],
            "objects": [{"type": "sphere", "radius": 1, "material": material},
                        {"type": "rect", "corner": [-10, -1, -10], "edge_u": [20, 0, 0], "edge_v": [0, 0, 20],
                         "material": {"kd": 0.5}}]}
    return ours, theirs


def _agrees_with_mitsuba(material, bsdf, rtol):
    """The sphere scene rendered by lumos (1,024 spp) and by Mitsuba (four renders of 256 spp): every 8×8 block
    within noise (z-test on lumos's variance AOV and the spread of Mitsuba's renders), the means within rtol."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    ours_scene, theirs_scene = _sphere_scenes(material, bsdf, 1024, 256)
    scene = mi.load_dict(theirs_scene)
    runs = [_blocks(np.asarray(mi.render(scene, seed=s), np.float64)) for s in range(4)]
    theirs = np.mean(runs, axis=0)
    var_t = np.var(runs, axis=0, ddof=1) / len(runs)
    img = lumos.render(ours_scene, aov=["variance"], seed=3)
    ours = _blocks(img.array.astype(np.float64))
    z = (ours - theirs) / np.sqrt(_blocks(img.aovs["variance"].astype(np.float64)) / 64 + var_t + 1e-12)
    assert np.abs(z).max() < 5.0, np.abs(z).max()
    assert abs(z.mean()) < 0.4, z.mean()
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), theirs.mean(axis=(0, 1)), rtol=rtol)


def test_anisotropic_roughness_follows_the_surfaces_u_direction():
    """A brushed metal plate (αu 0.05 along its edge_u, αv 0.4) seen from above its lamp: the highlight is narrow
    along u and long along v; turning the plate's uv a quarter (edge_u and edge_v swapped) turns the highlight with
    it, the same highlight to the noise (its spreads swap)."""
    def spreads(edge_u, edge_v):
        scene = {"camera": {"position": [0, 4, 0.01], "look_at": [0, 0, 0], "fov": 50, "up": [0, 0, -1]},
                 "lights": [{"type": "point", "position": [0, 3, 0], "intensity": 10}],
                 "objects": [{"type": "rect", "corner": [-2, 0, 2], "edge_u": edge_u, "edge_v": edge_v,
                              "material": {"conductor": {"alpha": [0.05, 0.4]}}}]}
        img = path(scene, width=64, height=64, spp=32, seed=1).array.mean(axis=2)
        w = img / img.sum()
        y, x = np.mgrid[0:64, 0:64]
        mx, my = (w * x).sum(), (w * y).sum()
        return np.sqrt((w * (x - mx) ** 2).sum()), np.sqrt((w * (y - my) ** 2).sum())

    sx, sy = spreads([4, 0, 0], [0, 0, -4])  # u along x (the image's x), v along −z (the image's y)
    assert sy > 3 * sx, (sx, sy)
    np.testing.assert_allclose(spreads([0, 0, -4], [4, 0, 0]), (sy, sx), rtol=0.05)


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.0, 0.05, 0.3, 0.7])
def test_metals_match_mitsuba(alpha):
    """Where Mitsuba 3 is installed: a gold sphere (`conductor`: GGX, Mitsuba's RGB η + ik of gold) at four widths
    agrees with Mitsuba's `conductor` / `roughconductor` (ggx) (means measured within 0.01–0.5%)."""
    from lumos.scene.materials import METALS

    eta, k = METALS["Au"]
    bsdf = {"type": "conductor"} if alpha == 0 else {"type": "roughconductor", "distribution": "ggx", "alpha": alpha}
    bsdf.update(eta={"type": "rgb", "value": list(eta)}, k={"type": "rgb", "value": list(k)})
    _agrees_with_mitsuba({"conductor": {"metal": "Au", "alpha": alpha}}, bsdf, rtol=0.006)


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.0, 0.05, 0.3, 0.7])
def test_plastics_match_mitsuba(alpha):
    """Where Mitsuba 3 is installed: an orange plastic sphere (`plastic`, η 1.5) at four widths agrees with
    Mitsuba's `plastic` / `roughplastic` (ggx) (means measured within 0.01–0.15%)."""
    kd = [0.6, 0.2, 0.1]
    bsdf = {"type": "plastic"} if alpha == 0 else {"type": "roughplastic", "distribution": "ggx", "alpha": alpha}
    bsdf.update(int_ior=1.5, ext_ior=1.0, diffuse_reflectance={"type": "rgb", "value": kd})
    _agrees_with_mitsuba({"kd": kd, "plastic": {"alpha": alpha, "ior": 1.5}}, bsdf, rtol=0.004)


@pytest.mark.slow
def test_denoising_brings_a_16_spp_render_closer_to_the_converged_one():
    """Where pyoidn is installed: OIDN (with the albedo and normal guides) on the 16-spp Cornell box lowers its
    error against Mitsuba's converged render, keeps the raw image as the `noisy` AOV, and invents no light."""
    pytest.importorskip("pyoidn")
    reference = np.load(MITSUBA_REF / "ref_depth8_256.npy").astype(np.float64)
    img = lumos.render(CORNELL, spp=16, denoise=True, aov=["noisy", "albedo", "normal"], seed=2)
    raw = img.aovs["noisy"].astype(np.float64)
    denoised = img.array.astype(np.float64)
    rmse = lambda a: float(np.sqrt(np.mean((a - reference) ** 2)))  # noqa: E731
    assert rmse(denoised) < 0.8 * rmse(raw), (rmse(denoised), rmse(raw))
    # the surfaces: without the light seen directly and the ring of pixels it partly covers (the light is kept out
    # of the denoiser, so those keep their coverage noise)
    light = reference.max(axis=2) > 2.0
    ring = light.copy()
    ring[1:] |= light[:-1]
    ring[:-1] |= light[1:]
    ring[:, 1:] |= light[:, :-1]
    ring[:, :-1] |= light[:, 1:]
    surfaces = ~ring
    rmse_s = lambda a: float(np.sqrt(np.mean((a - reference)[surfaces] ** 2)))  # noqa: E731
    assert rmse_s(denoised) < 0.5 * rmse_s(raw), (rmse_s(denoised), rmse_s(raw))
    assert denoised.min() >= 0.0 and denoised.max() <= 2.0 * raw.max()
    plain = lumos.render(CORNELL, spp=16, seed=2)
    np.testing.assert_array_equal(plain.array, img.aovs["noisy"])  # the noisy AOV is the image undenoised


@pytest.mark.slow
def test_thin_lens_and_motion_blur_agree_with_whitted():
    """Depth of field and motion blur are the camera's and the shutter's, the same in path as in whitted: with a
    thin lens and a moving sphere under a point light, path's direct light equals whitted's (block z-test)."""
    scene = {
        "camera": {"position": [0, 1.0, 5], "look_at": [0, 0.5, 0], "fov": 40, "aperture": 0.15,
                   "focus_distance": 5.0, "shutter": [0.0, 1.0]},
        "lights": [{"type": "point", "position": [2, 4, 3], "intensity": 2.0, "attenuation": [0, 0, 0.05]}],
        "objects": [
            {"type": "plane", "material": {"kd": 0.6}},
            {"type": "sphere", "center": [-0.8, 0.5, 0], "radius": 0.5, "motion": [1.2, 0, 0],
             "material": {"kd": [0.7, 0.3, 0.2]}},
            {"type": "box", "min": [0.6, 0, -1.5], "max": [1.4, 0.8, -0.7], "material": {"kd": [0.2, 0.4, 0.7]}},
        ],
    }
    w, h = 48, 32
    p = path(scene, width=w, height=h, spp=256, max_depth=0, aov=["variance"])
    runs = [lumos.render(scene, method="whitted", width=w, height=h, spp=128, max_depth=0, seed=s).array
            for s in (1, 2)]
    wt = 0.5 * (runs[0] + runs[1])
    var = p.aovs["variance"] + 0.25 * (runs[0] - runs[1]) ** 2
    z = np.abs(_block_means(p.array - wt)) / np.maximum(np.sqrt(_block_means(var) / 64), 1e-6)
    assert z.max() < 5.0, z.max()


def test_direct_and_indirect_aovs_split_the_image_where_max_depth_zero_does():
    # direct is what max_depth 0 gathers, sample for sample (the first vertices draw the same random numbers);
    # indirect is the rest, and the two add up to the raw image
    scene = "examples/path/cornell.yaml"
    full = lumos.render(scene, method="path", width=48, height=48, spp=8, aov=["direct", "indirect"])
    zero = lumos.render(scene, method="path", width=48, height=48, spp=8, max_depth=0, aov=["direct", "indirect"])
    assert np.allclose(full.aovs["direct"] + full.aovs["indirect"], full.array, atol=1e-5)
    assert np.allclose(full.aovs["direct"], zero.array, atol=1e-5)
    assert np.allclose(zero.aovs["indirect"], 0.0, atol=1e-6)
    assert full.aovs["indirect"].mean() > 0.2 * full.aovs["direct"].mean()  # colour bleeding and fill light


def _glass_scene(glass):
    """A glass sphere of lumos material `glass` over a checkerboard under a square lamp and a grey sky."""
    return {"camera": {"position": [0, 1.2, 4], "look_at": [0, 0.6, 0], "fov": 35},
            "render": {"method": "path", "width": 32, "height": 32, "max_depth": 6}, "background": 0.3,
            "lights": [{"type": "area", "shape": "rect", "corner": [-0.5, 3, -0.5], "edge_u": [1, 0, 0],
                        "edge_v": [0, 0, 1], "radiance": 10}],
            "objects": [{"type": "sphere", "center": [0, 0.7, 0], "radius": 0.7, "material": glass},
                        {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0],
                         "material": {"kd": 0.8, "texture": {"type": "checker", "scale": 6}}}]}


def test_nearly_smooth_rough_glass_renders_as_smooth_glass():
    """A `dielectric` of α 10⁻³ (the microfacet lobes, light sampling and MIS, the media and roulette's η²) and
    one of α 0 (the delta lobe) and classic kt/ior glass give the same image within noise, per 8×8 block."""
    imgs = [lumos.render(_glass_scene(m), spp=128, aov=["variance"], seed=4)
            for m in ({"dielectric": {"ior": 1.5, "alpha": 0.001}}, {"dielectric": {"ior": 1.5}},
                      {"kt": 1, "ior": 1.5})]
    means = [_blocks(i.array.astype(np.float64)) for i in imgs]
    var = [_blocks(i.aovs["variance"].astype(np.float64)) / 64 for i in imgs]
    for k in (1, 2):
        z = (means[0] - means[k]) / np.sqrt(var[0] + var[k] + 1e-10)
        assert np.abs(z).max() < 5.0 and abs(z.mean()) < 0.5, (k, np.abs(z).max(), z.mean())
