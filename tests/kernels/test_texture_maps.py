"""Material maps (issue 11): several textures per material, `mode: multiply`, `offset`, textured emission,
tangent-space normal maps (with a mesh's `tangents` or the uv frame) and opacity cut-outs.

Closed forms where there are any (multiply = coefficient × colour; an offset shifts the pattern by exactly
itself; a constant normal map tilts N·L to its closed form), and agreement between the methods.
"""

import math

import numpy as np
import pytest
from conftest import compile_dict
from PIL import Image as PILImage

import lumos
from lumos.kernels import layout as L
from lumos.kernels import texture as T
from lumos.kernels.texture import material_coeffs, texture_rgb
from lumos.kernels.views import textures_of

ORIGIN = (0.0, 0.0, 0.0)
RED, BLUE = [0.9, 0.2, 0.1], [0.1, 0.3, 0.8]
QUAD = {"type": "mesh", "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
        "faces": [[0, 1, 2], [0, 2, 3]], "normals": [[0, 0, 1]] * 4, "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]]}
TOP = {"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "size": 2.0}


def scene_of(material, objects=None, lights=(), camera=TOP, ambient=0.0):
    return {"camera": camera, "ambient": ambient, "lights": list(lights), "materials": {"m": material},
            "objects": [dict(o, material="m") for o in (objects or [QUAD])]}


def coeffs_at(compiled, u, v, mat_id=0):
    """(ka, kd, ks, kr, emission) of material row `mat_id` of a compiled scene at (u, v), as an array (5, 3)."""
    tex = textures_of(compiled.arrays)
    return np.array(material_coeffs(tex, compiled.arrays.materials[mat_id], float(u), float(v), ORIGIN)[:5])


def render(scene, method, size=32, **kw):
    kw.setdefault("antialias", "none")
    if method == "path":
        kw.setdefault("spp", 4)
        kw.setdefault("max_depth", 0)
    return lumos.render(scene, method=method, width=size, height=size, **kw)


# ------------------------------------------------------------------------------------------- several textures


def test_a_list_of_two_textures_on_different_targets_is_both_effects(rng):
    kd_tex = {"type": "checker", "scale": 4, "colors": [RED, BLUE], "apply_to": ["kd"]}
    ks_tex = {"type": "stripes", "scale": 3, "colors": [0.7, 0.05], "apply_to": ["ks"]}
    both = compile_dict(scene_of({"ka": 0.3, "kd": 0.5, "ks": 0.2, "texture": [kd_tex, ks_tex]}))
    one_kd = compile_dict(scene_of({"ka": 0.3, "kd": 0.5, "ks": 0.2, "texture": kd_tex}))
    one_ks = compile_dict(scene_of({"ka": 0.3, "kd": 0.5, "ks": 0.2, "texture": ks_tex}))
    row = both.arrays.materials[0]
    assert row[L.MAT_TEXTURE] == 0 and row[L.MAT_TEXTURE_COUNT] == 2
    for u, v in rng.uniform(0, 1, (50, 2)):
        got, a, b = coeffs_at(both, u, v), coeffs_at(one_kd, u, v), coeffs_at(one_ks, u, v)
        np.testing.assert_array_equal(got[1], a[1])  # kd from the checker
        np.testing.assert_array_equal(got[2], b[2])  # ks from the stripes
        np.testing.assert_array_equal(got[0], [0.3] * 3)  # ka untouched by either
        odd = (math.floor(4 * u) + math.floor(4 * v)) % 2
        np.testing.assert_allclose(got[1], BLUE if odd else RED)


def test_textures_apply_in_list_order(rng):
    """replace then multiply on the same target: kd = c1·c2; multiply then replace: kd = c2."""
    first = {"type": "checker", "scale": 2, "colors": [RED, BLUE], "apply_to": ["kd"]}
    second = {"type": "stripes", "scale": 5, "colors": [0.5, 0.25], "apply_to": ["kd"], "mode": "multiply"}
    c = compile_dict(scene_of({"kd": 0.8, "texture": [first, second]}))
    flipped = compile_dict(scene_of({"kd": 0.8, "texture": [second, dict(first)]}))
    for u, v in rng.uniform(0, 1, (40, 2)):
        c1 = np.array(BLUE if (math.floor(2 * u) + math.floor(2 * v)) % 2 else RED)
        c2 = 0.25 if math.floor(5 * u) % 2 else 0.5
        np.testing.assert_allclose(coeffs_at(c, u, v)[1], c1 * c2, rtol=1e-12)
        np.testing.assert_allclose(coeffs_at(flipped, u, v)[1], c1, rtol=1e-12)


def test_an_empty_texture_list_is_no_texture():
    c = compile_dict(scene_of({"kd": 0.5, "texture": []}))
    assert c.arrays.materials[0, L.MAT_TEXTURE] == -1 and c.arrays.materials[0, L.MAT_TEXTURE_COUNT] == 0


# ------------------------------------------------------------------------------------------- multiply, offset


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster", "path"])
def test_multiply_is_the_coefficient_times_the_replaced_colour(method):
    tex = {"type": "checker", "scale": 4, "colors": [RED, BLUE], "apply_to": ["kd"]}
    light = [{"type": "directional", "direction": [0.3, -0.2, -1.0], "intensity": 0.9}]
    replace = render(scene_of({"kd": 0.6, "texture": tex}, lights=light), method)
    multiply = render(scene_of({"kd": 0.6, "texture": dict(tex, mode="multiply")}, lights=light), method)
    assert replace.array.max() > 0.1
    np.testing.assert_allclose(multiply.array, 0.6 * replace.array, rtol=1e-5, atol=1e-6)


def test_offset_shifts_the_pattern_by_exactly_the_offset(rng, tmp_path):
    img = (rng.uniform(0, 1, (8, 16, 3)) * 255).astype(np.uint8)
    PILImage.fromarray(img).save(tmp_path / "t.png")
    for base in ({"type": "checker", "scale": [4, 3]}, {"type": "noise", "scale": [4, 2]},
                 {"type": "image", "file": str(tmp_path / "t.png"), "scale": [2, 1]}):
        offset = (0.37, -0.61)
        plain = compile_dict(scene_of({"kd": 0.5, "texture": base}))
        shifted = compile_dict(scene_of({"kd": 0.5, "texture": dict(base, offset=list(offset))}))
        su, sv = plain.arrays.tex_info[0, T.TEX_SCALE_U], plain.arrays.tex_info[0, T.TEX_SCALE_V]
        t_plain, t_shift = textures_of(plain.arrays), textures_of(shifted.arrays)
        for u, v in rng.uniform(0, 1, (40, 2)):
            # uv·scale + offset = (u + offset/scale)·scale
            want = texture_rgb(t_plain, 0, u + offset[0] / su, v + offset[1] / sv, ORIGIN)
            np.testing.assert_allclose(texture_rgb(t_shift, 0, u, v, ORIGIN), want, atol=1e-9)


def test_bump_maps_take_an_offset_too():
    c = compile_dict(scene_of({"kd": 0.5, "bump": {"type": "noise", "offset": [0.5, 0.25]}}))
    row = int(c.arrays.materials[0, L.MAT_BUMP])
    assert tuple(c.arrays.tex_info[row, T.TEX_SHIFT_U : T.TEX_SHIFT_V + 1]) == (0.5, 0.25)


# ------------------------------------------------------------------------------------------- emission


def emissive_scene(mode="multiply", emission=0.8):
    tex = {"type": "checker", "scale": 4, "colors": [RED, BLUE], "apply_to": ["emission"], "mode": mode}
    return scene_of({"emission": emission, "texture": tex})


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster", "path"])
def test_emission_texture_is_seen_by_every_method_with_the_same_mean(method):
    """The quad fills the view; 4 × 4 checker cells of 8 × 8 pixels each: the mean is the colours' mean."""
    img = render(emissive_scene(), method).array
    want = 0.8 * 0.5 * (np.array(RED) + np.array(BLUE))
    np.testing.assert_allclose(img.reshape(-1, 3).mean(axis=0), want, rtol=2e-3)
    # and it is a checker, not its mean: the pixel at the centre of the first cell is the first colour × 0.8
    np.testing.assert_allclose(img[-4, 3], 0.8 * np.array(RED), rtol=1e-4)


def test_replace_emission_needs_no_constant_emission():
    img = render(emissive_scene(mode="replace", emission=0.0), "raycast").array
    np.testing.assert_allclose(img[-4, 3], RED, rtol=1e-5)


def test_path_leaves_textured_emitters_to_bsdf_rays():
    """Light sampling reads the constant emission, so a textured emitter is not in the emitter table."""
    from lumos.api import resolve_settings
    from lumos.methods import compile_for

    for scene, textured in ((emissive_scene(), True), (scene_of({"emission": 0.8}), False)):
        s = lumos.load_scene(scene)
        compiled = compile_for(s, resolve_settings(s, {"method": "path"}))
        assert bool(np.any(compiled.emitters.tri_emit >= 0)) is not textured


# ------------------------------------------------------------------------------------------- normal maps


def normal_png(path, rgb):
    PILImage.fromarray(np.full((4, 4, 3), rgb, np.uint8)).save(path)
    return str(path)


def tilted(alpha_deg, axis="x"):
    """The bytes of a constant normal map tilted by alpha towards +x (or +y), and the unit normal they decode to
    in tangent space (the 8-bit quantisation included)."""
    a = math.radians(alpha_deg)
    m = (math.sin(a), 0.0, math.cos(a)) if axis == "x" else (0.0, math.sin(a), math.cos(a))
    rgb = [int(round((c + 1.0) * 0.5 * 255.0)) for c in m]
    dec = np.array(rgb) / 255.0 * 2.0 - 1.0
    return rgb, dec


def lit_quad(bump, obj=QUAD, L_dir=(0.5, 0.3, 0.81)):
    L_dir = np.array(L_dir) / np.linalg.norm(L_dir)
    light = {"type": "directional", "direction": list(-L_dir), "intensity": 1.0}
    return scene_of({"kd": 1.0, "bump": bump}, objects=[obj], lights=[light]), L_dir


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster", "path"])
def test_a_flat_normal_map_changes_nothing(tmp_path, method):
    flat = {"type": "normal", "file": normal_png(tmp_path / "flat.png", (128, 128, 255))}
    scene, _ = lit_quad(flat, L_dir=(0.1, 0.05, 1.0))
    plain, _ = lit_quad(None, L_dir=(0.1, 0.05, 1.0))
    del plain["materials"]["m"]["bump"]
    np.testing.assert_allclose(render(scene, method).array, render(plain, method).array, atol=1e-3)


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster", "path"])
def test_a_tilted_normal_map_tilts_n_dot_l_by_the_closed_form(tmp_path, method):
    rgb, m = tilted(30.0)
    bump = {"type": "normal", "file": normal_png(tmp_path / "n.png", rgb)}
    scene, L_dir = lit_quad(bump)
    n = m / np.linalg.norm(m)  # tangent space = world (T = +x along u, B = +y along v, N = +z)
    got = render(scene, method).array[16, 16]
    np.testing.assert_allclose(got, [n @ L_dir] * 3, rtol=1e-4)
    assert abs(n @ L_dir - L_dir[2]) > 0.1  # the tilt shows


def test_strength_scales_x_and_y(tmp_path):
    rgb, m = tilted(40.0, axis="y")
    bump = {"type": "normal", "file": normal_png(tmp_path / "n.png", rgb), "strength": 0.5}
    scene, L_dir = lit_quad(bump)
    n = m * [0.5, 0.5, 1.0]
    n /= np.linalg.norm(n)
    np.testing.assert_allclose(render(scene, "raycast").array[16, 16], [n @ L_dir] * 3, rtol=1e-4)


@pytest.mark.parametrize("w", [1.0, -1.0])
def test_mesh_tangents_set_the_frame(tmp_path, w):
    """Tangents along +y with handedness w: T = +y, B = w·(N × T) = −w·x, whatever the uvs say."""
    rgb, m = tilted(35.0)
    bump = {"type": "normal", "file": normal_png(tmp_path / "n.png", rgb)}
    quad = dict(QUAD, tangents=[[0, 1, 0, w]] * 4)
    scene, L_dir = lit_quad(bump, obj=quad)
    T_, B_ = np.array([0, 1, 0]), -w * np.array([1, 0, 0])
    n = m[0] * T_ + m[1] * B_ + m[2] * np.array([0, 0, 1])
    n /= np.linalg.norm(n)
    for method in ("raycast", "whitted", "path"):
        np.testing.assert_allclose(render(scene, method).array[16, 16], [n @ L_dir] * 3, rtol=1e-4)


def test_mesh_tangents_follow_the_transform(tmp_path):
    """Mirrored in x: the tangent +y stays +y, the handedness turns over (and the mirror image is lit the same
    as the original seen in a mirror)."""
    rgb, m = tilted(35.0, axis="y")
    bump = {"type": "normal", "file": normal_png(tmp_path / "n.png", rgb)}
    quad = dict(QUAD, tangents=[[1, 0, 0, 1]] * 4, transform={"scale": [-1, 1, 1]})
    scene, L_dir = lit_quad(bump, obj=quad)
    # T = −x (the mirrored +x), N = +z (the mirrored normal), B = w'·(N × T) with w' = −1: −(z × −x) = +y
    n = m[0] * np.array([-1, 0, 0]) + m[1] * np.array([0, 1, 0]) + m[2] * np.array([0, 0, 1])
    n /= np.linalg.norm(n)
    np.testing.assert_allclose(render(scene, "raycast").array[16, 16], [n @ L_dir] * 3, rtol=1e-4)


def test_analytic_shapes_use_their_uv_tangents(tmp_path):
    """A rect with edge_u along −y and edge_v along +x (normal +z): T = −y, B = +x."""
    rgb, m = tilted(30.0)
    bump = {"type": "normal", "file": normal_png(tmp_path / "n.png", rgb)}
    rect = {"type": "rect", "corner": [-1, 1, 0], "edge_u": [0, -2, 0], "edge_v": [2, 0, 0]}
    scene, L_dir = lit_quad(bump, obj=rect)
    n = m[0] * np.array([0, -1, 0]) + m[1] * np.array([1, 0, 0]) + m[2] * np.array([0, 0, 1])
    n /= np.linalg.norm(n)
    for method in ("raycast", "raster"):
        np.testing.assert_allclose(render(scene, method).array[16, 16], [n @ L_dir] * 3, rtol=1e-4)


def test_normal_maps_are_read_raw_not_srgb_decoded(tmp_path):
    from lumos.compile.textures import load_texels

    path = normal_png(tmp_path / "n.png", (64, 128, 200))
    np.testing.assert_allclose(load_texels(path, kind="normal")[0, 0], np.array([64, 128, 200]) / 255.0, rtol=1e-6)


@pytest.mark.parametrize("tangents, message", [
    ([[1, 0, 0]] * 4, "tangents"),
    ([[1, 0, 0, 0]] * 4, "handedness"),
    ([[1, 0, 0, 1]] * 3, "3 rows"),
    ([[1, 0, float("nan"), 1]] * 4, "not finite"),
])
def test_bad_tangents_are_one_line_errors(tangents, message):
    with pytest.raises(lumos.LumosError, match=message) as err:
        lumos.load_scene(scene_of({"kd": 1}, objects=[dict(QUAD, tangents=tangents)]))
    assert "\n" not in str(err.value)


def test_a_normal_map_needs_a_file():
    with pytest.raises(lumos.LumosError, match="needs file"):
        lumos.load_scene(scene_of({"kd": 1, "bump": {"type": "normal"}}))


# ------------------------------------------------------------------------------------------- cross-method


def test_textured_mesh_with_maps_raster_phong_equals_raycast():
    from helpers import TEXTURE_CAMERA as CAMERA
    from helpers import TEXTURE_LIGHTS as LIGHTS
    from helpers import agree, sphere_mesh

    v, f, n, uv = sphere_mesh()
    material = {"ka": 0.3, "kd": 0.7, "ks": 0.3, "shininess": 20, "emission": 0.2,
                "texture": [{"type": "checker", "scale": [8, 4], "colors": [RED, BLUE], "apply_to": ["ka", "kd"],
                             "offset": [0.3, 0.1]},
                            {"type": "stripes", "scale": 6, "colors": [1.0, 0.3], "apply_to": ["kd", "emission"],
                             "mode": "multiply"}]}
    scene = {"camera": CAMERA, "ambient": 0.2, "lights": LIGHTS, "materials": {"m": material},
             "objects": [{"type": "mesh", "vertices": v, "faces": f, "normals": n, "uvs": uv, "material": "m"}]}
    W, H = 160, 120
    ray = lumos.render(scene, method="raycast", width=W, height=H, antialias="none", mipmap=False,
                       aov=["object_id"])
    ras = lumos.render(scene, method="raster", shading="phong", width=W, height=H, antialias="none",
                       mipmap=False, aov=["object_id"])
    agree(ras, ray)


def test_radiosity_takes_the_mean_of_the_textures_in_order():
    from lumos.compile.textures import mean_coefficients

    m = lumos.load_scene(emissive_scene()).materials["m"]
    got = mean_coefficients(m)
    np.testing.assert_allclose(got["emission"], 0.8 * 0.5 * (np.array(RED) + np.array(BLUE)))
    np.testing.assert_allclose(got["kd"], 0.0)


# ------------------------------------------------------------------------------------------- opacity


def test_opacity_rows_read_alpha_or_raw_luminance(tmp_path):
    """A texture on kd and opacity is two rows (colour, then coverage); the coverage is the alpha channel, or
    the raw luminance of an image without one; the material is marked MAT_CUTOUT (holes: kernels/test_cutout.py)."""
    from lumos.kernels.texture import has_cutout, is_hole, material_alpha

    rgba = np.zeros((2, 2, 4), np.uint8)
    rgba[..., :3] = 200
    rgba[0, :, 3], rgba[1, :, 3] = 51, 204  # top row α 0.2, bottom row α 0.8
    PILImage.fromarray(rgba, "RGBA").save(tmp_path / "a.png")
    PILImage.fromarray(np.full((2, 2, 3), (255, 0, 0), np.uint8)).save(tmp_path / "l.png")
    for name, top, bottom in (("a.png", 0.2, 0.8), ("l.png", 0.2126, 0.2126)):
        tex = {"type": "image", "file": str(tmp_path / name), "apply_to": ["kd", "opacity"], "wrap": "clamp"}
        c = compile_dict(scene_of({"kd": 0.5, "texture": tex}))
        assert c.arrays.materials[0, L.MAT_TEXTURE_COUNT] == 2 and c.arrays.materials[0, L.MAT_CUTOUT] == 1.0
        assert list(c.arrays.tex_info[:, T.TEX_APPLY]) == [T.APPLY_KD, T.APPLY_OPACITY]
        t, mat = textures_of(c.arrays), c.arrays.materials[0]
        assert has_cutout(t, mat)
        np.testing.assert_allclose(material_alpha(t, mat, 0.5, 0.9, ORIGIN), top, atol=1e-6)
        np.testing.assert_allclose(material_alpha(t, mat, 0.5, 0.1, ORIGIN), bottom, atol=1e-6)
        assert is_hole(t, mat, 0.5, 0.9, ORIGIN) == (top < 0.5) and is_hole(t, mat, 0.5, 0.1, ORIGIN) == (bottom < 0.5)
        kd = [(200 / 255) ** 2.2] * 3 if name == "a.png" else [1.0, 0.0, 0.0]
        np.testing.assert_allclose(coeffs_at(c, 0.5, 0.1)[1], kd, rtol=0.05, atol=1e-6)  # kd: the colour
    plain = compile_dict(scene_of({"kd": 0.5}))
    assert not has_cutout(textures_of(plain.arrays), plain.arrays.materials[0])
    assert plain.arrays.materials[0, L.MAT_CUTOUT] == 0.0
