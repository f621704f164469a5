"""Image error metrics for `lumos compare` and the tests.

    figures = compare(rendered, reference)      # {'rmse', 'psnr', 'mean_rel_error', 'max_abs_error'}
    heat = diff_image(rendered, reference)      # float32 (H, W, 3) in [0, 1], black where equal
    heat = diff_image(rendered, reference, scale=0.25)   # the same colours mean the same error in every map

Both take arrays of the same shape (float (H, W, 3) linear images, usually from `read_image`); `b` is the
reference.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LumosError

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


def error_map(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-pixel absolute error of `a` against `b`: the largest |a − b| over the channels, float64 (H, W).

    a, b: (H, W, 3) or (H, W). A pixel where either image is NaN or inf has error inf.
    """
    a, b = _pair(a, b)
    err = np.abs(a - b)
    if err.ndim == 3:
        err = err.max(axis=2)
    err[~np.isfinite(err)] = np.inf
    return err


def heat_ramp(t: np.ndarray) -> np.ndarray:
    """The false-colour ramp of the heat maps: t in [0, 1] (clamped) to float32 RGB in [0, 1].

    A black-body ramp: black at 0, red at 1/3, yellow at 2/3, white at 1 (each channel rises linearly in turn).
    """
    t = np.asarray(t, dtype=np.float64)[..., None]
    return np.clip(3.0 * t - np.array([0.0, 1.0, 2.0]), 0.0, 1.0).astype(np.float32)


def diff_image(a: np.ndarray, b: np.ndarray, scale: float | None = None) -> np.ndarray:
    """A false-colour heat map of the per-pixel absolute error, float32 (H, W, 3) in [0, 1].

    The error of a pixel (`error_map`) is the largest |a − b| over its channels, divided by `scale`, or without
    one by the largest error in the image; that t goes through `heat_ramp`: black (equal), red, yellow, white at
    t ≥ 1. Identical images give all black; pixels where either image is NaN or inf show as the largest error.
    a, b: (H, W, 3) or (H, W). scale: the error shown white, the same for every map that is to be compared.
    """
    err = error_map(a, b)
    bad = np.isinf(err)
    err[bad] = 0.0
    if scale is not None and not scale > 0:
        raise LumosError(f"diff scale must be positive, got {scale}")
    peak = float(err.max()) if scale is None else float(scale)
    t = err / peak if peak > 0 else err
    t[bad] = 1.0
    return heat_ramp(t)
