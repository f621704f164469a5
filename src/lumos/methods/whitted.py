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
levels; each square's value is the mean of its corners, a pixel's the area-weighted mean of its squares. The
`samples` AOV holds the number of camera rays each pixel took.
"""

from __future__ import annotations

import numpy as np

from .. import config
from ..compile.camera import camera_arrays
from ..kernels.camera import camera_ray, camera_ray_at
from ..kernels.illumination import illuminate_whitted, is_solid
from ..kernels.jit import njit, njit_parallel, prange
from ..kernels.layout import (
    LIGHT_SPHERE,
    MAT_EMISSION,
    MAT_FRESNEL,
    MAT_BUMP,
    MAT_IOR,
    MAT_KT,
    MAT_SHININESS,
)
from ..kernels.optics import reflect, refract, schlick
from ..kernels.rng import rand01
from ..kernels.surface import offset_origin, shading_side, surface_at
from ..kernels.traverse import closest_hit
from ..kernels.texture import bump_normal, material_coeffs, surface_tangents
from ..kernels.views import geometry_of, lighting_of, surfaces_of, textures_of
from .common import Film, allocate_aovs, check_memory, row_bands, set_threads

#: Secondary rays whose path weight (largest channel) is below this are not traced.
CUTOFF = 1e-3
#: Nesting depth of the media a ray can be inside (a glass in water in a tank...).
MAX_MEDIA = 4
#: Random dimension of the shutter time (0–1 pixel position, 2–3 lens).
DIM_TIME = 4
AA_NONE, AA_SUPERSAMPLE, AA_ADAPTIVE = 0, 1, 2
_ANTIALIAS = {"none": AA_NONE, "supersample": AA_SUPERSAMPLE, "adaptive": AA_ADAPTIVE}


@njit
def _scratch(max_depth):
    """Per-thread work arrays for `trace`: the ray stack (origin, direction, weight; depth, media count;
    media objects and indices of refraction) and the BVH traversal stack."""
    size = 2 * max_depth + 4  # depth-first: at most one pending sibling per level, plus the ray in hand
    return (np.empty((size, 9)), np.empty((size, 2), np.int64), np.empty((size, MAX_MEDIA), np.int64),
            np.empty((size, MAX_MEDIA)), np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK))


@njit
def _push(st_f, st_i, st_mo, st_mi, sp, o, d, w0, w1, w2, depth, n_media, src_mo, src_mi, src, drop, add_obj, add_ior):
    """Push a ray; its media are those of stack entry `src` (already popped, still readable) without object
    `drop` (>= 0) and with (add_obj, add_ior) appended (add_obj >= 0)."""
    st_f[sp, 0], st_f[sp, 1], st_f[sp, 2] = o
    st_f[sp, 3], st_f[sp, 4], st_f[sp, 5] = d
    st_f[sp, 6], st_f[sp, 7], st_f[sp, 8] = w0, w1, w2
    st_i[sp, 0] = depth
    m = 0
    for k in range(n_media):
        if src_mo[src, k] == drop:
            drop = -2  # remove one occurrence only
            continue
        st_mo[sp, m] = src_mo[src, k]
        st_mi[sp, m] = src_mi[src, k]
        m += 1
    if add_obj >= 0 and m < MAX_MEDIA:
        st_mo[sp, m] = add_obj
        st_mi[sp, m] = add_ior
        m += 1
    st_i[sp, 1] = m
    return sp + 1


@njit
def trace(geo, surf, lit, tex, o, d, time, max_depth, seed, pixel, sample, scratch, background):
    """Radiance along the camera ray (o, d) at shutter time `time`.

    Returns (rgb, rays traced, (t, n_shading, kd, object id) of the primary hit; t = −1 on a miss)."""
    st_f, st_i, st_mo, st_mi, stack, stack_t = scratch
    r = g = b = 0.0
    rays = 0
    aov_t = -1.0
    aov_n = (0.0, 0.0, 0.0)
    aov_kd = (0.0, 0.0, 0.0)
    aov_obj = -1
    # the camera ray: weight 1, depth 0, in air
    st_f[0, 0], st_f[0, 1], st_f[0, 2] = o
    st_f[0, 3], st_f[0, 4], st_f[0, 5] = d
    st_f[0, 6] = st_f[0, 7] = st_f[0, 8] = 1.0
    st_i[0, 0] = 0
    st_i[0, 1] = 0
    sp = 1
    while sp > 0:
        sp -= 1
        top = sp
        ro = (st_f[top, 0], st_f[top, 1], st_f[top, 2])
        rd = (st_f[top, 3], st_f[top, 4], st_f[top, 5])
        w0, w1, w2 = st_f[top, 6], st_f[top, 7], st_f[top, 8]
        depth = st_i[top, 0]
        n_media = st_i[top, 1]
        hit = closest_hit(geo, ro, rd, 0.0, config.T_FAR, stack, stack_t, time)
        rays += 1
        t = hit[0]
        if t < 0.0:
            r += w0 * background[0]
            g += w1 * background[1]
            b += w2 * background[2]
            continue
        ref = hit[1]
        p, n_geo, n_sh, u, v, mat_id, obj, light = surface_at(surf, ro, rd, t, ref, hit[2], hit[3], hit[4], time)
        mat = lit.materials[mat_id]
        V = (-rd[0], -rd[1], -rd[2])
        entering = n_geo[0] * rd[0] + n_geo[1] * rd[1] + n_geo[2] * rd[2] < 0.0
        if mat[MAT_BUMP] >= 0.0:
            dpdu, dpdv = surface_tangents(surf, ref, hit[4], p, n_sh, time)
            n_sh = bump_normal(tex, mat, u, v, p, n_sh, dpdu, dpdv)
        n_s = shading_side(n_sh, n_geo, V)
        n_g = n_geo if entering else (-n_geo[0], -n_geo[1], -n_geo[2])
        # emitted light: one-sided for rect and disk area lights
        if light < 0 or lit.light_kind[light] == LIGHT_SPHERE or entering:
            r += w0 * mat[MAT_EMISSION]
            g += w1 * mat[MAT_EMISSION + 1]
            b += w2 * mat[MAT_EMISSION + 2]
        ka, kd, ks, kr = material_coeffs(tex, mat, u, v, p)  # the material's, or its texture's where it has one
        kt = (mat[MAT_KT], mat[MAT_KT + 1], mat[MAT_KT + 2])
        if depth == 0:
            aov_t, aov_n, aov_kd, aov_obj = t, n_s, kd, obj
        (lr, lg, lb), extra = illuminate_whitted(lit, geo, surf, p, n_s, n_g, V, ka, kd, ks, mat[MAT_SHININESS],
                                                 seed, pixel, sample, stack, stack_t, time)
        rays += extra
        r += w0 * lr
        g += w1 * lg
        b += w2 * lb
        if depth >= max_depth:
            continue
        # the weights of the two secondary rays
        wr0, wr1, wr2 = kr
        wt0, wt1, wt2 = kt
        transmit = wt0 > 0.0 or wt1 > 0.0 or wt2 > 0.0
        t_dir = rd
        drop, add_obj, add_ior = np.int64(-1), np.int64(-1), 1.0
        if transmit and is_solid(surf, ref):
            # the media on both sides of this surface
            n_out = st_mi[top, n_media - 1] if n_media > 0 else 1.0
            if entering:
                n1, n2 = n_out, mat[MAT_IOR]
                add_obj, add_ior = np.int64(obj), mat[MAT_IOR]
            else:
                n1 = n_out
                n2 = 1.0
                found = False
                for k in range(n_media - 1, -1, -1):  # the innermost medium once obj is left
                    if st_mo[top, k] == obj and not found:
                        found = True
                        continue
                    n2 = st_mi[top, k]
                    break
                drop = np.int64(obj)
            eta = n1 / n2
            cos_i = -(rd[0] * n_s[0] + rd[1] * n_s[1] + rd[2] * n_s[2])
            ok, t_dir = refract(rd, n_s, eta)
            if mat[MAT_FRESNEL] != 0.0:
                if ok:
                    cos_t = -(t_dir[0] * n_s[0] + t_dir[1] * n_s[1] + t_dir[2] * n_s[2])
                    F = schlick(max(cos_i, 0.0), eta, max(cos_t, 0.0))
                else:
                    F = 1.0
                wr0, wr1, wr2 = wr0 + wt0 * F, wr1 + wt1 * F, wr2 + wt2 * F
                wt0, wt1, wt2 = wt0 * (1.0 - F), wt1 * (1.0 - F), wt2 * (1.0 - F)
            if not ok:  # total internal reflection: the transmitted part goes the mirror way
                wr0, wr1, wr2 = wr0 + wt0, wr1 + wt1, wr2 + wt2
                transmit = False
        # the reflected ray first: it keeps the incident media, so the entry it overwrites (the ray in hand, already
        # read) still holds them for the transmitted ray's copy
        rw0, rw1, rw2 = w0 * wr0, w1 * wr1, w2 * wr2
        if max(rw0, rw1, rw2) >= CUTOFF:
            r_dir = reflect(rd, n_s)
            origin = offset_origin(p, n_geo, r_dir, config.RAY_EPSILON)
            sp = _push(st_f, st_i, st_mo, st_mi, sp, origin, r_dir, rw0, rw1, rw2, depth + 1, n_media, st_mo, st_mi,
                       top, np.int64(-1), np.int64(-1), 1.0)
        if transmit:
            tw0, tw1, tw2 = w0 * wt0, w1 * wt1, w2 * wt2
            if max(tw0, tw1, tw2) >= CUTOFF:
                origin = offset_origin(p, n_geo, t_dir, config.RAY_EPSILON)
                sp = _push(st_f, st_i, st_mo, st_mi, sp, origin, t_dir, tw0, tw1, tw2, depth + 1, n_media, st_mo,
                           st_mi, top, drop, add_obj, add_ior)
    return (r, g, b), rays, (aov_t, aov_n, aov_kd, aov_obj)


@njit
def _time_of(cam_time, seed, pixel, sample):
    """Shutter time of a sample: open + u·(close − open)."""
    if cam_time[1] <= cam_time[0]:
        return cam_time[0]
    return cam_time[0] + (cam_time[1] - cam_time[0]) * rand01(seed, pixel, sample, DIM_TIME)


@njit
def _store_aovs(x, y, info, depth, normal, albedo, object_id):
    t, n, kd, obj = info
    if t >= 0.0:
        depth[y, x] = t
        normal[y, x, 0], normal[y, x, 1], normal[y, x, 2] = n
        albedo[y, x, 0], albedo[y, x, 1], albedo[y, x, 2] = kd
        object_id[y, x] = obj


@njit_parallel
def _sample_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, spp, seed, max_depth,
                 radiance, depth, normal, albedo, object_id, samples, rays_per_row):
    """antialias none / supersample: `spp` camera rays per pixel (the pixel centre when spp is 1)."""
    for y in prange(y0, y1):
        geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
        scratch = _scratch(max_depth)
        rays = 0
        for x in range(width):
            pixel = y * width + x
            r = g = b = 0.0
            for s in range(spp):
                o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, s, spp, seed, pixel)
                time = _time_of(cam_time, seed, pixel, s)
                rgb, n, info = trace(geo, surf, lit, tex, o, d, time, max_depth, seed, pixel, s, scratch, sa.background)
                rays += n
                r += rgb[0]
                g += rgb[1]
                b += rgb[2]
                if s == 0:
                    _store_aovs(x, y, info, depth, normal, albedo, object_id)
            inv = 1.0 / spp
            radiance[y, x, 0] = r * inv
            radiance[y, x, 1] = g * inv
            radiance[y, x, 2] = b * inv
            samples[y, x] = spp
        rays_per_row[y] += rays


@njit
def _point(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, fx, fy, seed, key, sample, max_depth,
           scratch, background):
    """The radiance through image point (fx, fy); `key` and `sample` index its random numbers (lens, time)."""
    lx, ly = rand01(seed, key, sample, 2), rand01(seed, key, sample, 3)
    o, d = camera_ray_at(cam_vecs, cam_params, width, height, fx, fy, lx, ly)
    time = _time_of(cam_time, seed, key, sample)
    rgb, n, info = trace(geo, surf, lit, tex, o, d, time, max_depth, seed, key, sample, scratch, background)
    return rgb, n


@njit_parallel
def _corner_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, corners, rays_per_row):
    # rays_per_row here has height + 1 entries, one per row of corners
    """adaptive, stage 1: one ray through every pixel corner (W+1 × H+1 of them, shared by neighbours)."""
    for y in prange(y0, y1):
        geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
        scratch = _scratch(max_depth)
        rays = 0
        for x in range(width + 1):
            key = y * (width + 1) + x
            rgb, n = _point(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, np.float64(x),
                            np.float64(y), seed, key, 0, max_depth, scratch, sa.background)
            corners[y, x, 0], corners[y, x, 1], corners[y, x, 2] = rgb
            rays += n
        rays_per_row[y] += rays


@njit
def _contrast(c, k0, k1, k2, k3):
    """Largest spread over the channels of the four corners' displayed ([0, 1]-clamped) colours."""
    worst = 0.0
    for ch in range(3):
        a = min(max(c[k0, ch], 0.0), 1.0)
        b = min(max(c[k1, ch], 0.0), 1.0)
        e = min(max(c[k2, ch], 0.0), 1.0)
        f = min(max(c[k3, ch], 0.0), 1.0)
        worst = max(worst, max(a, b, e, f) - min(a, b, e, f))
    return worst


