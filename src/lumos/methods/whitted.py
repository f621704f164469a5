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
"""

from __future__ import annotations

import numpy as np

from .. import config
from ..compile.camera import camera_arrays
from ..kernels.camera import camera_ray, camera_ray_at
from ..kernels.cutout import closest_visible_hit
from ..kernels.illumination import PER_LIGHT_SIZE, illuminate_terms, is_solid
from ..kernels.jit import njit, njit_alloc, njit_inline, njit_serial
from ..kernels.layout import (
    LIGHT_SPHERE,
    MAT_FRESNEL,
    MAT_BUMP,
    MAT_IOR,
    MAT_KT,
    MAT_SHININESS,
)
from ..kernels.optics import reflect, refract, schlick
from ..kernels.rng import rand01
from ..kernels.surface import offset_origin, shading_side, surface_at
from ..kernels.texture import bump_frame, bump_normal, material_coeffs
from ..kernels.threads import parallel_for
from ..kernels.views import geometry_of, lighting_of, owned_views, surfaces_of, textures_of
from ..errors import LumosError
from .capabilities import check_settings
from .common import TERM_AOVS, TERM_CHANNELS, Film, allocate_aovs, check_memory, row_bands, set_threads, term_aovs

#: Secondary rays whose path weight (largest channel) is below this are not traced.
CUTOFF = 1e-3
#: Nesting depth of the media a ray can be inside (a glass in water in a tank...).
MAX_MEDIA = 4
#: Random dimension of the shutter time (0–1 pixel position, 2–3 lens).
DIM_TIME = 4
AA_NONE, AA_SUPERSAMPLE, AA_ADAPTIVE = 0, 1, 2
ANTIALIAS_MODES = {"none": AA_NONE, "supersample": AA_SUPERSAMPLE, "adaptive": AA_ADAPTIVE}


#: Columns of a ray-tree log row (`lumos.explain`): one row per ray traced from a camera ray.
LOG_PARENT, LOG_KIND, LOG_DEPTH, LOG_ORIGIN, LOG_DIR, LOG_WEIGHT, LOG_T, LOG_OBJECT, LOG_MATERIAL = 0, 1, 2, 3, 6, 9, 12, 13, 14
LOG_POINT, LOG_NORMAL, LOG_NGEO, LOG_AMBIENT, LOG_DIFFUSE, LOG_SPECULAR, LOG_EMITTED = 15, 18, 21, 24, 27, 30, 33
LOG_WR, LOG_WT, LOG_ENTERING, LOG_ETA, LOG_FRESNEL, LOG_TIR, LOG_BACKGROUND, LOG_UV = 36, 39, 42, 43, 44, 45, 46, 49
LOG_KA, LOG_KD, LOG_KS, LOG_TIME, LOG_FX, LOG_FY = 51, 54, 57, 60, 61, 62
LOG_COLS = 63
#: Ray kinds in the log (LOG_KIND), and the branch of the tree a ray is in (the term its light counts for).
RAY_CAMERA, RAY_REFLECTED, RAY_TRANSMITTED = 0, 1, 2
#: Term channels (as `common.TERM_CHANNELS`): ambient, diffuse, specular, emitted, reflected, transmitted.
T_AMBIENT, T_DIFFUSE, T_SPECULAR, T_EMITTED, T_REFLECTED, T_TRANSMITTED = 0, 3, 6, 9, 12, 15


@njit_alloc
def _scratch(max_depth, log_rows=0, n_lights=0, terms=False):
    """Per-thread work arrays for `trace`: the ray stack (origin, direction, weight; depth, media count, branch,
    log row of the ray that spawned it; media objects and indices of refraction), the BVH traversal stack,
    the sample's terms (18: see T_*; `terms` False: none kept, an empty array), and the ray-tree log (`log_rows` rows, none by default; its count is −1
    when logging is off) with each logged hit's per-light shares (`illuminate_terms`' per_light, for
    `n_lights` lights)."""
    size = 2 * max_depth + 4  # depth-first: at most one pending sibling per level, plus the ray in hand
    log_n = np.full(1, -1 if log_rows == 0 else 0, np.int64)
    return (np.empty((size, 9)), np.empty((size, 4), np.int64), np.empty((size, MAX_MEDIA), np.int64),
            np.empty((size, MAX_MEDIA)), np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK),
            np.zeros(18 if terms else 0), np.zeros((max(log_rows, 1), LOG_COLS)), log_n,
            np.zeros((max(log_rows, 1) * max(n_lights, 1), PER_LIGHT_SIZE)), np.int64(max(n_lights, 1)))


@njit
def _push(st_f, st_i, st_mo, st_mi, sp, o, d, w0, w1, w2, depth, n_media, src_mo, src_mi, src, drop, add_obj, add_ior,
          branch, parent):
    """Push a ray; its media are those of stack entry `src` (already popped, still readable) without object
    `drop` (>= 0) and with (add_obj, add_ior) appended (add_obj >= 0). `branch` is the kind of the camera
    ray's child it descends from (the term it counts for); `parent` the log row of the ray that spawned it
    (the kind of the ray itself is in the sign: >= 0 reflected, < 0 transmitted, parent = ~value)."""
    st_f[sp, 0], st_f[sp, 1], st_f[sp, 2] = o
    st_f[sp, 3], st_f[sp, 4], st_f[sp, 5] = d
    st_f[sp, 6], st_f[sp, 7], st_f[sp, 8] = w0, w1, w2
    st_i[sp, 0] = depth
    st_i[sp, 2] = branch
    st_i[sp, 3] = parent
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


@njit_inline
def _log3(log, row, col, v):
    log[row, col] = v[0]
    log[row, col + 1] = v[1]
    log[row, col + 2] = v[2]


@njit_inline
def _add_term(tacc, k, w0, w1, w2, c):
    tacc[k] += w0 * c[0]
    tacc[k + 1] += w1 * c[1]
    tacc[k + 2] += w2 * c[2]


@njit_inline
def trace(geo, surf, lit, tex, o, d, time, max_depth, seed, pixel, sample, scratch, background):
    """Radiance along the camera ray (o, d) at shutter time `time`.

    Returns (rgb, rays traced, (t, n_shading, kd, object id) of the primary hit; t = −1 on a miss). The
    sample's terms are left in scratch[6] (T_*: the primary hit's ambient, diffuse, specular and emitted light
    (or the background it misses into), and the light of its reflected and transmitted rays); with logging on,
    one row per ray in scratch[7] (LOG_*)."""
    st_f, st_i, st_mo, st_mi, stack, stack_t, tacc, log, log_n, light_log, light_stride = scratch
    logging = log_n[0] >= 0
    keep_terms = tacc.shape[0] > 0
    for k in range(tacc.shape[0]):  # element by element: device code makes no array views (kernels.jit)
        tacc[k] = 0.0
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
    st_i[0, 2] = RAY_CAMERA
    st_i[0, 3] = ~np.int64(-1)
    sp = 1
    while sp > 0:
        sp -= 1
        top = sp
        ro = (st_f[top, 0], st_f[top, 1], st_f[top, 2])
        rd = (st_f[top, 3], st_f[top, 4], st_f[top, 5])
        w0, w1, w2 = st_f[top, 6], st_f[top, 7], st_f[top, 8]
        depth = st_i[top, 0]
        n_media = st_i[top, 1]
        branch = st_i[top, 2]
        row = -1
        if logging and log_n[0] < log.shape[0]:
            row = log_n[0]
            log_n[0] += 1
            for k in range(LOG_COLS):
                log[row, k] = 0.0
            code = st_i[top, 3]
            log[row, LOG_PARENT] = -1 if depth == 0 else (code if code >= 0 else ~code)
            log[row, LOG_KIND] = RAY_CAMERA if depth == 0 else (RAY_REFLECTED if code >= 0 else RAY_TRANSMITTED)
            log[row, LOG_DEPTH] = depth
            _log3(log, row, LOG_ORIGIN, ro)
            _log3(log, row, LOG_DIR, rd)
            _log3(log, row, LOG_WEIGHT, (w0, w1, w2))
            log[row, LOG_T] = -1.0
            log[row, LOG_OBJECT] = -1
            log[row, LOG_MATERIAL] = -1
            log[row, LOG_FRESNEL] = -1.0
            log[row, LOG_TIME] = time
        # where this ray's light counts: the primary hit's own terms, or the reflected / transmitted term
        k_light = T_REFLECTED if branch == RAY_REFLECTED else T_TRANSMITTED
        hit = closest_visible_hit(geo, surf, lit, ro, rd, 0.0, config.T_FAR, stack, stack_t, time)
        rays += 1
        t = hit[0]
        if t < 0.0:
            r += w0 * background[0]
            g += w1 * background[1]
            b += w2 * background[2]
            if keep_terms:
                _add_term(tacc, T_EMITTED if depth == 0 else k_light, w0, w1, w2, background)
            if row >= 0:
                _log3(log, row, LOG_BACKGROUND, background)
            continue
        ref = hit[1]
        p, n_geo, n_sh, u, v, mat_id, obj, light = surface_at(surf, ro, rd, t, ref, hit[2], hit[3], hit[4], time)
        mat = lit.materials[mat_id]
        V = (-rd[0], -rd[1], -rd[2])
        entering = n_geo[0] * rd[0] + n_geo[1] * rd[1] + n_geo[2] * rd[2] < 0.0
        if mat[MAT_BUMP] >= 0.0:
            dpdu, dpdv = bump_frame(surf, tex, mat, ref, hit[4], hit[2], hit[3], p, n_sh, time)
            n_sh = bump_normal(tex, mat, u, v, p, n_sh, dpdu, dpdv)
        n_s = shading_side(n_sh, n_geo, V)
        n_g = n_geo if entering else (-n_geo[0], -n_geo[1], -n_geo[2])
        # emitted light: one-sided for rect and disk area lights
        ka, kd, ks, kr, ke = material_coeffs(tex, mat, u, v, p)  # the material's, with its textures applied
        e = (0.0, 0.0, 0.0)
        if light < 0 or lit.light_kind[light] == LIGHT_SPHERE or entering:
            e = ke
        kt = (mat[MAT_KT], mat[MAT_KT + 1], mat[MAT_KT + 2])
        if depth == 0:
            aov_t, aov_n, aov_kd, aov_obj = t, n_s, kd, obj
        la, ld, ls, extra = illuminate_terms(lit, geo, surf, p, n_s, n_g, V, ka, kd, ks, mat[MAT_SHININESS],
                                             seed, pixel, sample, True, stack, stack_t, time,
                                             light_log, row * light_stride if row >= 0 else -1)
        rays += extra
        r += w0 * (e[0] + la[0] + ld[0] + ls[0])
        g += w1 * (e[1] + la[1] + ld[1] + ls[1])
        b += w2 * (e[2] + la[2] + ld[2] + ls[2])
        if not keep_terms:
            pass
        elif depth == 0:
            _add_term(tacc, T_EMITTED, 1.0, 1.0, 1.0, e)
            _add_term(tacc, T_AMBIENT, 1.0, 1.0, 1.0, la)
            _add_term(tacc, T_DIFFUSE, 1.0, 1.0, 1.0, ld)
            _add_term(tacc, T_SPECULAR, 1.0, 1.0, 1.0, ls)
        else:
            _add_term(tacc, k_light, w0, w1, w2, (e[0] + la[0] + ld[0] + ls[0], e[1] + la[1] + ld[1] + ls[1],
                                                  e[2] + la[2] + ld[2] + ls[2]))
        if row >= 0:
            log[row, LOG_T] = t
            log[row, LOG_OBJECT] = obj
            log[row, LOG_MATERIAL] = mat_id
            _log3(log, row, LOG_POINT, p)
            _log3(log, row, LOG_NORMAL, n_s)
            _log3(log, row, LOG_NGEO, n_g)
            _log3(log, row, LOG_AMBIENT, la)
            _log3(log, row, LOG_DIFFUSE, ld)
            _log3(log, row, LOG_SPECULAR, ls)
            _log3(log, row, LOG_EMITTED, e)
            _log3(log, row, LOG_KA, ka)
            _log3(log, row, LOG_KD, kd)
            _log3(log, row, LOG_KS, ks)
            log[row, LOG_UV] = u
            log[row, LOG_UV + 1] = v
            log[row, LOG_ENTERING] = 1.0 if entering else 0.0
            _log3(log, row, LOG_WR, kr)  # the material's; Fresnel and total internal reflection adjust them below
            _log3(log, row, LOG_WT, kt)
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
            if row >= 0:
                log[row, LOG_ETA] = eta
                log[row, LOG_TIR] = 0.0 if ok else 1.0
            if mat[MAT_FRESNEL] != 0.0:
                if ok:
                    cos_t = -(t_dir[0] * n_s[0] + t_dir[1] * n_s[1] + t_dir[2] * n_s[2])
                    F = schlick(max(cos_i, 0.0), eta, max(cos_t, 0.0))
                else:
                    F = 1.0
                if row >= 0:
                    log[row, LOG_FRESNEL] = F
                wr0, wr1, wr2 = wr0 + wt0 * F, wr1 + wt1 * F, wr2 + wt2 * F
                wt0, wt1, wt2 = wt0 * (1.0 - F), wt1 * (1.0 - F), wt2 * (1.0 - F)
            if not ok:  # total internal reflection: the transmitted part goes the mirror way
                wr0, wr1, wr2 = wr0 + wt0, wr1 + wt1, wr2 + wt2
                transmit = False
        if row >= 0:
            _log3(log, row, LOG_WR, (wr0, wr1, wr2))
            _log3(log, row, LOG_WT, (wt0, wt1, wt2) if transmit else (0.0, 0.0, 0.0))
        # the reflected ray first: it keeps the incident media, so the entry it overwrites (the ray in hand, already
        # read) still holds them for the transmitted ray's copy
        rw0, rw1, rw2 = w0 * wr0, w1 * wr1, w2 * wr2
        if max(rw0, rw1, rw2) >= CUTOFF:
            r_dir = reflect(rd, n_s)
            origin = offset_origin(p, n_geo, r_dir, config.RAY_EPSILON)
            sp = _push(st_f, st_i, st_mo, st_mi, sp, origin, r_dir, rw0, rw1, rw2, depth + 1, n_media, st_mo, st_mi,
                       top, np.int64(-1), np.int64(-1), 1.0, RAY_REFLECTED if depth == 0 else branch, np.int64(row))
        if transmit:
            tw0, tw1, tw2 = w0 * wt0, w1 * wt1, w2 * wt2
            if max(tw0, tw1, tw2) >= CUTOFF:
                origin = offset_origin(p, n_geo, t_dir, config.RAY_EPSILON)
                sp = _push(st_f, st_i, st_mo, st_mi, sp, origin, t_dir, tw0, tw1, tw2, depth + 1, n_media, st_mo,
                           st_mi, top, drop, add_obj, add_ior, RAY_TRANSMITTED if depth == 0 else branch,
                           ~np.int64(row))
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


@njit_serial
def _sample_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, spp, seed, max_depth,
                 radiance, depth, normal, albedo, object_id, samples, terms, want_terms, rays_per_row):
    """antialias none / supersample: `spp` camera rays per pixel (the pixel centre when spp is 1); with
    `want_terms`, the mean of the samples' terms in terms[y, x, :18]. Rows y0 … y1−1."""
    _sample_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, spp, seed, max_depth, radiance, depth,
                 normal, albedo, object_id, samples, terms, want_terms, rays_per_row,
                 _scratch(max_depth, 0, 0, want_terms), np.zeros(18))


