"""Path tracing's integrator: the rendering equation solved by random paths from the eye (Kajiya 1986), the global
illumination of the chapter's section 3.3 — light reflected from other surfaces to the current one.

    L(x → eye) = Le(x) + ∫ f(wo, wi) L(wi) cos θ dω                           (the rendering equation)

Each sample follows one path: at every vertex it adds the light reached directly by two strategies, combined by
multiple importance sampling with the power heuristic (Veach & Guibas 1995):
- next-event estimation: an emitter picked by its estimated contribution at the vertex (the light tree,
  `kernels.light_tree`; or by power alone, `light_selection: power`), a point on it, and a shadow ray; delta lights (point, directional) are only reached this way;
- BSDF sampling: the direction the path continues in, whose hit adds the emission it finds.
The path continues with the BSDF sample; after `RR_DEPTH` bounces Russian roulette ends it with probability
1 − q, q = min(max throughput × η², 0.95), and reweights the survivors by 1/q (unbiased). `max_depth` D counts
bounces after the first hit, as whitted does: emission is gathered at vertices 0 … D+1 and light sampled at
0 … D (D = 0: direct light only; Mitsuba's max_depth is D + 2, pbrt-v4's D + 1); unset, paths are unbounded.

Materials are read physically (`kernels.bsdf`): kd Lambertian, ks/shininess a normalised Phong lobe, kr a mirror,
a `conductor` a GGX microfacet lobe with the complex Fresnel factor (`kernels.microfacet`), a `plastic` kd under a
clear coat (GGX lobe with the dielectric Fresnel factor over the base seen through it), kt/ior a smooth
dielectric with exact Fresnel (nested media as in whitted; a transparent surface that is not a
solid is a thin sheet that lets kt through unbent), a `dielectric` GGX reflection and refraction (Walter et al.
2007; light sampled on both sides of it; smooth at α = 0). ka and the scene's ambient are ignored. Shadow rays
stop at every surface: light through glass (caustics) is found by BSDF sampling alone.

`pass_rows` adds samples [s0, s1) of every pixel of a band of rows, in sample order, to float64 buffers. Every
random number is a function of (seed, pixel, sample, dimension), so a pixel's samples are the same whoever draws
them; the driver (`methods.path`) decides how samples are split into passes and blocks and how sums are added.
"""

from __future__ import annotations

import math

import numpy as np

from .. import config
from ..kernels.bsdf import (
    conserve_energy,
    eval_smooth,
    lobe_probs,
    mirror,
    power_heuristic,
    power_heuristic_over,
    relative_eta,
    sample_dielectric,
    sample_smooth,
    surface_fresnel,
)
from ..kernels.camera import camera_ray_at
from ..kernels.cutout import closest_visible_hit, occluded
from ..kernels.emitters import emitter_pdf, sample_emitter, selection_pmf
from ..kernels.environment import env_bilinear, env_pdf, env_radiance
from ..kernels.illumination import is_solid
from ..kernels.jit import njit, njit_alloc, njit_inline, njit_serial
from ..kernels.layout import (
    CAM_APERTURE,
    ENV_ENTRY,
    ENV_PRESENT,
    MAT_ALPHA,
    MAT_BUMP,
    MAT_IOR,
    MAT_KT,
    MAT_MODEL,
    MAT_ONE_SIDED,
    MAT_SIZE,
    MAT_TANGENT,
    MAT_TINT,
    MAT_TINT_T,
    MODEL_CLASSIC,
    MODEL_DIELECTRIC,
    MODEL_PRINCIPLED,
)
from ..kernels.principled import principled_at
from ..kernels.rng import pixel_hash, pixel_sample_key, rand2_key, rand_key
from ..kernels.sobol import pair_seed, sobol_block
from ..kernels.sampling import truncated_gaussian
from ..kernels.surface import offset_origin, shading_side, surface_at
from ..kernels.tangents import surface_tangents
from ..kernels.bump import bump_frame, bump_normal
from ..kernels.texture import material_coeffs
from ..kernels.vec import dot
from ..kernels.views import geometry_of, lighting_of, surfaces_of, textures_of

