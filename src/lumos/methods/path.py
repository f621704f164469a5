"""Path tracing's driver: samples split into passes (progress, checkpoints, --time-limit, Ctrl-C) and blocks
(the order the sums are added in); the integrator is `methods.path_trace`.

The image is refined pass by pass; each pass adds samples [s0, s1) to every pixel. A pixel's samples are summed in
blocks of `SAMPLE_BLOCK`: block b's samples [b·SAMPLE_BLOCK, (b+1)·SAMPLE_BLOCK) are summed in sample order from
zero into float64 buffers (`PathSums`), and each finished block is then added to the image's sums, in block order.
Every random number is a function of (seed, pixel, sample, dimension), so the image is the same, bit for bit, for
any thread count, any split of the samples into passes, and any split of the blocks and rows over processes or
machines: `lumos.cluster` renders (block, rows) pieces on Dask workers with `render_block` and adds them with
`PathSums.add` in block order, as `render_path` does here.
"""

from __future__ import annotations

import signal
import threading
import time as _time
from dataclasses import dataclass

import numpy as np

from ..compile.camera import camera_arrays
from ..kernels.threads import parallel_for
from .capabilities import check_settings
from .common import Film, check_memory, kernel_arrays, row_bands, set_threads
from .path_trace import (
    FILTER_BOX,
    FILTER_CENTRE,
    FILTER_GAUSSIAN,
    KEEP_DIRECT,
    KEEP_GUIDES,
    KEEP_SQUARES,
    MODE_BSDF,
    MODE_LIGHT,
    MODE_MIS,
    SAMPLER_INDEPENDENT,
    SAMPLER_SOBOL,
    pass_rows,
)

#: Samples of a pixel summed on their own before they join the image's sums (see the module's docstring), fixed
#: so that every split adds the same numbers in the same order. Large, because every block of a cluster render
#: brings one image of float64 sums back to the machine that adds them, the one part of the work that does not
#: spread over the workers (docs/cluster.md: 1024 keeps it under 2% of the work on 100 workers); a cluster cuts
#: a block into bands of rows instead. A render of at most SAMPLE_BLOCK samples sums them in plain sample order.
SAMPLE_BLOCK = 1024
#: Seconds a pass should take once the first pass has shown the speed (progress, --time-limit, Ctrl-C).
PASS_SECONDS = 1.0
_MODES = {"mis": MODE_MIS, "light": MODE_LIGHT, "bsdf": MODE_BSDF}