@njit
def _sample_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, spp, seed, max_depth, radiance, depth,
                 normal, albedo, object_id, samples, terms, want_terms, rays_per_row, scratch, tsum):
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        for x in range(width):
            rgb, n = sample_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, spp, seed,
                                  max_depth, scratch, sa.background, depth, normal, albedo, object_id, tsum,
                                  want_terms)
            rays += n
            radiance[y, x, 0], radiance[y, x, 1], radiance[y, x, 2] = rgb
            if want_terms:
                for k in range(18):
                    terms[y, x, k] = tsum[k]
            samples[y, x] = spp
        rays_per_row[y] += rays


@njit_inline
def sample_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, spp, seed, max_depth,
                 scratch, background, depth, normal, albedo, object_id, tsum, want_terms):
    """The mean of pixel (x, y)'s `spp` samples, and the rays traced; AOVs from its first sample; with
    `want_terms` the mean of its samples' terms in tsum (18). With logging on in `scratch`, every sample's rays
    go to its log, one tree after another (`lumos.explain`)."""
    pixel = y * width + x
    r = g = b = 0.0
    rays = 0
    if want_terms:
        for k in range(18):
            tsum[k] = 0.0
    for s in range(spp):
        o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, s, spp, seed, pixel)
        time = _time_of(cam_time, seed, pixel, s)
        rgb, n, info = trace(geo, surf, lit, tex, o, d, time, max_depth, seed, pixel, s, scratch, background)
        rays += n
        r += rgb[0]
        g += rgb[1]
        b += rgb[2]
        if want_terms:
            for k in range(18):
                tsum[k] += scratch[6][k]
        if s == 0:
            _store_aovs(x, y, info, depth, normal, albedo, object_id)
    inv = 1.0 / spp
    if want_terms:
        for k in range(18):
            tsum[k] *= inv
    return (r * inv, g * inv, b * inv), rays