#: Bounces before Russian roulette may end a path (Mitsuba's default rr_depth).
RR_DEPTH = 5
#: No path is longer than this, whatever max_depth says (roulette ends paths long before).
MAX_BOUNCES = 1024
#: Nesting depth of the media a path can be inside (as whitted).
MAX_MEDIA = 4
#: Random dimensions: 0–1 position in the pixel, 2–3 lens, 4 shutter time; vertex k uses DIM_PATH + k·DIM_VERTEX
#: + (0 lobe, 1 emitter, 2–3 direction, 4–5 point on the emitter, 6 roulette).
DIM_TIME = 4
DIM_PATH = 8
DIM_VERTEX = 8
#: Dimension pairs drawn from Sobol points (`_draw2`): 0 pixel, 1 lens, then per vertex k PAIR_PATH + k·PAIRS_VERTEX
#: + (0 lobe and emitter, 1 direction, 2 point on the emitter), for the first vertex only (the first surface hit).
PAIR_PATH = 2
PAIRS_VERTEX = 3
SOBOL_PAIRS = PAIR_PATH + 1 * PAIRS_VERTEX
#: Samples of a pixel whose Sobol points are drawn together (`sobol.sobol_block`: a loop LLVM vectorises).
SOBOL_CHUNK = 64
SAMPLER_INDEPENDENT, SAMPLER_SOBOL = 0, 1
MODE_MIS, MODE_LIGHT, MODE_BSDF = 0, 1, 2
FILTER_BOX, FILTER_GAUSSIAN, FILTER_CENTRE = 0, 1, 2
#: The Gaussian pixel filter: standard deviation and radius in pixels (Mitsuba's `gaussian`).
GAUSSIAN_SIGMA = 0.5
GAUSSIAN_RADIUS = 2.0
#: What `_pass_rows` accumulates besides the radiance: squares (the variance AOV), the denoiser's guides (albedo,
#: normal, the light seen directly) and the direct light (the direct and indirect AOVs).
KEEP_SQUARES, KEEP_GUIDES, KEEP_DIRECT = 1, 2, 4


@njit_alloc
def _scratch():
    """Per-thread work arrays: the BVH stack, the media the path is inside (object, index of refraction), and a
    material row for the hit's own values (`kernels.principled.principled_at`, `_anisotropic_at`)."""
    return (np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK), np.empty(MAX_MEDIA, np.int64),
            np.empty(MAX_MEDIA), np.empty(MAT_SIZE))


@njit_inline
def _emitter_entry(em, ref, light):
    """The emitter-table entry of the surface hit (area light, emissive triangle or shape), -1 if none."""
    if light >= 0:
        return em.light_emit[light]
    if ref >= 0:
        return em.tri_emit[ref]
    return em.shape_emit[~ref]


@njit_inline
def _shadow_ray(p, n_geo, wi, dist):
    """The shadow ray towards the light point p + dist·wi: from the origin offset off the surface, aimed at that
    point itself and stopping just short of it (the emitter is a surface too, and a ray aimed along wi from the
    offset origin would meet a grazing light before the point). Its direction is the whole segment, not a unit
    vector, so the ray ends at t = 1 − ε (every intersection test is in the ray's own parameter, whatever its
    length: a square root and a division saved per light sample). Directional lights keep wi and dist."""
    origin = offset_origin(p, n_geo, wi, config.RAY_EPSILON)
    if dist >= config.T_FAR:
        return origin, wi, dist
    to = (p[0] + dist * wi[0] - origin[0], p[1] + dist * wi[1] - origin[1], p[2] + dist * wi[2] - origin[2])
    if not (to[0] != 0.0 or to[1] != 0.0 or to[2] != 0.0):
        return origin, wi, 0.0
    return origin, to, 1.0 - config.RAY_EPSILON


@njit_inline
def _media_across(media_obj, media_ior, n_media, obj, ior, entering):
    """Indices of refraction (n1, n2) on the incident and transmitted sides of solid `obj`'s surface."""
    n1 = media_ior[n_media - 1] if n_media > 0 else 1.0
    if entering:
        return n1, ior
    n2 = 1.0
    found = False
    for k in range(n_media - 1, -1, -1):  # the innermost medium once obj is left
        if media_obj[k] == obj and not found:
            found = True
            continue
        n2 = media_ior[k]
        break
    return n1, n2


