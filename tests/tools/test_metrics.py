"""Image metrics on hand-made arrays whose errors are worked out by hand."""

import math

import numpy as np
import pytest

from lumos.errors import LumosError
from lumos.tools.metrics import compare, diff_image, error_map, heat_ramp


def test_identical_images():
    a = np.random.default_rng(1).random((3, 4, 3)).astype(np.float32)
    figures = compare(a, a.copy())
    assert figures == {"rmse": 0.0, "psnr": math.inf, "mean_rel_error": 0.0, "max_abs_error": 0.0}


def test_hand_computed_values():
    b = np.zeros((2, 2, 3))  # reference
    a = b.copy()
    a[0, 0, 0] = 0.6  # one of 12 values off by 0.6: mse = 0.36 / 12 = 0.03
    figures = compare(a, b)
    assert figures["rmse"] == pytest.approx(math.sqrt(0.03))
    assert figures["psnr"] == pytest.approx(10 * math.log10(1 / 0.03))  # 15.23 dB
    assert figures["mean_rel_error"] == pytest.approx(0.6 / 0.01 / 12)  # |b| = 0: divided by the epsilon only
    assert figures["max_abs_error"] == pytest.approx(0.6)


def test_relative_error_uses_reference():
    a = np.full((1, 2), 1.5)
    b = np.array([[1.0, 3.0]])
    expected = (0.5 / 1.01 + 1.5 / 3.01) / 2
    assert compare(a, b)["mean_rel_error"] == pytest.approx(expected)
    assert compare(b, a)["mean_rel_error"] == pytest.approx((0.5 / 1.51 + 1.5 / 1.51) / 2)


def test_uniform_offset_psnr():
    a = np.full((4, 4, 3), 0.5)
    figures = compare(a + 0.1, a)
    assert figures["rmse"] == pytest.approx(0.1)
    assert figures["psnr"] == pytest.approx(20.0)  # 10·log10(1/0.01)
    assert all(isinstance(v, float) for v in figures.values())


def test_shape_mismatch_names_both_shapes():
    with pytest.raises(LumosError, match=r"\(2, 2, 3\).*\(2, 3, 3\)"):
        compare(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))
    with pytest.raises(LumosError):
        diff_image(np.zeros((2, 2, 3)), np.zeros((2, 2)))


def test_diff_image_heat_map():
    b = np.zeros((2, 3, 3), dtype=np.float32)
    a = b.copy()
    a[0, 0] = [0.0, 2.0, 0.0]  # the largest error → white
    a[1, 2] = [0.5, 0.0, 0.0]  # a quarter of it → t = 0.25: red 0.75, no green or blue
    heat = diff_image(a, b)
    assert heat.shape == (2, 3, 3) and heat.dtype == np.float32
    np.testing.assert_allclose(heat[0, 0], [1, 1, 1])
    np.testing.assert_allclose(heat[1, 2], [0.75, 0, 0])
    assert (heat[0, 1] == 0).all() and (heat[1, 0] == 0).all()  # equal pixels are black
    assert (diff_image(b, b) == 0).all()
    assert heat.min() >= 0 and heat.max() <= 1


def test_diff_image_marks_non_finite_as_largest():
    b = np.zeros((1, 2, 3), dtype=np.float32)
    a = b.copy()
    a[0, 0, 1] = np.inf
    a[0, 1, 0] = 0.1
    heat = diff_image(a, b)
    np.testing.assert_allclose(heat[0, 0], [1, 1, 1])
    np.testing.assert_allclose(heat[0, 1], [1, 1, 1])  # the largest finite error is also t = 1


def test_error_map_is_the_largest_channel_difference():
    b = np.zeros((1, 3, 3))
    a = b.copy()
    a[0, 0] = [0.1, -0.4, 0.2]  # |a - b| largest in green
    a[0, 1, 2] = np.nan
    err = error_map(a, b)
    assert err.shape == (1, 3) and err.dtype == np.float64
    np.testing.assert_allclose(err[0, [0, 2]], [0.4, 0.0])
    assert err[0, 1] == np.inf  # NaN in either image: an infinite error
    np.testing.assert_allclose(error_map(np.full((2, 2), 0.25), np.zeros((2, 2))), 0.25)  # (H, W) images too


def test_heat_ramp_stops():
    np.testing.assert_allclose(heat_ramp(np.array([0.0, 1 / 3, 0.5, 2 / 3, 1.0, 7.0, -1.0])),
                               [[0, 0, 0], [1, 0, 0], [1, 0.5, 0], [1, 1, 0], [1, 1, 1], [1, 1, 1], [0, 0, 0]],
                               atol=1e-6)


def test_diff_image_with_a_fixed_scale():
    """With `scale`, t = error / scale whatever the image's largest error: two maps on one scale compare."""
    b = np.zeros((1, 3, 3), dtype=np.float32)
    a = b.copy()
    a[0, 0, 0] = 0.125  # half the scale: t = 0.5, orange
    a[0, 1, 1] = 0.25   # the scale: white
    a[0, 2, 2] = 3.0    # beyond it: white too
    heat = diff_image(a, b, scale=0.25)
    np.testing.assert_allclose(heat[0], [[1, 0.5, 0], [1, 1, 1], [1, 1, 1]], atol=1e-6)
    small = diff_image(a[:, :1], b[:, :1], scale=0.25)  # alone, the half-scale pixel keeps its colour
    np.testing.assert_allclose(small[0, 0], [1, 0.5, 0], atol=1e-6)
    np.testing.assert_allclose(diff_image(a[:, :1], b[:, :1])[0, 0], [1, 1, 1])  # without a scale: its own peak
    with pytest.raises(LumosError, match="scale must be positive"):
        diff_image(a, b, scale=0.0)