@njit_inline
def _point(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, fx, fy, seed, key, sample, max_depth,
           scratch, background):
    """The radiance through image point (fx, fy); `key` and `sample` index its random numbers (lens, time)."""
    lx, ly = rand01(seed, key, sample, 2), rand01(seed, key, sample, 3)
    o, d = camera_ray_at(cam_vecs, cam_params, width, height, fx, fy, lx, ly)
    time = _time_of(cam_time, seed, key, sample)
    log, log_n = scratch[7], scratch[8]
    first = log_n[0]
    rgb, n, info = trace(geo, surf, lit, tex, o, d, time, max_depth, seed, key, sample, scratch, background)
    if 0 <= first < log.shape[0]:  # where the camera ray went through the image (lumos.explain)
        log[first, LOG_FX] = fx
        log[first, LOG_FY] = fy
    return rgb, n


@njit_serial
def _corner_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, corners, rays_per_row):
    """adaptive, stage 1: one ray through every pixel corner (W+1 × H+1 of them, shared by neighbours): its
    radiance in corners[y, x, 0:3] and, when corners has 21 channels, its terms after it. Corner rows y0 … y1−1
    (rays_per_row here has height + 1 entries, one per row of corners)."""
    _corner_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, corners, rays_per_row,
                 _scratch(max_depth, 0, 0, corners.shape[2] > 3))


