"""Image files: write a film to PNG / EXR / PFM / NPY, read images back as linear float32.

    write_image("out.png", rgb, exposure=2.0)   # rgb: float32 (H, W, 3) linear; PNG gets sRGB 8-bit
    write_image("depth.exr", depth)             # (H, W) arrays become one channel 'Y' (grey)
    rgb = read_image("ref.exr")                 # float32 (H, W, 3) linear

The format follows the extension (case-insensitive). EXR, PFM and NPY hold linear float32, unclamped (inf
stays inf); PNG holds `round(255 · srgb_encode(clamp(exposure · L)))` (see `lumos.tonemap`). Writes are atomic:
the data goes to a temporary file in the target folder, which `os.replace` moves over the target only once
it is complete, so a failed write never leaves a half-written or clobbered file. Bad paths and unreadable
files raise `LumosError` with a one-line message naming the path.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Callable

import numpy as np

from .. import tonemap
from ..errors import LumosError
from .atomic import check_output_path as _check_path
from .atomic import one_line, write_atomically

#: Extensions `write_image` can write (and `read_image` can read).
SUPPORTED = (".png", ".exr", ".pfm", ".npy")
#: Extensions `read_image` can read: the above plus JPEG.
READABLE = SUPPORTED + (".jpg", ".jpeg")


_one_line = one_line


# ---------------------------------------------------------------------------------------------------- writing


def check_output_path(path: str | os.PathLike) -> Path:
    """Check that an image could be written to `path` without writing anything; return it as a `Path`.

    Raises LumosError for an unsupported extension, a path that is a directory, a folder that does not
    exist (or is not a folder) and a folder that is not writable.
    """
    return _check_path(path, tuple(SUPPORTED), "cannot write image")


def write_image(path: str | os.PathLike, array: np.ndarray, exposure: float = 1.0, *, srgb: bool = True) -> None:
    """Write `array` to `path`, atomically, in the format its extension names.

    array: float32 (H, W, 3) RGB or (H, W) grey, linear; other numeric dtypes (e.g. int32 object ids) are
        written as float32.
    exposure: multiplies the values before the PNG tone map; ignored by the linear formats.
    srgb: PNG only; False stores `round(255 · clamp(v))` without the transfer curve (data maps).
    """
    out = check_output_path(path)
    data = np.asarray(array)
    if data.ndim not in (2, 3) or (data.ndim == 3 and data.shape[2] != 3) or 0 in data.shape:
        raise LumosError(f"cannot write image '{path}': expected an (H, W, 3) or (H, W) array, got {data.shape}")
    # Looked up at call time so tests can replace a single encoder.
    writer: Callable[[str, np.ndarray], None] = {
        ".png": lambda p, a: _write_png(p, tonemap.to_png8(a, exposure, srgb=srgb)),
        ".exr": _write_exr,
        ".pfm": _write_pfm,
        ".npy": _write_npy,
    }[out.suffix.lower()]
    _atomic_write(out, lambda tmp: writer(tmp, np.ascontiguousarray(data, dtype=np.float32)))


def _atomic_write(out: Path, write: Callable[[str], None]) -> None:
    """Run `write(tmp_name)` on a temporary file beside `out`, then move it over `out`; clean up on failure."""
    write_atomically(out, write, f"cannot write image '{out}'")


def _write_png(path: str, pixels: np.ndarray) -> None:
    """pixels: uint8 (H, W, 3) → RGB PNG, or (H, W) → greyscale 'L' PNG."""
    from PIL import Image as PILImage

    PILImage.fromarray(pixels, mode="RGB" if pixels.ndim == 3 else "L").save(path, format="PNG")


def _write_exr(path: str, data: np.ndarray) -> None:
    """data: float32 (H, W, 3) → channels R, G, B; (H, W) → one channel Y. ZIP-compressed scanlines."""
    import OpenEXR

    if data.ndim == 3:
        channels = {name: np.ascontiguousarray(data[:, :, i]) for i, name in enumerate("RGB")}
    else:
        channels = {"Y": data}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, channels).write(path)


def _write_pfm(path: str, data: np.ndarray) -> None:
    """data: float32 (H, W, 3) → 'PF', (H, W) → 'Pf'; little-endian (scale −1.0), bottom row first."""
    height, width = data.shape[:2]
    kind = "PF" if data.ndim == 3 else "Pf"
    with open(path, "wb") as f:
        f.write(f"{kind}\n{width} {height}\n-1.0\n".encode("ascii"))
        f.write(np.ascontiguousarray(data[::-1], dtype="<f4").tobytes())


def _write_npy(path: str, data: np.ndarray) -> None:
    """data: float32 (H, W, 3) or (H, W), saved as is."""
    np.save(path, data, allow_pickle=False)


# ---------------------------------------------------------------------------------------------------- reading


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Read an image file as float32 (H, W, 3) linear values.

    PNG and JPEG are decoded from sRGB to linear (16-bit PNG too); EXR, PFM and NPY are returned as stored.
    Grey images become three equal channels; alpha is dropped. Raises LumosError for a missing, corrupt or
    unsupported file.
    """
    src = Path(path)
    ext = src.suffix.lower()
    fail = f"cannot read image '{path}'"
    if ext not in READABLE:
        raise LumosError(f"{fail}: unsupported extension '{src.suffix}' (readable: {', '.join(READABLE)})")
    if not src.is_file():
        raise LumosError(f"{fail}: {'it is a directory' if src.is_dir() else 'file not found'}")
    reader = {".exr": _read_exr, ".pfm": _read_pfm, ".npy": _read_npy}.get(ext, _read_pillow)
    try:
        data = reader(str(src))
    except LumosError as exc:
        raise LumosError(f"{fail}: {exc}") from None
    except Exception as exc:  # every decoder has its own exception types for a damaged file
        raise LumosError(f"{fail}: not a valid {ext[1:].upper()} file ({_one_line(exc)})") from None
    return _as_rgb(data, fail)


