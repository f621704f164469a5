"""Textures, UV derivatives and bump mapping (`kernels.texture`, `compile.textures`) against NumPy twins written
from the definitions in `kernels/texture.py`'s docstring, closed forms and finite differences.
"""

import math
from itertools import combinations

import numba
import numpy as np
import pytest
from conftest import compile_dict, surfaces
from PIL import Image

import lumos
from lumos.tonemap import srgb_decode
from lumos.kernels import layout as L
from lumos.kernels import texture as T
from lumos.kernels.csg import CSG_PART_STRIDE
from lumos.kernels.tangents import surface_tangents
from lumos.kernels.bump import bump_normal
from lumos.kernels.texture import material_coeffs, noise01, texture_rgb
from lumos.kernels.views import surfaces_of

ORIGIN = (0.0, 0.0, 0.0)


# ------------------------------------------------------------------------------------------------ helpers


def tex_row(kind, scale=(1.0, 1.0), wrap=T.WRAP_REPEAT, c0=(0.0, 0.0, 0.0), c1=(1.0, 1.0, 1.0), offset=0, size=(0, 0),
            apply=0, strength=0.0):
    row = np.zeros(T.TEX_SIZE)
    row[T.TEX_KIND] = kind
    row[T.TEX_SCALE_U], row[T.TEX_SCALE_V] = scale
    row[T.TEX_WRAP] = wrap
    row[T.TEX_COLOR0 : T.TEX_COLOR0 + 3] = c0
    row[T.TEX_COLOR1 : T.TEX_COLOR1 + 3] = c1
    row[T.TEX_OFFSET] = offset
    row[T.TEX_WIDTH], row[T.TEX_HEIGHT] = size
    row[T.TEX_APPLY] = apply
    row[T.TEX_STRENGTH] = strength
    return row


def textures(rows, image=None):
    """A `layout.Textures` view over tex_info `rows` and one image (H, W, 3), top row first, stored bottom first."""
    pixels = np.zeros((0, 3), np.float32) if image is None else image[::-1].reshape(-1, 3)
    return L.Textures(np.ascontiguousarray(np.array(rows, dtype=np.float64).reshape(-1, T.TEX_SIZE)),
                      np.ascontiguousarray(pixels, dtype=np.float32), np.zeros((0, 12), np.float32))


def lookup(tex, row, u, v):
    return np.array(texture_rgb(tex, np.int64(row), float(u), float(v), ORIGIN))


@numba.njit(cache=True)
def _lookups(tex, row, us, vs, out):
    for k in range(len(us)):
        out[k] = texture_rgb(tex, row, us[k], vs[k], (0.0, 0.0, 0.0))


def lookups(tex, row, us, vs):
    out = np.empty((len(us), 3))
    _lookups(tex, np.int64(row), np.ascontiguousarray(us, dtype=np.float64), np.ascontiguousarray(vs, dtype=np.float64),
             out)
    return out


def material(ka=(0.1, 0.2, 0.3), kd=(0.4, 0.5, 0.6), ks=(0.7, 0.8, 0.9), kr=(0.15, 0.25, 0.35), texture=-1, bump=-1):
    row = np.zeros(L.MAT_SIZE)
    row[L.MAT_KA : L.MAT_KA + 3] = ka
    row[L.MAT_KD : L.MAT_KD + 3] = kd
    row[L.MAT_KS : L.MAT_KS + 3] = ks
    row[L.MAT_KR : L.MAT_KR + 3] = kr
    row[L.MAT_TEXTURE] = texture
    row[L.MAT_TEXTURE_COUNT] = 0 if texture < 0 else 1
    row[L.MAT_BUMP] = bump
    return row


def bumped(tex, mat, n, dpdu, dpdv, u=0.5, v=0.5):
    f = lambda x: tuple(float(c) for c in x)  # noqa: E731
    return np.array(bump_normal(tex, mat, float(u), float(v), ORIGIN, f(n), f(dpdu), f(dpdv)))


# ------------------------------------------------------------------------------------------------ NumPy twins