@dataclass(frozen=True)
class PathJob:
    """Everything a path render reads besides the samples and rows it is asked for: the scene's arrays and emitter
    table, the camera's arrays, and the settings as the kernel takes them (NumPy scalars). Picklable and small:
    what a cluster ships once to each worker."""

    sa: tuple
    em: tuple
    cam_vecs: np.ndarray
    cam_params: np.ndarray
    cam_time: np.ndarray
    width: np.int64
    height: np.int64
    spp: np.int64
    seed: np.int64
    max_depth: np.int64
    mode: np.int64
    sampler: np.int64
    filter_kind: np.int64
    keep: np.int64
    block: int  # SAMPLE_BLOCK when the job was made (a worker reads it here, not from its own module)

    @property
    def blocks(self) -> int:
        """Number of sample blocks: the last one holds the remainder of spp."""
        return -(-int(self.spp) // self.block)

    def block_samples(self, block: int) -> tuple[int, int]:
        """Samples [s0, s1) of block `block`."""
        s0 = block * self.block
        return s0, min(s0 + self.block, int(self.spp))


def path_job(compiled, camera, settings) -> PathJob:
    """The `PathJob` of rendering `compiled` (with its `emitters`) through `camera` with `settings`."""
    cam_vecs, cam_params = camera_arrays(camera)
    max_depth = settings.resolved_max_depth()
    return PathJob(
        sa=compiled.arrays, em=compiled.emitters, cam_vecs=cam_vecs, cam_params=cam_params,
        cam_time=np.array(camera.shutter, dtype=np.float64), width=np.int64(settings.width),
        height=np.int64(settings.height), spp=np.int64(settings.spp), seed=np.int64(settings.seed),
        max_depth=np.int64(-1 if max_depth is None else max_depth), mode=np.int64(_MODES[settings.sampling]),
        sampler=np.int64(SAMPLER_SOBOL if settings.sampler == "sobol" else SAMPLER_INDEPENDENT),
        filter_kind=np.int64(FILTER_CENTRE if settings.antialias == "none" else
                             FILTER_GAUSSIAN if settings.filter == "gaussian" else FILTER_BOX),
        keep=np.int64(_keep(settings)), block=SAMPLE_BLOCK)


class PathSums:
    """Float64 sums of some samples over rows y0 … y0+rows−1 (the whole image unless cut with `rows`): radiance
    (rows, W, 3); its squares and the guides (albedo, normal, emission seen, direct light: rows, W, 12) where the
    job's keep bits ask for them ((1, 1, C) stand-ins the kernel never touches otherwise); depth and object id of
    sample 0; the rays traced and the samples dropped per row."""

    def __init__(self, job: PathJob):
        h, w, keep = int(job.height), int(job.width), int(job.keep)
        self.y0, self.keep = 0, keep
        self.sums = np.zeros((h, w, 3))
        self.sums2 = np.zeros((h, w, 3) if keep & KEEP_SQUARES else (1, 1, 3))
        self.guides = np.zeros((h, w, 12) if keep & (KEEP_GUIDES | KEEP_DIRECT) else (1, 1, 12))
        self.depth = np.full((h, w), np.inf, np.float32)
        self.object_id = np.full((h, w), -1, np.int32)
        self.rays_per_row = np.zeros(h, np.int64)
        self.bad_per_row = np.zeros(h, np.int64)
        self.empty = True

    def trace(self, job: PathJob, y0: int, y1: int, s0: int, s1: int, threads: int | None = None) -> None:
        """Add samples [s0, s1) of rows y0 … y1−1 (whole-image buffers only), the rows spread over the threads."""
        s0, s1 = np.int64(s0), np.int64(s1)
        sa = kernel_arrays(pass_rows, job.sa)  # (compile.features)
        parallel_for(lambda r0, r1: pass_rows(
            sa, job.em, job.cam_vecs, job.cam_params, job.cam_time, job.width, job.height, np.int64(r0),
            np.int64(r1), s0, s1, job.spp, job.seed, job.max_depth, job.mode, job.sampler, job.filter_kind,
            job.keep, self.sums, self.sums2, self.guides, self.depth, self.object_id, self.rays_per_row,
            self.bad_per_row), y0, y1, threads=threads)
        self.empty = False

    #: the buffers, by attribute name (what a piece of a cluster render carries)
    BUFFERS = ("sums", "sums2", "guides", "depth", "object_id", "rays_per_row", "bad_per_row")

    @classmethod
    def of_buffers(cls, y0: int, keep: int, buffers: dict) -> "PathSums":
        """Sums over rows y0 … from the `BUFFERS` given (a piece sent back by a worker or read from disk)."""
        part = object.__new__(cls)
        part.y0, part.keep, part.empty = int(y0), int(keep), False
        for name in cls.BUFFERS:
            setattr(part, name, buffers[name])
        return part

    def rows(self, y0: int, y1: int, first_block: bool = True) -> "PathSums":
        """A copy of rows y0 … y1−1 (what a cluster worker sends back); without `first_block` (the sums hold no
        sample 0) depth and object ids are left out ((1, 1) stand-ins: `add` reads them only from block 0)."""
        return PathSums.of_buffers(y0, self.keep, {
            name: (getattr(self, name)[y0:y1].copy() if self._kept(name, first_block)
                   else getattr(self, name)[:1, :1].copy())
            for name in self.BUFFERS})

    def add(self, part: "PathSums", first_block: bool) -> None:
        """Add `part`'s sums (over its rows) to these; with `first_block` (part holds sample 0) take its depth
        and object ids. Elementwise float64 additions: adding blocks in block order gives the same bits however
        the rows were cut."""
        rows = slice(part.y0, part.y0 + len(part.rays_per_row))
        self.sums[rows] += part.sums
        if self._kept("sums2"):
            self.sums2[rows] += part.sums2
        if self._kept("guides"):
            self.guides[rows] += part.guides
        if first_block:
            self.depth[rows] = part.depth
            self.object_id[rows] = part.object_id
        self.rays_per_row[rows] += part.rays_per_row
        self.bad_per_row[rows] += part.bad_per_row
        self.empty = False

    def _kept(self, name: str, first_block: bool = True) -> bool:
        """Whether buffer `name` is a per-pixel one (not a stand-in)."""
        if name in ("depth", "object_id"):
            return first_block
        bits = {"sums2": KEEP_SQUARES, "guides": KEEP_GUIDES | KEEP_DIRECT}.get(name)
        return bits is None or bool(self.keep & bits)

    def clear(self) -> None:
        for buf in (self.sums, self.sums2, self.guides, self.rays_per_row, self.bad_per_row):
            buf[...] = 0
        self.depth[...] = np.inf
        self.object_id[...] = -1
        self.empty = True

    def plus(self, other: "PathSums", first_block: bool) -> "PathSums":
        """A new `PathSums`: these plus `other` (the image so far, while a block is under way)."""
        both = self.rows(0, len(self.rays_per_row))
        both.add(other, first_block)
        return both


def render_block(job: PathJob, block: int, y0: int, y1: int, threads: int | None = None) -> PathSums:
    """The sums of sample block `block` over rows y0 … y1−1, from zero (a cluster's unit of work)."""
    s0, s1 = job.block_samples(block)
    acc = PathSums(job)
    acc.trace(job, y0, y1, s0, s1, threads)
    return acc.rows(y0, y1, first_block=block == 0)


class _StopOnSigint:
    """While rendering in the main thread: the first Ctrl-C asks to stop after the current pass (the image is
    kept); a second one interrupts at once."""

    def __init__(self):
        self.requested = False
        self._previous = None

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
        return self

    def _handle(self, signum, frame):
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    def __exit__(self, *exc):
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
        return False


def render_path(compiled, camera, settings, progress=None, on_pass=None) -> Film:
    """Path-trace `compiled` (a `CompiledScene` with its `emitters`) through `camera` with `settings`.

    `progress(fraction)` is called after each band of rows; `on_pass(film)` after each pass with the image so far
    (for checkpoints). Stops early after the pass that crosses `settings.time_limit`, or on Ctrl-C."""
    width, height = settings.width, settings.height
    check_settings(settings)
    check_memory(width, height, bytes_per_pixel=350)
    threads = set_threads(settings.threads)
    job = path_job(compiled, camera, settings)
    total, block = PathSums(job), PathSums(job)  # the finished blocks; the block under way
    bands = row_bands(height, bands=16)
    spp, done, passes, stopped = settings.spp, 0, 0, None
    started = _time.perf_counter()
    per_sample_s = None

    def film(final=False):
        sums = total if block.empty else total.plus(block, first_block=done <= job.block)
        return film_of(sums, done, settings, threads, passes, stopped, final)

    with _StopOnSigint() as sigint:
        while done < spp:
            # pass size: one sample first, then passes of about PASS_SECONDS
            n = 1 if per_sample_s is None else max(1, min(spp - done, int(PASS_SECONDS / max(per_sample_s, 1e-9))))
            t0 = _time.perf_counter()
            end = done + n
            while done < end:  # the pass, cut where blocks end
                cut = min(end, (done // job.block + 1) * job.block)
                for y0, y1 in bands:
                    block.trace(job, y0, y1, done, cut)
                    if progress is not None:
                        fraction = (done + (cut - done) * y1 / height) / spp
                        if settings.time_limit is not None:
                            fraction = max(fraction, min((_time.perf_counter() - started) / settings.time_limit, 1.0))
                        progress(min(fraction, 1.0))
                if cut % job.block == 0 or cut == spp:
                    total.add(block, first_block=cut <= job.block)
                    block.clear()
                done = cut
            passes += 1
            per_sample_s = (_time.perf_counter() - t0) / n
            if sigint.requested:
                stopped = "interrupted"
            elif settings.time_limit is not None and _time.perf_counter() - started >= settings.time_limit:
                stopped = "time limit"
            if stopped is not None or done >= spp:
                break
            if on_pass is not None:
                on_pass(film())
    if not block.empty:  # stopped inside a block: its samples count
        total.add(block, first_block=done <= job.block)
        block.clear()
    return film(final=True)


def _keep(settings) -> int:
    """The `KEEP_*` bits the asked-for AOVs and the denoiser need."""
    aov = set(settings.aov)
    keep = KEEP_SQUARES if "variance" in aov else 0
    if settings.denoise or aov & {"albedo", "normal"}:
        keep |= KEEP_GUIDES
    if aov & {"direct", "indirect"}:
        keep |= KEEP_DIRECT
    return keep


def film_of(acc: PathSums, n: int, settings, threads: int, passes: int, stopped, final: bool) -> Film:
    """The image and the AOVs asked for, from the sums of n samples per pixel; denoised when asked and `final`."""
    sums, guides = acc.sums, acc.guides
    mean = (sums / n).astype(np.float32)
    aovs = {}

    def albedo_normal():
        albedo = (guides[:, :, :3] / n).astype(np.float32)
        normal = guides[:, :, 3:6] / n
        length = np.linalg.norm(normal, axis=2, keepdims=True)
        return albedo, np.where(length > 0, normal / np.maximum(length, 1e-30), 0.0).astype(np.float32)

    radiance = mean
    if settings.denoise and final:
        from ..denoise import denoise

        # the light seen directly has no noise to remove (only its edges' coverage): it is kept out of the
        # denoiser, whose network would smear a bright emitter's edges and shift its flat HDR interior
        emitted = (guides[:, :, 6:9] / n).astype(np.float32)
        radiance = denoise(np.maximum(mean - emitted, 0.0), *albedo_normal()) + emitted
    for name in settings.aov:
        if name == "depth":
            aovs[name] = acc.depth
        elif name == "object_id":
            aovs[name] = acc.object_id
        elif name in ("albedo", "normal"):
            aovs[name] = albedo_normal()[0 if name == "albedo" else 1]
        elif name == "samples":
            aovs[name] = np.full(acc.depth.shape, n, np.int32)
        elif name == "variance":
            variance = (np.maximum(acc.sums2 - sums * sums / n, 0.0) / (n * (n - 1.0)) if n > 1
                        else np.zeros_like(sums))
            aovs[name] = variance.astype(np.float32)
        elif name == "noisy":
            aovs[name] = mean
        elif name in ("direct", "indirect"):
            direct = (guides[:, :, 9:12] / n).astype(np.float32)
            aovs[name] = direct if name == "direct" else mean - direct
    extra = {"spp": int(n), "passes": int(passes), "stopped": stopped,
             "discarded_samples": int(acc.bad_per_row.sum())}
    return Film(radiance, aovs, int(acc.rays_per_row.sum()), threads, primary_rays=int(n) * acc.depth.size,
                extra=extra)