@njit
def _corner_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, corners, rays_per_row,
                 scratch):
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        for x in range(width + 1):
            key = y * (width + 1) + x
            rgb, n = _point(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, np.float64(x),
                            np.float64(y), seed, key, 0, max_depth, scratch, sa.background)
            corners[y, x, 0], corners[y, x, 1], corners[y, x, 2] = rgb
            for k in range(3, corners.shape[2]):  # the terms, when they are asked for
                corners[y, x, k] = scratch[6][k - 3]
            rays += n
        rays_per_row[y] += rays


@njit_serial
def _adaptive_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, threshold,
                   max_level, corners, radiance, samples, terms, rays_per_row):
    """adaptive, stage 2: each pixel from its corners, its squares cut in four where the corners differ
    (`adaptive_pixel`); with 21-channel corners, also its terms. Rows y0 … y1−1."""
    n = (np.int64(1) << max_level) + 1
    channels = corners.shape[2]
    _adaptive_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, threshold, max_level,
                   corners, radiance, samples, terms, rays_per_row, _scratch(max_depth, 0, 0, channels > 3),
                   np.empty((n, n, channels)), np.full((n, n), -1, np.int64), np.zeros((1, 1)),
                   np.empty((4 * max_level + 4, 4), np.int64), np.empty(channels))


