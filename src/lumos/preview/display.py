"""What the preview page shows of a float `Image`: the image through a tone map, or one of its AOVs normalised,
encoded as a PNG.

Tone maps (`TONEMAPS`), each applied to `exposure · L` and then sRGB-encoded (`lumos.tonemap`):

    srgb       clamp(x, 0, 1), what `lumos render -o out.png` writes
    reinhard   x / (1 + Y(x)), Y the luminance (Rec. 709 weights): Reinhard et al. 2002, eq. 3, on luminance
    filmic     the ACES filmic curve fitted by Narkowicz (2015), (x(2.51x + 0.03)) / (x(2.43x + 0.59) + 0.14),
               on 0.6·x per channel as his fit expects

AOV views (`view_array`): depth, normal, object_id and samples as `Image.aov_for_display` draws them; albedo as
a colour; variance as the noise left in each pixel (its square root) over its 99th percentile; the classic terms
(ambient, diffuse, specular, emitted, reflected, transmitted) and path's direct and indirect light over their
own 99.5th percentile (normalised: a faint transmitted term is as visible as a bright diffuse one), then the
exposure and the tone map as for the image.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from ..tonemap import quantize8, srgb_encode

TONEMAPS = ("srgb", "reinhard", "filmic")
#: Views that are colours of light: normalised, then exposed and tone-mapped like the image.
RADIANCE_VIEWS = ("ambient", "diffuse", "specular", "emitted", "reflected", "transmitted", "direct", "indirect",
                  "noisy")
#: Views that are data maps: shown as `Image.aov_for_display` draws them, without the sRGB curve or exposure.
DATA_VIEWS = ("depth", "normal", "object_id", "samples")
#: Luminance weights of linear Rec. 709 / sRGB primaries.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722], np.float32)
#: The percentile of a radiance view's brightest channel that is shown as white (the few brightest pixels clip).
RADIANCE_PEAK_PERCENTILE = 99.5
VARIANCE_PEAK_PERCENTILE = 99.0
#: zlib level of the PNGs sent to the page: 1 encodes a 320x240 frame in about 3 ms, 6 (Pillow's default) in 10
PNG_LEVEL = 1


@dataclass(frozen=True)
class Display:
    """How a frame is shown: the exposure, the tone map and the view ("image" or an AOV name)."""

    exposure: float = 1.0
    tonemap: str = "srgb"
    view: str = "image"


def tone_map(radiance: np.ndarray, exposure: float, curve: str) -> np.ndarray:
    """Linear radiance (H, W, 3) to display values in [0, 1] (before the sRGB curve) by `curve` (`TONEMAPS`)."""
    x = np.nan_to_num(np.asarray(radiance, np.float32) * np.float32(exposure), nan=0.0, posinf=0.0, neginf=0.0)
    x = np.maximum(x, 0.0)
    if curve == "reinhard":
        y = x @ LUMINANCE
        x = x / (1.0 + y)[..., None]
    elif curve == "filmic":
        x = 0.6 * x
        x = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
    elif curve != "srgb":
        raise ValueError(f"unknown tone map {curve!r} (choose from {', '.join(TONEMAPS)})")
    return np.clip(x, 0.0, 1.0)


def view_array(image, display: Display) -> np.ndarray:
    """uint8 (H, W, 3): what the page shows of `image` (a `lumos.Image`) with `display`."""
    view = display.view
    if view == "image" or view not in image.aovs:
        return quantize8(srgb_encode(tone_map(image.array, display.exposure, display.tonemap)))
    if view in DATA_VIEWS:
        return quantize8(image.aov_for_display(view))
    value = np.nan_to_num(np.asarray(image.aovs[view], np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    if value.ndim == 2:
        value = np.repeat(value[:, :, None], 3, axis=2)
    if view == "albedo":
        return quantize8(srgb_encode(np.clip(value, 0.0, 1.0)))
    if view == "variance":
        noise = np.sqrt(np.maximum(value, 0.0))
        return quantize8(srgb_encode(np.clip(noise / _peak(noise, VARIANCE_PEAK_PERCENTILE), 0.0, 1.0)))
    normalised = value / _peak(value, RADIANCE_PEAK_PERCENTILE)
    return quantize8(srgb_encode(tone_map(normalised, display.exposure, display.tonemap)))


def encode_png(pixels: np.ndarray) -> bytes:
    """uint8 (H, W, 3) as a PNG file in memory."""
    from PIL import Image as PILImage

    buffer = io.BytesIO()
    PILImage.fromarray(np.ascontiguousarray(pixels), mode="RGB").save(buffer, format="PNG", compress_level=PNG_LEVEL)
    return buffer.getvalue()


def _peak(value: np.ndarray, percentile: float) -> float:
    """The `percentile` of the brightest channel of each pixel that has any light (1 if none has)."""
    brightest = np.abs(value).max(axis=2)
    lit = brightest[brightest > 0.0]
    if lit.size == 0:
        return 1.0
    peak = float(np.percentile(lit, percentile))
    return peak if peak > 0.0 else float(lit.max())
