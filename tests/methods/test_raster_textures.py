"""Textures and bump maps in the scan-line renderer, and mip-mapping.

* raster Phong with textures against raycast on the same polygons (a textured smooth mesh; a tessellated sphere
  with an image texture): the two methods interpolate the same uvs, so they agree pixel for pixel;
* Gouraud applies the texture per pixel on top of the interpolated light; flat uses the centroid's uv;
* perspective-correct uvs against screen-space (affine) ones;
* the mip-map pyramid, the trilinear lookup and the closed-form box-filtered checker against their definitions;
* mip-mapping lowers the error of a checkerboard floor to the horizon against a supersampled reference.
"""

import math

import numpy as np
import pytest
from PIL import Image as PILImage

from helpers import TEXTURE_CAMERA, TEXTURE_LIGHTS, agree, interior_of, sphere_mesh

import lumos
from lumos.api import resolve_settings
from lumos.methods import compile_for
from lumos.compile.textures import mip_levels
from lumos.kernels import texture as T
from lumos.kernels.views import textures_of

LIGHTS, CAMERA = TEXTURE_LIGHTS, TEXTURE_CAMERA


def checker_png(path, cells=8, size=256):
    i, j = np.meshgrid(np.arange(size), np.arange(size))
    odd = ((i * cells // size) + (j * cells // size)) % 2
    rgb = np.where(odd[..., None], [30, 60, 200], [240, 230, 200]).astype(np.uint8)
    PILImage.fromarray(rgb).save(path)
    return str(path)


PROCEDURAL = {
    "ka": 0.3, "ks": 0.4, "shininess": 25.0,
    "texture": {"type": "checker", "scale": [8, 4], "colors": [[0.9, 0.8, 0.2], [0.1, 0.3, 0.7]],
                "apply_to": ["ka", "kd"]},
    "bump": {"type": "noise", "scale": [6, 3], "strength": 0.03},
}


@pytest.mark.parametrize("camera", ["perspective", "ortho"])
def test_textured_smooth_mesh_raster_phong_equals_raycast(camera):
    v, f, n, uv = sphere_mesh()
    cam = CAMERA if camera == "perspective" else {"type": "orthographic", "position": [0.3, 0.4, 3.2],
                                                  "look_at": [0, 0, 0], "size": 2.4}
    scene = {"camera": cam, "ambient": 0.2, "lights": LIGHTS,
             "objects": [{"type": "mesh", "vertices": v, "faces": f, "normals": n, "uvs": uv,
                          "material": PROCEDURAL}]}
    W, H = 160, 120
    ray = lumos.render(scene, method="raycast", width=W, height=H, antialias="none", mipmap=False,
                       aov=["object_id"])
    ras = lumos.render(scene, method="raster", shading="phong", width=W, height=H, antialias="none",
                       mipmap=False, aov=["object_id"])
    agree(ras, ray)
    # the texture shows: both colours of the checker appear (their kd differ most in blue)
    blue = ras.array[..., 2][interior_of(ras.aovs["object_id"])]
    assert blue.max() > 3 * blue.min() + 0.05


def test_tessellated_sphere_with_an_image_texture_matches_raycast_of_its_polygons(tmp_path):
    png = checker_png(tmp_path / "check.png", cells=16)
    material = {"ka": 0.2, "ks": 0.3, "shininess": 30.0, "texture": {"type": "image", "file": png}}
    analytic = {"camera": CAMERA, "ambient": 0.2, "lights": LIGHTS,
                "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "material": material}]}
    scene = lumos.load_scene(analytic)
    cfg = resolve_settings(scene, dict(method="raster", tessellation=64))
    mesh = compile_for(scene, cfg).raster
    faces, _ = mesh.triangles()
    polygons = {"camera": CAMERA, "ambient": 0.2, "lights": LIGHTS,
                "objects": [{"type": "mesh", "vertices": mesh.positions, "faces": faces, "normals": mesh.normals,
                             "uvs": mesh.uvs, "material": material}]}
    W, H = 160, 120
    ras = lumos.render(analytic, method="raster", tessellation=64, width=W, height=H, antialias="none",
                       mipmap=False, aov=["object_id"])
    ray = lumos.render(polygons, method="raycast", width=W, height=H, antialias="none", mipmap=False,
                       aov=["object_id"])
    agree(ras, ray)


def quad_scene(material, camera=None, lights=None, ambient=0.2):
    """A unit-uv square in the z = 0 plane, two triangles."""
    v = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return {"camera": camera or {"position": [0.0, 0.0, 3.0], "look_at": [0, 0, 0], "fov": 50.0},
            "ambient": ambient, "lights": lights if lights is not None else
            [{"type": "directional", "direction": [0.2, -0.3, -1.0], "intensity": 0.8}],
            "objects": [{"type": "mesh", "vertices": v, "faces": [[0, 1, 2], [0, 2, 3]], "uvs": uv,
                         "material": material}]}


def test_gouraud_applies_the_texture_per_pixel_on_the_interpolated_light():
    # a directional light and no highlight: the light is the same at every vertex, so Gouraud's interpolated
    # light times the per-pixel texture is Phong's per-pixel model exactly, checks and all
    scene = quad_scene({"ka": 0.5, "texture": {"type": "checker", "scale": 6}})
    W, H = 96, 96
    g = lumos.render(scene, method="raster", shading="gouraud", width=W, height=H, antialias="none", mipmap=False)
    p = lumos.render(scene, method="raster", shading="phong", width=W, height=H, antialias="none", mipmap=False)
    assert np.allclose(g.array, p.array, atol=1e-5)
    assert g.array.max() > 2 * g.array[g.array > 0].min()  # both checks show


def test_flat_shading_takes_each_polygons_texture_at_its_centroid():
    scene = quad_scene({"ka": 0.5, "kd": 0.0, "texture": {"type": "stripes", "scale": 2,
                                                        "colors": [[1, 1, 1], [0, 0, 0]], "apply_to": ["ka"]}},
                       lights=[])
    img = lumos.render(scene, method="raster", shading="flat", width=64, height=64, antialias="none",
                       aov=["object_id"])
    # centroids: (2/3, 1/3) → u·2 = 1.33, odd stripe (colour 1, black); (1/3, 2/3) → 0.67, even (white)
    values = np.unique(np.round(img.array[..., 0][img.aovs["object_id"] >= 0], 6))
    assert np.allclose(sorted(values), [0.0, 1.0 * 0.2]), values  # the texture replaces ka


def test_affine_uvs_swim_under_perspective_and_correct_ones_match_raycast():
    camera = {"position": [0.0, -2.2, 1.0], "look_at": [0.0, 0.3, 0.0], "fov": 60.0}
    scene = quad_scene({"ka": 1.0, "kd": 0.0, "texture": {"type": "checker", "scale": 4, "apply_to": ["ka"]}},
                       camera=camera, lights=[], ambient=1.0)
    W, H = 120, 90
    ray = lumos.render(scene, method="raycast", width=W, height=H, antialias="none", mipmap=False,
                       aov=["object_id"])
    correct = lumos.render(scene, method="raster", width=W, height=H, antialias="none", mipmap=False,
                           aov=["object_id"])
    affine = lumos.render(scene, method="raster", width=W, height=H, antialias="none", mipmap=False,
                          perspective_correct=False, aov=["object_id"])
    inner = interior_of(ray.aovs["object_id"])
    wrong_correct = np.mean(np.abs(correct.array - ray.array).max(axis=2)[inner] > 1e-3)
    wrong_affine = np.mean(np.abs(affine.array - ray.array).max(axis=2)[inner] > 1e-3)
    assert wrong_correct < 0.01
    assert wrong_affine > 0.1  # the checks bend along the diagonal the two triangles share


# ------------------------------------------------------------------------------------------ mip-mapping


def test_mip_levels_halve_to_one_texel_and_keep_the_mean():
    rng = np.random.default_rng(1)
    for shape in [(8, 8), (5, 12), (7, 3), (1, 6)]:
        texels = rng.random(shape + (3,)).astype(np.float32)
        levels = mip_levels(texels)
        h, w = shape
        for level in levels[1:]:
            h, w = max(1, h // 2), max(1, w // 2)
            assert level.shape == (h, w, 3)
            assert np.allclose(level.mean(axis=(0, 1)), texels.mean(axis=(0, 1)), atol=1e-5)
        assert levels[-1].shape == (1, 1, 3)
    texels = rng.random((4, 4, 3)).astype(np.float32)
    assert np.allclose(mip_levels(texels)[1][0, 0], texels[:2, :2].mean(axis=(0, 1)), atol=1e-6)


def lookup_table(tmp_path, texture):
    """The compiled texture arrays (mip-mapped) of one material with `texture`, and its tex_info row."""
    scene = lumos.load_scene({"camera": CAMERA, "objects": [
        {"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": {"texture": texture}}]})
    compiled = compile_for(scene, resolve_settings(scene, dict(method="raster")))
    return textures_of(compiled.arrays), 0


def test_trilinear_lookup_between_levels_and_point_lookup_for_no_footprint(tmp_path):
    png = checker_png(tmp_path / "c.png", cells=4, size=64)
    tex, row = lookup_table(tmp_path, {"type": "image", "file": png})
    assert tex.tex_info[row, T.TEX_LEVELS] == 7
    rng = np.random.default_rng(2)
    for u, v in rng.random((20, 2)):
        point = T.texture_rgb(tex, row, u, v, (0.0, 0.0, 0.0))
        assert T.texture_rgb_filtered(tex, row, u, v, (0.0, 0.0, 0.0), 0.0, 0.0, 0.0, 0.0) == point
        # magnified (footprint below a texel): the bilinear lookup itself
        assert T.texture_rgb_filtered(tex, row, u, v, (0, 0, 0), 0.5 / 64, 0.0, 0.0, 0.5 / 64) == point
    # a footprint of the whole texture: its mean, whatever the point
    mean = np.asarray(PILImage.open(png), np.float64) / 255.0
    from lumos.tonemap import srgb_decode

    mean = srgb_decode(mean).mean(axis=(0, 1))
    got = T.texture_rgb_filtered(tex, row, 0.3, 0.6, (0, 0, 0), 2.0, 0.0, 0.0, 2.0)
    assert np.allclose(got, mean, atol=1e-5)
    # a footprint of 4 texels: level 2 exactly (4 × 4 blocks of one checker cell of 16 × 16 are uniform)
    got = T.texture_rgb_filtered(tex, row, 0.1, 0.1, (0, 0, 0), 4.0 / 64, 0.0, 0.0, 4.0 / 64)
    texels = mip_levels(srgb_decode(np.asarray(PILImage.open(png), np.float64)[::-1] / 255.0))[2]
    assert np.allclose(got, texels[1, 1], atol=1e-5)


def test_box_filtered_checker_is_the_mean_over_the_footprint(tmp_path):
    tex, row = lookup_table(tmp_path, {"type": "checker", "scale": 1, "colors": [[1, 1, 1], [0, 0, 0]]})
    rng = np.random.default_rng(3)
    for _ in range(30):
        u, v = rng.uniform(-3, 3, 2)
        du, dv = rng.uniform(0.05, 2.0, 2)
        got = T.texture_rgb_filtered(tex, row, u, v, (0, 0, 0), du, 0.0, 0.0, dv)[0]
        # the box one footprint wide, [u − du/2, u + du/2] × [v − dv/2, v + dv/2], integrated numerically
        s = u + 0.5 * du * (2 * (np.arange(4000) + 0.5) / 4000 - 1)
        t = v + 0.5 * dv * (2 * (np.arange(4000) + 0.5) / 4000 - 1)
        odd_s = np.mean(np.floor(s) % 2 == 1)
        odd_t = np.mean(np.floor(t) % 2 == 1)
        white = 1.0 - (odd_s * (1 - odd_t) + odd_t * (1 - odd_s))
        assert abs(got - white) < 2e-3, (u, v, du, dv, got, white)


def floor_scene(material):
    return {"camera": {"position": [0.0, 0.6, 0.0], "look_at": [0.0, 0.45, -4.0], "fov": 50.0},
            "ambient": 1.0, "lights": [],
            "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": material}]}


@pytest.mark.parametrize("kind", ["image", "checker"])
def test_mip_mapping_lowers_the_error_of_a_floor_to_the_horizon(tmp_path, kind):
    if kind == "image":
        texture = {"type": "image", "file": checker_png(tmp_path / "floor.png", cells=2, size=64),
                   "apply_to": ["ka"]}
    else:
        texture = {"type": "checker", "apply_to": ["ka"]}
    scene = floor_scene({"ka": 1.0, "kd": 0.0, "texture": texture})
    W, H = 96, 64
    common = dict(method="raster", width=W, height=H, tessellation=16)
    reference = lumos.render(scene, spp=256, mipmap=False, **common).array  # the box-filtered truth
    point = lumos.render(scene, antialias="none", mipmap=False, **common).array
    filtered = lumos.render(scene, antialias="none", mipmap=True, **common).array
    rmse_point = math.sqrt(np.mean((point - reference) ** 2))
    rmse_filtered = math.sqrt(np.mean((filtered - reference) ** 2))
    assert rmse_filtered < 0.6 * rmse_point, (rmse_filtered, rmse_point)
