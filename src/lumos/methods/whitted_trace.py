"""The Whitted integrator (`trace`): one camera ray's radiance, recursing at each hit into shadow, reflected and
transmitted rays on an explicit stack, with its terms and, for `lumos.explain`, its ray tree logged (see
`methods.whitted` for the model). Every camera ray of the method, supersampled or adaptive, comes to it from
one call in `whitted_pixels.pixel`.
"""

from __future__ import annotations

import numpy as np

from .. import config
from ..kernels.cutout import closest_visible_hit
from ..kernels.environment import sky_radiance
from ..kernels.illumination import PER_LIGHT_SIZE, illuminate_terms, is_solid
from ..kernels.jit import njit, njit_alloc, njit_inline
from ..kernels.layout import MAT_FRESNEL, MAT_IOR, MAT_KT, MAT_ONE_SIDED
from ..kernels.optics import reflect, refract, schlick
from ..kernels.rng import rand01
from ..kernels.surface import curvature_seen, offset_origin, shading_side, surface_at
from ..kernels.bump import material_in_cone

#: Secondary rays whose path weight (largest channel) is below this are not traced.
CUTOFF = 1e-3
#: Nesting depth of the media a ray can be inside (a glass in water in a tank...).
MAX_MEDIA = 4
#: Random dimension of the shutter time (0–1 pixel position, 2–3 lens).
DIM_TIME = 4


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
def trace_scratch(max_depth, log_rows=0, n_lights=0, terms=False):
    """Per-thread work arrays for `trace`: the ray stack (origin, direction, weight, cone width and spread; depth,
    media count, branch,
    log row of the ray that spawned it; media objects and indices of refraction), the BVH traversal stack,
    the sample's terms (18: see T_*; `terms` False: none kept, an empty array), and the ray-tree log (`log_rows` rows, none by default; its count is −1
    when logging is off) with each logged hit's per-light shares (`illuminate_terms`' per_light, for
    `n_lights` lights)."""
    size = 2 * max_depth + 4  # depth-first: at most one pending sibling per level, plus the ray in hand
    log_n = np.full(1, -1 if log_rows == 0 else 0, np.int64)
    return (np.empty((size, 11)), np.empty((size, 4), np.int64), np.empty((size, MAX_MEDIA), np.int64),
            np.empty((size, MAX_MEDIA)), np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK),
            np.zeros(18 if terms else 0), np.zeros((max(log_rows, 1), LOG_COLS)), log_n,
            np.zeros((max(log_rows, 1) * max(n_lights, 1), PER_LIGHT_SIZE)), np.int64(max(n_lights, 1)))


