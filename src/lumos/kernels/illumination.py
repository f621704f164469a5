"""The classic illumination model — the one function every method calls.

    I = Ka·Ia + Σ_lights [ Kd·Id·max(N·L, 0) + Ks·Is·max(R·V, 0)^n ] / att(d),   R = 2(N·L)N − L

per RGB channel (the textbook's Phong model, eq. for "illumination = ambient + diffuse + specular"), with
`att(d) = c + l·d + q·d²` for point lights and att = 1 for directional ones. A spot light is a point light
times its cone's falloff s² (`spot_falloff`). A light contributes nothing where N·L <= 0. An area light of
radiance Le is sampled at `samples` stratified points; each sample y acts as a point light of intensity
Le·cosθ_y·A / (π·r²·N), so that its diffuse part is Kd·E/π with E the irradiance the light delivers
(DESIGN.md §3). A sphere light is sampled uniformly in the cone it subtends (intensity Le·Ω/(π·N)).

With an environment that lights the model (no `ambient` given), Ia is its irradiance over π by the normal
(`ambient_light`) and the specular term gains its glossy reflection, Ks·L_n(R_V) with R_V = 2(N·V)N − V the
mirror direction and L_n the environment seen through a normalised Phong lobe of the material's exponent
(`environment.glossy_radiance`): each direction of the sky a light, the way Ia is its diffuse part, with the lobe
normalised so that Ks is the share of a uniform sky a glossy surface reflects. Neither is shadowed.

With `shadows` set, each light sample is tested with a shadow ray: opaque objects block it, transparent ones
let their kt through, the holes of opacity cut-outs let everything through (`shadow_transmittance`); raycast
passes False.
"""

import math

from .. import config
from .environment import glossy_radiance
from .jit import njit, njit_inline
from .layout import (
    AMBIENT_ROWS,
    LIGHT_DIRECTIONAL,
    LIGHT_DISK,
    LIGHT_POINT,
    LIGHT_RECT,
    LIGHT_SPOT,
    LS_AREA,
    LS_ATT_C,
    LS_ATT_L,
    LS_ATT_Q,
    LS_COS_INNER,
    LS_COS_OUTER,
    LS_RADIUS,
    LS_TWO_SIDED,
    LV_DIFFUSE,
    LV_DIRECTION,
    LV_EDGE_U,
    LV_EDGE_V,
    LV_POSITION,
    LV_SPECULAR,
    MAT_CUTOUT,
    MAT_KA,
    MAT_KD,
    MAT_KS,
    MAT_KT,
    MAT_SHININESS,
    FLAG_CAPPED,
    INFO_FLAGS,
    INFO_KIND,
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CSG,
    SHAPE_CYLINDER,
    SHAPE_MESH_SOLID,
    SHAPE_SPHERE,
)
from .rng import rand01
from .sampling import concentric_disk, stratified_2d, turn
from .surface import offset_origin, surface_at_of
from .texture import is_hole, lighting_textures
from .traverse import SHADOW_CUTOFF, closest_hit_of, transmittance_of
from .vec import dot, length, madd, mul, normalize, orthonormal_basis, row3, sub

_INV_PI = 1.0 / math.pi
#: Dimensions of the per-pixel random stream used by light sampling start here (camera/lens use 0..3, time 4).
DIM_LIGHTS = 16
#: A point within this factor of a sphere's radius squared counts as on it (rounding puts the sphere's own
#: surface points on either side): the cone it subtends is empty, for sampling and for the pdf alike.
_ON_SPHERE = 1.0 + 1e-9
#: A shadow ray passes through at most this many transparent surfaces before it counts as blocked.
MAX_SHADOW_CROSSINGS = 32


