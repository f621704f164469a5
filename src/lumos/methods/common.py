"""What every method shares: the film buffers it fills, thread settings, and row bands for progress reports."""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np

from ..errors import LumosError
from ..scene.model import TERM_AOVS

#: Channels of a method's term buffer (H, W, TERM_CHANNELS): each of TERM_AOVS as (r, g, b), in that order.
TERM_CHANNELS = 3 * len(TERM_AOVS)


@dataclass
class Film:
    """A method's output: linear radiance float32 (H, W, 3), the requested AOVs, and how many rays it traced."""

    radiance: np.ndarray
    aovs: dict = field(default_factory=dict)
    rays: int = 0
    threads: int = 1
    primary_rays: int = 0  # camera rays (methods that count them apart)
    extra: dict = field(default_factory=dict)  # method-specific figures for the stats (path: spp taken, passes)


def allocate_aovs(height: int, width: int):
    """Buffers for every AOV (depth, normal, albedo, object_id); methods fill all, the film keeps the requested."""
    depth = np.full((height, width), np.inf, np.float32)
    normal = np.zeros((height, width, 3), np.float32)
    albedo = np.zeros((height, width, 3), np.float32)
    object_id = np.full((height, width), -1, np.int32)
    return depth, normal, albedo, object_id


def term_aovs(terms: np.ndarray) -> dict:
    """The term AOVs of a (H, W, TERM_CHANNELS) buffer: {"ambient": (H, W, 3) float32, ...}."""
    return {name: np.ascontiguousarray(terms[:, :, 3 * k:3 * k + 3], np.float32) for k, name in enumerate(TERM_AOVS)}


def set_threads(threads: int | None) -> int:
    """Use `threads` worker threads (at most the cores Numba was started with); returns the number used."""
    available = numba.config.NUMBA_NUM_THREADS
    n = available if threads is None else threads
    if n > available:
        raise LumosError(f"--threads {n}: at most {available} threads are available (NUMBA_NUM_THREADS)")
    numba.set_num_threads(n)
    return n


def row_bands(height: int, bands: int = 48):
    """(y0, y1) ranges covering the image, so a kernel can be run band by band between progress reports."""
    step = max(1, -(-height // bands))
    return [(y0, min(height, y0 + step)) for y0 in range(0, height, step)]


def available_memory() -> int | None:
    """Bytes the system can give without swapping (MemAvailable counts reclaimable cache; free pages do not)."""
    import os

    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return None


def check_memory(width: int, height: int, bytes_per_pixel: int = 64) -> None:
    """Refuse images whose buffers would not fit in memory, before allocating anything."""
    need = width * height * bytes_per_pixel
    avail = available_memory()
    if avail is None:
        return
    if need > 0.8 * avail:
        raise LumosError(
            f"render: {width}x{height} needs about {need / 2**30:.1f} GiB of buffers, "
            f"more than the {avail / 2**30:.1f} GiB of memory available"
        )