def twin_image(img, s, t, clamp, scale):
    """Bilinear filtering as a tent-weighted sum over texel centres: texel (i, j) of the W×H image (j = 0 the
    BOTTOM row) sits at texel coordinates (i + ½, j + ½) and repeats with period (W, H); under clamp the lookup
    point is held between the centres of the first and last texels of the strip of `scale` copies."""
    h, w = img.shape[:2]
    x, y = s * w, t * h
    if clamp:
        x = min(max(x, 0.5), max(scale[0] * w - 0.5, 0.5))
        y = min(max(y, 0.5), max(scale[1] * h - 0.5, 0.5))
    total = np.zeros(3)
    for i in range(math.floor(x) - 2, math.floor(x) + 3):
        for j in range(math.floor(y) - 2, math.floor(y) + 3):
            weight = max(0.0, 1 - abs(x - (i + 0.5))) * max(0.0, 1 - abs(y - (j + 0.5)))
            total += weight * img[h - 1 - (j % h), i % w]
    return total


def twin_noise(s, t, period_s, period_t):
    """Perlin gradient noise from its definition: unit gradients at angle 45°·hash(lattice point), quintic fade."""

    def gradient(ix, iy):
        h = (ix * 374761393 + iy * 668265263) & 0xFFFFFFFF
        h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
        angle = ((h ^ (h >> 16)) & 7) * math.pi / 4
        return math.cos(angle), math.sin(angle)

    x0, y0 = math.floor(s), math.floor(t)
    fade = lambda a: 6 * a**5 - 15 * a**4 + 10 * a**3  # noqa: E731
    total = 0.0
    for cx in (0, 1):
        for cy in (0, 1):
            gx, gy = gradient((x0 + cx) % period_s, (y0 + cy) % period_t)
            dx, dy = s - (x0 + cx), t - (y0 + cy)
            wx = fade(s - x0) if cx else 1 - fade(s - x0)
            wy = fade(t - y0) if cy else 1 - fade(t - y0)
            total += wx * wy * (gx * dx + gy * dy)
    return 0.5 + total / math.sqrt(2.0)


def canonical_point(kind, part, u, v):
    """The point of a canonical shape (`layout.SHAPE_*`) with surface coordinates (u, v), from the uv maps of
    `surface._canonical_normal_uv` inverted by hand."""
    phi = 2 * math.pi * (u - 0.5)
    if kind == L.SHAPE_SPHERE:
        theta = math.pi * (v - 0.5)
        return np.array([math.cos(theta) * math.sin(phi), math.sin(theta), math.cos(theta) * math.cos(phi)])
    if kind == L.SHAPE_BOX:
        axis, level = part // 2, float(part % 2)
        return np.array([[level, v, u], [u, level, v], [u, v, level]][axis])
    if kind in (L.SHAPE_CYLINDER, L.SHAPE_CONE):
        if part in (1, 2):
            return np.array([2 * u - 1, 2 * v - 1, float(part - 1)])
        rho = 1.0 if kind == L.SHAPE_CYLINDER else 1.0 - v
        return np.array([rho * math.cos(phi), rho * math.sin(phi), v])
    if kind == L.SHAPE_DISK:
        return np.array([2 * u - 1, 2 * v - 1, 0.0])
    return np.array([u, v, 0.0])  # plane, rect


# ------------------------------------------------------------------------------------------------ lookups


@pytest.mark.parametrize("wrap", [T.WRAP_REPEAT, T.WRAP_CLAMP])
@pytest.mark.parametrize("scale", [(1.0, 1.0), (2.0, 3.0), (0.7, 1.6)])
def test_image_bilinear_matches_twin(rng, wrap, scale):
    img = rng.random((4, 5, 3)).astype(np.float32)
    tex = textures([tex_row(T.TEXTURE_IMAGE, scale=scale, wrap=wrap, size=(5, 4))], img)
    us, vs = rng.uniform(-1.5, 2.5, 300), rng.uniform(-1.5, 2.5, 300)
    got = lookups(tex, 0, us, vs)
    for k, (u, v) in enumerate(zip(us, vs)):
        if wrap == T.WRAP_CLAMP:
            u, v = min(max(u, 0.0), 1.0), min(max(v, 0.0), 1.0)
        want = twin_image(img.astype(np.float64), scale[0] * u, scale[1] * v, wrap == T.WRAP_CLAMP, scale)
        np.testing.assert_allclose(got[k], want, atol=1e-6)


def test_image_texel_centres_and_orientation(rng):
    """At a texel's centre the lookup is that texel; v = 0 is the bottom row of the picture, u = 0 its left."""
    img = rng.random((3, 4, 3)).astype(np.float32)
    tex = textures([tex_row(T.TEXTURE_IMAGE, size=(4, 3))], img)
    for i in range(4):
        for j in range(3):
            np.testing.assert_allclose(lookup(tex, 0, (i + 0.5) / 4, (j + 0.5) / 3), img[2 - j, i], atol=1e-7)
    np.testing.assert_allclose(lookup(tex, 0, 0.125, 2.5 / 3), img[0, 0], atol=1e-7)  # top-left texel


