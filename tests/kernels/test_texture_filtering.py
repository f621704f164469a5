"""Texture filtering in the ray methods (ray cones) and of bump and normal maps in raster.

Each test renders a floor that stretches to the horizon at one sample per pixel, with filtering on (the default)
and off (`mipmap: false`, point lookups), and measures the mean absolute error of both against 256 supersampled
point-looked-up samples per pixel (the box-filtered truth): filtering must at least halve it.

* raycast and whitted, a checkerboard floor (procedural checker and an image texture);
* whitted, the same floor seen in a mirror (the cone carried through the reflection);
* raster, a bump-mapped floor (height image, noise, normal map: the colour is plain, so only the bumps alias).
"""

import numpy as np
import pytest
from PIL import Image as PILImage

import lumos
from lumos.kernels import bump as B
from lumos.kernels import texture as T
from lumos.kernels.views import textures_of
from lumos.methods import compile_for
from lumos.api import resolve_settings

W, H = 96, 64


def checker_png(path, cells=2, size=64):
    i, j = np.meshgrid(np.arange(size), np.arange(size))
    odd = ((i * cells // size) + (j * cells // size)) % 2
    rgb = np.where(odd[..., None], [30, 60, 200], [240, 230, 200]).astype(np.uint8)
    PILImage.fromarray(rgb).save(path)
    return str(path)


def floor_texture(tmp_path, kind):
    if kind == "image":
        return {"type": "image", "file": checker_png(tmp_path / "floor.png"), "apply_to": ["ka"]}
    return {"type": "checker", "apply_to": ["ka"]}


def floor_scene(material, mirror=False):
    """A plane y = 0 seen from just above it, towards the horizon; with `mirror`, the plane is seen in a mirror
    plane below the camera (the camera looks down into it)."""
    if not mirror:
        return {"camera": {"position": [0.0, 0.6, 0.0], "look_at": [0.0, 0.45, -4.0], "fov": 50.0},
                "ambient": 1.0, "lights": [],
                "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": material}]}
    return {"camera": {"position": [0.0, 0.6, 0.0], "look_at": [0.0, 0.75, -4.0], "up": [0, 1, 0], "fov": 50.0},
            "ambient": 1.0, "lights": [], "background": [0.2, 0.2, 0.2],
            "objects": [{"type": "plane", "point": [0, 1.2, 0], "normal": [0, -1, 0],
                         "material": {"ka": 0.0, "kd": 0.0, "kr": 1.0}},
                        {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": material}]}


def errors(scene, **common):
    """(mean absolute error filtered, unfiltered) at 1 spp against 256 supersampled point samples."""
    reference = lumos.render(scene, spp=256, mipmap=False, **common).array
    point = lumos.render(scene, antialias="none", mipmap=False, **common).array
    filtered = lumos.render(scene, antialias="none", mipmap=True, **common).array
    return float(np.abs(filtered - reference).mean()), float(np.abs(point - reference).mean())


@pytest.mark.parametrize("method", ["raycast", "whitted"])
@pytest.mark.parametrize("kind", ["image", "checker"])
def test_ray_cones_halve_the_error_of_a_floor_to_the_horizon(tmp_path, method, kind):
    scene = floor_scene({"ka": 1.0, "kd": 0.0, "texture": floor_texture(tmp_path, kind)})
    filtered, point = errors(scene, method=method, width=W, height=H)
    assert point > 0.02, point  # the floor aliases without filtering
    assert filtered <= 0.5 * point, (filtered, point)


def test_whitted_carries_the_cone_through_a_mirror(tmp_path):
    scene = floor_scene({"ka": 1.0, "kd": 0.0, "texture": floor_texture(tmp_path, "checker")}, mirror=True)
    filtered, point = errors(scene, method="whitted", width=W, height=H)
    assert point > 0.02, point
    assert filtered <= 0.5 * point, (filtered, point)


def test_filtering_off_is_the_point_lookup(tmp_path):
    """mipmap: false in the ray methods is what they rendered before filtering existed: point lookups."""
    scene = floor_scene({"ka": 1.0, "kd": 0.0, "texture": floor_texture(tmp_path, "checker")})
    for method in ("raycast", "whitted"):
        off = lumos.render(scene, method=method, width=W, height=H, antialias="none", mipmap=False).array
        on = lumos.render(scene, method=method, width=W, height=H, antialias="none").array
        assert not np.array_equal(on, off)
        near = off[-8:]  # the bottom rows: the floor close by, a pixel is much smaller than a check
        assert np.abs(on[-8:] - near).mean() < 0.01


def height_png(path, size=64, seed=3):
    """A height map of fine bumps: random texels."""
    rng = np.random.default_rng(seed)
    grey = (rng.random((size, size)) * 255).astype(np.uint8)
    PILImage.fromarray(np.repeat(grey[..., None], 3, axis=2)).save(path)
    return str(path)


def normal_png(path, size=64, seed=4):
    """A normal map of random tilts (raw RGB = (n + 1)/2)."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-0.6, 0.6, (size, size, 2))
    z = np.sqrt(1.0 - (xy ** 2).sum(axis=2, keepdims=True) / 2.0)
    n = np.concatenate([xy, z], axis=2)
    n /= np.linalg.norm(n, axis=2, keepdims=True)
    PILImage.fromarray(np.round((n + 1.0) * 127.5).astype(np.uint8)).save(path)
    return str(path)


@pytest.mark.parametrize("bump", ["image", "noise", "normal"])
def test_raster_filters_bump_and_normal_maps(tmp_path, bump):
    # gentle slopes (up to ~0.3): steeper bumps darken the supersampled mean (the mean of max(N·L, 0) over tilted
    # normals is below the flat surface's), which no filtering of the normal alone reproduces
    if bump == "image":
        spec = {"type": "image", "file": height_png(tmp_path / "h.png"), "scale": 4, "strength": 0.003}
    elif bump == "noise":
        spec = {"type": "noise", "scale": 40, "strength": 0.008}
    else:
        spec = {"type": "normal", "file": normal_png(tmp_path / "n.png"), "scale": 4}
    material = {"ka": 0.1, "kd": 0.8, "ks": 0.0, "bump": spec}
    scene = floor_scene(material)
    scene["ambient"] = 0.2
    scene["lights"] = [{"type": "directional", "direction": [0.3, -1.0, -0.6], "intensity": 1.0}]
    filtered, point = errors(scene, method="raster", width=W, height=H, tessellation=16)
    assert point > 0.01, point
    assert filtered <= 0.5 * point, (filtered, point)


def test_bump_lookups_without_footprint_are_the_point_ones(tmp_path):
    """bump_normal_filtered with a zero footprint is bump_normal (the path tracer's), and a footprint of many
    texels flattens fine bumps."""
    scene = floor_scene({"ka": 0.1, "kd": 0.8, "bump": {"type": "image", "file": height_png(tmp_path / "h.png"),
                                                         "strength": 0.05}})
    loaded = lumos.load_scene(scene)
    compiled = compile_for(loaded, resolve_settings(loaded, {"method": "raycast"}))
    tex = textures_of(compiled.arrays)
    mat = compiled.arrays.materials[0]
    n, dpdu, dpdv = (0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, -1.0)
    rng = np.random.default_rng(0)
    for u, v in rng.random((20, 2)):
        point = B.bump_normal(tex, mat, u, v, (u, 0.0, -v), n, dpdu, dpdv)
        assert B.bump_normal_filtered(tex, mat, u, v, (u, 0.0, -v), n, dpdu, dpdv, 0.0, 0.0, 0.0, 0.0) == point
        wide = B.bump_normal_filtered(tex, mat, u, v, (u, 0.0, -v), n, dpdu, dpdv, 0.5, 0.0, 0.0, 0.5)
        assert wide[1] > 0.999 and wide[1] >= point[1] - 1e-12