@njit
def _adaptive_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth, threshold, max_level,
                   corners, radiance, samples, terms, rays_per_row, scratch, grid, stamp, weights, stack, value):
    """(`_adaptive_rows`; stack: the squares to visit, as ix, iy, size in cells, level)"""
    channels = corners.shape[2]
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        for x in range(width):
            count, nr = adaptive_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, seed,
                                       max_depth, threshold, max_level, corners, scratch, sa.background, grid, stamp,
                                       stack, weights, value)
            rays += nr
            radiance[y, x, 0], radiance[y, x, 1], radiance[y, x, 2] = value[0], value[1], value[2]
            for k in range(3, channels):
                terms[y, x, k - 3] = value[k]
            samples[y, x] = count
        rays_per_row[y] += rays


@njit_inline
def adaptive_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, seed, max_depth,
                   threshold, max_level, corners, scratch, background, grid, stamp, stack, weights, value):
    """Pixel (x, y) by adaptive subdivision: value[:] = the area-weighted mean over its squares of their corners'
    values (every channel of `corners`: radiance, then the terms if present); returns (camera rays it took, rays
    traced beyond its corners).

    Its points live on a (2^max_level + 1)² grid, so a point shared by neighbouring squares is traced once;
    `stamp` marks the points already traced for this pixel. With `weights` (n, n) (`lumos.explain`), each
    point's weight in the pixel is added to it; with logging on in `scratch`, each new point's tree goes to
    the log."""
    cells = np.int64(1) << max_level
    n = cells + 1
    inv = 1.0 / cells
    channels = grid.shape[2]
    explain = weights.shape[0] == n
    pixel = y * width + x
    key = (height + 1) * (width + 1) + pixel  # random keys of this pixel's extra points
    for ch in range(channels):
        grid[0, 0, ch] = corners[y, x, ch]
        grid[0, cells, ch] = corners[y, x + 1, ch]
        grid[cells, 0, ch] = corners[y + 1, x, ch]
        grid[cells, cells, ch] = corners[y + 1, x + 1, ch]
    stamp[0, 0] = stamp[0, cells] = stamp[cells, 0] = stamp[cells, cells] = pixel
    count = 1  # its own corner ray
    rays = 0
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = 0, 0, cells, 0
    sp = 1
    for ch in range(channels):
        value[ch] = 0.0
    while sp > 0:
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
        # the five middles (top, left, centre, right, bottom) that are not traced yet
        for k in range(5):
            if k == 0:
                px, py = ix + h, iy
            elif k == 1:
                px, py = ix, iy + h
            elif k == 2:
                px, py = ix + h, iy + h
            elif k == 3:
                px, py = ix + size, iy + h
            else:
                px, py = ix + h, iy + size
            if stamp[py, px] == pixel:
                continue
            stamp[py, px] = pixel
            rgb, nr = _point(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height,
                             x + px * inv, y + py * inv, seed, key, py * n + px, max_depth, scratch, background)
            grid[py, px, 0], grid[py, px, 1], grid[py, px, 2] = rgb
            for ch in range(3, channels):
                grid[py, px, ch] = scratch[6][ch - 3]
            rays += nr
            count += 1
        for k in range(4):
            stack[sp, 0] = ix + (k % 2) * h
            stack[sp, 1] = iy + (k // 2) * h
            stack[sp, 2] = h
            stack[sp, 3] = level + 1
            sp += 1
    return count, rays


@njit_serial
def _aov_rows(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, max_depth,
              depth, normal, albedo, object_id, rays_per_row):
    """adaptive with AOVs: one more ray through each pixel centre, for the AOVs only. Rows y0 … y1−1."""
    _aov_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, depth, normal, albedo, object_id,
              rays_per_row, _scratch(np.int64(0)))


