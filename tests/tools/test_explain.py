"""`lumos explain` / `lumos.explain`: the numbers it prints are the renderer's own.

The explained value equals the rendered pixel (to 1e-5) for raycast, whitted (every anti-aliasing mode) and raster
(every shading), on pixels of the examples — one seen through glass, one in a soft shadow; the whitted tree adds
up (each ray's I = local + w_r·I_r + w_t·I_t, the pixel = Σ weight · I), and the per-light shares add up to the
diffuse and specular terms."""

import json

import numpy as np
import pytest

import lumos
from lumos import cli
from lumos.tools.explain import format_text

CLASSIC = "examples/whitted/classic.yaml"
SMALL = {"width": 160, "height": 120}
#: a pixel of classic.yaml (160x120) on the glass sphere that sees the checkerboard through it, and one on the
#: board in the mirror sphere's shadow
THROUGH_GLASS, ON_BOARD = (90, 50), (28, 63)

SOFT = {
    "camera": {"position": [0.0, 2.0, 4.0], "look_at": [0.0, 0.3, 0.0], "fov": 45.0},
    "ambient": 0.1,
    "lights": [{"type": "area", "shape": "rect", "corner": [-0.5, 2.5, -0.5], "edge_u": [1.0, 0.0, 0.0],
                "edge_v": [0.0, 0.0, 1.0], "radiance": 2.0, "samples": 16}],
    "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"kd": 0.8, "ka": 0.5}},
                {"type": "sphere", "center": [0.3, 0.6, 0.0], "radius": 0.4,
                 "material": {"kd": 0.6, "ks": 0.4, "shininess": 30, "kr": 0.2}}],
}


def tree_checks(tree):
    """Every whitted ray's I from its children, the pixel from its samples, the terms from the lights."""
    def walk(node):
        hit = node["hit"]
        if hit is None:
            return np.array(node["background"])
        local = sum(np.array(hit[k]) for k in ("emitted", "ambient", "diffuse", "specular"))
        assert np.allclose(local, hit["local"], atol=1e-12)
        for key in ("diffuse", "specular"):
            assert np.allclose(sum(np.array(light[key]) for light in hit["lights"]), hit[key], atol=1e-12)
        value = local.copy()
        for child in node["children"]:
            w = hit["reflected_weight"] if child["kind"] == "reflected" else hit["transmitted_weight"]
            value = value + np.array(w) * walk(child)
        assert np.allclose(value, node["radiance"], atol=1e-12)
        return value

    total = sum(s["weight"] * walk(s["ray"]) for s in tree["samples"])
    assert np.allclose(sum(s["weight"] for s in tree["samples"]), 1.0)
    assert np.allclose(total, tree["value"], atol=1e-9)


@pytest.mark.parametrize("antialias", ["none", "supersample", "adaptive"])
def test_whitted_explains_the_rendered_pixel(antialias):
    settings = dict(SMALL, antialias=antialias, spp=3)
    img = lumos.render(CLASSIC, **settings)
    for x, y in (THROUGH_GLASS, ON_BOARD, (5, 5)):
        tree = lumos.explain(CLASSIC, x, y, **settings)
        assert np.allclose(tree["value"], img.array[y, x], atol=1e-5), (x, y)
        tree_checks(tree)
    glass = lumos.explain(CLASSIC, *THROUGH_GLASS, **settings)
    first = glass["samples"][0]["ray"]
    assert first["hit"]["material_name"] == "'glass'"
    kinds = [c["kind"] for c in first["children"]]
    assert "transmitted" in kinds and first["hit"]["fresnel"] is not None
    # through the glass: the transmitted ray leaves the sphere and lands on the board
    inner = next(c for c in first["children"] if c["kind"] == "transmitted")
    out = next(c for c in inner["children"] if c["kind"] == "transmitted")
    assert out["hit"]["material_name"] == "'board'"
    assert "transmitted ray" in format_text(glass)


def test_whitted_soft_shadow_pixel_reports_the_light_samples_it_sees():
    settings = dict(method="whitted", width=80, height=60, antialias="none")
    img = lumos.render(SOFT, aov=["object_id"], **settings)
    shadows = []
    for y in range(30, 60, 2):
        for x in range(0, 80, 2):
            if img.aovs["object_id"][y, x] != 0:
                continue
            tree = lumos.explain(SOFT, x, y, **settings)
            light = tree["samples"][0]["ray"]["hit"]["lights"][0]
            if 0 < light["samples_lit"] < 16:  # the penumbra: some samples blocked, some not
                assert np.allclose(tree["value"], img.array[y, x], atol=1e-5)
                assert 0.0 < light["shadow"][0] < 1.0
                shadows.append((x, y))
    assert shadows, "no pixel in the penumbra"