@njit_inline
def _media_update(media_obj, media_ior, n_media, obj, ior, entering):
    """The media after a refraction through solid obj: pushed on entering, removed on leaving."""
    if entering:
        if n_media < MAX_MEDIA:
            media_obj[n_media] = obj
            media_ior[n_media] = ior
            return n_media + 1
        return n_media
    for k in range(n_media - 1, -1, -1):
        if media_obj[k] == obj:
            for j in range(k, n_media - 1):
                media_obj[j] = media_obj[j + 1]
                media_ior[j] = media_ior[j + 1]
            return n_media - 1
    return n_media


@njit_inline
def trace_path(geo, surf, lit, tex, em, o, d, time, max_depth, mode, sampler, points, col, key, scratch, background):
    """Radiance along the camera ray (o, d) at shutter time `time`: one path, in the order of the maths.

    Random numbers: `_draw2(sampler, points, col, key, pair, dim)` (see there). Returns (rgb, rays
    traced, t and object id of the first hit (t = −1 on a miss), albedo and shading normal of the first hit (the
    denoiser's guides), the emission of the first hit itself (the light seen directly, which the denoiser
    leaves alone), and the direct light: the part of rgb that `max_depth: 0` gathers — the emission (and
    background) found at vertices 0 and 1 and the light sampled at vertex 0 — which the `direct` AOV holds)."""
    stack, stack_t, media_obj, media_ior, hit_row = scratch
    L0 = L1 = L2 = 0.0
    b0 = b1 = b2 = 1.0  # throughput
    eta_scale = 1.0  # 1/η² of the refractions so far: roulette looks at the throughput without them
    rays = 0
    n_media = 0
    # the camera ray, and rays from mirrors and glass, see emitters with full weight (a plain bool from the start:
    # a literal True here had Numba compile `_missed` and `_emission_weight` a second time, for Literal[bool])
    prev_delta = np.bool_(True)
    prev_pdf = 0.0
    prev_p = o
    prev_n = (0.0, 0.0, 0.0)  # the previous vertex's shading normal: light selection there depends on it
    first_t = -1.0
    first_obj = -1
    albedo = (0.0, 0.0, 0.0)
    normal = (0.0, 0.0, 0.0)
    e0 = e1 = e2 = 0.0  # the emission of the first hit itself
    D0 = D1 = D2 = 0.0  # the direct light: what max_depth 0 gathers (vertices 0 and 1's emission, NEE at 0)
    depth = 0
    while True:
        # stage 1: the nearest surface along the ray
        hit = closest_visible_hit(geo, surf, lit, o, d, 0.0, config.T_FAR, stack, stack_t, time)
        rays += 1
        t = hit[0]
        if t < 0.0:  # the background, or the environment (weighted against sampling it as a light)
            bg, w = _missed(em, d, background, prev_p, prev_n, prev_delta, prev_pdf, mode)
            L0 += b0 * bg[0] * w
            L1 += b1 * bg[1] * w
            L2 += b2 * bg[2] * w
            if depth <= 1:
                D0, D1, D2 = D0 + b0 * bg[0] * w, D1 + b1 * bg[1] * w, D2 + b2 * bg[2] * w
            break
        ref = hit[1]
        p, n_geo, n_sh, u, v, mat_id, obj, light = surface_at(surf, o, d, t, ref, hit[2], hit[3], hit[4], time)
        mat = lit.materials[mat_id]
        wo = (-d[0], -d[1], -d[2])
        entering = n_geo[0] * d[0] + n_geo[1] * d[1] + n_geo[2] * d[2] < 0.0
        ka, kd, ks, kr, le, _ = material_coeffs(tex, mat, u, v, p)  # the material's, with its textures applied
        # stage 2: emission found by the BSDF-sampled ray, weighted against light sampling
        le0, le1, le2 = le
        if (le0 > 0.0 or le1 > 0.0 or le2 > 0.0) and (entering or mat[MAT_ONE_SIDED] == 0.0):
            w = _emission_weight(em, lit, surf, ref, light, hit[4], prev_p, prev_n, d, t, n_geo, time, prev_delta,
                                 prev_pdf, mode)
            L0 += b0 * le0 * w
            L1 += b1 * le1 * w
            L2 += b2 * le2 * w
            if depth <= 1:
                D0, D1, D2 = D0 + b0 * le0 * w, D1 + b1 * le1 * w, D2 + b2 * le2 * w
            if depth == 0:
                e0, e1, e2 = le0 * w, le1 * w, le2 * w
        if depth == 0:
            first_t, first_obj = t, obj
        if max_depth >= 0 and depth > max_depth:
            break
        # stage 3: the surface: bump map, normals on the viewer's side, the material's lobes
        if mat[MAT_BUMP] >= 0.0:
            dpdu, dpdv = bump_frame(surf, tex, mat, ref, hit[4], hit[2], hit[3], p, n_sh, time)
            n_sh = bump_normal(tex, mat, u, v, p, n_sh, dpdu, dpdv)
        n_s = shading_side(n_sh, n_geo, wo)
        n_g = n_geo if entering else (-n_geo[0], -n_geo[1], -n_geo[2])
        kt = (mat[MAT_KT], mat[MAT_KT + 1], mat[MAT_KT + 2])
        if mat[MAT_MODEL] == MODEL_CLASSIC:  # (a physical model conserves energy by its own construction)
            kd, ks, kr, kt = conserve_energy(kd, ks, kr, kt)
        wd, ws = kd, ks  # the weights the lobe choice draws by
        if mat[MAT_MODEL] == MODEL_PRINCIPLED:  # its factors times its textures, in the thread's own row
            kd, kt, wd, ws = principled_at(tex, mat, hit_row, u, v, p, dot(n_s, wo))
            mat = hit_row
            kr = (0.0, 0.0, 0.0)  # (a texture's classic targets do not reach it)
        elif mat[MAT_ALPHA] != mat[MAT_ALPHA + 1]:  # anisotropic: αu along the surface's ∂p/∂u, in the thread's row
            _anisotropic_at(surf, mat, hit_row, ref, hit[4], p, n_s, time)
            mat = hit_row
        p_d, p_s, p_r, p_t = lobe_probs(wd, ws, kr, kt)
        if depth == 0:
            albedo = (min(wd[0] + ws[0] + kr[0] + kt[0], 1.0), min(wd[1] + ws[1] + kr[1] + kt[1], 1.0),
                      min(wd[2] + ws[2] + kr[2] + kt[2], 1.0))
            normal = n_s
        if p_d + p_s + p_r + p_t == 0.0:
            break  # black: nothing leaves
        dim = DIM_PATH + depth * DIM_VERTEX
        pair = PAIR_PATH + depth * PAIRS_VERTEX
        # one pair picks the lobe and the emitter; with a single lobe that is not glass (whose pair also decides
        # between reflection and refraction) and a single emitter it decides nothing, and is not read (the
        # first vertex's Sobol pair is in the sample's batch all the same; a later vertex's hash is saved)
        u_lobe = u_pick = 0.0
        lobes = (p_d > 0.0) + (p_s > 0.0) + (p_r > 0.0)
        # (u_lobe also chooses a rough dielectric's reflection or refraction, a clear coat's lobe or the base's)
        one_more_choice = mat[MAT_MODEL] == MODEL_DIELECTRIC or mat[MAT_MODEL] == MODEL_PRINCIPLED
        if p_t > 0.0 or lobes > 1 or em.emit_cdf.shape[0] > 1 or one_more_choice:
            u_lobe, u_pick = _draw2(sampler, points, col, key, pair, dim)
        # stage 4: next-event estimation (the smooth lobes only: a mirror or glass cannot meet a light sample)
        if p_d + p_s > 0.0:
            ul1, ul2 = _draw2(sampler, points, col, key, pair + 2, dim + 4)
            c0, c1, c2, w, seen, extra = _next_event(geo, surf, lit, em, p, n_geo, n_s, n_g, wo, kd, ks, mat, p_d,
                                                     p_s, u_pick, ul1, ul2, mode, stack, stack_t, time)
            rays += extra
            if seen:
                L0 += b0 * c0 * w
                L1 += b1 * c1 * w
                L2 += b2 * c2 * w
                if depth == 0:
                    D0, D1, D2 = D0 + c0 * w, D1 + c1 * w, D2 + c2 * w
        # stage 5: BSDF sampling: the direction the path goes on in, and its weight f·cos/pdf
        u1, u2 = _draw2(sampler, points, col, key, pair + 1, dim + 2)
        p_smooth = p_d + p_s
        if u_lobe < p_smooth:
            eta = relative_eta(mat, entering)
            wi, (w0, w1, w2), pdf = sample_smooth(kd, ks, mat, p_d, p_s, eta, n_s, wo, u_lobe, u1, u2)
            cos_g = n_g[0] * wi[0] + n_g[1] * wi[1] + n_g[2] * wi[2]
            if not pdf > 0.0 or cos_g * (n_s[0] * wi[0] + n_s[1] * wi[1] + n_s[2] * wi[2]) <= 0.0:
                break
            if cos_g < 0.0:  # refracted by a rough dielectric (w holds its 1/η²)
                eta_scale *= eta * eta
                if is_solid(surf, ref):
                    n_media = _media_update(media_obj, media_ior, n_media, obj, mat[MAT_IOR], entering)
            prev_delta = False
            prev_pdf = pdf
        elif u_lobe < p_smooth + p_r:
            wi = mirror(wo, n_s)
            if n_g[0] * wi[0] + n_g[1] * wi[1] + n_g[2] * wi[2] <= 0.0:
                break
            f0, f1, f2 = surface_fresnel(mat, n_s[0] * wo[0] + n_s[1] * wo[1] + n_s[2] * wo[2])
            inv_p = 1.0 / p_r
            w0, w1, w2 = kr[0] * f0 * inv_p, kr[1] * f1 * inv_p, kr[2] * f2 * inv_p
            prev_delta = True
        else:
            wi, w0, w1, w2, eta2, n_media = _transmit(surf, ref, mat, obj, kt, p_t, (u_lobe - p_smooth - p_r) / p_t,
                                                       wo, n_s, d, entering, media_obj, media_ior, n_media)
            eta_scale /= eta2
            prev_delta = True
        b0 *= w0
        b1 *= w1
        b2 *= w2
        if not (b0 > 0.0 or b1 > 0.0 or b2 > 0.0):
            break
        # stage 6: Russian roulette
        if depth + 1 >= RR_DEPTH:
            q = min(max(b0, b1, b2) * eta_scale, 0.95)
            if rand_key(key, dim + 6) >= q:
                break
            inv_q = 1.0 / q
            b0 *= inv_q
            b1 *= inv_q
            b2 *= inv_q
        depth += 1
        if depth >= MAX_BOUNCES:
            break
        prev_p = p
        prev_n = n_s
        o = offset_origin(p, n_geo, wi, config.RAY_EPSILON)
        d = wi
    return (L0, L1, L2), rays, first_t, first_obj, albedo, normal, (e0, e1, e2), (D0, D1, D2)