def test_repeat_tiles_and_clamp_extends_the_edge(rng):
    img = rng.random((4, 6, 3)).astype(np.float32)
    rows = [tex_row(T.TEXTURE_IMAGE, size=(6, 4)), tex_row(T.TEXTURE_IMAGE, wrap=T.WRAP_CLAMP, size=(6, 4))]
    tex = textures(rows, img)
    for u, v in rng.uniform(0, 1, (20, 2)):
        np.testing.assert_allclose(lookup(tex, 0, u + 3, v - 2), lookup(tex, 0, u, v), atol=1e-6)
    v_centre = 2.5 / 4  # texel row j = 2 from the bottom, image row 1
    np.testing.assert_allclose(lookup(tex, 1, 1.7, v_centre), img[1, 5], atol=1e-7)
    np.testing.assert_allclose(lookup(tex, 1, -0.4, v_centre), img[1, 0], atol=1e-7)
    # repeat blends the two edge columns across the seam; clamp does not
    np.testing.assert_allclose(lookup(tex, 0, 0.0, v_centre), 0.5 * (img[1, 0] + img[1, 5]), atol=1e-6)
    np.testing.assert_allclose(lookup(tex, 1, 0.0, v_centre), img[1, 0], atol=1e-7)


@pytest.mark.parametrize("wrap", [T.WRAP_REPEAT, T.WRAP_CLAMP])
def test_checker_and_stripes_cells(rng, wrap):
    c0, c1 = np.array([0.9, 0.2, 0.1]), np.array([0.05, 0.3, 0.8])
    scale = (4.0, 3.0)
    tex = textures([tex_row(T.TEXTURE_CHECKER, scale, wrap, c0, c1), tex_row(T.TEXTURE_STRIPES, scale, wrap, c0, c1)])
    us, vs = rng.uniform(-2, 3, 400), rng.uniform(-2, 3, 400)
    checker, stripes = lookups(tex, 0, us, vs), lookups(tex, 1, us, vs)
    if wrap == T.WRAP_CLAMP:
        us, vs = np.clip(us, 0, 1 - 1e-9), np.clip(vs, 0, 1 - 1e-9)
    odd = (np.floor(scale[0] * us) + np.floor(scale[1] * vs)) % 2 == 1
    np.testing.assert_array_equal(checker, np.where(odd[:, None], c1, c0))
    odd = np.floor(scale[0] * us) % 2 == 1
    np.testing.assert_array_equal(stripes, np.where(odd[:, None], c1, c0))


def test_noise_matches_twin_in_unit_interval_and_deterministic(rng):
    s, t = rng.uniform(-20, 20, 3000), rng.uniform(-20, 20, 3000)
    for k in range(200):
        assert noise01(s[k], t[k], np.int64(5), np.int64(3)) == pytest.approx(twin_noise(s[k], t[k], 5, 3), abs=1e-12)
    c0, c1 = np.array([0.2, 0.4, 0.1]), np.array([0.8, 0.5, 0.9])
    tex = textures([tex_row(T.TEXTURE_NOISE, (8.0, 8.0), c0=c0, c1=c1)])
    a = lookups(tex, 0, s, t)
    x = (a[:, 0] - c0[0]) / (c1[0] - c0[0])
    assert x.min() >= 0.0 and x.max() <= 1.0
    assert x.std() > 0.08  # not a constant
    np.testing.assert_allclose(a, c0 + x[:, None] * (c1 - c0), atol=1e-12)  # one blend factor for all channels
    np.testing.assert_array_equal(lookups(tex, 0, s, t), a)  # deterministic


def test_noise_is_smooth_and_seamless(rng):
    tex = textures([tex_row(T.TEXTURE_NOISE, (5.0, 3.0))])
    u, v = rng.uniform(0, 1, 2000), rng.uniform(0, 1, 2000)
    eps = 1e-6
    du = (lookups(tex, 0, u + eps, v)[:, 0] - lookups(tex, 0, u - eps, v)[:, 0]) / (2 * eps)
    assert np.abs(du).max() < 5.0 * 5  # |∇perlin| ≤ ~2 per lattice cell, times the scale, over √2
    # continuous across lattice lines (s = 2, t = 1) and across the seam u = 0 / 1 with an integer scale
    w = rng.uniform(0, 1, 50)
    for a, b in [((0.4 - 1e-9, w), (0.4 + 1e-9, w)), ((w, 1 / 3 - 1e-9), (w, 1 / 3 + 1e-9)), ((1 - 1e-9, w), (0.0, w))]:
        np.testing.assert_allclose(lookups(tex, 0, *np.broadcast_arrays(*a)), lookups(tex, 0, *np.broadcast_arrays(*b)),
                                   atol=1e-7)


