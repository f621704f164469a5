"""Tone mapping: linear radiance to display values.

The film holds float32 linear radiance; EXR, PFM and NPY files store it as is. PNG (and Jupyter) get
`round(255 · srgb_encode(clamp(exposure · L, 0, 1)))`, the sRGB transfer curve of IEC 61966-2-1:1999 §5.2:

    encode(x) = 12.92 · x                     for x ≤ 0.0031308
              = 1.055 · x^(1/2.4) − 0.055     otherwise
    decode(y) = y / 12.92                     for y ≤ 0.04045
              = ((y + 0.055) / 1.055)^2.4     otherwise
"""

from __future__ import annotations

import numpy as np

#: Breakpoints of the piecewise sRGB curve (IEC 61966-2-1), linear side and encoded side.
_LINEAR_KNEE = 0.0031308
_ENCODED_KNEE = 0.04045


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer curve (IEC 61966-2-1) applied elementwise.

    linear: float array of any shape with values in [0, 1] (negative values map to 12.92·x).
    Returns a float array of the same shape (float32 for float32 input, else float64) in [0, 1].
    """
    x = np.asarray(linear)
    x = x if np.issubdtype(x.dtype, np.floating) else x.astype(np.float64)
    curve = 1.055 * np.power(np.maximum(x, _LINEAR_KNEE), 1.0 / 2.4) - 0.055
    return np.where(x <= _LINEAR_KNEE, 12.92 * x, curve).astype(x.dtype, copy=False)


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """Inverse of `srgb_encode`: sRGB-encoded values in [0, 1] back to linear, elementwise.

    encoded: float array of any shape. Returns a float array of the same shape and float dtype.
    """
    y = np.asarray(encoded)
    y = y if np.issubdtype(y.dtype, np.floating) else y.astype(np.float64)
    curve = np.power((np.maximum(y, _ENCODED_KNEE) + 0.055) / 1.055, 2.4)
    return np.where(y <= _ENCODED_KNEE, y / 12.92, curve).astype(y.dtype, copy=False)


def quantize8(values: np.ndarray) -> np.ndarray:
    """Display values in [0, 1] (clamped; NaN → 0) to uint8 `round(255 · v)`, same shape."""
    v = np.nan_to_num(np.asarray(values, dtype=np.float32), nan=0.0)
    return np.rint(255.0 * np.clip(v, 0.0, 1.0)).astype(np.uint8)


def to_png8(array: np.ndarray, exposure: float = 1.0, srgb: bool = True) -> np.ndarray:
    """Linear radiance to 8-bit display values: `round(255 · srgb_encode(clamp(exposure · L, 0, 1)))`.

    array: float (H, W, 3) or (H, W) linear values. NaN becomes 0.
    srgb: False skips the transfer curve (for data maps such as normals that are stored as is).
    Returns uint8 of the same shape.
    """
    scaled = np.clip(np.nan_to_num(exposure * np.asarray(array, dtype=np.float32), nan=0.0), 0.0, 1.0)
    return quantize8(srgb_encode(scaled) if srgb else scaled)