@njit
def _push(st_f, st_i, st_mo, st_mi, sp, o, d, w0, w1, w2, cone, depth, n_media, src_mo, src_mi, src, drop, add_obj,
          add_ior, branch, parent):
    """Push a ray (its cone: width, spread); its media are those of stack entry `src` (already popped, still
    readable) without object `drop` (>= 0) and with (add_obj, add_ior) appended (add_obj >= 0). `branch` is the
    kind of the camera ray's child it descends from (the term it counts for); `parent` the log row of the ray that
    spawned it (the kind of the ray itself is in the sign: >= 0 reflected, < 0 transmitted, parent = ~value)."""
    st_f[sp, 0], st_f[sp, 1], st_f[sp, 2] = o
    st_f[sp, 3], st_f[sp, 4], st_f[sp, 5] = d
    st_f[sp, 6], st_f[sp, 7], st_f[sp, 8] = w0, w1, w2
    st_f[sp, 9], st_f[sp, 10] = cone
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
def trace(geo, surf, lit, tex, o, d, cone, time, max_depth, seed, pixel, sample, scratch, sky):
    """Radiance along the camera ray (o, d) at shutter time `time`. `cone` (width at o, spread angle;
    `kernels.camera.camera_cone`) is its ray cone, which the reflected and transmitted rays carry on (wider with
    distance, spread more by curved surfaces): the textures at each hit are filtered over its footprint.

    Returns (rgb, rays traced, (t, n_shading, kd, object id) of the primary hit; t = −1 on a miss). The
    sample's terms are left in scratch[6] (T_*: the primary hit's ambient, diffuse, specular and emitted light
    (or the background it misses into), and the light of its reflected and transmitted rays); with logging on,
    one row per ray in scratch[7] (LOG_*).

    A loop over the rays of an explicit stack, each in named steps: pop it (and open its log row), find its
    hit, shade it (`_shade`: the material, the local illumination model), count its light (`_add_terms`), and
    push its reflected and transmitted rays (`_secondaries`)."""
    st_f, st_i, st_mo, st_mi, stack, stack_t, tacc, log, log_n, light_log, light_stride = scratch
    logging = log_n[0] >= 0
    keep_terms = tacc.shape[0] > 0
    for k in range(tacc.shape[0]):  # element by element: device code makes no array views (kernels.jit)
        tacc[k] = 0.0
    r = g = b = 0.0
    rays = 0
    aov_t, aov_n, aov_kd, aov_obj = -1.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), -1
    sp = _push_camera_ray(st_f, st_i, o, d, cone)
    while sp > 0:
        sp -= 1
        top = sp
        ro = (st_f[top, 0], st_f[top, 1], st_f[top, 2])
        rd = (st_f[top, 3], st_f[top, 4], st_f[top, 5])
        w0, w1, w2 = st_f[top, 6], st_f[top, 7], st_f[top, 8]
        depth = st_i[top, 0]
        branch = st_i[top, 2]
        row = _open_log_row(log, log_n, st_i[top, 3], depth, ro, rd, w0, w1, w2, time) if logging else -1
        # where this ray's light counts: the primary hit's own terms, or the reflected / transmitted term
        k_light = T_REFLECTED if branch == RAY_REFLECTED else T_TRANSMITTED
        hit = closest_visible_hit(geo, surf, lit, ro, rd, 0.0, config.T_FAR, stack, stack_t, time)
        rays += 1
        t = hit[0]
        if t < 0.0:  # a miss: the background, or the environment in that direction
            bg = sky_radiance(sky[0], sky[1], sky[2], rd)
            r, g, b = r + w0 * bg[0], g + w1 * bg[1], b + w2 * bg[2]
            if keep_terms:
                _add_term(tacc, T_EMITTED if depth == 0 else k_light, w0, w1, w2, bg)
            if row >= 0:
                _log3(log, row, LOG_BACKGROUND, bg)
            continue
        width = st_f[top, 9] + st_f[top, 10] * t  # the cone's (signed) width here
        p, n_geo, n_s, n_g, obj, mat, entering, kr, kt, light_rgb, terms, extra = _shade(
            geo, surf, lit, tex, ro, rd, hit, width, time, seed, pixel, sample, stack, stack_t, light_log,
            row * light_stride if row >= 0 else -1, log, row)
        rays += extra
        r += w0 * light_rgb[0]
        g += w1 * light_rgb[1]
        b += w2 * light_rgb[2]
        if depth == 0:
            aov_t, aov_n, aov_kd, aov_obj = t, n_s, terms[4], obj
        if keep_terms:
            _add_terms(tacc, depth, k_light, w0, w1, w2, terms, light_rgb)
        if depth >= max_depth:
            continue
        sp = _secondaries(st_f, st_i, st_mo, st_mi, sp, top, surf, hit[1], mat, rd, p, n_geo, n_s, obj, entering,
                          kr, kt, width, depth, branch, log, row)
    return (r, g, b), rays, (aov_t, aov_n, aov_kd, aov_obj)


@njit_inline
def _push_camera_ray(st_f, st_i, o, d, cone):
    """The camera ray on the empty stack: weight 1, depth 0, in air, no parent. Returns the stack size, 1."""
    st_f[0, 0], st_f[0, 1], st_f[0, 2] = o
    st_f[0, 3], st_f[0, 4], st_f[0, 5] = d
    st_f[0, 6] = st_f[0, 7] = st_f[0, 8] = 1.0
    st_f[0, 9], st_f[0, 10] = cone
    st_i[0, 0] = 0
    st_i[0, 1] = 0
    st_i[0, 2] = RAY_CAMERA
    st_i[0, 3] = ~np.int64(-1)
    return 1


@njit
def _open_log_row(log, log_n, code, depth, ro, rd, w0, w1, w2, time):
    """A new log row for the ray just popped (its parent from `code`, the row of the ray that pushed it: >= 0
    reflected, ~row transmitted), or −1 when the log is full."""
    if log_n[0] >= log.shape[0]:
        return -1
    row = log_n[0]
    log_n[0] += 1
    for k in range(LOG_COLS):
        log[row, k] = 0.0
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
    return row