@pytest.mark.parametrize("shading", ["flat", "gouraud", "phong"])
def test_raster_explains_the_rendered_pixel(shading):
    settings = dict(method="raster", shading=shading, width=80, height=60, spp=4, shadows=True)
    img = lumos.render(SOFT, **settings)
    for x, y in ((40, 30), (20, 50), (70, 10), (5, 5)):
        tree = lumos.explain(SOFT, x, y, **settings)
        assert np.allclose(tree["value"], img.array[y, x], atol=1e-5), (x, y)
        assert len(tree["passes"]) == 4
        for p in tree["passes"]:
            assert np.allclose(sum(np.array(v) for v in p["terms"].values()), p["value"], atol=1e-5)
    tree = lumos.explain(SOFT, 40, 30, **settings)
    poly = tree["passes"][0]["polygon"]
    assert poly is not None and poly["object"] in (0, 1) and len(poly["vertices"]) >= 3
    if shading == "gouraud":
        assert "light_front" in poly["vertices"][0]
    if shading == "phong":
        lights = tree["passes"][0]["lights"]
        assert np.allclose(sum(np.array(l["diffuse"]) for l in lights), tree["passes"][0]["terms"]["diffuse"],
                           atol=1e-6)
    assert "polygon" in format_text(tree)


def test_raycast_explains_the_rendered_pixel():
    settings = dict(method="raycast", width=80, height=60, antialias="none")
    img = lumos.render(SOFT, **settings)
    for x, y in ((40, 30), (20, 50), (5, 5)):
        tree = lumos.explain(SOFT, x, y, **settings)
        assert np.allclose(tree["value"], img.array[y, x], atol=1e-5)
        assert np.allclose(tree["sum_of_terms"], tree["value"], atol=1e-5)
    ids = lumos.render(SOFT, aov=["object_id"], **settings).aovs["object_id"]
    ys, xs = np.nonzero(ids == 1)
    x, y = int(np.median(xs)), int(np.median(ys))
    tree = lumos.explain(SOFT, x, y, **settings)
    assert tree["hit"]["object"] == 1 and len(tree["hit"]["lights"]) == 1
    assert np.allclose(tree["hit"]["lights"][0]["diffuse"], tree["terms"]["diffuse"], atol=1e-6)


def test_cli_explain_text_json_and_errors(capsys):
    args = ["explain", CLASSIC, "--pixel", str(THROUGH_GLASS[0]), str(THROUGH_GLASS[1]), "--width", "160",
            "--height", "120", "--antialias", "none"]
    assert cli.main(args + ["--json"]) == 0
    tree = json.loads(capsys.readouterr().out)
    assert len(tree["value"]) == 3 and tree["samples"][0]["ray"]["kind"] == "camera"
    assert cli.main(args) == 0
    assert "value = (" in capsys.readouterr().out
    assert cli.main(["explain", CLASSIC, "--pixel", "160", "0", "--width", "160", "--height", "120"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "outside the image" in err
    assert cli.main(["explain", CLASSIC, "--pixel", "1", "1", "--method", "path"]) == 2
    assert "cannot explain" in capsys.readouterr().err


@pytest.mark.parametrize("method, settings", [("raycast", {}), ("raster", {"shading": "gouraud"}),
                                              ("raster", {"shading": "phong"})])
def test_raycast_and_raster_explain_pixels_of_the_classic_example(method, settings):
    # the scene asks for whitted's adaptive anti-aliasing: the other methods supersample at 4 spp instead
    settings = dict(SMALL, method=method, **settings)
    with pytest.warns(lumos.LumosWarning, match="supersamples"):
        img = lumos.render(CLASSIC, **settings)
    for x, y in (THROUGH_GLASS, ON_BOARD):
        with pytest.warns(lumos.LumosWarning, match="supersamples"):
            tree = lumos.explain(CLASSIC, x, y, **settings)
        assert np.allclose(tree["value"], img.array[y, x], atol=1e-5), (method, x, y)