@njit_parallel
def _adaptive_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, threshold,
                   max_level, corners, radiance, samples, rays_per_row):
    """adaptive, stage 2: each pixel from its corners, its squares cut in four where the corners differ."""
    n_levels = max_level + 1
    for y in prange(y0, y1):
        geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
        scratch = _scratch(max_depth)
        # a square: x0, y0, size, weight; its corner colours in `col` (4 rows per square, in stack order)
        sq = np.empty((4 * n_levels + 4, 4))
        lvl = np.empty(4 * n_levels + 4, np.int64)
        col = np.empty((4 * (4 * n_levels + 4), 3))
        mid = np.empty((5, 3))
        rays = 0
        for x in range(width):
            key = (height + 1) * (width + 1) + y * width + x  # random keys of this pixel's extra points
            count = 1  # its corner ray
            sample = 0
            sq[0, 0], sq[0, 1], sq[0, 2], sq[0, 3] = x, y, 1.0, 1.0
            lvl[0] = 0
            for ch in range(3):
                col[0, ch] = corners[y, x, ch]
                col[1, ch] = corners[y, x + 1, ch]
                col[2, ch] = corners[y + 1, x, ch]
                col[3, ch] = corners[y + 1, x + 1, ch]
            sp = 1
            r = g = b = 0.0
            while sp > 0:
                sp -= 1
                k = 4 * sp
                fx, fy, size, weight = sq[sp, 0], sq[sp, 1], sq[sp, 2], sq[sp, 3]
                level = lvl[sp]
                if level >= max_level or _contrast(col, k, k + 1, k + 2, k + 3) <= threshold:
                    q = 0.25 * weight
                    r += q * (col[k, 0] + col[k + 1, 0] + col[k + 2, 0] + col[k + 3, 0])
                    g += q * (col[k, 1] + col[k + 1, 1] + col[k + 2, 1] + col[k + 3, 1])
                    b += q * (col[k, 2] + col[k + 1, 2] + col[k + 2, 2] + col[k + 3, 2])
                    continue
                # five new points: top, left, centre, right and bottom middles
                h = 0.5 * size
                pts = ((fx + h, fy), (fx, fy + h), (fx + h, fy + h), (fx + size, fy + h), (fx + h, fy + size))
                for i in range(5):
                    sample += 1
                    rgb, n = _point(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, pts[i][0],
                                    pts[i][1], seed, key, sample, max_depth, scratch, sa.background)
                    mid[i, 0], mid[i, 1], mid[i, 2] = rgb
                    rays += n
                count += 5
                # the parent's corners (top-left, top-right, bottom-left, bottom-right) before they are overwritten
                c00 = (col[k, 0], col[k, 1], col[k, 2])
                c10 = (col[k + 1, 0], col[k + 1, 1], col[k + 1, 2])
                c01 = (col[k + 2, 0], col[k + 2, 1], col[k + 2, 2])
                c11 = (col[k + 3, 0], col[k + 3, 1], col[k + 3, 2])
                top_m = (mid[0, 0], mid[0, 1], mid[0, 2])
                left_m = (mid[1, 0], mid[1, 1], mid[1, 2])
                centre = (mid[2, 0], mid[2, 1], mid[2, 2])
                right_m = (mid[3, 0], mid[3, 1], mid[3, 2])
                bottom_m = (mid[4, 0], mid[4, 1], mid[4, 2])
                children = (
                    (fx, fy, c00, top_m, left_m, centre),
                    (fx + h, fy, top_m, c10, centre, right_m),
                    (fx, fy + h, left_m, centre, c01, bottom_m),
                    (fx + h, fy + h, centre, right_m, bottom_m, c11),
                )
                for i in range(4):
                    cx, cy, a0, a1, a2, a3 = children[i]
                    sq[sp, 0], sq[sp, 1], sq[sp, 2], sq[sp, 3] = cx, cy, h, 0.25 * weight
                    lvl[sp] = level + 1
                    j = 4 * sp
                    col[j, 0], col[j, 1], col[j, 2] = a0
                    col[j + 1, 0], col[j + 1, 1], col[j + 1, 2] = a1
                    col[j + 2, 0], col[j + 2, 1], col[j + 2, 2] = a2
                    col[j + 3, 0], col[j + 3, 1], col[j + 3, 2] = a3
                    sp += 1
            radiance[y, x, 0] = r
            radiance[y, x, 1] = g
            radiance[y, x, 2] = b
            samples[y, x] = count
        rays_per_row[y] += rays


