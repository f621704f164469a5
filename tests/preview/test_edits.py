"""Live edits of the scene dict: orbiting keeps the distance and the look-at point and never flips over the up
axis; a colour slider keeps the hue; a light's strength scales its colours together; `describe` lists what the
page edits."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import yaml
from helpers import EXAMPLES

from lumos.errors import LumosError
from lumos.preview.edits import PITCH_LIMITS, apply_edit, describe

SHOWCASE = yaml.safe_load((EXAMPLES / "showcase.yaml").read_text())


def offset(data):
    return np.subtract(data["camera"]["position"], data["camera"]["look_at"])


def test_orbit_turns_about_the_look_at_point():
    base = SHOWCASE
    turned = apply_edit(base, base, {"type": "camera", "yaw": 90.0})
    a, b = offset(base), offset(turned)
    assert np.linalg.norm(b) == pytest.approx(np.linalg.norm(a), rel=1e-5)
    assert b[1] == pytest.approx(a[1], abs=1e-4)  # yaw keeps the height
    assert np.dot(a[[0, 2]], b[[0, 2]]) == pytest.approx(0.0, abs=1e-3)  # a quarter turn
    assert turned["camera"]["look_at"] == base["camera"]["look_at"] and base == SHOWCASE  # nothing else moved


def test_pitch_stops_short_of_the_pole():
    over = apply_edit(SHOWCASE, SHOWCASE, {"type": "camera", "pitch": 200.0})
    b = offset(over)
    angle = math.degrees(math.acos(b[1] / np.linalg.norm(b)))
    assert angle == pytest.approx(PITCH_LIMITS[0], abs=1e-3)


def test_dolly_and_reset():
    near = apply_edit(SHOWCASE, SHOWCASE, {"type": "camera", "dolly": 0.5})
    assert np.linalg.norm(offset(near)) == pytest.approx(0.5 * np.linalg.norm(offset(SHOWCASE)), rel=1e-5)
    assert apply_edit(near, SHOWCASE, {"type": "camera", "reset": True})["camera"] == SHOWCASE["camera"]


def test_a_colour_slider_keeps_the_hue_and_a_scalar_stays_a_scalar():
    data = copy.deepcopy(SHOWCASE)
    data = apply_edit(data, SHOWCASE, {"type": "material", "name": "red", "key": "kd", "value": 0.3})
    assert data["materials"]["red"]["kd"] == pytest.approx([0.3, 0.04, 0.03])
    data = apply_edit(data, SHOWCASE, {"type": "material", "name": "red", "key": "kd", "value": 0.0})
    data = apply_edit(data, SHOWCASE, {"type": "material", "name": "red", "key": "kd", "value": 0.6})
    assert data["materials"]["red"]["kd"] == pytest.approx([0.6, 0.08, 0.06])  # back from black, same hue
    data = apply_edit(data, SHOWCASE, {"type": "material", "name": "porcelain", "key": "ks", "value": 0.5})
    assert data["materials"]["porcelain"]["ks"] == 0.5
    data = apply_edit(data, SHOWCASE, {"type": "material", "name": "floor", "key": "kr", "value": 0.2})
    assert data["materials"]["floor"]["kr"] == 0.2  # was not given (black): grey
    data = apply_edit(data, SHOWCASE, {"type": "material", "name": "red", "key": "ior", "value": 1.5})
    assert data["materials"]["red"]["ior"] == 1.5


def test_a_light_strength_scales_its_colour():
    data = apply_edit(SHOWCASE, SHOWCASE, {"type": "light", "index": 0, "key": "strength", "value": 2.8})
    assert data["lights"][0]["intensity"] == pytest.approx([2.8, 2.6, 2.3])
    data = apply_edit(data, SHOWCASE, {"type": "light", "index": 2, "key": "strength", "value": 8.0})
    assert data["lights"][2]["radiance"] == pytest.approx([8.0, 5.0, 2.0])
    data = apply_edit(data, SHOWCASE, {"type": "light", "index": 2, "key": "center", "value": [0, 3, 0]})
    assert data["lights"][2]["center"] == [0.0, 3.0, 0.0]
    with pytest.raises(LumosError, match="cannot be"):
        apply_edit(data, SHOWCASE, {"type": "light", "index": 1, "key": "direction", "value": [0, 0, 0]})
    with pytest.raises(LumosError, match="out of range"):
        apply_edit(data, SHOWCASE, {"type": "light", "index": 0, "key": "position", "value": [0, 1e9, 0]})


def test_describe_lists_lights_and_named_materials():
    found = describe(SHOWCASE)
    assert [light["label"] for light in found["lights"]] == ["0: point", "1: directional", "2: sphere"]
    assert found["lights"][0]["vectors"] == {"position": [-3.0, 5.0, 4.0]}
    assert found["lights"][1]["vectors"] == {"direction": [-0.5, -0.2, 0.8]}
    assert found["lights"][2]["strength_key"] == "radiance" and found["lights"][2]["strength"] == 16.0
    names = [m["name"] for m in found["materials"]]
    assert names == ["floor", "red", "blue", "gold", "porcelain"]
    red = found["materials"][1]["values"]
    assert red == {"ka": 0.6, "kd": 0.6, "ks": 0.6, "shininess": 80.0, "kr": 0.0, "kt": 0.0, "ior": 1.0}