@njit_inline
def sample_light(lit, j, p, u1, u2):
    """One sample of light j seen from point p.

    Returns (L, dist, w) with L the unit direction to the light, dist the distance to the sampled point (a large
    number for directional lights) and w the factor that scales the light's Id and Is for this sample
    (1/att for point lights, their cone's falloff/att for spot lights, 1 for directional, the equivalent-intensity
    factor for area lights; 0 if the sample cannot light p).
    """
    kind = lit.light_kind[j]
    vecs = lit.light_vecs[j]
    sc = lit.light_scalars[j]
    if kind == LIGHT_DIRECTIONAL:
        return mul(row3(vecs, LV_DIRECTION), -1.0), config.T_FAR, 1.0
    if kind == LIGHT_POINT or kind == LIGHT_SPOT:
        to = sub(row3(vecs, LV_POSITION), p)
        dist = length(to)
        if dist == 0.0:
            return (0.0, 0.0, 1.0), 0.0, 0.0
        att = sc[LS_ATT_C] + sc[LS_ATT_L] * dist + sc[LS_ATT_Q] * dist * dist
        L = mul(to, 1.0 / dist)
        if kind == LIGHT_SPOT:
            return L, dist, spot_factor(lit, j, L) / att
        return L, dist, 1.0 / att
    if kind == LIGHT_RECT or kind == LIGHT_DISK:
        if kind == LIGHT_RECT:
            a, b = u1, u2
        else:
            a, b = concentric_disk(u1, u2)
        y = madd(madd(row3(vecs, LV_POSITION), row3(vecs, LV_EDGE_U), a), row3(vecs, LV_EDGE_V), b)
        to = sub(y, p)
        dist = length(to)
        if dist == 0.0:
            return (0.0, 0.0, 1.0), 0.0, 0.0
        inv = 1.0 / dist
        L = mul(to, inv)
        cos_light = -dot(row3(vecs, LV_DIRECTION), L)  # one-sided: emits along its normal only
        if sc[LS_TWO_SIDED] != 0.0:
            cos_light = abs(cos_light)
        if cos_light <= 0.0:
            return L, dist, 0.0
        return L, dist, cos_light * sc[LS_AREA] * _INV_PI * (inv * inv)
    # sphere light: uniform directions in the cone it subtends from p
    L, dist, solid_angle = sphere_cone(row3(vecs, LV_POSITION), sc[LS_RADIUS], p, u1, u2)
    return L, dist, solid_angle * _INV_PI


@njit_inline
def spot_falloff(cos_theta, cos_outer, cos_inner):
    """The one spot-light falloff every method uses: s² with s = clamp((cosθ − cos angle)/(cos inner_angle −
    cos angle), 0, 1) (glTF KHR_lights_punctual's recommended falloff, smoothed by squaring); a hard step
    (1 where cosθ >= cos angle, else 0) when the two cones coincide (their cosines within SPOT_HARD_EDGE)."""
    width = cos_inner - cos_outer
    if width < config.SPOT_HARD_EDGE:
        return 1.0 if cos_theta >= cos_outer else 0.0
    s = (cos_theta - cos_outer) / width
    if s <= 0.0:
        return 0.0
    if s >= 1.0:
        return 1.0
    return s * s


@njit_inline
def spot_factor(lit, j, L):
    """The falloff of spot light j towards a point that sees it along the unit direction L (from the point to
    the light): cosθ = dot(axis, −L)."""
    vecs = lit.light_vecs[j]
    sc = lit.light_scalars[j]
    cos_theta = -(vecs[LV_DIRECTION, 0] * L[0] + vecs[LV_DIRECTION, 1] * L[1] + vecs[LV_DIRECTION, 2] * L[2])
    return spot_falloff(cos_theta, sc[LS_COS_OUTER], sc[LS_COS_INNER])


@njit_inline
def sphere_cone(center, r, p, u1, u2):
    """A uniform direction in the cone that the sphere (center, r) subtends from p: (L, dist to the sphere's near
    surface along L, solid angle of the cone); the solid angle is 0 when p is inside the sphere."""
    to = sub(center, p)
    dc = length(to)
    if dc * dc <= r * r * _ON_SPHERE:
        return (0.0, 0.0, 1.0), 0.0, 0.0  # inside the light (or on it: a point of an emissive sphere itself)
    axis = mul(to, 1.0 / dc)
    sin2_max = (r * r) / (dc * dc)
    cos_max = math.sqrt(max(0.0, 1.0 - sin2_max))
    cos_t = 1.0 - u1 * (1.0 - cos_max)
    sin_t = math.sqrt(max(0.0, 1.0 - cos_t * cos_t))
    cp, sp = turn(u2)
    t1, t2 = orthonormal_basis(axis)
    L = normalize(madd(madd(mul(axis, cos_t), t1, sin_t * cp), t2, sin_t * sp))
    # distance to the near surface of the sphere along L
    b = dot(to, L)
    disc = b * b - (dc * dc - r * r)
    dist = b - math.sqrt(max(0.0, disc))
    return L, dist, 2.0 * math.pi * (1.0 - cos_max)


