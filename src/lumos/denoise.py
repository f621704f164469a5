"""Denoising a path-traced image with Intel Open Image Denoise (the `pyoidn` binding, an optional dependency).

    denoised = denoise(color, albedo, normal)      # float32 (H, W, 3) each; linear HDR colour

OIDN's `RT` filter is a neural network trained on path-traced images; the albedo and normal guides (the
first hit's, averaged over each pixel's samples) let it keep texture and geometric edges that the noise would
otherwise blur. Install it with `pip install "lumos[denoise]"` (or `pip install pyoidn`).
"""

from __future__ import annotations

import numpy as np

from .errors import LumosError

MISSING = ("--denoise needs Intel Open Image Denoise, which is not installed: pip install pyoidn "
           "(or pip install \"lumos[denoise]\")")


def require() -> None:
    """Raise LumosError naming the package when pyoidn cannot be imported."""
    try:
        import pyoidn  # noqa: F401
    except ImportError:
        raise LumosError(MISSING) from None
    except OSError as exc:  # the package is there but its library will not load
        raise LumosError(f"--denoise: Intel Open Image Denoise (pyoidn) failed to load: {exc}") from None


def denoise(color: np.ndarray, albedo: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """OIDN's RT filter on a linear HDR image with its albedo and normal guides; returns float32 (H, W, 3)."""
    require()
    import pyoidn

    color = np.ascontiguousarray(np.nan_to_num(color, nan=0.0, posinf=0.0, neginf=0.0), np.float32)
    albedo = np.ascontiguousarray(np.clip(albedo, 0.0, 1.0), np.float32)
    normal = np.ascontiguousarray(np.clip(normal, -1.0, 1.0), np.float32)
    try:
        out = pyoidn.denoise(color, albedo, normal, hdr=True, quality="high")
    except RuntimeError as exc:
        raise LumosError(f"--denoise: Intel Open Image Denoise failed: {exc}") from None
    return np.maximum(np.asarray(out, np.float32), 0.0)
