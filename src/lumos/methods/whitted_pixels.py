"""A Whitted pixel's camera rays, all traced from one place: supersampling (`spp` stratified, jittered samples of
the pixel, each with its own lens point and shutter time) and the classic adaptive anti-aliasing (rays through the
pixel corners, shared with the neighbours; where the four corners of a square differ by more than
`adaptive_threshold`, the square is cut in four through five new rays, down to `adaptive_depth` levels; each
square's value is the mean of its corners, a pixel's the area-weighted mean of its squares; see
`methods.whitted`).

Every stage of either (`SAMPLES`, `CORNERS`, `SQUARES`, and `AOVS`, the pixel-centre pass that adaptive's surface
AOVs take) is one kernel, `pixel_rows`, whose pixels call the tracer from one line of `pixel`: one inlined copy
of `whitted_trace.trace` to compile for the whole method, not one per stage (BENCHMARKS.md, issue 26).
"""

from __future__ import annotations

import numpy as np

from ..kernels.camera import camera_cone, camera_ray, camera_ray_at
from ..kernels.jit import njit, njit_inline, njit_serial
from ..kernels.rng import rand01
from ..kernels.views import geometry_of, lighting_of, sky_of, surfaces_of, textures_of
from .whitted_trace import LOG_FX, LOG_FY, shutter_time, store_aovs, trace, trace_scratch

#: What a pass of `pixel_rows` computes: each pixel's `spp` samples (antialias none and supersample); the ray
#: through every pixel corner (adaptive, stage 1); each pixel from its corners, cut into squares where they differ
#: (adaptive, stage 2); the surface AOVs alone, from one ray through each pixel centre (adaptive's AOVs).
SAMPLES, CORNERS, SQUARES, AOVS = 0, 1, 2, 3


@njit_serial
def pixel_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, stage, spp, seed, max_depth, mipmap,
               threshold, max_level, corners, radiance, depth, normal, albedo, object_id, samples, terms,
               rays_per_row):
    """One `stage` of the pixels of rows y0 … y1−1 (for CORNERS, corner rows y0 … y1−1: rays_per_row then has
    height + 1 entries). `corners` (rows+1, cols+1, channels) holds the corner rays' values for CORNERS and
    SQUARES; its channels say what each pixel keeps: 3, the radiance, or 21, the radiance and its terms (into
    terms[y, x, :18]); the other stages take a (1, 1, channels) stand-in. SAMPLES and SQUARES write radiance,
    terms and samples (camera rays per pixel); SAMPLES (from its first sample) and AOVS write depth, normal,
    albedo and object_id. `mipmap`: textures filtered over each ray's cone (`kernels.camera.camera_cone`)."""
    n = (np.int64(1) << max_level) + 1
    channels = corners.shape[2]
    cone = camera_cone(cam_params, height, spp if stage == SAMPLES else 1, mipmap)
    _band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, stage, spp, seed, max_depth, cone, threshold,
          max_level, corners, radiance, depth, normal, albedo, object_id, samples, terms, rays_per_row,
          trace_scratch(max_depth, 0, 0, channels > 3), np.empty((n, n, channels)), np.full((n, n), -1, np.int64),
          np.zeros((1, 1)), np.empty((4 * max_level + 4, 4), np.int64), np.empty(channels),
          np.empty((5, 2), np.int64))


@njit
def _band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, stage, spp, seed, max_depth, cone, threshold,
          max_level, corners, radiance, depth, normal, albedo, object_id, samples, terms, rays_per_row, scratch, grid,
          stamp, weights, stack, value, pending):
    """(`pixel_rows`; the scratch arrays are `pixel`'s)"""
    channels = corners.shape[2]
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        for x in range(width + 1 if stage == CORNERS else width):
            count, nr = pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, stage, spp,
                              seed, max_depth, cone, threshold, max_level, corners, scratch, sky_of(sa), grid, stamp,
                              stack, weights, value, pending, depth, normal, albedo, object_id)
            rays += nr
            if stage == SAMPLES or stage == SQUARES:
                radiance[y, x, 0], radiance[y, x, 1], radiance[y, x, 2] = value[0], value[1], value[2]
                for k in range(3, channels):
                    terms[y, x, k - 3] = value[k]
                samples[y, x] = count
        rays_per_row[y] += rays


