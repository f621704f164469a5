"""Whitted ray tracing: rays from the eye, recursing at each hit into shadow, reflected and transmitted rays.

    I = emission + I_local + w_r·I(reflected) + w_t·I(transmitted)              (DESIGN.md §3, recursion)

- I_local is the classic model with shadow rays to every light sample; a shadow ray is blocked by an opaque
  object and multiplied by kt for each transparent object it passes through (coloured glass, coloured shadow).
- w_r = kr and w_t = kt, or with `fresnel: true`, w_r = kr + kt·F and w_t = kt·(1 − F), F from Schlick.
- Reflection is the mirror direction about the shading normal. Refraction follows Snell's law: every ray
  carries the list of solids it is inside (innermost last; air outside), so a ray entering glass from water
  bends by n_water/n_glass (nested dielectrics); on total internal reflection the transmitted part takes the
  mirror direction. A surface that is not a solid (plane, disk, triangle) lets a transmitted ray through
  unbent, as a thin sheet.
- `max_depth` counts bounces (0: no secondary rays); a ray whose weight along its path (the product of the
  w's, largest channel) falls below `CUTOFF` is not traced. The recursion runs on an explicit stack.

Anti-aliasing (`antialias`): `none` (pixel centres), `supersample` (`spp` stratified jittered samples, a box
filter; with a thin-lens camera or a shutter interval each sample also takes its own lens point and time: depth
of field and motion blur), or `adaptive`: the classic method — rays through the pixel corners, shared with the
neighbours; where the four corners of a square differ by more than `adaptive_threshold` (any channel of the
displayed, [0, 1]-clamped colour), the square is cut in four through five new rays, down to `adaptive_depth`
levels (a point shared by neighbouring squares is traced once); each square's value is the mean of its corners,
a pixel's the area-weighted mean of its squares. The `samples` AOV holds the number of camera rays each pixel
took.

Textures and bump maps are filtered over each ray's cone (`kernels.camera.camera_cone`; the secondary rays carry
it on, `whitted_trace.trace`) unless `mipmap` is false.
"""

from __future__ import annotations

import numpy as np

from ..compile.camera import camera_arrays
from ..kernels.camera import camera_cone
from ..kernels.jit import njit_alloc
from ..errors import LumosError
from ..kernels.views import owned_views
from .common import SURFACE_AOVS, TERM_CHANNELS, Film, finish, kernel_arrays, row_bands, run_bands, start
from .whitted_pixels import AOVS, CORNERS, SAMPLES, SQUARES, pixel, pixel_rows
from .whitted_trace import LOG_DEPTH, LOG_FX, LOG_FY, trace_scratch

AA_NONE, AA_SUPERSAMPLE, AA_ADAPTIVE = 0, 1, 2
ANTIALIAS_MODES = {"none": AA_NONE, "supersample": AA_SUPERSAMPLE, "adaptive": AA_ADAPTIVE}


@njit_alloc
def explain_pixel(sa, cam_vecs, cam_params, cam_time, width, height, x, y, mode, spp, seed, max_depth, threshold,
                  max_level, log_rows, mipmap=True):
    """Pixel (x, y) exactly as `render_whitted` makes it (with `mipmap` as the render's setting), with every ray
    logged (`lumos.explain`).

    Returns (value (3,), log (rows, LOG_COLS), per-light log (rows · n_lights, PER_LIGHT_SIZE): row r's lights
    from r · n_lights, rows used, weight of each row's camera ray in the pixel (rows,), 0 for the rays it
    spawned)."""
    geo, surf, lit, tex = owned_views(sa)
    sky = (sa.env_pixels, sa.env_info, sa.background)  # (built here, with the runtime: see views.owned_views)
    scratch = trace_scratch(max_depth, log_rows, lit.light_kind.shape[0])
    log, log_n = scratch[7], scratch[8]
    weight = np.zeros(log_rows)
    value = np.zeros(3)
    cone = camera_cone(cam_params, height, spp if mode != AA_ADAPTIVE else 1, mipmap)
    cells = np.int64(1) << max_level
    n = cells + 1
    # the buffers the pixel writes, as far as its own row and column reach: rows 0 … y (+1 for its corners) and
    # columns 0 … x (+1), not the whole image's (`pixel` takes the image's size apart, for its random keys)
    depth, normal, albedo = np.zeros((y + 1, x + 1)), np.zeros((y + 1, x + 1, 3)), np.zeros((y + 1, x + 1, 3))
    object_id = np.zeros((y + 1, x + 1), np.int32)
    grid = np.empty((n, n, 3))
    stamp = np.full((n, n), -1, np.int64)
    stack = np.empty((4 * max_level + 4, 4), np.int64)
    pending = np.empty((5, 2), np.int64)
    weights = np.zeros((n, n))
    corners = np.zeros((y + 2, x + 2, 3))
    grid_row = np.full((n, n), -1, np.int64)  # the log row of each point's camera ray
    start = 0
    # one call of the pixel (one inlined tracer): its samples, or its four corners (top left, top right, bottom
    # left, bottom right) and then its squares
    for step in range(1 if mode != AA_ADAPTIVE else 5):
        stage, px, py = SAMPLES, x, y
        if mode == AA_ADAPTIVE and step < 4:
            stage, px, py = CORNERS, x + step % 2, y + step // 2
            grid_row[(py - y) * cells, (px - x) * cells] = log_n[0]
        elif mode == AA_ADAPTIVE:
            stage, start = SQUARES, log_n[0]
        k = spp if stage == SAMPLES else 1
        pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, px, py, stage, k, seed, max_depth,
              cone, threshold, max_level, corners, scratch, sky, grid, stamp, stack, weights, value, pending, depth,
              normal, albedo, object_id)
    if mode != AA_ADAPTIVE:
        for row in range(log_n[0]):
            if log[row, LOG_DEPTH] == 0.0:
                weight[row] = 1.0 / spp
        return value, log, scratch[9], log_n[0], weight
    for row in range(start, log_n[0]):
        if log[row, LOG_DEPTH] == 0.0:
            gx = np.int64(np.round((log[row, LOG_FX] - x) * cells))
            gy = np.int64(np.round((log[row, LOG_FY] - y) * cells))
            grid_row[gy, gx] = row
    for gy in range(n):
        for gx in range(n):
            if grid_row[gy, gx] >= 0:
                weight[grid_row[gy, gx]] = weights[gy, gx]
    return value, log, scratch[9], log_n[0], weight