@njit
def _anisotropic_at(surf, mat, row, ref, part, p, n, time):
    """The material row `mat` copied into `row` (the thread's own) with the hit's ∂p/∂u as its MAT_TANGENT, the
    direction its GGX width αu lies along (`microfacet.tangent_frame`; as Mitsuba's shading frame)."""
    for i in range(mat.shape[0]):
        row[i] = mat[i]
    dpdu = surface_tangents(surf, ref, part, p, n, time)[0]
    row[MAT_TANGENT], row[MAT_TANGENT + 1], row[MAT_TANGENT + 2] = dpdu


@njit_inline
def _missed(em, d, background, prev_p, prev_n, prev_delta, prev_pdf, mode):
    """What a ray that leaves the scene along d finds: the environment's radiance there with its MIS weight against
    the environment's light samples, or the background colour (weight 1). After the camera, a mirror or glass
    (weight 1: no light sample meets such a ray) the image is seen directly, filtered as the other methods show
    it (`env_bilinear`)."""
    if em.env_info[ENV_PRESENT] == 0.0:
        return (background[0], background[1], background[2]), 1.0
    if prev_delta:
        return env_bilinear(em.env_pixels, em.env_info, d), 1.0
    le = env_radiance(em, d)
    e = np.int64(em.env_info[ENV_ENTRY])
    if mode == MODE_BSDF or e < 0:
        return le, 1.0
    pdf_light = selection_pmf(em, e, prev_p, prev_n) * env_pdf(em, d)
    if not pdf_light > 0.0:
        return le, 1.0
    return le, 0.0 if mode == MODE_LIGHT else power_heuristic(prev_pdf, pdf_light)


