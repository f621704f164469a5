"""What every method shares: the film buffers it fills, thread settings, and row bands for progress reports."""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np

from ..errors import LumosError
from ..kernels.threads import parallel_for
from ..scene.model import TERM_AOVS
from .capabilities import check_settings

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


#: the methods whose top-level kernels take `kernel_arrays`: lean arrays for a plain scene (`compile.features`)
LEAN_METHODS = ("raycast", "whitted", "path")


def kernel_arrays(kernel, sa):
    """The scene arrays to call top-level `kernel` with: `sa` itself (the general arrays) where this process has
    compiled `kernel` for them or the kernel cache holds it so compiled (after `pip install .` or `lumos warmup`,
    always), else `compile.features.lean_arrays(sa)`, for which it compiles without the features the scene does not
    use: less to compile on a cold first render, the same image. LUMOS_LEAN_KERNELS=0 always takes the general
    arrays (`lumos warmup` does: it compiles what every scene can use), =1 the lean ones of a plain scene. (Under
    NUMBA_DISABLE_JIT the kernel is a Python function, which compiles nothing: the general arrays.)"""
    import os

    from ..compile.features import lean_arrays
    from ..kernels.cache import has_entry_for

    choice = os.environ.get("LUMOS_LEAN_KERNELS")
    if choice == "0" or not hasattr(kernel, "overloads"):
        return sa
    lean = lean_arrays(sa)
    if lean is sa or choice == "1":
        return lean
    general = numba.typeof(sa)
    if any(sig and sig[0] == general for sig in kernel.overloads) or has_entry_for(kernel, general):
        return sa
    return lean


def set_threads(threads: int | None) -> int:
    """Use `threads` worker threads (at most the cores Numba was started with); returns the number used."""
    available = numba.config.NUMBA_NUM_THREADS
    n = available if threads is None else threads
    if n > available:
        raise LumosError(f"--threads {n}: at most {available} threads are available (NUMBA_NUM_THREADS)")
    numba.set_num_threads(n)
    return n


def row_bands(height: int, bands: int = 48, rows: tuple[int, int] | None = None):
    """(y0, y1) ranges covering the image (or only its rows [rows[0], rows[1]): a tile of a cluster render), so a
    kernel can be run band by band between progress reports."""
    lo, hi = (0, height) if rows is None else rows
    step = max(1, -(-(hi - lo) // bands))
    return [(y0, min(hi, y0 + step)) for y0 in range(lo, hi, step)]


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


# -------------------------------------------------------------------------------------- one render's set-up

#: The AOVs a method's kernels write per pixel into the depth, normal, albedo and object id buffers.
SURFACE_AOVS = ("depth", "normal", "albedo", "object_id")


@dataclass
class Buffers:
    """What the classic methods' kernels write: radiance float32 (H, W, 3); the surface AOV buffers (or None
    where `start` was told to leave them out); the term buffer (H, W, TERM_CHANNELS), or a (1, 1, …) stand-in
    when no term is asked for; the rays traced per row."""

    radiance: np.ndarray
    depth: np.ndarray | None
    normal: np.ndarray | None
    albedo: np.ndarray | None
    object_id: np.ndarray | None
    terms: np.ndarray
    want_terms: bool
    rays_per_row: np.ndarray


def start(settings, bytes_per_pixel: int = 64, aovs_if_asked: bool = False) -> tuple[int, Buffers]:
    """Every render's first steps: refuse what the method cannot do (`capabilities.check_settings`) and images
    that would not fit in memory, take the threads asked for, and allocate the buffers. With `aovs_if_asked` the
    surface AOV buffers are allocated only when one of them is asked for (None otherwise: a kernel that takes
    None compiles without the stores). Returns (threads, buffers)."""
    width, height = settings.width, settings.height
    check_settings(settings)
    check_memory(width, height, bytes_per_pixel=bytes_per_pixel)
    threads = set_threads(settings.threads)
    want = not aovs_if_asked or any(name in SURFACE_AOVS for name in settings.aov)
    depth, normal, albedo, object_id = allocate_aovs(height, width) if want else (None, None, None, None)
    want_terms = any(name in TERM_AOVS for name in settings.aov)
    terms = np.zeros((height, width, TERM_CHANNELS) if want_terms else (1, 1, TERM_CHANNELS), np.float32)
    return threads, Buffers(np.zeros((height, width, 3), np.float32), depth, normal, albedo, object_id, terms,
                            want_terms, np.zeros(height, np.int64))


def run_bands(rows, height: int, progress=None, bands=None) -> None:
    """rows(y0, y1) over the image in bands of rows (`row_bands`, or the (y0, y1) list given), each band's rows
    on the threads (`threads.parallel_for`), calling progress(fraction done) after each band."""
    bands = row_bands(height) if bands is None else bands
    total = sum(y1 - y0 for y0, y1 in bands)
    done = 0
    for y0, y1 in bands:
        parallel_for(rows, y0, y1)
        done += y1 - y0
        if progress is not None:
            progress(done / max(total, 1))


def finish(settings, buffers: Buffers, threads: int, samples, rays: int, primary_rays: int = 0) -> Film:
    """The `Film` of a render: its radiance, the AOVs asked for (the surface buffers, `samples` (H, W) int32 —
    camera rays per pixel — and the terms), the rays traced."""
    b = buffers
    all_aovs = {"depth": b.depth, "normal": b.normal, "albedo": b.albedo, "object_id": b.object_id,
                "samples": samples}
    if b.want_terms:
        all_aovs.update(term_aovs(b.terms))
    return Film(b.radiance, {name: all_aovs[name] for name in settings.aov}, rays, threads,
                primary_rays=primary_rays)


def background_image(environment, background, camera, width: int, height: int) -> np.ndarray:
    """float64 (H, W, 3): what a camera ray through each pixel's centre sees where it leaves the scene, for the
    methods that scan-convert (raster, radiosity's display): the environment (`CompiledScene.environment`) looked
    up along it as the ray methods do (`kernels.environment.sky_radiance`: bilinear), or the background colour."""
    out = np.empty((height, width, 3))
    if environment is None:
        out[:] = np.asarray(background, np.float64)
        return out
    from ..compile.camera import camera_arrays
    from ..kernels.layout import ENV_COS, ENV_SIN
    from ..kernels.queries import camera_rays_kernel
    from ..mesh.directions import lat_long_bilinear

    pixels, _, _, info = environment
    vecs, params = camera_arrays(camera)
    fx, fy = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    origins, d = np.empty((width * height, 3)), np.empty((width * height, 3))
    camera_rays_kernel(vecs, params, np.int64(width), np.int64(height), fx.ravel(), fy.ravel(), origins, d)
    c, s = info[ENV_COS], info[ENV_SIN]
    turned = np.column_stack([c * d[:, 0] - s * d[:, 2], d[:, 1], s * d[:, 0] + c * d[:, 2]])  # by the rotation
    out[:] = lat_long_bilinear(pixels, turned.reshape(height, width, 3))
    return out