def render_whitted(compiled, camera, settings, progress=None, rows=None) -> Film:
    """Whitted-trace `compiled` (a `CompiledScene`) through `camera` with `settings` (a `RenderSettings`); with
    `rows` = (y0, y1) only those rows (a cluster's tile; every pixel is computed from its own corners and
    samples, so a tile's pixels are those of the whole image)."""
    width, height = settings.width, settings.height
    threads, b = start(settings, bytes_per_pixel=80)
    cam_vecs, cam_params = camera_arrays(camera, settings.filter)
    cam_time = np.array(camera.shutter, dtype=np.float64)
    sa = kernel_arrays(pixel_rows, compiled.arrays)  # (compile.features)
    seed = np.int64(settings.seed)
    if settings.resolved_max_depth() is None:
        raise LumosError("render.max_depth: whitted needs a finite number of bounces (-1, unbounded, is for path)")
    max_depth = np.int64(settings.resolved_max_depth())
    mode = ANTIALIAS_MODES[settings.antialias]
    mipmap = bool(settings.mipmap)
    w, h = np.int64(width), np.int64(height)
    samples = np.zeros((height, width), np.int32)
    y_lo, y_hi = (0, height) if rows is None else rows
    bands = row_bands(height, rows=(y_lo, y_hi))
    corner_rays = np.zeros(height + 1, np.int64)
    channels = 3 + TERM_CHANNELS if b.want_terms else 3

    threshold, max_level = float(settings.adaptive_threshold), np.int64(settings.adaptive_depth)

    def stage_pass(stage, corners, counts, spp=1, depth=max_depth, level=max_level):
        """A pass of `pixel_rows` over a band of rows (`whitted_pixels`)."""
        return lambda r0, r1: pixel_rows(sa, cam_vecs, cam_params, cam_time, w, h, np.int64(r0), np.int64(r1),
                                         np.int64(stage), np.int64(spp), seed, depth, mipmap, threshold,
                                         np.int64(level), corners, b.radiance, b.depth, b.normal, b.albedo,
                                         b.object_id, samples, b.terms, counts)

    if mode == AA_ADAPTIVE:
        corners = np.zeros((height + 1, width + 1, channels))
        half = None if progress is None else (lambda f: progress(0.5 * f))
        run_bands(stage_pass(CORNERS, corners, corner_rays), height + 1, half,
                  row_bands(height + 1, rows=(y_lo, y_hi + 1)))
        rest = None if progress is None else (lambda f: progress(0.5 + 0.5 * f))
        run_bands(stage_pass(SQUARES, corners, b.rays_per_row), height, rest, bands)
        if set(settings.aov) & set(SURFACE_AOVS):  # one more ray through each pixel centre, for the AOVs only
            run_bands(stage_pass(AOVS, np.zeros((1, 1, 3)), b.rays_per_row, depth=np.int64(0), level=0), height, None,
                      bands)
    else:  # (no adaptive grid: level 0)
        spp = 1 if mode == AA_NONE else settings.spp
        run_bands(stage_pass(SAMPLES, np.zeros((1, 1, channels)), b.rays_per_row, spp=spp, level=0), height, progress,
                  bands)
    rays = int(corner_rays.sum())
    return finish(settings, b, threads, samples, rays + int(b.rays_per_row.sum()), primary_rays=int(samples.sum()))