@njit
def _aov_band(sa, cam_vecs, cam_params, cam_time, width, height, y0, y1, seed, depth, normal, albedo, object_id,
              rays_per_row, scratch):
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        for x in range(width):
            o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, 0, 1, seed, y * width + x)
            rgb, n, info = trace(geo, surf, lit, tex, o, d, cam_time[0], np.int64(0), seed, y * width + x, 0, scratch,
                                 sa.background)
            rays += n
            _store_aovs(x, y, info, depth, normal, albedo, object_id)
        rays_per_row[y] += rays


@njit_alloc
def explain_pixel(sa, cam_vecs, cam_params, cam_time, width, height, x, y, mode, spp, seed, max_depth, threshold,
                  max_level, log_rows):
    """Pixel (x, y) exactly as `render_whitted` makes it, with every ray logged (`lumos.explain`).

    Returns (value (3,), log (rows, LOG_COLS), per-light log (rows · n_lights, PER_LIGHT_SIZE): row r's lights
    from r · n_lights, rows used, weight of each row's camera ray in the pixel (rows,), 0 for the rays it
    spawned)."""
    geo, surf, lit, tex = owned_views(sa)
    scratch = _scratch(max_depth, log_rows, lit.light_kind.shape[0])
    log, log_n = scratch[7], scratch[8]
    weight = np.zeros(log_rows)
    value = np.zeros(3)
    if mode != AA_ADAPTIVE:
        depth, normal, albedo = np.zeros((height, width)), np.zeros((height, width, 3)), np.zeros((height, width, 3))
        object_id = np.zeros((height, width), np.int32)
        rgb, _ = sample_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, spp, seed,
                              max_depth, scratch, sa.background, depth, normal, albedo, object_id, np.zeros(18),
                              False)
        value[0], value[1], value[2] = rgb
        for row in range(log_n[0]):
            if log[row, LOG_DEPTH] == 0.0:
                weight[row] = 1.0 / spp
        return value, log, scratch[9], log_n[0], weight
    cells = np.int64(1) << max_level
    n = cells + 1
    corners = np.zeros((height + 1, width + 1, 3))
    grid_row = np.full((n, n), -1, np.int64)  # the log row of each point's camera ray
    for cy in range(y, y + 2):
        for cx in range(x, x + 2):
            grid_row[(cy - y) * cells, (cx - x) * cells] = log_n[0]
            rgb, _ = _point(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, np.float64(cx),
                            np.float64(cy), seed, cy * (width + 1) + cx, 0, max_depth, scratch, sa.background)
            corners[cy, cx, 0], corners[cy, cx, 1], corners[cy, cx, 2] = rgb
    start = log_n[0]
    grid = np.empty((n, n, 3))
    stamp = np.full((n, n), -1, np.int64)
    stack = np.empty((4 * max_level + 4, 4), np.int64)
    weights = np.zeros((n, n))
    adaptive_pixel(geo, surf, lit, tex, cam_vecs, cam_params, cam_time, width, height, x, y, seed, max_depth,
                   threshold, max_level, corners, scratch, sa.background, grid, stamp, stack, weights, value)
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


