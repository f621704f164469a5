"""Frames to a video file: `.mp4` (H.264, through imageio's ffmpeg plugin) or `.gif` (Pillow).

    write_video("turntable.mp4", frames, fps=24)      # frames: (H, W, 3) uint8 sRGB arrays, any iterable

The file is written whole or not at all (`io.atomic`): the frames are encoded into a temporary file beside the
destination, which replaces it only once the last frame is in, so a render that fails or is interrupted half-way
leaves no half video. MP4 is H.264 (libx264) in yuv420p, the form every player reads; that format needs even
dimensions, so an odd width or height gains one column or row, a copy of the last. GIF frames get an adaptive
palette of 256 colours each and loop forever.

MP4 needs the optional packages imageio and imageio-ffmpeg (`pip install "lumos[animation]"`, which bundles an
ffmpeg binary); GIF only Pillow, which lumos always has.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

import numpy as np

from ..errors import LumosError
from .atomic import check_output_path, one_line, write_atomically

VIDEO_SUFFIXES = (".mp4", ".gif")
#: imageio's quality for H.264 (0–10, 10 best): 8 keeps rendered edges and gradients clean at a modest size
MP4_QUALITY = 8


def is_video(path: str | os.PathLike | None) -> bool:
    """Whether `path` names a video file (.mp4, .gif) by its extension."""
    return path is not None and Path(path).suffix.lower() in VIDEO_SUFFIXES


def require(suffix: str) -> None:
    """Raise LumosError, one line with the command that fixes it, when the packages a `suffix` video needs are
    missing."""
    if suffix.lower() != ".mp4":
        return
    missing = []
    for module, package in (("imageio", "imageio"), ("imageio_ffmpeg", "imageio-ffmpeg")):
        try:
            __import__(module)
        except ImportError:
            missing.append(package)
    if missing:
        raise LumosError(f"writing .mp4 video needs {' and '.join(missing)}: pip install \"lumos[animation]\" "
                         f"(or pip install imageio imageio-ffmpeg)")


def check_video_path(path: str | os.PathLike) -> Path:
    """Check that a video could be written to `path` (extension, folder, the packages it needs) without writing
    anything; return it as a Path."""
    out = check_output_path(path, VIDEO_SUFFIXES, "cannot write video")
    require(out.suffix)
    return out


def even(frame: np.ndarray) -> np.ndarray:
    """`frame` with a copy of its last column and/or row added where its width or height is odd."""
    h, w = frame.shape[:2]
    if h % 2 or w % 2:
        frame = np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
    return frame


def _frame(frame, shape) -> np.ndarray:
    arr = np.asarray(frame)
    if arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[2] != 3:
        raise LumosError(f"video frames must be (H, W, 3) uint8 arrays, got {arr.dtype} {arr.shape}")
    if shape is not None and arr.shape != shape:
        raise LumosError(f"video frames must all have one size: {shape[1]}x{shape[0]}, then {arr.shape[1]}x"
                         f"{arr.shape[0]}")
    return np.ascontiguousarray(arr)


def _write_mp4(tmp: str, frames: Iterable, fps: float) -> int:
    import imageio.v2 as imageio

    count, shape, writer = 0, None, None
    try:
        for frame in frames:
            arr = _frame(frame, shape)
            shape = arr.shape
            if writer is None:
                writer = imageio.get_writer(tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                                            pixelformat="yuv420p", quality=MP4_QUALITY, macro_block_size=1,
                                            ffmpeg_log_level="error", output_params=["-movflags", "+faststart"])
            writer.append_data(even(arr))
            count += 1
    finally:
        if writer is not None:
            writer.close()
    return count


def _write_gif(tmp: str, frames: Iterable, fps: float) -> int:
    from PIL import Image

    images, shape = [], None
    for frame in frames:
        arr = _frame(frame, shape)
        shape = arr.shape
        images.append(Image.fromarray(arr, mode="RGB").quantize(256, method=Image.Quantize.MEDIANCUT,
                                                                dither=Image.Dither.NONE))
    if images:
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:], loop=0,
                       duration=max(1, round(1000.0 / fps)), disposal=1)
    return len(images)


def _guarded(frames: Iterable, failed: list):
    """`frames`, with any exception raised while making a frame also put in `failed` (to tell it from the
    encoder's)."""
    it = iter(frames)
    while True:
        try:
            frame = next(it)
        except StopIteration:
            return
        except BaseException as exc:
            failed.append(exc)
            raise
        yield frame


def write_video(path: str | os.PathLike, frames: Iterable, fps: float) -> int:
    """Encode `frames` ((H, W, 3) uint8 sRGB arrays, one size) at `fps` frames per second into `path` (.mp4 or
    .gif), atomically; the frames are consumed as they come (an iterator of renders is fine). Returns the
    number of frames written. Raises LumosError for a bad path, missing packages, no frames or an encoder
    failure; the destination is then left as it was."""
    out = check_video_path(path)
    if not fps > 0:
        raise LumosError(f"cannot write video '{path}': fps must be positive, got {fps}")
    write = _write_mp4 if out.suffix.lower() == ".mp4" else _write_gif
    counted, failed = [], []

    def encode(tmp: str) -> None:
        try:
            n = write(tmp, _guarded(frames, failed), fps)
        except (OSError, RuntimeError, ValueError) as exc:
            if failed and exc is failed[0] or isinstance(exc, LumosError):
                raise  # from making the frames (a render), not from the encoder
            raise LumosError(f"cannot write video '{path}': {one_line(exc)}") from None
        if n == 0:
            raise LumosError(f"cannot write video '{path}': there are no frames")
        counted.append(n)

    write_atomically(out, encode, f"cannot write video '{path}'")
    return counted[0]
