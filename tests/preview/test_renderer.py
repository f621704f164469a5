"""The preview's renderer keeps the compiled scene while its key holds: the camera is not in it (except for
raster, which tessellates planes about the camera), the scene's objects, lights and materials are."""

from __future__ import annotations

import copy

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