def render_whitted(compiled, camera, settings, progress=None) -> Film:
    """Whitted-trace `compiled` (a `CompiledScene`) through `camera` with `settings` (a `RenderSettings`)."""
    width, height = settings.width, settings.height
    check_settings(settings)
    check_memory(width, height, bytes_per_pixel=80)
    threads = set_threads(settings.threads)
    cam_vecs, cam_params = camera_arrays(camera)
    cam_time = np.array(camera.shutter, dtype=np.float64)
    sa = compiled.arrays
    seed = np.int64(settings.seed)
    if settings.resolved_max_depth() is None:
        raise LumosError("render.max_depth: whitted needs a finite number of bounces (-1, unbounded, is for path)")
    max_depth = np.int64(settings.resolved_max_depth())
    mode = ANTIALIAS_MODES[settings.antialias]
    want_terms = any(name in TERM_AOVS for name in settings.aov)
    terms = np.zeros((height, width, TERM_CHANNELS) if want_terms else (1, 1, TERM_CHANNELS), np.float32)
    radiance = np.zeros((height, width, 3), np.float32)
    depth, normal, albedo, object_id = allocate_aovs(height, width)
    samples = np.zeros((height, width), np.int32)
    rays_per_row = np.zeros(height, np.int64)
    bands = row_bands(height)
    if mode == AA_ADAPTIVE:
        corners = np.zeros((height + 1, width + 1, 3 + TERM_CHANNELS if want_terms else 3))
        corner_rays = np.zeros(height + 1, np.int64)
        total = len(bands) * 2
        done = 0
        for y0, y1 in row_bands(height + 1):
            parallel_for(lambda r0, r1: _corner_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width),
                                                     np.int64(height), np.int64(r0), np.int64(r1), seed, max_depth,
                                                     corners, corner_rays), y0, y1)
            done += 1
            if progress is not None:
                progress(min(done / total, 0.5))
        for y0, y1 in bands:
            parallel_for(lambda r0, r1: _adaptive_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width),
                                                       np.int64(height), np.int64(r0), np.int64(r1), seed, max_depth,
                                                       float(settings.adaptive_threshold),
                                                       np.int64(settings.adaptive_depth), corners, radiance, samples,
                                                       terms, rays_per_row), y0, y1)
            if progress is not None:
                progress(0.5 + 0.5 * y1 / height)
        if set(settings.aov) & {"depth", "normal", "albedo", "object_id"}:
            for y0, y1 in bands:
                parallel_for(lambda r0, r1: _aov_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width),
                                                      np.int64(height), np.int64(r0), np.int64(r1), seed, max_depth,
                                                      depth, normal, albedo, object_id, rays_per_row), y0, y1)
    else:
        spp = np.int64(1 if mode == AA_NONE else settings.spp)
        for y0, y1 in bands:
            parallel_for(lambda r0, r1: _sample_rows(sa, cam_vecs, cam_params, cam_time, np.int64(width),
                                                     np.int64(height), np.int64(r0), np.int64(r1), spp, seed,
                                                     max_depth, radiance, depth, normal, albedo, object_id, samples,
                                                     terms, want_terms, rays_per_row), y0, y1)
            if progress is not None:
                progress(y1 / height)
    all_aovs = {"depth": depth, "normal": normal, "albedo": albedo, "object_id": object_id, "samples": samples}
    if want_terms:
        all_aovs.update(term_aovs(terms))
    aovs = {name: all_aovs[name] for name in settings.aov}
    rays = int(rays_per_row.sum()) + (int(corner_rays.sum()) if mode == AA_ADAPTIVE else 0)
    return Film(radiance, aovs, rays, threads, primary_rays=int(samples.sum()))