@njit_inline
def _emission_weight(em, lit, surf, ref, light, part, prev_p, prev_n, d, t, n_geo, time, prev_delta, prev_pdf,
                     mode):
    """The MIS weight of emission a BSDF-sampled ray found: 1 after the camera, a mirror or glass (delta), or
    for an emitter light sampling cannot find (a textured one: not in the emitter table); else the power
    heuristic against light sampling's pdf for the same direction (0 under light sampling alone)."""
    if prev_delta or mode == MODE_BSDF:
        return 1.0
    e = _emitter_entry(em, ref, light)
    if e < 0:
        return 1.0
    pdf_light = emitter_pdf(em, lit, surf, e, prev_p, prev_n, d, t, n_geo, ref, part, time)
    if not pdf_light > 0.0:  # (pdf 0: it could not have found it from there)
        return 1.0
    return 0.0 if mode == MODE_LIGHT else power_heuristic(prev_pdf, pdf_light)


@njit_inline
def _next_event(geo, surf, lit, em, p, n_geo, n_s, n_g, wo, kd, ks, mat, p_d, p_s, u_pick, ul1, ul2, mode, stack,
                stack_t, time):
    """Next-event estimation at p: an emitter sampled (u_pick, ul1, ul2), the smooth lobes evaluated towards
    it, a shadow ray, MIS against BSDF sampling. Returns (its unweighted contribution
    f·L·cos per channel, its MIS weight, whether the light is seen, rays traced)."""
    wi, dist, led, les, pdf_light, delta = sample_emitter(em, lit, surf, p, n_s, u_pick, ul1, ul2, time)
    if not (pdf_light > 0.0 and (delta or mode != MODE_BSDF)):
        return 0.0, 0.0, 0.0, 0.0, False, 0
    cos_i = n_s[0] * wi[0] + n_s[1] * wi[1] + n_s[2] * wi[2]
    cos_g = n_g[0] * wi[0] + n_g[1] * wi[1] + n_g[2] * wi[2]
    if not (cos_i > 0.0 and cos_g > 0.0 or cos_i < 0.0 and cos_g < 0.0 and mat[MAT_MODEL] == MODEL_DIELECTRIC):
        return 0.0, 0.0, 0.0, 0.0, False, 0  # (a rough dielectric lets light through from below)
    entering = n_g[0] * n_geo[0] + n_g[1] * n_geo[1] + n_g[2] * n_geo[2] > 0.0
    fd, fs, pdf_bsdf = eval_smooth(kd, ks, mat, p_d, p_s, relative_eta(mat, entering), n_s, wo, wi)
    cos_i = abs(cos_i)
    c0 = (fd[0] * led[0] + fs[0] * les[0]) * cos_i
    c1 = (fd[1] * led[1] + fs[1] * les[1]) * cos_i
    c2 = (fd[2] * led[2] + fs[2] * les[2]) * cos_i
    if not (c0 > 0.0 or c1 > 0.0 or c2 > 0.0):
        return 0.0, 0.0, 0.0, 0.0, False, 0
    origin, ws, t_light = _shadow_ray(p, n_geo, wi, dist)
    if occluded(geo, surf, lit, origin, ws, t_light, stack, stack_t, time):
        return 0.0, 0.0, 0.0, 0.0, False, 1
    w = 1.0 / pdf_light if delta or mode == MODE_LIGHT else power_heuristic_over(pdf_light, pdf_bsdf)
    return c0, c1, c2, w, True, 1


