"""The preview's renderer keeps the compiled scene while its key holds: the camera is not in it (except for
raster, which tessellates planes about the camera), the scene's objects, lights and materials are."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml
from helpers import EXAMPLES

from lumos.api import resolve_settings
from lumos.preview.renderer import compile_key
from lumos.scene.loader import load_scene

SHOWCASE = yaml.safe_load((EXAMPLES / "showcase.yaml").read_text())


def key(data, method):
    cfg = resolve_settings(load_scene(EXAMPLES / "showcase.yaml"), {"method": method})
    return compile_key(data, cfg)


def test_what_the_compiled_scene_depends_on():
    moved = copy.deepcopy(SHOWCASE)
    moved["camera"]["position"] = [1.0, 2.0, 8.0]
    resized = copy.deepcopy(SHOWCASE)
    resized["render"]["width"] = 99
    shiny = copy.deepcopy(SHOWCASE)
    shiny["materials"]["red"]["ks"] = 0.9
    assert key(moved, "raycast") == key(SHOWCASE, "raycast") == key(resized, "raycast")
    assert key(SHOWCASE, "raycast") == key(SHOWCASE, "whitted") != key(SHOWCASE, "path")
    assert key(moved, "raster") != key(SHOWCASE, "raster")
    assert key(shiny, "raycast") != key(SHOWCASE, "raycast")
    blurred = copy.deepcopy(SHOWCASE)
    blurred["camera"]["shutter"] = [0.0, 1.0]
    assert key(blurred, "raycast") != key(SHOWCASE, "raycast")


@pytest.mark.parametrize("method, settings", [("raycast", {"aov": ["depth"]}),
                                              ("whitted", {"antialias": "adaptive", "adaptive_depth": 1})])
def test_raycast_and_whitted_show_their_image_band_by_band_and_end_with_the_whole_render(method, settings):
    import lumos
    from lumos.preview import renderer as R

    scene = load_scene(EXAMPLES / "showcase.yaml")
    cfg = resolve_settings(scene, {"method": method, "width": 40, "height": 24, **settings})
    shown = []
    image = R.Renderer().render(SHOWCASE, scene, cfg, check=lambda f: None,
                                on_pass=lambda img: shown.append(img.array.copy()))
    assert len(shown) == R.BANDS - 1
    assert not shown[0][-1].any() and shown[0][0].any()  # the first band drawn, the last rows not yet
    whole = lumos.render(scene, method=method, width=40, height=24, **settings)
    np.testing.assert_array_equal(image.array, whole.array)
    for name in whole.aovs:
        np.testing.assert_array_equal(image.aovs[name], whole.aovs[name])