# ------------------------------------------------------------------------------------------------ compile


def write_png(path, values):
    Image.fromarray(np.asarray(values, np.uint8), mode="RGB" if np.ndim(values) == 3 else "L").save(path)
    return str(path)


def textured_scene(materials, objects=None):
    objects = objects or [{"type": "sphere", "material": name} for name in materials]
    return {"materials": materials, "objects": objects, "lights": [{"type": "point", "position": [0, 3, 3]}]}


def test_loaded_texels_are_linear_and_bottom_row_first(tmp_path, rng):
    values = rng.integers(0, 256, (3, 5, 3))
    values[0, 0] = (128, 10, 255)
    path = write_png(tmp_path / "c.png", values)
    compiled = compile_dict(textured_scene({
        "colour": {"texture": {"type": "image", "file": path}},
        "height": {"bump": {"type": "image", "file": path, "strength": 0.2}},
    }))
    info, pixels = compiled.arrays.tex_info, compiled.arrays.tex_pixels
    # each image is followed by its mip-map levels: 5 × 3, 2 × 1, 1 × 1 texels
    assert info.shape == (2, T.TEX_SIZE) and pixels.dtype == np.float32 and pixels.shape == (2 * 18, 3)
    colour = pixels[: 15].reshape(3, 5, 3)[::-1]
    np.testing.assert_allclose(colour, srgb_decode(values / 255.0), rtol=1e-6)
    # the sRGB curve itself (IEC 61966-2-1) at the three hand-picked channels
    np.testing.assert_allclose(colour[0, 0], [0.21586050, 10 / 255 / 12.92, 1.0], rtol=1e-6)
    # a bump map keeps the raw values: its height is their Rec. 709 luminance
    height = pixels[18:33].reshape(3, 5, 3)[::-1]
    np.testing.assert_allclose(height[..., 1], values @ [0.2126, 0.7152, 0.0722] / 255.0, rtol=1e-6)
    assert info[1, T.TEX_OFFSET] == 18 and info[1, T.TEX_STRENGTH] == 0.2 and info[1, T.TEX_LEVELS] == 3


def test_image_appears_upright_on_a_sphere(tmp_path):
    """Seen from +z (y up), a latitude–longitude map shows its top-left quadrant at the sphere's upper left."""
    quadrants = np.zeros((16, 16, 3), np.uint8)
    quadrants[:8, :8] = (255, 0, 0)  # top left: red
    quadrants[:8, 8:] = (0, 255, 0)  # top right: green
    quadrants[8:, :8] = (0, 0, 255)  # bottom left: blue
    quadrants[8:, 8:] = 255  # bottom right: white
    path = write_png(tmp_path / "q.png", quadrants)
    arrays = compile_dict(textured_scene({"m": {"texture": {"type": "image", "file": path, "apply_to": ["kd"]}}}))
    arrays = arrays.arrays
    from lumos.kernels.views import textures_of

    tex = textures_of(arrays)
    expected = {(-1, 1): (1, 0, 0), (1, 1): (0, 1, 0), (-1, -1): (0, 0, 1), (1, -1): (1, 1, 1)}
    for (sx, sy), colour in expected.items():
        hit = surfaces(arrays, [[0.3 * sx, 0.3 * sy, 5.0]], [[0.0, 0.0, -1.0]])[0]
        kd = material_coeffs(tex, arrays.materials[hit["material"]], hit["u"], hit["v"], tuple(hit["p"]))[1]
        np.testing.assert_allclose(kd, colour, atol=1e-6)