@njit_inline
def _transmit(surf, ref, mat, obj, kt, p_t, u_t, wo, n_s, d, entering, media_obj, media_ior, n_media):
    """The transmission lobe chosen (with probability p_t; u_t uniform in [0, 1) again): through a solid's
    surface, reflect or refract by the Fresnel factor (radiance scaled by (n1/n2)² when it refracts, and the
    media updated); through a thin sheet, straight on. Returns (direction, weight (3), the η² that
    roulette's throughput divides by (1 when nothing refracts), the media count)."""
    inv_p = 1.0 / p_t
    w0, w1, w2 = kt[0] * inv_p, kt[1] * inv_p, kt[2] * inv_p
    if mat[MAT_MODEL] == MODEL_DIELECTRIC:
        return _smooth_glass(surf, ref, mat, obj, w0, w1, w2, u_t, wo, n_s, entering, media_obj, media_ior, n_media)
    if not is_solid(surf, ref):
        return d, w0, w1, w2, 1.0, n_media  # a thin transparent sheet: straight through
    n1, n2 = _media_across(media_obj, media_ior, n_media, obj, mat[MAT_IOR], entering)
    eta = n1 / n2
    wi, through, F = sample_dielectric(wo, n_s, eta, u_t)
    if not through:
        return wi, w0, w1, w2, 1.0, n_media
    n_media = _media_update(media_obj, media_ior, n_media, obj, mat[MAT_IOR], entering)
    return wi, w0 * eta * eta, w1 * eta * eta, w2 * eta * eta, eta * eta, n_media  # radiance ∝ (n1/n2)²


