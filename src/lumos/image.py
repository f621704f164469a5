"""`Image`: what `lumos.render` returns — linear radiance, optional AOVs and the render's figures.

    img = lumos.render(scene)
    img.array                 # float32 (H, W, 3) linear radiance
    img.aovs["depth"]         # float32 (H, W), inf where no surface was hit
    img.save("out.exr")       # also writes out.depth.exr, out.normal.exr ... for each AOV
    img                       # in Jupyter: shown as a PNG
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Iterable

import numpy as np

from . import tonemap
from .errors import LumosError
from .io.image_files import check_output_path, write_image

#: PNG display of AOVs: these are data maps, stored as round(255 · v) without the sRGB curve (so a normal
#: map holds the usual 0.5·n + 0.5); any other AOV (albedo) is a colour and gets the curve like the image.
_DATA_AOVS = ("depth", "normal", "object_id")
#: Smallest display value of a hit in the depth view, so the farthest surface is not as black as the void.
_DEPTH_FLOOR = 0.1


class Image:
    """A rendered image.

    array:    float32 (H, W, 3) C-contiguous linear radiance.
    aovs:     dict[str, ndarray] of extra outputs ('arbitrary output variables'), each (H, W) or (H, W, 3):
              'depth' float32 (H, W), np.inf where nothing was hit; 'normal' float32 (H, W, 3), 0 where no
              hit; 'albedo' float32 (H, W, 3); 'object_id' int32 (H, W), −1 where no hit.
    stats:    dict of figures from the render (load_s, build_s, render_s, total_s, rays, mrays_per_s ...).
    exposure: scale applied before the sRGB tone map when shown or saved as PNG.
    """

    def __init__(self, array: np.ndarray, aovs: dict | None = None, stats: dict | None = None, exposure: float = 1.0):
        self.array = np.ascontiguousarray(array, dtype=np.float32)
        if self.array.ndim != 3 or self.array.shape[2] != 3:
            raise LumosError(f"Image: expected an (H, W, 3) array, got shape {self.array.shape}")
        self.aovs = {name: np.asarray(value) for name, value in (aovs or {}).items()}
        for name, value in self.aovs.items():
            if value.shape[:2] != self.array.shape[:2]:
                raise LumosError(f"Image: AOV {name!r} has shape {value.shape}, the image {self.array.shape}")
        self.stats = dict(stats or {})
        self.exposure = float(exposure)

    @property
    def width(self) -> int:
        return self.array.shape[1]

    @property
    def height(self) -> int:
        return self.array.shape[0]

    def __repr__(self) -> str:
        parts = [f"{self.width}x{self.height}"]
        if "method" in self.stats:
            parts.append(str(self.stats["method"]))
        seconds = self.stats.get("total_s", self.stats.get("render_s"))
        if seconds is not None:
            parts.append(f"{seconds:.2f} s")
        return f"<lumos.Image {' '.join(parts)}>"

    # ------------------------------------------------------------------------------------------------ files

    def save(self, path: str | os.PathLike, aovs: bool | Iterable[str] = True) -> list[Path]:
        """Write the image to `path` and each AOV beside it as `<stem>.<aov><suffix>` (out.png → out.depth.png).

        The format follows the extension (.png, .exr, .pfm, .npy; see `lumos.io.image_files`). PNG AOVs are the
        `aov_for_display` views; the linear formats get the raw values (depth keeps its inf).
        aovs: True for all, False for none, or the names to write. Returns the paths written, image first.
        """
        out = check_output_path(path)
        names = list(self.aovs) if aovs is True else [] if aovs is False else list(aovs)
        for name in names:
            if name not in self.aovs:
                raise LumosError(f"cannot save AOV {name!r}: the image has {', '.join(self.aovs) or 'no AOVs'}")
        write_image(out, self.array, exposure=self.exposure)
        written = [out]
        for name in names:
            aov_path = out.with_name(f"{out.stem}.{name}{out.suffix}")
            if out.suffix.lower() == ".png":
                write_image(aov_path, self.aov_for_display(name), srgb=name not in _DATA_AOVS)
            else:
                write_image(aov_path, self.aovs[name])
            written.append(aov_path)
        return written

    # ---------------------------------------------------------------------------------------------- display

    def _hit_mask(self) -> np.ndarray | None:
        """bool (H, W): where a surface was hit, from object_id or depth; None if neither AOV is present."""
        if "object_id" in self.aovs:
            return self.aovs["object_id"] >= 0
        if "depth" in self.aovs:
            return np.isfinite(self.aovs["depth"])
        return None

    def aov_for_display(self, name: str) -> np.ndarray:
        """A view of AOV `name` for PNG or the screen: float32 (H, W, 3) in [0, 1], black where nothing was hit.

        depth:     1 − 0.9·d / d_max with d_max the largest finite depth (near = bright, farthest = 0.1)
        normal:    0.5·n + 0.5 (the usual normal-map colours)
        albedo:    as is, clamped to [0, 1]
        object_id: a fixed colour per id from a hash palette (`id_colors`)
        samples:   the count divided by the largest, grey (background included)
        others:    (H, W) values divided by their largest finite value, grey; (H, W, 3) clamped
        """
        if name not in self.aovs:
            raise LumosError(f"no AOV {name!r} (the image has {', '.join(self.aovs) or 'no AOVs'})")
        value = self.aovs[name]
        hit = self._hit_mask()
        if name == "object_id":
            view = id_colors(value)
        elif name == "depth":
            finite = np.isfinite(value)
            d_max = value[finite].max() if finite.any() else 1.0
            view = np.where(finite, 1.0 - (1.0 - _DEPTH_FLOOR) * value / (d_max if d_max > 0 else 1.0), 0.0)
            hit = finite if hit is None else hit & finite
        elif name == "normal":
            view = 0.5 * value + 0.5
            hit = np.any(value != 0, axis=2) if hit is None else hit
        elif value.ndim == 2:
            if name == "samples":  # camera rays per pixel: the background took rays too
                hit = None
            finite = np.isfinite(value)
            peak = np.abs(value[finite]).max() if finite.any() else 0.0
            view = np.where(finite, value / peak if peak > 0 else value, 0.0)
        else:
            view = value
        view = np.asarray(view, dtype=np.float32)
        if view.ndim == 2:
            view = np.repeat(view[:, :, None], 3, axis=2)
        if hit is not None:
            view = np.where(hit[:, :, None], view, 0.0)
        return np.clip(np.nan_to_num(view, nan=0.0), 0.0, 1.0).astype(np.float32)

    def to_png_bytes(self) -> bytes:
        """The image as an 8-bit sRGB PNG file in memory (after `exposure`)."""
        from PIL import Image as PILImage

        buffer = io.BytesIO()
        PILImage.fromarray(tonemap.to_png8(self.array, self.exposure), mode="RGB").save(buffer, format="PNG")
        return buffer.getvalue()

    def _repr_png_(self) -> bytes:
        """Jupyter's hook: show the image inline."""
        return self.to_png_bytes()


def id_colors(ids: np.ndarray) -> np.ndarray:
    """A distinct, fixed colour per integer id: float32 (H, W, 3) in [0.25, 1] per channel; black for ids < 0.

    The id is mixed with the 32-bit finaliser of MurmurHash3 (fmix32) and its three low bytes are the colour,
    so neighbouring ids get unrelated colours and an id keeps its colour from image to image.
    """
    ids = np.asarray(ids, dtype=np.int64)
    h = (ids & 0xFFFFFFFF).astype(np.uint64)
    for shift, mult in ((16, 0x85EBCA6B), (13, 0xC2B2AE35), (16, None)):
        h ^= h >> np.uint64(shift)
        if mult is not None:
            h = (h * np.uint64(mult)) & np.uint64(0xFFFFFFFF)
    rgb = np.stack([(h >> np.uint64(8 * k)) & np.uint64(0xFF) for k in range(3)], axis=-1).astype(np.float32)
    colors = 0.25 + 0.75 * rgb / 255.0
    return np.where((ids >= 0)[..., None], colors, 0.0).astype(np.float32)