def _as_rgb(data: np.ndarray, fail: str) -> np.ndarray:
    """(H, W), (H, W, 1), (H, W, 3) or (H, W, 4) → float32 C-contiguous (H, W, 3)."""
    if data.ndim == 3 and data.shape[2] in (3, 4):
        data = data[:, :, :3]
    elif data.ndim == 3 and data.shape[2] == 1:
        data = data[:, :, 0]
    elif data.ndim != 2:
        raise LumosError(f"{fail}: expected an (H, W) or (H, W, 3) image, got shape {data.shape}")
    if data.ndim == 2:
        data = np.repeat(data[:, :, None], 3, axis=2)
    return np.ascontiguousarray(data, dtype=np.float32)


def _read_pillow(path: str) -> np.ndarray:
    """PNG / JPEG (8 or 16 bit, grey, RGB, palette, with or without alpha) → linear float32."""
    from PIL import Image as PILImage

    with PILImage.open(path) as img:
        if img.mode in ("I", "I;16", "I;16B", "I;16L"):
            encoded = np.asarray(img, dtype=np.float64) / 65535.0
        else:
            encoded = np.asarray(img.convert("L" if img.mode in ("1", "L", "LA") else "RGB"), dtype=np.float64) / 255.0
    return tonemap.srgb_decode(encoded)


def _read_exr(path: str) -> np.ndarray:
    """R, G, B channels (or a single one such as Y) of the first part → float32."""
    import OpenEXR

    with OpenEXR.File(path, separate_channels=True) as f:
        channels = {name: c.pixels for name, c in f.channels().items()}
    if all(name in channels for name in "RGB"):
        return np.stack([channels[name] for name in "RGB"], axis=2).astype(np.float32)
    if "Y" in channels or len(channels) == 1:
        return np.asarray(channels.get("Y", next(iter(channels.values()))), dtype=np.float32)
    raise LumosError(f"no R, G, B or Y channels (has {', '.join(sorted(channels))})")


_PFM_HEADER = re.compile(rb"(P[Ff])\s+(\d+)\s+(\d+)\s+([-+0-9.eE]+)\s")


def _read_pfm(path: str) -> np.ndarray:
    """'PF' (colour) or 'Pf' (grey); the sign of the scale gives the byte order; rows stored bottom-up."""
    with open(path, "rb") as f:
        raw = f.read()
    m = _PFM_HEADER.match(raw)
    if m is None:
        raise LumosError("not a valid PFM file (bad header)")
    width, height, scale = int(m.group(2)), int(m.group(3)), float(m.group(4))
    shape = (height, width, 3) if m.group(1) == b"PF" else (height, width)
    count = int(np.prod(shape))
    body = raw[m.end():]
    if len(body) < 4 * count:
        raise LumosError(f"not a valid PFM file (truncated: {len(body)} of {4 * count} data bytes)")
    pixels = np.frombuffer(body, dtype="<f4" if scale < 0 else ">f4", count=count).reshape(shape)
    return pixels[::-1].astype(np.float32)


def _read_npy(path: str) -> np.ndarray:
    data = np.load(path, allow_pickle=False)
    if not np.issubdtype(data.dtype, np.number):
        raise LumosError(f"not an image: dtype {data.dtype}")
    return data