@njit
def _smooth_glass(surf, ref, mat, obj, w0, w1, w2, u_t, wo, n_s, entering, media_obj, media_ior, n_media):
    """`_transmit` for a smooth `dielectric` (MODEL_DIELECTRIC at α = 0): as Mitsuba's `dielectric`, its own
    int_ior/ext_ior on the two sides (not the media the path is in) and refraction on any surface; the reflected
    and the transmitted light take their own tints."""
    eta = 1.0 / relative_eta(mat, entering)  # (n_i/n_t, as sample_dielectric takes it)
    wi, through, F = sample_dielectric(wo, n_s, eta, u_t)
    if not through:
        return wi, w0 * mat[MAT_TINT], w1 * mat[MAT_TINT + 1], w2 * mat[MAT_TINT + 2], 1.0, n_media
    if is_solid(surf, ref):  # (for a classic glass inside it)
        n_media = _media_update(media_obj, media_ior, n_media, obj, mat[MAT_IOR], entering)
    k = eta * eta  # radiance ∝ (n1/n2)²
    return wi, w0 * mat[MAT_TINT_T] * k, w1 * mat[MAT_TINT_T + 1] * k, w2 * mat[MAT_TINT_T + 2] * k, k, n_media


@njit_inline
def _draw2(sampler, points, col, key, pair, dim):
    """Two random numbers for a pair of dimensions of a sample: padded Owen-scrambled Sobol points
    (`kernels.sobol`) for the pairs that matter most (the pixel, the lens, and the first vertex's lobe choice
    and light pick, BSDF direction and point on a light), read from column `col` of the pixel's `points`
    (`sobol.sobol_block`, drawn for a chunk of its samples at once); independent ones (dimensions dim, dim + 1
    of the sample's hash `key`, from one hash) for the rest or with `sampler: independent`."""
    if sampler == SAMPLER_SOBOL and pair < SOBOL_PAIRS:
        return points[2 * pair, col], points[2 * pair + 1, col]
    return rand2_key(key, dim)


@njit
def _pixel_point(filter_kind, u1, u2, x, y):
    """The image point of a sample of pixel (x, y) from (u1, u2): uniform in the pixel (box), drawn from the
    Gaussian filter around its centre, or the centre itself."""
    if filter_kind == FILTER_CENTRE:
        return x + 0.5, y + 0.5
    if filter_kind == FILTER_BOX:
        return x + u1, y + u2
    return (x + 0.5 + truncated_gaussian(u1, GAUSSIAN_SIGMA, GAUSSIAN_RADIUS),
            y + 0.5 + truncated_gaussian(u2, GAUSSIAN_SIGMA, GAUSSIAN_RADIUS))


