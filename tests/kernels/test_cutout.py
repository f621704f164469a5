"""Opacity cut-outs (issue 11): a texture applied to `opacity` cuts a hole where its α < 0.5, for every method.

The closed form: an orthographic camera looks straight down at a quad whose uv square holds a 4 × 4 checker of
coverage over a background of another colour; the pixel centres keep clear of the cells' edges, so exactly the
pixels over the hole cells show the background, in raycast, whitted, raster (flat, Gouraud, Phong) and path.
Shadows: a directional light at 45° casts the quad's checker onto a floor; the lit pixels are exactly those
under the holes' shadows. Scenes without opacity maps render bit for bit as a map that covers everything.
"""

import numpy as np
import pytest
from PIL import Image as PILImage

import lumos
from lumos.kernels import layout as L

N = 32  # image size: the quad's 4 × 4 cells are 8 × 8 pixels each
CELLS = 4
RED, BLUE, GREEN = [0.8, 0.1, 0.1], [0.1, 0.2, 0.9], [0.1, 0.7, 0.2]
TOP = {"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "size": 2.0}
#: every method, with its variants (path with max_depth 0: what the first hit emits, and the light it samples)
METHODS = [("raycast", {}), ("whitted", {}), ("raster", {"shading": "flat"}), ("raster", {"shading": "gouraud"}),
           ("raster", {"shading": "phong"}), ("path", {"spp": 2, "max_depth": 0})]
IDS = ["raycast", "whitted", "raster-flat", "raster-gouraud", "raster-phong", "path"]


def checker(scale=CELLS, colors=((1.0, 1.0, 1.0), (0.0, 0.0, 0.0))):
    """Coverage 1 on the even cells, 0 (a hole) on the odd ones."""
    return {"type": "checker", "scale": scale, "colors": [list(c) for c in colors], "apply_to": ["opacity"]}


def quad(z, x0=-1.0, x1=1.0, y0=-1.0, y1=1.0):
    return {"type": "mesh", "vertices": [[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]],
            "faces": [[0, 1, 2], [0, 2, 3]], "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]]}


def glowing(color, texture=None):
    m = {"ka": 0.0, "kd": 0.0, "ks": 0.0, "emission": list(color)}
    if texture is not None:
        m["texture"] = texture
    return m


def front_and_back(texture):
    """The cut-out quad (red) over a background quad (blue) at z = −1, both emitting, no lights."""
    return {"camera": TOP, "ambient": 0.0, "lights": [],
            "materials": {"front": glowing(RED, texture), "back": glowing(BLUE)},
            "objects": [dict(quad(0.0), material="front"), dict(quad(-1.0, -3, 3, -3, 3), material="back")]}


def render(scene, method, options=None, size=N):
    return np.asarray(lumos.render(scene, method=method, width=size, height=size, antialias="none",
                                   **(options or {})).array)


def pixel_uv(size=N):
    """(u, v) of the quad [-1, 1]² under each pixel centre: float64 (size, size) each (row 0 at the top)."""
    c = (np.arange(size) + 0.5) / size
    return np.meshgrid(c, 1.0 - c)


def holes(scale=CELLS, size=N):
    """Where the checker of `checker(scale)` is a hole: bool (size, size)."""
    u, v = pixel_uv(size)
    return (np.floor(scale * u) + np.floor(scale * v)) % 2 == 1


def colour_mask(img, color):
    return np.all(np.abs(img - np.asarray(color, np.float32)) < 1e-5, axis=2)


# ------------------------------------------------------------------------------------------- camera rays


@pytest.mark.parametrize("method,options", METHODS, ids=IDS)
def test_exactly_the_hole_cells_show_the_background(method, options):
    img = render(front_and_back(checker()), method, options)
    hole = holes()
    assert hole.sum() == N * N // 2
    assert colour_mask(img, BLUE)[hole].all()
    assert colour_mask(img, RED)[~hole].all()


@pytest.mark.parametrize("method,options", METHODS[:3] + METHODS[4:], ids=IDS[:3] + IDS[4:])
def test_alpha_channel_and_luminance_cut_the_same_holes(tmp_path, method, options):
    """An RGBA image's alpha channel, or the luminance of an image without one, is the coverage: a 4 × 4 image
    of coverage 1 / 0 in checker order (bilinear between texel centres crosses 0.5 exactly at the cells' edges)."""
    cover = ~((np.add.outer(np.arange(CELLS), np.arange(CELLS)) % 2).astype(bool))[::-1]  # top row first
    rgba = np.zeros((CELLS, CELLS, 4), np.uint8)
    rgba[..., :3] = 40  # dark: its luminance alone would be all holes
    rgba[..., 3] = np.where(cover, 255, 0)
    PILImage.fromarray(rgba, "RGBA").save(tmp_path / "alpha.png")
    grey = np.where(cover, 255, 0).astype(np.uint8)
    PILImage.fromarray(np.stack([grey] * 3, axis=2)).save(tmp_path / "luma.png")
    expected = holes()
    for name in ("alpha.png", "luma.png"):
        tex = {"type": "image", "file": str(tmp_path / name), "apply_to": ["opacity"], "wrap": "clamp"}
        img = render(front_and_back(tex), method, options)
        assert (colour_mask(img, BLUE) == expected).all(), name
        assert (colour_mask(img, RED) == ~expected).all(), name


@pytest.mark.parametrize("method,options", METHODS[:2] + METHODS[4:], ids=IDS[:2] + IDS[4:])
def test_a_stack_of_three_cut_out_quads(method, options):
    """Three cut-out quads at z = 0, −0.3, −0.6 (checkers of 2, 4 and 8 cells, each emitting its own colour)
    over the background: each pixel shows the first quad that is there, or the background."""
    colours = [RED, GREEN, [0.9, 0.8, 0.1]]
    scales = [2, 4, 8]
    scene = {"camera": TOP, "ambient": 0.0, "lights": [],
             "materials": {f"q{k}": glowing(c, checker(s)) for k, (c, s) in enumerate(zip(colours, scales))}
             | {"back": glowing(BLUE)},
             "objects": [dict(quad(-0.3 * k), material=f"q{k}") for k in range(3)]
             + [dict(quad(-1.0, -3, 3, -3, 3), material="back")]}
    img = render(scene, method, options)
    expected = np.zeros((N, N, 3), np.float32)
    expected[:] = BLUE
    for k in reversed(range(3)):
        expected[~holes(scales[k])] = colours[k]
    np.testing.assert_allclose(img, expected, atol=1e-5)
    assert len({tuple(np.round(c, 4)) for c in img.reshape(-1, 3)}) == 4  # all four are seen somewhere


@pytest.mark.parametrize("method", ["raycast", "whitted", "path"])
def test_the_hole_bound_ends_the_walk(method):
    """64 quads that are all hole let the background through; the 65th surface a ray meets counts as opaque."""
    none = checker(colors=((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
    for n, seen in ((64, BLUE), (65, RED)):
        scene = {"camera": TOP, "ambient": 0.0, "lights": [],
                 "materials": {"cut": glowing(RED, none), "back": glowing(BLUE)},
                 "objects": [dict(quad(-0.01 * k), material="cut") for k in range(n)]
                 + [dict(quad(-1.0, -3, 3, -3, 3), material="back")]}
        img = render(scene, method, {"spp": 1, "max_depth": 0} if method == "path" else None, size=8)
        assert colour_mask(img, seen).all(), n


def test_analytic_shapes_have_holes_too():
    """A rect (an analytic shape) with the checker: its uv is the rect's own square, the same cells."""
    scene = front_and_back(checker())
    scene["objects"][0] = {"type": "rect", "corner": [-1, -1, 0], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0],
                           "material": "front"}
    for method in ("raycast", "whitted"):
        img = render(scene, method)
        assert (colour_mask(img, BLUE) == holes()).all(), method


# ------------------------------------------------------------------------------------------- shadows


def shadow_scene(texture):
    """A white floor at z = 0 seen from just above it (z = 0.5: the occluder at z = 1 is behind the camera), lit
    by a directional light travelling along (1, 0, −1)/√2 through a cut-out quad over x in [−2, 0] at z = 1:
    the quad's shadow is its checker moved by +1 in x, exactly the view."""
    cam = dict(TOP, position=[0, 0, 0.5])
    return {"camera": cam, "ambient": 0.0,
            "lights": [{"type": "directional", "direction": [1, 0, -1], "intensity": [1, 1, 1]}],
            "materials": {"cut": {"kd": 0.5, "ks": 0.0, "ka": 0.0, "texture": texture},
                          "floor": {"kd": 0.8, "ks": 0.0, "ka": 0.0}},
            "objects": [dict(quad(1.0, -2.0, 0.0), material="cut"), dict(quad(0.0, -3, 3, -3, 3), material="floor")]}


@pytest.mark.parametrize("method,options", [("whitted", {}), ("path", {"spp": 2, "max_depth": 0}),
                                            ("raster", {"shading": "phong", "shadows": True})],
                         ids=["whitted", "path", "raster-phong"])
def test_shadows_through_holes_are_the_checker(method, options):
    img = render(shadow_scene(checker()), method, options)
    lum = img.mean(axis=2)
    lit_value = lum.max()
    assert lit_value > 0.1
    lit = lum > 0.5 * lit_value
    assert lit.sum() == N * N // 2  # the closed form: half the cells are holes
    assert (lit == holes()).all()
    np.testing.assert_allclose(lum[lit], lit_value, rtol=1e-6)  # the light through a hole is all of it
    assert (lum[~lit] == 0.0).all()


def test_shadow_walk_and_fast_transmittance_agree_without_holes():
    """With a coverage that is 1 everywhere the walk runs (the quad is a cut-out) but finds no hole: the floor
    is the full shadow, as with no opacity map."""
    full = checker(colors=((1.0, 1.0, 1.0), (1.0, 1.0, 1.0)))
    for method in ("whitted", "path"):
        options = {"spp": 2, "max_depth": 0} if method == "path" else {}
        a = render(shadow_scene(full), method, options)
        b = render(shadow_scene(None), method, options)
        np.testing.assert_array_equal(a, b)
        assert (a == 0.0).all()


# ------------------------------------------------------------------------------------------- nothing changes


def _lit_scene(texture):
    """A lit, textured, shadowed scene with reflection and refraction (the paths a cut-out test could perturb)."""
    kd_tex = {"type": "checker", "scale": 3, "colors": [RED, BLUE], "apply_to": ["kd"]}
    textures = [kd_tex] + ([texture] if texture is not None else [])
    return {"camera": {"position": [0.3, -2.5, 2.0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov": 50},
            "ambient": 0.1,
            "lights": [{"type": "point", "position": [1, -1, 3], "intensity": [1, 1, 1]},
                       {"type": "area", "shape": "rect", "corner": [-0.5, -0.5, 2.5], "edge_u": [1, 0, 0], "edge_v": [0, 1, 0],
                        "radiance": [2, 2, 2], "samples": 2}],
            "materials": {"wall": {"kd": 0.6, "ks": 0.2, "texture": textures},
                          "glass": {"kd": 0.0, "ks": 0.1, "kt": 0.8, "ior": 1.5},
                          "mirror": {"kd": 0.1, "kr": 0.7}},
            "objects": [dict(quad(0.0, -2, 2, -2, 2), material="wall"),
                        {"type": "sphere", "center": [0.4, 0, 0.5], "radius": 0.4, "material": "glass"},
                        {"type": "sphere", "center": [-0.5, 0.3, 0.4], "radius": 0.35, "material": "mirror"}]}


@pytest.mark.parametrize("method,options", [("raycast", {}), ("whitted", {}), ("raster", {"shading": "phong"}),
                                            ("path", {"spp": 4, "max_depth": 3})],
                         ids=["raycast", "whitted", "raster", "path"])
def test_a_map_that_covers_everything_changes_no_bit(method, options):
    """The cut-out machinery (the hole lookup after every hit on the wall, the hit-by-hit shadow walk, the raster
    discard test) on a coverage of 1 everywhere renders bit for bit what the scene without an opacity map does."""
    full = checker(colors=((1.0, 1.0, 1.0), (1.0, 1.0, 1.0)))
    a = render(_lit_scene(full), method, options, size=24)
    b = render(_lit_scene(None), method, options, size=24)
    np.testing.assert_array_equal(a, b)


def test_only_opacity_textures_mark_a_material_cut_out():
    from conftest import compile_dict

    c = compile_dict(_lit_scene(checker()))
    assert list(c.arrays.materials[:3, L.MAT_CUTOUT]) == [1.0, 0.0, 0.0]  # then the rect light's
    assert not compile_dict(_lit_scene(None)).arrays.materials[:, L.MAT_CUTOUT].any()


def test_radiosity_says_it_ignores_opacity_maps():
    scene = front_and_back(checker())
    scene["materials"]["front"] = {"kd": 0.5, "texture": checker()}
    scene["lights"] = [{"type": "point", "position": [0, 0, 3]}]
    with pytest.warns(lumos.LumosWarning, match="ignores opacity maps"):
        lumos.render(scene, method="radiosity", width=8, height=8)