def test_a_second_compile_reuses_the_decoded_image_until_the_file_changes(tmp_path, rng, monkeypatch):
    """Decoded texels are kept for the process (a sheet or an animation compiles the same scene again), keyed by
    the file's modification time and size: the same bytes are decoded once, a rewritten file again; the colours
    come from an exact table of the 256 sRGB codes."""
    import os

    from lumos.compile import textures as compile_textures

    codes = rng.integers(0, 256, (4, 6, 3))
    path = write_png(tmp_path / "cached.png", codes)
    decodes = []
    original = compile_textures._decode
    monkeypatch.setattr(compile_textures, "_decode", lambda *a: decodes.append(a) or original(*a))
    scene = textured_scene({"a": {"kd": 0.5, "texture": {"type": "image", "file": path}}})
    first = compile_dict(scene).arrays.tex_pixels
    np.testing.assert_array_equal(compile_dict(scene).arrays.tex_pixels, first)
    assert len(decodes) == 1
    np.testing.assert_array_equal(compile_textures.load_texels(path), srgb_decode(codes / 255.0).astype(np.float32))
    write_png(tmp_path / "cached.png", 255 - codes)
    os.utime(path, ns=(1, 1))  # (a new mtime even on a coarse clock)
    assert not np.array_equal(compile_dict(scene).arrays.tex_pixels, first) and len(decodes) == 2


def test_shared_image_file_is_loaded_once(tmp_path, rng, monkeypatch):
    from lumos.compile import textures as compile_textures

    path = write_png(tmp_path / "shared.png", rng.integers(0, 256, (4, 6, 3)))
    (tmp_path / "sub").mkdir()  # the second material spells the same file another way
    calls = []
    original = compile_textures.load_texels
    monkeypatch.setattr(compile_textures, "load_texels", lambda *a, **k: calls.append(a) or original(*a, **k))
    compiled = compile_dict(textured_scene({
        "a": {"kd": 0.5, "texture": {"type": "image", "file": path}},
        "b": {"ks": 0.5, "texture": {"type": "image", "file": f"{tmp_path}/sub/../shared.png", "scale": 2}},
        "plain": {"kd": 0.3},
    }))
    arrays = compiled.arrays
    assert len(calls) == 1
    assert arrays.tex_pixels.shape == (24 + 6 + 1, 3)  # 6 × 4 texels and their mip-map levels, 3 × 2 and 1 × 1
    assert len(arrays.tex_info) == 2 and np.all(arrays.tex_info[:, T.TEX_OFFSET] == 0)
    assert sorted(arrays.materials[:3, L.MAT_TEXTURE]) == [-1.0, 0.0, 1.0]
    assert np.all(arrays.materials[:, L.MAT_BUMP] == -1.0)


def test_compiled_rows_of_procedural_textures_and_bumps():
    compiled = compile_dict(textured_scene({
        "m": {"kd": 0.5, "texture": {"type": "checker", "colors": [[1, 0, 0], 0.25], "scale": [3, 2],
                                     "wrap": "clamp", "apply_to": ["ks", "kr"]},
              "bump": {"type": "noise", "scale": 4, "strength": -0.3}},
    }))
    materials, info = compiled.arrays.materials, compiled.arrays.tex_info
    tex, bump = int(materials[0, L.MAT_TEXTURE]), int(materials[0, L.MAT_BUMP])
    assert {tex, bump} == {0, 1}
    np.testing.assert_array_equal(info[tex, :14], [T.TEXTURE_CHECKER, 3, 2, T.WRAP_CLAMP, 1, 0, 0, 0.25, 0.25, 0.25,
                                                   0, 0, 0, T.APPLY_KS | T.APPLY_KR])
    assert info[bump, T.TEX_KIND] == T.TEXTURE_NOISE and info[bump, T.TEX_STRENGTH] == -0.3
    assert tuple(info[bump, T.TEX_SCALE_U : T.TEX_SCALE_V + 1]) == (4, 4)


def test_missing_image_is_a_one_line_error_naming_the_key(tmp_path):
    scene = textured_scene({"m": {"texture": {"type": "image", "file": str(tmp_path / "nope.png")}}})
    with pytest.raises(lumos.LumosError) as err:
        lumos.load_scene(scene)
    message = str(err.value)
    assert "materials.m.texture.file" in message and "nope.png" in message and "\n" not in message


def test_unreadable_image_is_a_lumos_error(tmp_path):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png at all")
    with pytest.raises(lumos.LumosError, match="cannot read image"):
        compile_dict(textured_scene({"m": {"texture": {"type": "image", "file": str(bad)}}}))


