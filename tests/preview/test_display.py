"""What the page shows of an image: the tone maps, the AOV views, the PNG."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image as PILImage

from lumos import tonemap
from lumos.image import Image
from lumos.preview.display import TONEMAPS, Display, encode_png, tone_map, view_array


def ramp():
    values = np.linspace(0.0, 8.0, 64, dtype=np.float32)
    return np.repeat(np.repeat(values[None, :, None], 4, axis=0), 3, axis=2)


def test_srgb_is_what_a_png_file_holds():
    image = Image(ramp() * 0.2, exposure=1.0)
    np.testing.assert_array_equal(view_array(image, Display(exposure=1.5)), tonemap.to_png8(image.array, 1.5))


@pytest.mark.parametrize("curve", TONEMAPS)
def test_tone_maps_rise_from_black_and_stay_below_white(curve):
    y = tone_map(ramp(), 1.0, curve)[0, :, 1]
    assert y[0] == 0.0 and np.all(np.diff(y) >= 0) and y.max() <= 1.0
    if curve != "srgb":
        assert y[-1] < 1.0 and y[-1] > 0.8  # bright light rolls off instead of clipping


def test_unknown_tone_map():
    with pytest.raises(ValueError, match="unknown tone map"):
        tone_map(ramp(), 1.0, "hable")


def test_aov_views():
    h, w = 4, 6
    depth = np.full((h, w), np.inf, np.float32)
    depth[1:3, 1:4] = [[1, 2, 3], [4, 5, 6]]
    diffuse = np.zeros((h, w, 3), np.float32)
    diffuse[0, 0] = 0.001  # a faint term is normalised to full brightness
    image = Image(np.zeros((h, w, 3), np.float32), aovs={"depth": depth, "diffuse": diffuse,
                                                           "variance": np.full((h, w, 3), 4e-6, np.float32)})
    np.testing.assert_array_equal(view_array(image, Display(view="depth")),
                                  tonemap.quantize8(image.aov_for_display("depth")))
    assert view_array(image, Display(view="diffuse"))[0, 0].tolist() == [255, 255, 255]
    assert view_array(image, Display(view="variance")).min() == 255
    assert view_array(image, Display(view="normal")).max() == 0  # not in the image: the image itself


def test_png_round_trip():
    pixels = (np.arange(4 * 5 * 3) % 256).astype(np.uint8).reshape(4, 5, 3)
    back = np.asarray(PILImage.open(io.BytesIO(encode_png(pixels))))
    np.testing.assert_array_equal(back, pixels)