@njit_serial
def pass_rows(sa, em, cam_vecs, cam_params, cam_time, width, height, y0, y1, s0, s1, spp, seed, max_depth, mode,
               sampler, filter_kind, keep, sums, sums2, guides, depth, object_id, rays_per_row, bad_per_row):
    """Rows y0 … y1−1 of a pass (`_pass_band`); the driver (`methods.path`) runs it band by band on the threads, with their scratch buffers."""
    scratch = _scratch()
    seeds = np.empty(SOBOL_PAIRS, np.uint64)  # the pixel's Sobol pair seeds (`sobol.pair_seed`)
    points = np.empty((2 * SOBOL_PAIRS, SOBOL_CHUNK))  # a chunk of the pixel's samples' Sobol points
    walk = np.empty(SOBOL_CHUNK, np.uint64)  # sobol_block's scratch
    _pass_band(sa, em, cam_vecs, cam_params, cam_time, width, height, y0, y1, s0, s1, spp, seed, max_depth, mode,
               sampler, filter_kind, keep, sums, sums2, guides, depth, object_id, rays_per_row, bad_per_row, scratch,
               seeds, points, walk)


@njit
def _pass_band(sa, em, cam_vecs, cam_params, cam_time, width, height, y0, y1, s0, s1, spp, seed, max_depth, mode,
               sampler, filter_kind, keep, sums, sums2, guides, depth, object_id, rays_per_row, bad_per_row, scratch,
               seeds, points, walk):
    """Samples s0 … s1−1 of every pixel of rows y0 … y1−1, added (in sample order) to the float64 buffers:
    sums (H, W, 3) of radiance; where `keep` says so (`KEEP_*` bits: only what the asked-for AOVs and the
    denoiser read is stored, a third of the stores per sample otherwise), sums2 (H, W, 3) of its square and
    guides (H, W, 12) of albedo, normal, the first hit's own emission and the direct light; depth and object_id
    from sample 0."""
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    for y in range(y0, y1):
        rays = 0
        bad = 0
        for x in range(width):
            pixel = y * width + x
            pixel_h = pixel_hash(seed, pixel)
            pixel_key = pixel_sample_key(pixel_h, np.int64(1) << 62)  # the pixel's own hash (no sample is 2^62)
            for k in range(SOBOL_PAIRS):
                seeds[k] = pair_seed(pixel_key, k)
            for s in range(s0, s1):
                col = (s - s0) % SOBOL_CHUNK
                if sampler == SAMPLER_SOBOL and col == 0:
                    sobol_block(seeds, spp, s, min(SOBOL_CHUNK, s1 - s), points, walk)
                key = pixel_sample_key(pixel_h, s)  # = rng.sample_key(seed, pixel, s)
                u1, u2 = _draw2(sampler, points, col, key, 0, 0)
                fx, fy = _pixel_point(filter_kind, u1, u2, x, y)
                lx, ly = 0.5, 0.5
                if cam_params[CAM_APERTURE] != 0.0:
                    lx, ly = _draw2(sampler, points, col, key, 1, 2)
                o, dr = camera_ray_at(cam_vecs, cam_params, width, height, fx, fy, lx, ly)
                tau = cam_time[0]
                if cam_time[1] > cam_time[0]:
                    tau = cam_time[0] + (cam_time[1] - cam_time[0]) * rand_key(key, DIM_TIME)
                rgb, n, t, obj, alb, nrm, emits, direct = trace_path(geo, surf, lit, tex, em, o, dr, tau, max_depth,
                                                                     mode, sampler, points, col, key, scratch,
                                                                     sa.background)
                rays += n
                r, g, b = rgb
                if not (math.isfinite(r) and math.isfinite(g) and math.isfinite(b)):
                    bad += 1  # a sample that divided by a vanishing pdf: dropped, never on the film
                    r = g = b = 0.0
                    direct = (0.0, 0.0, 0.0)
                sums[y, x, 0] += r
                sums[y, x, 1] += g
                sums[y, x, 2] += b
                if keep & KEEP_SQUARES:
                    sums2[y, x, 0] += r * r
                    sums2[y, x, 1] += g * g
                    sums2[y, x, 2] += b * b
                if keep & KEEP_GUIDES:
                    for c in range(3):
                        guides[y, x, c] += alb[c]
                        guides[y, x, 3 + c] += nrm[c]
                    if math.isfinite(emits[0] + emits[1] + emits[2]):
                        for c in range(3):
                            guides[y, x, 6 + c] += emits[c]
                if keep & KEEP_DIRECT:
                    for c in range(3):
                        guides[y, x, 9 + c] += direct[c]
                if s == 0 and t >= 0.0:
                    depth[y, x] = t
                    object_id[y, x] = obj
        rays_per_row[y] += rays
        bad_per_row[y] += bad
