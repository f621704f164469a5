"""The `principled` material (glTF's metallic–roughness) in every method: `path` reads it exactly
(`kernels.principled`, tested there against the specification), its textures per hit; the local methods and
radiosity read its classic stand-in (`Principled.classic`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import lumos
from lumos.scene.materials import Material, Principled
from lumos.tonemap import srgb_decode


def scene(material, env=(1.0, 1.0, 1.0), light=True):
    """A sphere over a floor under an even sky and a point light."""
    return {"camera": {"position": [0, 1.2, 4], "look_at": [0, 0.4, 0], "fov": 35},
            "environment": {"color": list(env)},
            "lights": [{"type": "point", "position": [2, 4, 3], "intensity": 6}] if light else [],
            "materials": {"m": material, "floor": {"kd": 0.5}},
            "objects": [{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "m"},
                        {"type": "rect", "corner": [-3, 0, 3], "edge_u": [6, 0, 0], "edge_v": [0, 0, -6],
                         "material": "floor"}]}


def path(material, **kw):
    return lumos.render(scene(material), method="path", width=32, height=24, spp=16, seed=3, **kw).array


def test_a_dielectric_without_specular_is_lambert_pixel_for_pixel():
    """specular 0 makes F0 = F90 = 0: no glossy lobe, and the base weighs 1 − 0: exactly kd = b."""
    b = [0.7, 0.5, 0.3]
    got = path({"principled": {"base_color": b, "metallic": 0.0, "roughness": 0.4, "specular": 0.0}})
    np.testing.assert_array_equal(got, path({"kd": b}))


def png(path, rgb):
    Image.fromarray(np.full((4, 4, 3), rgb, np.uint8)).save(path)
    return str(path)


def maps_and_their_factors(tmp_path):
    """(a metal of roughness 0.6 whose metallic–roughness map, blue 0 and green 255, says dielectric of roughness
    0.6 (raw texels: 255 is 1, no sRGB curve), under a base colour map; the plain dielectric of the decoded
    colour)."""
    mr = png(tmp_path / "mr.png", (0, 255, 0))
    base = png(tmp_path / "base.png", (200, 120, 90))
    textured = {"principled": {"metallic": 1.0, "roughness": 0.6},
                "texture": [{"type": "image", "file": base, "apply_to": ["base_color"], "mode": "multiply"},
                            {"type": "image", "file": mr, "apply_to": ["metallic_roughness"]}]}
    decoded = srgb_decode(np.array([200, 120, 90]) / 255.0).astype(np.float32).astype(np.float64)
    return textured, {"principled": {"base_color": decoded.tolist(), "metallic": 0.0, "roughness": 0.6}}


def test_textures_multiply_the_factors_per_hit(tmp_path):
    """A metallic–roughness map of blue 0 and green 255 turns a metal of roughness 0.6 into the dielectric of
    roughness 0.6, and a base colour map multiplies the base colour by its decoded texels."""
    textured, plain = maps_and_their_factors(tmp_path)
    np.testing.assert_allclose(path(textured), path(plain), rtol=1e-5, atol=1e-6)
    assert not np.allclose(path(textured), path({"principled": {"metallic": 1.0, "roughness": 0.6}}), rtol=0.05)


def sphere_under_white_sky(principled, n=33, spp=32):
    """A unit sphere alone under an even white sky, seen from z = 5 (fov 30°): (the image, cos θ between the
    view and the normal at each pixel centre's hit, where the pixel centre's ray meets the sphere)."""
    img = lumos.render({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 30},
                        "environment": {"color": [1, 1, 1]},
                        "materials": {"m": {"principled": principled}},
                        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]},
                       method="path", width=n, height=n, spp=spp, seed=1).array
    t = np.tan(np.radians(15.0))
    x, y = np.meshgrid((np.arange(n) + 0.5) / n * 2 - 1, 1 - (np.arange(n) + 0.5) / n * 2)
    d = np.stack([x * t, y * t, -np.ones_like(x)], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.array([0.0, 0.0, 5.0])
    bo = d @ o
    disc = bo**2 - (o @ o - 1.0)
    p = o + (-bo - np.sqrt(np.maximum(disc, 0.0)))[..., None] * d
    return img, np.where(disc > 0, np.einsum("ijk,ijk->ij", -d, p), np.nan)


def test_a_metal_reflects_its_base_colour_by_schlicks_curve():
    """Each pixel of a nearly smooth metal sphere under an even white sky is the surface's directional albedo
    there, Schlick's F(cos θ) = b + (1 − b)(1 − cos θ)⁵ from F0 = b (the lobe at roughness 0.05 loses nothing
    measurable): b at the centre, whiter towards the rim."""
    b = np.array([1.0, 0.78, 0.34])
    img, cos = sphere_under_white_sky({"base_color": b.tolist(), "metallic": 1.0, "roughness": 0.05})
    inner = cos > 0.5  # (near the rim a pixel spans too wide a range of angles)
    err = np.abs(img - (b + (1.0 - b) * (1.0 - cos[..., None]) ** 5))[inner]
    assert err.mean() < 0.004 and err.max() < 0.05, (err.mean(), err.max())  # (a few noisy pixels at 32 spp)
    ring = (cos > 0.25) & (cos < 0.35)  # the rim does whiten (where Schlick's curve rises)
    assert img[ring][:, 2].mean() > b[2] + 0.1, img[ring][:, 2].mean()


def test_a_clear_coat_over_black_reflects_its_fresnel_factor():
    """A black base (no specular) under a smooth clear coat: what the sphere shows is the coat alone,
    c·Fc(cos θ) = c·(0.04 + 0.96(1 − cos θ)⁵), 0.04·c head-on."""
    c = 0.8
    img, cos = sphere_under_white_sky({"base_color": 0.0, "metallic": 0.0, "specular": 0.0, "clearcoat": c,
                                       "clearcoat_roughness": 0.05})
    inner = cos > 0.5
    err = np.abs(img - c * (0.04 + 0.96 * (1.0 - cos[..., None]) ** 5))[inner]
    assert err.mean() < 0.002 and err.max() < 0.02, (err.mean(), err.max())
    np.testing.assert_allclose(img[16, 16], 0.04 * c, atol=0.003)


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_local_methods_read_the_classic_stand_in(method):
    """The local methods read a principled material as its classic coefficients, as given where the environment
    lights the model (ka = kd: the environment's reflection is shown, not read as ambient light)."""
    principled = {"base_color": [0.8, 0.3, 0.2], "metallic": 0.3, "roughness": 0.5}
    classic = Principled(**principled).classic(environment_lit=True)
    assert classic["ka"] == classic["kd"] != Principled(**principled).classic()["ka"]
    a = lumos.render(scene({"principled": principled}), method=method, width=24, height=18).array
    b = lumos.render(scene(classic), method=method, width=24, height=18).array
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_the_local_methods_read_the_maps_per_point(tmp_path, method):
    """The local methods' classic reading follows the maps too: a metal of roughness 0.6 whose metallic–roughness
    map says dielectric, under a base colour map, shows what the plain dielectric of that colour shows (the
    classic reading of the metal alone differs: all of its reflection is specular)."""
    textured, plain = maps_and_their_factors(tmp_path)
    metal = {"principled": {"metallic": 1.0, "roughness": 0.6}}
    for env in (None, (1.0, 1.0, 1.0)):  # (without an environment ka also holds the reflection)
        images = []
        for material in (textured, plain, metal):
            sc = scene(material)
            if env is None:
                del sc["environment"]
                sc["ambient"] = 0.3
            images.append(lumos.render(sc, method=method, width=24, height=18).array)
        np.testing.assert_allclose(images[0], images[1], rtol=1e-5, atol=1e-6)
        assert not np.allclose(images[0], images[2], rtol=0.05)


def test_the_kernels_classic_reading_is_the_materials():
    """`kernels.principled_classic` (a textured point) computes what `Principled.classic` does (the factors),
    with and without an environment lighting the model, clear coat and transmission included."""
    from lumos.compile import compile_scene
    from lumos.kernels.principled_classic import principled_classic

    rng = np.random.default_rng(7)
    for trial in range(40):
        model = {"base_color": rng.random(3).tolist(), "metallic": float(rng.random()),
                 "roughness": float(rng.random()), "ior": float(1.2 + rng.random()),
                 "specular": float(rng.random()), "transmission": float(rng.random() * (trial % 2)),
                 "clearcoat": float(rng.random() * (trial % 3 == 0)), "clearcoat_roughness": float(rng.random())}
        for env in (False, True):
            sc = scene({"principled": model})
            if not env:
                del sc["environment"]
            row = compile_scene(lumos.load_scene(sc)).arrays.materials[0]
            got = principled_classic(row, tuple(model["base_color"]), model["metallic"], model["roughness"])
            want = Principled(**model).classic(environment_lit=env)
            for value, key in zip(got, ("ka", "kd", "ks", "kr", "shininess")):
                np.testing.assert_allclose(value, want[key], rtol=1e-12, atol=1e-15, err_msg=f"{key} {model}")


def test_given_classic_coefficients_win_over_the_stand_in():
    mat = Material(principled={"metallic": 1.0, "roughness": 0.2}, kd=0.5)
    assert mat.classic()["kd"] == (0.5, 0.5, 0.5) and mat.classic()["ks"] == Principled(roughness=0.2).classic()["ks"]


@pytest.mark.parametrize("bad, message", [
    ({"principled": {"metallic": 1.5}}, "metallic"),
    ({"principled": {"roughness": -0.1}}, "roughness"),
    ({"principled": {}, "conductor": {"metal": "Au"}}, "give one of"),
    ({"kd": 0.5, "texture": {"type": "checker", "apply_to": ["base_color"]}}, "needs a principled material"),
    ({"principled": {}, "texture": {"type": "checker", "apply_to": ["metallic_roughness"]}}, "is an image"),
    ({"principled": {}, "texture": {"type": "image", "file": "x.png", "apply_to": ["occlusion", "kd"]}},
     "apply it to nothing else"),
])
def test_bad_principled_materials_are_one_line_errors(bad, message):
    with pytest.raises(lumos.LumosError) as info:
        lumos.load_scene(scene(bad))
    assert message in str(info.value) and "\n" not in str(info.value)


def test_a_transmitting_sheet_passes_what_its_glossy_lobe_does_not_reflect():
    """glTF's thin-walled transmission: a white principled sheet of transmission 1, nearly smooth, before an even
    white sky reflects F and passes 1 − F of it, so it shows the sky's own radiance, 1; counted twice (the
    glossy lobe's reflection and the glass's own) it would show F more."""
    scene = {"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 30},
             "environment": {"color": [1, 1, 1]},
             "materials": {"m": {"principled": {"base_color": 1.0, "metallic": 0.0, "roughness": 0.05,
                                                "transmission": 1.0}}},
             "objects": [{"type": "rect", "corner": [-1, -1, 0], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0],
                          "material": "m"}]}
    img = lumos.render(scene, method="path", width=16, height=16, spp=64, seed=2).array
    np.testing.assert_allclose(img[4:12, 4:12].mean(axis=(0, 1)), 1.0, atol=0.01)