def test_example_textures_load():
    from helpers import EXAMPLES

    from lumos.compile.textures import load_texels

    folder = EXAMPLES / "data" / "textures"
    planet, bumps = load_texels(folder / "planet.png"), load_texels(folder / "bumps.png", bump=True)
    assert planet.shape == (128, 256, 3) and bumps.shape == (128, 128, 3)
    assert 0.0 <= planet.min() and planet.max() <= 1.0 and 0.2 < bumps.mean() < 0.8


# ------------------------------------------------------------------------------------------------ materials


def test_material_coeffs_replace_exactly_the_apply_to_set():
    colour = np.array([0.11, 0.22, 0.33])
    names = ("ka", "kd", "ks", "kr")
    bits = dict(zip(names, (T.APPLY_KA, T.APPLY_KD, T.APPLY_KS, T.APPLY_KR)))
    mat = material()
    own = dict(zip(names, (mat[L.MAT_KA : L.MAT_KA + 3], mat[L.MAT_KD : L.MAT_KD + 3], mat[L.MAT_KS : L.MAT_KS + 3],
                           mat[L.MAT_KR : L.MAT_KR + 3])))
    subsets = [set(c) for k in range(1, 5) for c in combinations(names, k)]
    rows = [tex_row(T.TEXTURE_CHECKER, c0=colour, c1=colour, apply=sum(bits[n] for n in s)) for s in subsets]
    tex = textures(rows)
    for k, subset in enumerate(subsets):
        got = material_coeffs(tex, material(texture=k), 0.3, 0.6, ORIGIN)
        for name, value in zip(names, got):
            np.testing.assert_array_equal(value, colour if name in subset else own[name])
    untextured = material_coeffs(tex, mat, 0.3, 0.6, ORIGIN)
    for name, value in zip(names, untextured):
        np.testing.assert_array_equal(value, own[name])


# ------------------------------------------------------------------------------------------------ bump mapping


def ramp_textures(strength, along="u", width=256):
    """A height ramp: texel column i (or row j from the bottom) has height i/255, so between the texel centres
    h(u) = (256·u − ½)/255 and h_u = 256/255 exactly."""
    ramp = (np.arange(width) / 255.0).astype(np.float32)
    img = np.repeat(np.tile(ramp, (4, 1))[..., None], 3, axis=2)
    size = (width, 4)
    if along == "v":
        img = np.ascontiguousarray(img.transpose(1, 0, 2)[::-1])
        size = (4, width)
    return textures([tex_row(T.TEXTURE_IMAGE, c1=(1, 1, 1), size=size, strength=strength)], img)


@pytest.mark.parametrize("flip_v", [False, True])
def test_bump_ramp_tilts_normal_by_closed_form_angle(rng, flip_v):
    """p(u, v) = (a·u, ±b·v, 0) displaced by s·h(u)·n is the plane z = s·h_u·x/a: its normal leans away from +x
    by atan(s·h_u/a), whichever way v runs. The same in any rotated frame."""
    a, b, s = 2.0, 3.0, 0.05
    h_u = 256 / 255
    tex = ramp_textures(s)
    mat = material(bump=0)
    dpdv = (0.0, -b if flip_v else b, 0.0)
    n1 = bumped(tex, mat, (0, 0, 1), (a, 0, 0), dpdv, u=0.4, v=0.5)
    angle = math.atan(s * h_u / a)
    np.testing.assert_allclose(n1, [-math.sin(angle), 0.0, math.cos(angle)], atol=1e-12)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # any rotation (or reflection) carries the result along
    q *= np.sign(np.linalg.det(q))
    n2 = bumped(tex, mat, q @ [0, 0, 1], q @ [a, 0, 0], q @ dpdv, u=0.4, v=0.5)
    np.testing.assert_allclose(n2, q @ n1, atol=1e-12)


def test_bump_ramp_along_v_and_zero_strength():
    a, b, s = 1.5, 0.5, 0.02
    tex = ramp_textures(s, along="v")
    n1 = bumped(tex, material(bump=0), (0, 0, 1), (a, 0, 0), (0, b, 0), u=0.5, v=0.6)
    slope = s * (256 / 255) / b
    np.testing.assert_allclose(n1, np.array([0.0, -slope, 1.0]) / math.hypot(1, slope), atol=1e-12)
    n = (0.0, 0.6, 0.8)
    np.testing.assert_array_equal(bumped(ramp_textures(0.0), material(bump=0), n, (1, 0, 0), (0, 0.8, -0.6)), n)
    np.testing.assert_array_equal(bumped(tex, material(), n, (1, 0, 0), (0, 0.8, -0.6)), n)  # no bump map