@njit
def sphere_cone_solid_angle(center, r, p):
    """The solid angle of the cone the sphere (center, r) subtends from p (0 inside it): 2π(1 − cos θ_max)."""
    to = sub(center, p)
    dc2 = dot(to, to)
    if dc2 <= r * r * _ON_SPHERE:
        return 0.0
    return 2.0 * math.pi * (1.0 - math.sqrt(max(0.0, 1.0 - r * r / dc2)))


@njit
def phong(n, L, V, mat, Id, Is, w):
    """One light's term of the classic model for unit N, L, V: (Kd·Id·(N·L) + Ks·Is·(R·V)^n)·w, per channel."""
    kd = (mat[MAT_KD], mat[MAT_KD + 1], mat[MAT_KD + 2])
    ks = (mat[MAT_KS], mat[MAT_KS + 1], mat[MAT_KS + 2])
    return phong_coeffs(n, L, V, kd, ks, mat[MAT_SHININESS], Id, Is, w)


#: Columns of `illuminate_terms`' per-light record.
PL_DIFFUSE, PL_SPECULAR, PL_SHADOW, PL_COS, PL_LIT, PL_SPOT = 0, 3, 6, 9, 10, 11
PER_LIGHT_SIZE = 12


@njit_inline
def phong_coeffs(n, L, V, kd, ks, shininess, Id, Is, w):
    """`phong` with the coefficients given as (r, g, b) tuples (a textured surface's, which vary per point)."""
    d, s = phong_terms(n, L, V, kd, ks, shininess, Id, Is, w)
    return d[0] + s[0], d[1] + s[1], d[2] + s[2]


@njit_inline
def phong_terms(n, L, V, kd, ks, shininess, Id, Is, w):
    """One light's diffuse term Kd·Id·(N·L)·w and specular term Ks·Is·(R·V)^n·w, apart: ((r, g, b), (r, g, b))."""
    n_dot_l = dot(n, L)
    if n_dot_l <= 0.0 or w == 0.0:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    R = madd(mul(L, -1.0), n, 2.0 * n_dot_l)
    r_dot_v = dot(R, V)
    spec = r_dot_v**shininess if r_dot_v > 0.0 else 0.0  # no highlight where R·V <= 0, even for n = 0
    dw = n_dot_l * w
    sw = spec * w
    return ((kd[0] * Id[0] * dw, kd[1] * Id[1] * dw, kd[2] * Id[2] * dw),
            (ks[0] * Is[0] * sw, ks[1] * Is[1] * sw, ks[2] * Is[2] * sw))


@njit
def illuminate(lit, geo, surf, p, n, n_geo, V, mat_id, seed, pixel, sample, shadows, stack, stack_t, time):
    """The classic model at point p with unit shading normal n and geometric normal n_geo (both facing the
    viewer) and unit V towards the eye, with the coefficients of material `mat_id` (see `illuminate_coeffs`)."""
    mat = lit.materials[mat_id]
    ka = (mat[MAT_KA], mat[MAT_KA + 1], mat[MAT_KA + 2])
    kd = (mat[MAT_KD], mat[MAT_KD + 1], mat[MAT_KD + 2])
    ks = (mat[MAT_KS], mat[MAT_KS + 1], mat[MAT_KS + 2])
    return illuminate_coeffs(lit, geo, surf, p, n, n_geo, V, ka, kd, ks, mat[MAT_SHININESS], seed, pixel, sample,
                             shadows, stack, stack_t, time)