@njit_inline
def _shade(geo, surf, lit, tex, ro, rd, hit, width, time, seed, pixel, sample, stack, stack_t, light_log, light_at,
           log, row):
    """The hit of ray (ro, rd) shaded: its point, normals and material (textures filtered over the ray cone
    `width` wide there, bump map applied), its emission (one-sided for rect and disk area lights) and the
    illumination model's ambient, diffuse and specular light. Returns (p, n_geo, n_s, n_g, object, material row,
    entering, kr, kt, the light it sends back along the ray, (e, la, ld, ls, kd), shadow rays traced)."""
    t, ref = hit[0], hit[1]
    p, n_geo, n_sh, u, v, mat_id, obj, light = surface_at(surf, ro, rd, t, ref, hit[2], hit[3], hit[4], time)
    mat = lit.materials[mat_id]
    V = (-rd[0], -rd[1], -rd[2])
    entering = n_geo[0] * rd[0] + n_geo[1] * rd[1] + n_geo[2] * rd[2] < 0.0
    # the material's coefficients and the shading normal, textures and bump map filtered over the ray's cone
    ka, kd, ks, kr, ke, shininess, n_sh = material_in_cone(surf, tex, mat, ref, hit[4], hit[2], hit[3], p, n_geo,
                                                           n_sh, u, v, rd, abs(width), time)
    n_s = shading_side(n_sh, n_geo, V)
    n_g = n_geo if entering else (-n_geo[0], -n_geo[1], -n_geo[2])
    e = (0.0, 0.0, 0.0)
    if mat[MAT_ONE_SIDED] == 0.0 or entering:  # a one-sided emitter (rect and disk lights): its front only
        e = ke
    kt = (mat[MAT_KT], mat[MAT_KT + 1], mat[MAT_KT + 2])
    la, ld, ls, extra = illuminate_terms(lit, geo, surf, p, n_s, n_g, V, ka, kd, ks, shininess,
                                         seed, pixel, sample, True, stack, stack_t, time, light_log, light_at,
                                         geo)
    sent = (e[0] + la[0] + ld[0] + ls[0], e[1] + la[1] + ld[1] + ls[1], e[2] + la[2] + ld[2] + ls[2])
    if row >= 0:
        _log_hit(log, row, t, obj, mat_id, p, n_s, n_g, la, ld, ls, e, ka, kd, ks, u, v, entering, kr, kt)
    return p, n_geo, n_s, n_g, obj, mat, entering, kr, kt, sent, (e, la, ld, ls, kd), extra


@njit
def _log_hit(log, row, t, obj, mat_id, p, n_s, n_g, la, ld, ls, e, ka, kd, ks, u, v, entering, kr, kt):
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
    _log3(log, row, LOG_WR, kr)  # the material's; Fresnel and total internal reflection adjust them later
    _log3(log, row, LOG_WT, kt)


@njit_inline
def _add_terms(tacc, depth, k_light, w0, w1, w2, terms, sent):
    """The hit's light into the sample's terms: the primary hit's emitted, ambient, diffuse and specular light
    each in its own, a secondary ray's (weighted) in the reflected or transmitted term of its branch."""
    if depth == 0:
        e, la, ld, ls = terms[0], terms[1], terms[2], terms[3]
        _add_term(tacc, T_EMITTED, 1.0, 1.0, 1.0, e)
        _add_term(tacc, T_AMBIENT, 1.0, 1.0, 1.0, la)
        _add_term(tacc, T_DIFFUSE, 1.0, 1.0, 1.0, ld)
        _add_term(tacc, T_SPECULAR, 1.0, 1.0, 1.0, ls)
    else:
        _add_term(tacc, k_light, w0, w1, w2, sent)


@njit_inline
def _secondaries(st_f, st_i, st_mo, st_mi, sp, top, surf, ref, mat, rd, p, n_geo, n_s, obj, entering, kr, kt, width,
                 depth, branch, log, row):
    """Push the reflected and transmitted rays of the hit (stack entry `top`, already popped) whose weights
    (kr, kt, split by Fresnel and by total internal reflection at a solid) keep at least CUTOFF; returns the
    stack size. Their cones are as wide as this one at the hit; a curved surface spreads them (ray cones,
    paraxial: a convex mirror by twice the angle its normals turn across the cone, a lens by (1 − η) times it)."""
    w0, w1, w2 = st_f[top, 6], st_f[top, 7], st_f[top, 8]
    n_media = st_i[top, 1]
    wr0, wr1, wr2 = kr
    wt0, wt1, wt2 = kt
    transmit = wt0 > 0.0 or wt1 > 0.0 or wt2 > 0.0
    t_dir = rd
    spread = st_f[top, 10]
    bend = 0.0 if width == 0.0 else curvature_seen(surf, ref, rd, n_geo) * width
    t_cone = (width, spread)
    drop, add_obj, add_ior = np.int64(-1), np.int64(-1), 1.0
    if transmit and is_solid(surf, ref):
        n1, n2, drop, add_obj, add_ior = _media_across(st_mo, st_mi, top, n_media, entering, obj, mat[MAT_IOR])
        eta = n1 / n2
        t_cone = (width, eta * spread - (1.0 - eta) * bend)
        transmit, t_dir, wr0, wr1, wr2, wt0, wt1, wt2 = _refract_split(rd, n_s, eta, mat[MAT_FRESNEL] != 0.0, wr0,
                                                                       wr1, wr2, wt0, wt1, wt2, log, row)
    if row >= 0:
        _log3(log, row, LOG_WR, (wr0, wr1, wr2))
        _log3(log, row, LOG_WT, (wt0, wt1, wt2) if transmit else (0.0, 0.0, 0.0))
    # the reflected ray first: it keeps the incident media, so the entry it overwrites (the ray in hand, already
    # read) still holds them for the transmitted ray's copy
    rw0, rw1, rw2 = w0 * wr0, w1 * wr1, w2 * wr2
    if max(rw0, rw1, rw2) >= CUTOFF:
        r_dir = reflect(rd, n_s)
        origin = offset_origin(p, n_geo, r_dir, config.RAY_EPSILON)
        sp = _push(st_f, st_i, st_mo, st_mi, sp, origin, r_dir, rw0, rw1, rw2, (width, spread + 2.0 * bend),
                   depth + 1, n_media, st_mo, st_mi, top, np.int64(-1), np.int64(-1), 1.0,
                   RAY_REFLECTED if depth == 0 else branch, np.int64(row))
    if transmit:
        tw0, tw1, tw2 = w0 * wt0, w1 * wt1, w2 * wt2
        if max(tw0, tw1, tw2) >= CUTOFF:
            origin = offset_origin(p, n_geo, t_dir, config.RAY_EPSILON)
            sp = _push(st_f, st_i, st_mo, st_mi, sp, origin, t_dir, tw0, tw1, tw2, t_cone, depth + 1, n_media,
                       st_mo, st_mi, top, drop, add_obj, add_ior, RAY_TRANSMITTED if depth == 0 else branch,
                       ~np.int64(row))
    return sp