@njit_parallel
def _aov_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth,
              depth, normal, albedo, object_id, rays_per_row):
    """adaptive with AOVs: one more ray through each pixel centre, for the AOVs only."""
    for y in prange(y0, y1):
        geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
        scratch = _scratch(np.int64(0))
        rays = 0
        for x in range(width):
            o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, 0, 1, seed, y * width + x)
            rgb, n, info = trace(geo, surf, lit, tex, o, d, cam_time[0], np.int64(0), seed, y * width + x, 0, scratch,
                                 sa.background)
            rays += n
            _store_aovs(x, y, info, depth, normal, albedo, object_id)
        rays_per_row[y] += rays


def render_whitted(compiled, camera, settings, progress=None) -> Film:
    """Whitted-trace `compiled` (a `CompiledScene`) through `camera` with `settings` (a `RenderSettings`)."""
    width, height = settings.width, settings.height
    check_memory(width, height, bytes_per_pixel=80)
    threads = set_threads(settings.threads)
    cam_vecs, cam_params = camera_arrays(camera)
    cam_time = np.array(camera.shutter, dtype=np.float64)
    sa = compiled.arrays
    seed = np.int64(settings.seed)
    max_depth = np.int64(settings.max_depth)
    mode = _ANTIALIAS[settings.antialias]
    radiance = np.zeros((height, width, 3), np.float32)
    depth, normal, albedo, object_id = allocate_aovs(height, width)
    samples = np.zeros((height, width), np.int32)
    rays_per_row = np.zeros(height, np.int64)
    bands = row_bands(height)
    if mode == AA_ADAPTIVE:
        corners = np.zeros((height + 1, width + 1, 3))
        corner_rays = np.zeros(height + 1, np.int64)
        total = len(bands) * 2
        done = 0
        for y0, y1 in row_bands(height + 1):
            _corner_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width), np.int64(height), np.int64(y0),
                         np.int64(y1), seed, max_depth, corners, corner_rays)
            done += 1
            if progress is not None:
                progress(min(done / total, 0.5))
        for y0, y1 in bands:
            _adaptive_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width), np.int64(height), np.int64(y0),
                           np.int64(y1), seed, max_depth, float(settings.adaptive_threshold),
                           np.int64(settings.adaptive_depth), corners, radiance, samples, rays_per_row)
            if progress is not None:
                progress(0.5 + 0.5 * y1 / height)
        if set(settings.aov) & {"depth", "normal", "albedo", "object_id"}:
            for y0, y1 in bands:
                _aov_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width), np.int64(height), np.int64(y0),
                          np.int64(y1), seed, max_depth, depth, normal, albedo, object_id, rays_per_row)
    else:
        spp = np.int64(1 if mode == AA_NONE else settings.spp)
        for y0, y1 in bands:
            _sample_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width), np.int64(height), np.int64(y0),
                         np.int64(y1), spp, seed, max_depth, radiance, depth, normal, albedo, object_id, samples,
                         rays_per_row)
            if progress is not None:
                progress(y1 / height)
    all_aovs = {"depth": depth, "normal": normal, "albedo": albedo, "object_id": object_id, "samples": samples}
    aovs = {name: all_aovs[name] for name in settings.aov}
    rays = int(rays_per_row.sum()) + (int(corner_rays.sum()) if mode == AA_ADAPTIVE else 0)
    return Film(radiance, aovs, rays, threads, primary_rays=int(samples.sum()))
