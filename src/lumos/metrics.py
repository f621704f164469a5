"""Image error metrics for `lumos compare` and the tests.

    figures = compare(rendered, reference)      # {'rmse', 'psnr', 'mean_rel_error', 'max_abs_error'}
    heat = diff_image(rendered, reference)      # float32 (H, W, 3) in [0, 1], black where equal

Both take arrays of the same shape (float (H, W, 3) linear images, usually from `read_image`); `b` is the
reference.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import LumosError

#: Added to |reference| in the relative error so dark pixels do not blow it up (as in Rousselle et al.'s relMSE).
REL_EPSILON = 1e-2


def _pair(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise LumosError(f"cannot compare images of different shapes: {a.shape} and {b.shape}")
    if a.size == 0:
        raise LumosError("cannot compare empty images")
    return a, b


def compare(a: np.ndarray, b: np.ndarray) -> dict[str, float]:
    """Error of image `a` against the reference `b` (same shape, any numeric dtype).

    rmse            sqrt(mean((a − b)²))
    psnr            10·log10(1 / mse) in dB for a peak value of 1.0; inf when the images are identical
    mean_rel_error  mean(|a − b| / (|b| + 0.01))
    max_abs_error   max |a − b|
    """
    a, b = _pair(a, b)
    diff = np.abs(a - b)
    mse = float(np.mean(diff * diff))
    return {
        "rmse": math.sqrt(mse),
        "psnr": math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse),
        "mean_rel_error": float(np.mean(diff / (np.abs(b) + REL_EPSILON))),
        "max_abs_error": float(diff.max()),
    }


def diff_image(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """A false-colour heat map of the per-pixel absolute error, float32 (H, W, 3) in [0, 1].

    The error of a pixel is the largest |a − b| over its channels, divided by the largest error in the image;
    t = 0 is black (equal), then red, yellow and white at t = 1 (a black-body ramp). Identical images give
    all black; pixels where either image is NaN or inf show as the largest error. a, b: (H, W, 3) or (H, W).
    """
    a, b = _pair(a, b)
    err = np.abs(a - b)
    if err.ndim == 3:
        err = err.max(axis=2)
    bad = ~np.isfinite(err)  # NaN or inf in either image: shown as the largest error
    err[bad] = 0.0
    peak = err.max()
    t = err / peak if peak > 0 else err
    t[bad] = 1.0
    ramp = np.stack([3.0 * t, 3.0 * t - 1.0, 3.0 * t - 2.0], axis=-1)
    return np.clip(ramp, 0.0, 1.0).astype(np.float32)