@njit
def _media_across(st_mo, st_mi, top, n_media, entering, obj, ior):
    """The indices of refraction on both sides of a solid's surface (n1 the ray's side), and how the media of
    the ray that crosses change: (n1, n2, object left (or −1), object entered (or −1), its index)."""
    n_out = st_mi[top, n_media - 1] if n_media > 0 else 1.0
    if entering:
        return n_out, ior, np.int64(-1), np.int64(obj), ior
    n2 = 1.0
    found = False
    for k in range(n_media - 1, -1, -1):  # the innermost medium once obj is left
        if st_mo[top, k] == obj and not found:
            found = True
            continue
        n2 = st_mi[top, k]
        break
    return n_out, n2, np.int64(obj), np.int64(-1), 1.0


@njit
def _refract_split(rd, n_s, eta, fresnel, wr0, wr1, wr2, wt0, wt1, wt2, log, row):
    """The refracted direction, and the reflected and transmitted weights split by Schlick's Fresnel factor
    (with `fresnel`) and by total internal reflection (all of kt goes the mirror way): (transmit, direction,
    wr, wt), logged in `row` when >= 0."""
    cos_i = -(rd[0] * n_s[0] + rd[1] * n_s[1] + rd[2] * n_s[2])
    ok, t_dir = refract(rd, n_s, eta)
    if row >= 0:
        log[row, LOG_ETA] = eta
        log[row, LOG_TIR] = 0.0 if ok else 1.0
    if fresnel:
        if ok:
            cos_t = -(t_dir[0] * n_s[0] + t_dir[1] * n_s[1] + t_dir[2] * n_s[2])
            F = schlick(max(cos_i, 0.0), eta, max(cos_t, 0.0))
        else:
            F = 1.0
        if row >= 0:
            log[row, LOG_FRESNEL] = F
        wr0, wr1, wr2 = wr0 + wt0 * F, wr1 + wt1 * F, wr2 + wt2 * F
        wt0, wt1, wt2 = wt0 * (1.0 - F), wt1 * (1.0 - F), wt2 * (1.0 - F)
    transmit = True
    if not ok:  # total internal reflection: the transmitted part goes the mirror way
        wr0, wr1, wr2 = wr0 + wt0, wr1 + wt1, wr2 + wt2
        transmit = False
    return transmit, t_dir, wr0, wr1, wr2, wt0, wt1, wt2


@njit
def shutter_time(cam_time, seed, pixel, sample):
    """Shutter time of a sample: open + u·(close − open)."""
    if cam_time[1] <= cam_time[0]:
        return cam_time[0]
    return cam_time[0] + (cam_time[1] - cam_time[0]) * rand01(seed, pixel, sample, DIM_TIME)


@njit
def store_aovs(x, y, info, depth, normal, albedo, object_id):
    t, n, kd, obj = info
    if t >= 0.0:
        depth[y, x] = t
        normal[y, x, 0], normal[y, x, 1], normal[y, x, 2] = n
        albedo[y, x, 0], albedo[y, x, 1], albedo[y, x, 2] = kd
        object_id[y, x] = obj
