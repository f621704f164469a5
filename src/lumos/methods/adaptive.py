"""Whitted's adaptive anti-aliasing, the classic method: rays through the pixel corners, shared with the
neighbours; where the four corners of a square differ by more than `adaptive_threshold`, the square is cut in four
through five new rays, down to `adaptive_depth` levels; each square's value is the mean of its corners, a pixel's
the area-weighted mean of its squares (see `methods.whitted`).
"""

from __future__ import annotations

import numpy as np

from ..kernels.camera import camera_cone, camera_ray
from ..kernels.jit import njit, njit_inline, njit_serial
from ..kernels.views import geometry_of, lighting_of, sky_of, surfaces_of, textures_of
from .whitted_trace import point_radiance, store_aovs, trace, trace_scratch


@njit_serial
def adaptive_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, mipmap, threshold,
                  max_level, corners, radiance, samples, terms, rays_per_row, corner_pass):
    """Both stages of adaptive anti-aliasing, in one kernel that traces from one place (one inlined copy of the
    tracer to compile, not two). With `corner_pass`, stage 1: one ray through every pixel corner (W+1 × H+1 of
    them, shared by neighbours), its radiance into corners[y, x, 0:3] and, when corners has 21 channels, its
    terms after it, for corner rows y0 … y1−1 (rays_per_row then has height + 1 entries, one per row of
    corners; radiance, samples and terms are not touched). Else stage 2: each pixel of rows y0 … y1−1 from its
    corners, its squares cut in four where the corners differ (`adaptive_pixel`); with 21-channel corners, also
    its terms. `mipmap`: textures filtered over each ray's cone, a pixel wide (`kernels.camera.camera_cone`)."""
    n = (np.int64(1) << max_level) + 1
    channels = corners.shape[2]
    _adaptive_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth,
                   camera_cone(cam_params, height, 1, mipmap), threshold, max_level,
                   corners, radiance, samples, terms, rays_per_row, trace_scratch(max_depth, 0, 0, channels > 3),
                   np.empty((n, n, channels)), np.full((n, n), -1, np.int64), np.zeros((1, 1)),
                   np.empty((4 * max_level + 4, 4), np.int64), np.empty(channels), np.empty((5, 2), np.int64),
                   corner_pass)


@njit
def _adaptive_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, cone, threshold,
                   max_level, corners, radiance, samples, terms, rays_per_row, scratch, grid, stamp, weights, stack,
                   value, pending, corner_pass):
    """(`adaptive_rows`; stack: the squares to visit, as ix, iy, size in cells, level; pending: the points of
    a square to trace before its quarters)"""
    channels = corners.shape[2]
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        for x in range(width + 1 if corner_pass else width):
            count, nr = adaptive_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, seed,
                                       max_depth, cone, threshold, max_level, corners, scratch, sky_of(sa), grid,
                                       stamp, stack, weights, value, pending, corner_pass)
            rays += nr
            if corner_pass:
                continue
            radiance[y, x, 0], radiance[y, x, 1], radiance[y, x, 2] = value[0], value[1], value[2]
            for k in range(3, channels):
                terms[y, x, k - 3] = value[k]
            samples[y, x] = count
        rays_per_row[y] += rays


@njit_inline
def adaptive_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, seed, max_depth, cone,
                   threshold, max_level, corners, scratch, sky, grid, stamp, stack, weights, value, pending,
                   corner_pass):
    """Pixel (x, y) by adaptive subdivision: value[:] = the area-weighted mean over its squares of their corners'
    values (every channel of `corners`: radiance, then the terms if present); returns (camera rays it took, rays
    traced beyond its corners). With `corner_pass`, instead the ray through corner (x, y) into corners[y, x]
    (returns 1 and the rays it traced).

    Its points live on a (2^max_level + 1)² grid, so a point shared by neighbouring squares is traced once;
    `stamp` marks the points already traced for this pixel. A square that is cut queues its untraced middles in
    `pending` (int64 (5, 2)) and its quarters on `stack`; the queue is traced before the next square is taken, in
    the order the middles were found, from the one call of the tracer below. With `weights` (n, n)
    (`lumos.explain`), each point's weight in the pixel is added to it; with logging on in `scratch`, each new
    point's tree goes to the log."""
    cells = np.int64(1) << max_level
    n = cells + 1
    inv = 1.0 / cells
    channels = grid.shape[2]
    explain = weights.shape[0] == n
    pixel = y * width + x
    key = (height + 1) * (width + 1) + pixel  # random keys of this pixel's extra points
    count = 1  # its own corner ray
    rays = 0
    queued, next_point = 0, 0  # the points in `pending`, and the next one to trace
    sp = 0
    if corner_pass:
        queued = 1
    else:
        for ch in range(channels):
            grid[0, 0, ch] = corners[y, x, ch]
            grid[0, cells, ch] = corners[y, x + 1, ch]
            grid[cells, 0, ch] = corners[y + 1, x, ch]
            grid[cells, cells, ch] = corners[y + 1, x + 1, ch]
            value[ch] = 0.0
        stamp[0, 0] = stamp[0, cells] = stamp[cells, 0] = stamp[cells, cells] = pixel
        stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = 0, 0, cells, 0
        sp = 1
    while True:
        if next_point < queued:  # the one place this method traces a camera ray
            if corner_pass:
                px = py = 0
                fx, fy, k, sample = np.float64(x), np.float64(y), y * (width + 1) + x, 0
            else:
                px, py = pending[next_point, 0], pending[next_point, 1]
                fx, fy, k, sample = x + px * inv, y + py * inv, key, py * n + px
            next_point += 1
            rgb, nr = point_radiance(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, fx, fy,
                                     seed, k, sample, max_depth, scratch, sky, cone)
            rays += nr
            if corner_pass:
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
            if stamp[py, px] == pixel:
                continue
            stamp[py, px] = pixel
            pending[queued, 0], pending[queued, 1] = px, py
            queued += 1
        for m in range(4):
            stack[sp, 0] = ix + (m % 2) * h
            stack[sp, 1] = iy + (m // 2) * h
            stack[sp, 2] = h
            stack[sp, 3] = level + 1
            sp += 1
    return count, rays


@njit_serial
def aov_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, mipmap,
              depth, normal, albedo, object_id, rays_per_row):
    """adaptive with AOVs: one more ray through each pixel centre, for the AOVs only. Rows y0 … y1−1."""
    _aov_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed,
              camera_cone(cam_params, height, 1, mipmap), depth, normal, albedo, object_id, rays_per_row,
              trace_scratch(np.int64(0)))


@njit
def _aov_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, cone, depth, normal, albedo, object_id,
              rays_per_row, scratch):
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        for x in range(width):
            o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, 0, 1, seed, y * width + x)
            rgb, n, info = trace(geo, surf, lit, tex, o, d, cone, cam_time[0], np.int64(0), seed, y * width + x, 0,
                                 scratch, sky_of(sa))
            rays += n
            store_aovs(x, y, info, depth, normal, albedo, object_id)
        rays_per_row[y] += rays