# Real spherical harmonics of bands 0-2 (the constants of Ramamoorthi & Hanrahan 2001), in the order of `sh9`
_SH0 = 0.28209479177387814  # 1/(2·sqrt(π))
_SH1 = 0.4886025119029199  # sqrt(3/(4π))
_SH2 = 1.0925484305920792  # sqrt(15/(4π))
_SH20 = 0.31539156525252005  # sqrt(5/(16π))
_SH22 = 0.5462742152960396  # sqrt(15/(16π))


def sh9(x, y, z):
    """The nine basis functions at unit direction(s) (x, y, z): NumPy arrays of any shape (stacked first), for
    `compile.environment.irradiance_sh`; `ambient_light` evaluates the same in the kernels."""
    import numpy as np

    one = np.ones_like(x)
    return np.stack([_SH0 * one, _SH1 * y, _SH1 * z, _SH1 * x, _SH2 * x * y, _SH2 * y * z,
                     _SH20 * (3.0 * z * z - 1.0), _SH2 * x * z, _SH22 * (x * x - y * y)])


@njit_inline
def ambient_light(amb, n):
    """Ia at a surface of unit normal n (`layout.AMBIENT_ROWS`): the constant row 0 plus the environment's
    irradiance over π in the spherical harmonics of rows 1-9 where there are ten rows, never negative (nine terms
    of a sun ring a little on its far side)."""
    x, y, z = n[0], n[1], n[2]
    basis = (_SH0, _SH1 * y, _SH1 * z, _SH1 * x, _SH2 * x * y, _SH2 * y * z, _SH20 * (3.0 * z * z - 1.0), _SH2 * x * z,
             _SH22 * (x * x - y * y))
    r, g, b = amb[0, 0], amb[0, 1], amb[0, 2]
    for k in range(min(amb.shape[0], AMBIENT_ROWS) - 1):  # (one row, the constant, without an environment to read)
        r += amb[k + 1, 0] * basis[k]
        g += amb[k + 1, 1] * basis[k]
        b += amb[k + 1, 2] * basis[k]
    return max(r, 0.0), max(g, 0.0), max(b, 0.0)


@njit_inline
def illuminate_coeffs(lit, geo, surf, p, n, n_geo, V, ka, kd, ks, shininess, seed, pixel, sample, shadows, stack,
                      stack_t, time):
    """The classic model with the coefficients given as (r, g, b) tuples (a textured surface's vary per point):
    the sum of `illuminate_terms`. Returns ((r, g, b), shadow rays traced)."""
    a, d, s, rays = illuminate_terms(lit, geo, surf, p, n, n_geo, V, ka, kd, ks, shininess, seed, pixel, sample,
                                     shadows, stack, stack_t, time, lit.light_scalars, -1, geo)
    return (a[0] + d[0] + s[0], a[1] + d[1] + s[1], a[2] + d[2] + s[2]), rays