@njit_inline
def pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, stage, spp, seed, max_depth, cone,
          threshold, max_level, corners, scratch, sky, grid, stamp, stack, weights, value, pending, depth, normal,
          albedo, object_id):
    """One `stage` (`pixel_rows`) of pixel (x, y), or for CORNERS of corner (x, y); returns (camera rays it took,
    rays traced). value[:] = the pixel's value in every channel of `corners` (radiance, then the terms if
    present): for SAMPLES the mean of its samples, for SQUARES the area-weighted mean over its squares of their
    corners' values. CORNERS writes corners[y, x]; SAMPLES (its first sample) and AOVS write the surface AOVs.

    A queue of points to trace, each traced from the one call of the tracer below: a pixel's samples, a corner,
    or the middles of a square being cut. Adaptive points live on a (2^max_level + 1)² grid, so a point shared
    by neighbouring squares is traced once; `stamp` marks the points already traced for this pixel. A square
    that is cut queues its untraced middles in `pending` (int64 (5, 2)) and its quarters on `stack`; the queue is
    traced before the next square is taken, in the order the middles were found. With `weights` (n, n)
    (`lumos.explain`), each point's weight in the pixel is added to it; with logging on in `scratch`, each new
    point's tree goes to the log."""
    cells = np.int64(1) << max_level
    n = cells + 1
    inv = 1.0 / cells
    channels = grid.shape[2]
    explain = weights.shape[0] == n
    log, log_n = scratch[7], scratch[8]
    pixel_key = y * width + x
    key = (height + 1) * (width + 1) + pixel_key  # random keys of this pixel's extra points
    count = 1  # its own corner ray
    rays = 0
    queued, next_point = 0, 0  # the points in the queue, and the next one to trace
    sp = 0
    for ch in range(channels):
        value[ch] = 0.0
    if stage == SAMPLES or stage == AOVS:
        queued = spp
    elif stage == CORNERS:
        queued = 1
    else:
        for ch in range(channels):
            grid[0, 0, ch] = corners[y, x, ch]
            grid[0, cells, ch] = corners[y, x + 1, ch]
            grid[cells, 0, ch] = corners[y + 1, x, ch]
            grid[cells, cells, ch] = corners[y + 1, x + 1, ch]
        stamp[0, 0] = stamp[0, cells] = stamp[cells, 0] = stamp[cells, cells] = pixel_key
        stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = 0, 0, cells, 0
        sp = 1
    while True:
        if next_point < queued:  # the one place this method traces a camera ray
            s = next_point
            next_point += 1
            px = py = 0
            fx, fy = np.float64(x), np.float64(y)
            if stage == SAMPLES or stage == AOVS:  # sample s of the pixel
                k, sample = pixel_key, s
                o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, s, spp, seed, pixel_key)
                time = shutter_time(cam_time, seed, k, sample) if stage == SAMPLES else cam_time[0]
            else:  # a point of the adaptive grid: a corner, or a middle of a square
                k, sample = y * (width + 1) + x, 0
                if stage == SQUARES:
                    px, py = pending[s, 0], pending[s, 1]
                    fx, fy, k, sample = x + px * inv, y + py * inv, key, py * n + px
                lx, ly = rand01(seed, k, sample, 2), rand01(seed, k, sample, 3)
                o, d = camera_ray_at(cam_vecs, cam_params, width, height, fx, fy, lx, ly)
                time = shutter_time(cam_time, seed, k, sample)
            first = log_n[0]
            rgb, nr, info = trace(geo, surf, lit, tex, o, d, cone, time, max_depth, seed, k, sample, scratch, sky)
            rays += nr
            if stage == SAMPLES or stage == AOVS:
                value[0], value[1], value[2] = value[0] + rgb[0], value[1] + rgb[1], value[2] + rgb[2]
                for ch in range(3, channels):
                    value[ch] += scratch[6][ch - 3]
                if s == 0:
                    store_aovs(x, y, info, depth, normal, albedo, object_id)
                continue
            if 0 <= first < log.shape[0]:  # where the camera ray went through the image (lumos.explain)
                log[first, LOG_FX] = fx
                log[first, LOG_FY] = fy
            if stage == CORNERS:
                corners[y, x, 0], corners[y, x, 1], corners[y, x, 2] = rgb
                for ch in range(3, corners.shape[2]):  # the terms, when they are asked for
                    corners[y, x, ch] = scratch[6][ch - 3]
            else:
                grid[py, px, 0], grid[py, px, 1], grid[py, px, 2] = rgb
                for ch in range(3, channels):
                    grid[py, px, ch] = scratch[6][ch - 3]
                count += 1
            continue
        if sp == 0:
            break
        sp -= 1
        ix, iy, size, level = stack[sp, 0], stack[sp, 1], stack[sp, 2], stack[sp, 3]
        # the four corners, as grid rows (iy) and columns (ix)
        worst = 0.0
        for ch in range(3):
            c0 = min(max(grid[iy, ix, ch], 0.0), 1.0)
            c1 = min(max(grid[iy, ix + size, ch], 0.0), 1.0)
            c2 = min(max(grid[iy + size, ix, ch], 0.0), 1.0)
            c3 = min(max(grid[iy + size, ix + size, ch], 0.0), 1.0)
            worst = max(worst, max(c0, c1, c2, c3) - min(c0, c1, c2, c3))
        if level >= max_level or worst <= threshold:
            q = 0.25 * (size * inv) * (size * inv)  # the mean of the corners, weighted by the area
            ex, ey = ix + size, iy + size
            for ch in range(channels):
                value[ch] += q * (grid[iy, ix, ch] + grid[iy, ex, ch] + grid[ey, ix, ch] + grid[ey, ex, ch])
            if explain:
                weights[iy, ix] += q
                weights[iy, ex] += q
                weights[ey, ix] += q
                weights[ey, ex] += q
            continue
        h = size // 2
        # the five middles (top, left, centre, right, bottom) that are not traced yet, queued in that order
        queued, next_point = 0, 0
        for m in range(5):
            if m == 0:
                px, py = ix + h, iy
            elif m == 1:
                px, py = ix, iy + h
            elif m == 2:
                px, py = ix + h, iy + h
            elif m == 3:
                px, py = ix + size, iy + h
            else:
                px, py = ix + h, iy + size
            if stamp[py, px] == pixel_key:
                continue
            stamp[py, px] = pixel_key
            pending[queued, 0], pending[queued, 1] = px, py
            queued += 1
        for m in range(4):
            stack[sp, 0] = ix + (m % 2) * h
            stack[sp, 1] = iy + (m // 2) * h
            stack[sp, 2] = h
            stack[sp, 3] = level + 1
            sp += 1
    if stage == SAMPLES or stage == AOVS:
        mean = 1.0 / spp
        for ch in range(channels):
            value[ch] *= mean
        return spp, rays
    return count, rays