def test_noise_bump_is_normal_to_the_displaced_surface():
    """On the plane p = (u, v, 0) displaced by s·h(u, v) along z, the bumped normal is perpendicular to the
    displaced surface's finite-difference tangents."""
    s = 0.1
    tex = textures([tex_row(T.TEXTURE_NOISE, (3.0, 3.0), c1=(1, 1, 1), strength=s)])
    mat = material(bump=0)
    tilted = 0
    for u, v in [(0.13, 0.71), (0.52, 0.28), (0.9, 0.45)]:
        n = bumped(tex, mat, (0, 0, 1), (1, 0, 0), (0, 1, 0), u, v)
        eps = 1e-5
        height = lambda uu, vv: lookup(tex, 0, uu, vv)[0]  # noqa: E731
        tu = np.array([2 * eps, 0, s * (height(u + eps, v) - height(u - eps, v))])
        tv = np.array([0, 2 * eps, s * (height(u, v + eps) - height(u, v - eps))])
        assert abs(n @ tu) / np.linalg.norm(tu) < 1e-4 and abs(n @ tv) / np.linalg.norm(tv) < 1e-4
        tilted += n[2] < 1 - 1e-4
    assert tilted >= 2


# ------------------------------------------------------------------------------------------------ tangents

TRANSFORM = {"rotate": [25, -40, 15], "scale": [1.0, 1.8, 0.6], "translate": [0.3, -0.2, 0.1]}
SHAPES = [
    {"type": "sphere", "center": [0.1, 0.2, -0.3], "radius": 0.9},
    {"type": "box", "min": [-0.5, -0.4, -0.6], "max": [0.7, 0.5, 0.4]},
    {"type": "cylinder", "base": [0, -0.6, 0], "top": [0.2, 0.7, 0.1], "radius": 0.5, "capped": True},
    {"type": "cone", "base": [0, -0.6, 0], "top": [0.1, 0.8, 0.2], "radius": 0.6, "capped": True},
    {"type": "disk", "center": [0, 0, 0], "normal": [0.3, 0.4, 1.0], "radius": 1.0},
    {"type": "plane", "point": [0.1, 0.0, 0.2], "normal": [0.2, 1.0, 0.3]},
    {"type": "csg", "op": "difference",
     "left": {"type": "sphere", "center": [0, 0, 0], "radius": 0.8},
     "right": {"type": "box", "min": [-0.3, -0.3, -0.3], "max": [0.3, 0.3, 1.0], "transform": {"rotate": [0, 0, 30]}}},
]


def shape_hits(obj, rng, n=150):
    # a textured material, so that surface_at computes uv (it skips it for materials that read none)
    compiled = compile_dict({"materials": {"checks": {"texture": {"type": "checker"}}},
                             "objects": [dict(obj, transform=TRANSFORM, material="checks")]})
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    target = np.asarray(TRANSFORM["translate"]) + rng.normal(scale=0.2, size=(n, 3))
    hits = [h for h in surfaces(compiled.arrays, target + 6 * dirs, -dirs) if h is not None]
    return compiled.arrays, hits


def tangents(arrays, hit):
    surf = surfaces_of(arrays)
    p = tuple(float(x) for x in hit["p"])
    n = tuple(float(x) for x in hit["n_sh"])
    dpdu, dpdv = surface_tangents(surf, np.int64(hit["ref"]), np.int64(hit["part"]), p, n, 0.0)
    return np.array(dpdu), np.array(dpdv)