@njit_inline
def illuminate_terms(lit, geo, surf, p, n, n_geo, V, ka, kd, ks, shininess, seed, pixel, sample, shadows, stack,
                     stack_t, time, per_light, log_base, shaped):
    """The classic model's three terms apart: (ambient Ka·Ia, diffuse Σ Kd·Id·(N·L), specular Σ Ks·Is·(R·V)^n,
    shadow rays traced), each term an (r, g, b) tuple, each light's share multiplied by its shadow transmittance.

    `lit`, `geo` and `surf` are the `layout.Lighting`, `Geometry` and `Surfaces` views; n is the shading normal
    and n_geo the geometric one, both on the viewer's side. With `shadows`, each light sample is tested by a
    shadow ray that transparent objects attenuate (`shadow_transmittance`); raycast passes None, for which Numba
    prunes the shadow rays' code before typing it (a literal False it would type and compile all the same). Random
    numbers for area-light samples come from (seed, pixel, sample, DIM_LIGHTS + ...), so the result depends on
    nothing else. With `log_base` >= 0, rows log_base + j of `per_light` (float64 (m, PER_LIGHT_SIZE)) receive
    light j's share (`lumos.explain`; with −1, any float64 2-D array, never touched): PL_DIFFUSE, PL_SPECULAR (rgb, shadowed), PL_SHADOW (the mean transmittance of its
    samples, 0 for samples behind the surface), PL_COS (the mean N·L over its samples), PL_LIT (how many of its
    samples face the surface and are not blocked), PL_SPOT (spot lights: the falloff of their cone towards p).
    `shaped`: `geo`, or None for a scene of triangles only (raster's polygons), whose shadow rays are then
    compiled without the analytic shapes' tests (`shadow_transmittance`).
    """
    log = log_base >= 0
    if log:  # (element by element: a device function makes no array views, see kernels.jit)
        for j in range(lit.light_kind.shape[0]):
            for c in range(PER_LIGHT_SIZE):
                per_light[log_base + j, c] = 0.0
    ia = ambient_light(lit.ambient, n)
    ambient = (ka[0] * ia[0], ka[1] * ia[1], ka[2] * ia[2])
    dr = dg = db = 0.0
    sr = sg = sb = 0.0
    rays = 0
    dim = DIM_LIGHTS
    for j in range(lit.light_kind.shape[0]):
        Id = row3(lit.light_vecs[j], LV_DIFFUSE)
        Is = row3(lit.light_vecs[j], LV_SPECULAR)
        n_samples = lit.light_samples[j]
        inv_n = 1.0 / n_samples
        for s in range(n_samples):
            u1, u2 = 0.5, 0.5
            if lit.light_kind[j] > LIGHT_DIRECTIONAL:
                u1, u2 = stratified_2d(s, n_samples, rand01(seed, pixel, sample, dim),
                                       rand01(seed, pixel, sample, dim + 1))
                dim += 2
            L, dist, w = sample_light(lit, j, p, u1, u2)
            if log and lit.light_kind[j] == LIGHT_SPOT:
                per_light[log_base + j, PL_SPOT] += spot_factor(lit, j, L) * inv_n
            if w == 0.0 or dot(n, L) <= 0.0:
                continue
            tr, tg, tb = 1.0, 1.0, 1.0
            if shadows is not None and shadows:  # (None, raycast's: the shadow rays' code is not compiled)
                origin = offset_origin(p, n_geo, L, config.RAY_EPSILON)
                (tr, tg, tb), extra = shadow_transmittance(geo, surf, lit, origin, L,
                                                           dist * (1.0 - config.RAY_EPSILON), stack, stack_t, time,
                                                           shaped)
                rays += extra
            if log:
                per_light[log_base + j, PL_SHADOW] += tr * inv_n
                per_light[log_base + j, PL_SHADOW + 1] += tg * inv_n
                per_light[log_base + j, PL_SHADOW + 2] += tb * inv_n
                per_light[log_base + j, PL_COS] += dot(n, L) * inv_n
            if tr == 0.0 and tg == 0.0 and tb == 0.0:
                continue
            d, sp = phong_terms(n, L, V, kd, ks, shininess, Id, Is, w * inv_n)
            if log:
                for k in range(3):
                    per_light[log_base + j, PL_DIFFUSE + k] += d[k] * (tr, tg, tb)[k]
                    per_light[log_base + j, PL_SPECULAR + k] += sp[k] * (tr, tg, tb)[k]
                per_light[log_base + j, PL_LIT] += 1.0
            dr += d[0] * tr
            dg += d[1] * tg
            db += d[2] * tb
            sr += sp[0] * tr
            sg += sp[1] * tg
            sb += sp[2] * tb
    if lit.ambient.shape[0] > AMBIENT_ROWS:  # an environment that lights the model: its glossy reflection too
        c = 2.0 * dot(n, V)
        gr, gg, gb = glossy_radiance(lit.ambient, (c * n[0] - V[0], c * n[1] - V[1], c * n[2] - V[2]), shininess)
        sr += ks[0] * gr
        sg += ks[1] * gg
        sb += ks[2] * gb
    return ambient, (dr, dg, db), (sr, sg, sb), rays