def test_the_local_methods_reflect_the_environment_as_path_does_within_their_approximation():
    """Under the courtyard HDR, a glTF metal (roughness 0.4) and a blue dielectric (roughness 0.5) seen by raycast
    and raster (the environment's irradiance for the diffuse part, its glossy and mirror reflection for the
    specular one) have the mean radiance path's GGX gives them to within 15% per channel (measured: 0.90-1.08).
    Without the environment's reflection the metal would be black."""
    env = {"file": str(Path(__file__).parents[2] / "examples/data/env/courtyard.exr"), "rotation": 30}
    for principled in ({"base_color": [0.9, 0.6, 0.3], "metallic": 1.0, "roughness": 0.4},
                       {"base_color": [0.2, 0.4, 0.8], "metallic": 0.0, "roughness": 0.5}):
        sc = {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 30}, "environment": env,
              "objects": [{"type": "sphere", "material": {"principled": principled}}]}
        means = {}
        for method, kw in (("path", {"spp": 64, "seed": 2}), ("raycast", {}), ("raster", {"tessellation": 96})):
            img = lumos.render(sc, method=method, width=48, height=48, aov=["object_id"], **kw)
            means[method] = img.array[img.aovs["object_id"] >= 0].mean(axis=0)
        for method in ("raycast", "raster"):
            ratio = means[method] / means["path"]
            assert np.all(np.abs(ratio - 1.0) < 0.15), (principled, method, ratio)