@pytest.mark.parametrize("obj", SHAPES, ids=[s["type"] for s in SHAPES])
def test_shape_tangents_match_finite_differences(obj, rng):
    arrays, hits = shape_hits(obj, rng)
    assert len(hits) >= 20
    parts, leaves = set(), set()
    for hit in hits:
        s, part = ~hit["ref"], hit["part"]
        if arrays.shape_info[s, L.INFO_KIND] == L.SHAPE_CSG:  # the leaf solid hit (record: see kernels.csg)
            s, part = divmod(part, CSG_PART_STRIDE)
            leaves.add(int(arrays.shape_info[s, L.INFO_KIND]))
        object_from_world = np.eye(4)
        object_from_world[:3] = arrays.shape_xform[s, :3]
        world_from_object = np.linalg.inv(object_from_world)
        kind = int(arrays.shape_info[s, L.INFO_KIND])
        if kind == L.SHAPE_SPHERE and abs(hit["v"] - 0.5) > 0.45:
            continue  # near a pole ∂p/∂u vanishes

        def position(u, v, kind=kind, part=part, m=world_from_object):
            return (m @ np.append(canonical_point(kind, part, u, v), 1.0))[:3]

        u, v = float(hit["u"]), float(hit["v"])
        np.testing.assert_allclose(position(u, v), hit["p"], atol=1e-9)  # the twin agrees with surface_at's uv
        eps = 1e-6
        fd_u = (position(u + eps, v) - position(u - eps, v)) / (2 * eps)
        fd_v = (position(u, v + eps) - position(u, v - eps)) / (2 * eps)
        dpdu, dpdv = tangents(arrays, hit)
        np.testing.assert_allclose(dpdu, fd_u, rtol=1e-6, atol=1e-7 * np.linalg.norm(fd_u))
        np.testing.assert_allclose(dpdv, fd_v, rtol=1e-6, atol=1e-7 * np.linalg.norm(fd_v))
        assert abs(np.cross(dpdu, dpdv) @ hit["n_sh"]) > 0.999 * np.linalg.norm(np.cross(dpdu, dpdv))
        parts.add(part)
    if obj["type"] == "box":
        assert len(parts) >= 5
    if obj["type"] in ("cylinder", "cone"):
        assert parts == ({0, 1, 2} if obj["type"] == "cylinder" else {0, 1})  # side and caps (a cone has one)
    if obj["type"] == "csg":
        assert leaves == {L.SHAPE_SPHERE, L.SHAPE_BOX}  # hits on both solids


@pytest.mark.parametrize("with_uvs", [True, False])
def test_triangle_tangents_match_finite_differences(rng, with_uvs):
    vertices = [[-1.0, -0.8, 0.1], [1.2, -0.5, -0.3], [0.1, 1.1, 0.4]]
    mesh = {"type": "mesh", "vertices": vertices, "faces": [[0, 1, 2]]}
    if with_uvs:
        mesh["uvs"] = [[0.2, 0.1], [0.9, 0.3], [0.4, 1.7]]
    compiled = compile_dict({"objects": [dict(mesh, transform=TRANSFORM)]})
    arrays = compiled.arrays
    points = np.asarray(TRANSFORM["translate"]) + rng.normal(scale=0.2, size=(20, 3))
    hits = [h for h in surfaces(arrays, points + (0.2, 0.3, 5.0), np.tile([-0.04, -0.06, -1.0], (20, 1)))
            if h is not None]
    assert len(hits) >= 5
    for hit in hits:
        tri = arrays.tri_verts[hit["ref"]].reshape(3, 3).astype(np.float64)
        uv = arrays.tri_uvs[hit["ref"]].reshape(3, 2).astype(np.float64) if with_uvs else np.eye(3)[:, 1:]

        def position(u, v):
            """The point whose interpolated uv is (u, v): solve for its barycentrics, then interpolate."""
            b = np.linalg.solve(np.vstack([uv.T, np.ones(3)]), [u, v, 1.0])
            return b @ tri

        u, v = float(hit["u"]), float(hit["v"])
        np.testing.assert_allclose(position(u, v), hit["p"], atol=1e-5)
        eps = 1e-4
        fd_u = (position(u + eps, v) - position(u - eps, v)) / (2 * eps)
        fd_v = (position(u, v + eps) - position(u, v - eps)) / (2 * eps)
        dpdu, dpdv = tangents(arrays, hit)
        np.testing.assert_allclose(dpdu, fd_u, rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(dpdv, fd_v, rtol=1e-6, atol=1e-9)


def test_degenerate_tangents_fall_back_to_an_orthonormal_frame():
    """At a sphere's pole ∂p/∂u vanishes: the tangents become an orthonormal pair around n with t × b = n."""
    sphere = {"type": "sphere", "center": [0, 0, 0], "radius": 2.0, "material": "checks"}
    arrays = compile_dict({"materials": {"checks": {"texture": {"type": "checker"}}}, "objects": [sphere]}).arrays
    hit = surfaces(arrays, [[0.0, 5.0, 0.0]], [[0.0, -1.0, 0.0]])[0]
    assert hit["v"] == pytest.approx(1.0)
    t, b = tangents(arrays, hit)
    np.testing.assert_allclose([t @ t, b @ b, t @ b, t @ hit["n_sh"]], [1, 1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(np.cross(t, b), hit["n_sh"], atol=1e-12)