@njit_inline
def is_solid(surf, ref):
    """True for hits on closed solids (sphere, box, capped cylinder or cone, csg, mesh solid): shadow and
    refracted rays enter and leave them. Triangles, planes, disks, rects and open cylinders are surfaces."""
    if ref >= 0:
        return False
    info = surf.shape_info[~ref]
    kind = info[INFO_KIND]
    if kind == SHAPE_SPHERE or kind == SHAPE_BOX or kind == SHAPE_CSG or kind == SHAPE_MESH_SOLID:
        return True
    if kind == SHAPE_CYLINDER or kind == SHAPE_CONE:
        return (info[INFO_FLAGS] & FLAG_CAPPED) != 0
    return False


@njit_inline
def shadow_transmittance(geo, surf, lit, origin, L, dist, stack, stack_t, time, shaped):
    """What reaches `origin` from a light at `dist` along L: (rgb factor, rays traced). Opaque objects (kt = 0)
    block; a transparent object multiplies by its kt each time the ray enters it if it is a solid, each time
    the ray crosses it if it is a surface (DESIGN.md §3: once per transparent object passed through). `shaped`:
    `geo`, or None for a scene of triangles only (raster's polygons), whose analytic shapes' tests are then not
    compiled (`traverse._pass_through`)."""
    # one any-order traversal settles a shadow ray unless a csg object or an open cylinder or cone that lets
    # light through, or a surface with an opacity cut-out, is on it: nothing in the way, an opaque occluder, or transparent triangles, planes and
    # convex solids, each counted once
    rgb, settled = transmittance_of(geo, shaped, surf.tri_info, lit.materials, origin, L, dist, stack, time)
    if settled:
        return rgb, 1
    rgb, rays = walk_transmittance_of(geo, shaped, surf, lit, origin, L, dist, stack, stack_t, time)
    return rgb, rays + 1


@njit
def walk_transmittance(geo, surf, lit, origin, L, dist, stack, stack_t, time):
    """`shadow_transmittance` hit by hit, in order along the ray, one closest-hit traversal each: (rgb factor,
    rays traced). It handles every kind of surface (a csg object may be entered several times) and the holes of
    opacity cut-outs (`kernels.cutout`), and is the slow twin that `traverse.transmittance` is tested against."""
    return walk_transmittance_of(geo, geo, surf, lit, origin, L, dist, stack, stack_t, time)


@njit
def walk_transmittance_of(geo, shaped, surf, lit, origin, L, dist, stack, stack_t, time):
    """`walk_transmittance`, with `shaped` `geo`, or None for a scene of triangles only."""
    tr, tg, tb = 1.0, 1.0, 1.0
    o = origin
    t_max = dist
    rays = 0
    for _ in range(MAX_SHADOW_CROSSINGS):
        rays += 1
        hit = closest_hit_of(geo, shaped, o, L, 0.0, t_max, stack, stack_t, time)
        t = hit[0]
        if t < 0.0:
            return (tr, tg, tb), rays
        p, n_geo, n_sh, u, v, mat_id, obj, light = surface_at_of(surf, shaped, o, L, t, hit[1], hit[2], hit[3],
                                                                 hit[4], time)
        mat = lit.materials[mat_id]
        if light >= 0:  # the emitting surface of an area light is not an occluder
            pass
        elif mat[MAT_CUTOUT] != 0.0 and is_hole(lighting_textures(lit), mat, u, v, p):  # a cut-out's hole: passes
            pass
        else:
            kt0, kt1, kt2 = mat[MAT_KT], mat[MAT_KT + 1], mat[MAT_KT + 2]
            if kt0 <= 0.0 and kt1 <= 0.0 and kt2 <= 0.0:
                return (0.0, 0.0, 0.0), rays
            if not is_solid(surf, hit[1]) or dot(L, n_geo) < 0.0:
                tr *= kt0
                tg *= kt1
                tb *= kt2
                if max(tr, tg, tb) < SHADOW_CUTOFF:
                    return (0.0, 0.0, 0.0), rays
        # continue just past the hit
        o = offset_origin(p, n_geo, L, config.RAY_EPSILON)
        t_max = t_max - t
        if t_max <= 0.0:
            break
    return (tr, tg, tb), rays
