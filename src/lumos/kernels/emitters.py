"""Light sampling for the path tracer: pick an emitter by power, sample a point on it, and the solid-angle pdf
of a direction that reaches it (for multiple importance sampling).

    wi, dist, le_d, le_s, pdf, delta = sample_emitter(em, lit, surf, p, n, u_pick, u1, u2, time)
    pdf = emitter_pdf(em, lit, surf, entry, p, n, wi, dist, n_geo, ref, part, time)
    e, pmf = select_emitter(em, p, n, u_pick);  pmf = selection_pmf(em, e, p, n)

`em` is a `layout.Emitters` table (`compile.emitters`), `lit` and `surf` the `Lighting` and `Surfaces` views;
p is the shading point and n its unit shading normal. The pdfs include the probability of picking the entry:
by the light tree (`kernels.light_tree`), which weighs each emitter by its estimated contribution at (p, n), or,
with `light_selection: power` (no tree in the table), by power alone. Light sampling and the MIS weight of an
emitter found by a BSDF ray call the same `selection_pmf`, so they agree.

Area lights use the routines of the classic model
(`illumination.sample_light`): its weight w for an area light is the equivalent-intensity factor cosθ_y·A/(π·d²)
(or Ω/π for a sphere), which is 1/(π·pdf) with pdf the solid-angle density of its sample. Delta lights (point,
spot, directional) return their irradiance factor instead (DESIGN.md §3: E = π·I·cosθ/att(d)) with delta = True.

Emissive primitives emit on both sides unless their material row says one (`MAT_ONE_SIDED`: an object with
`two_sided: false`, the front being the side its geometric normal faces); area lights of shape rect and disk on
the side of their normal only, unless `two_sided` (`LS_TWO_SIDED`). Emissive shapes are sampled uniformly over the area of their canonical
form, part by part, and the density carried to the world by the Jacobian J = |det M|·|M⁻ᵀ n| of the area
element (M the linear part of world_from_canonical, n the canonical unit normal), so any affine placement,
non-uniform scale included, is sampled exactly.
"""

import math

import numpy as np

from .. import config
from .environment import env_radiance, env_sample
from .illumination import sample_light, sphere_cone, sphere_cone_solid_angle
from .jit import njit, njit_inline
from .light_tree import tree_pick, tree_pmf
from .layout import (
    EMIT_ENV,
    EMIT_LIGHT,
    EMIT_PARTS,
    EMIT_SPHERE,
    EMIT_TRIANGLE,
    INFO_KIND,
    INFO_MATERIAL,
    LIGHT_DIRECTIONAL,
    LIGHT_SPHERE,
    LS_AREA,
    LS_RADIUS,
    LV_DIFFUSE,
    LV_DIRECTION,
    LV_POSITION,
    LV_SPECULAR,
    MAT_EMISSION,
    MAT_ONE_SIDED,
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CYLINDER,
    SHAPE_RECT,
    SHAPE_SPHERE,
)
from .sampling import concentric_disk, turn
from .vec import cross, dot, length, mul, normalize, row3, sub, xform_normal, xform_point

_NO_SAMPLE = ((0.0, 0.0, 1.0), 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, False)


@njit_inline
def pick_emitter(em, u):
    """The entry whose CDF interval holds u ∈ [0, 1) (bisection); -1 for an empty table."""
    cdf = em.emit_cdf
    n = cdf.shape[0]
    if n == 0:
        return -1
    lo = 0
    hi = n - 1
    while lo < hi:
        mid = (lo + hi) >> 1
        if u < cdf[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo


@njit_inline
def _by_tree(em):
    """True when the table has a light tree (`light_selection: tree`), False when it picks by power."""
    return em.tree_nodes.shape[0] > 0 or em.emit_unbounded.shape[0] > 0


@njit_inline
def select_emitter(em, p, n, u):
    """(entry, its probability) for the shading point p with unit normal n from u ∈ [0, 1); (-1, 0.0): none."""
    if _by_tree(em):
        return tree_pick(em, p, n, u)
    e = pick_emitter(em, u)
    if e < 0:
        return np.int64(-1), 0.0
    return np.int64(e), em.emit_pmf[e]


@njit_inline
def selection_pmf(em, e, p, n):
    """The probability that `select_emitter` at (p, n) picks entry e."""
    if _by_tree(em):
        return tree_pmf(em, e, p, n)
    return em.emit_pmf[e]


@njit
def _canonical_point(kind, part, u1, u2):
    """A point of the canonical shape's part, uniform by canonical area, and its unit canonical normal."""
    if kind == SHAPE_SPHERE:
        z = 1.0 - 2.0 * u1
        r = math.sqrt(max(0.0, 1.0 - z * z))
        cp, sp = turn(u2)
        q = (r * cp, r * sp, z)
        return q, q
    if kind == SHAPE_BOX:
        axis = part // 2
        c = 1.0 if part % 2 == 1 else 0.0
        s = 1.0 if part % 2 == 1 else -1.0
        if axis == 0:
            return (c, u1, u2), (s, 0.0, 0.0)
        if axis == 1:
            return (u1, c, u2), (0.0, s, 0.0)
        return (u1, u2, c), (0.0, 0.0, s)
    if (kind == SHAPE_CYLINDER or kind == SHAPE_CONE) and part == 0:
        cp, sp = turn(u2)
        if kind == SHAPE_CYLINDER:
            return (cp, sp, u1), (cp, sp, 0.0)
        rho = math.sqrt(u1)  # the cone's area element grows with the radius ρ = 1 − z
        k = 1.0 / math.sqrt(2.0)
        return (rho * cp, rho * sp, 1.0 - rho), (cp * k, sp * k, k)
    if kind == SHAPE_RECT:
        return (u1, u2, 0.0), (0.0, 0.0, 1.0)
    x, y = concentric_disk(u1, u2)  # caps and disks
    if part == 1:
        return (x, y, 0.0), (0.0, 0.0, -1.0)
    if part == 2:
        return (x, y, 1.0), (0.0, 0.0, 1.0)
    return (x, y, 0.0), (0.0, 0.0, 1.0)


@njit
def _part_area(kind, part):
    """Canonical area of a part (as `compile.emitters._PART_AREAS`)."""
    if kind == SHAPE_SPHERE:
        return 4.0 * math.pi
    if kind == SHAPE_BOX or kind == SHAPE_RECT:
        return 1.0
    if part == 0 and kind == SHAPE_CYLINDER:
        return 2.0 * math.pi
    if part == 0 and kind == SHAPE_CONE:
        return math.pi * math.sqrt(2.0)
    return math.pi


@njit_inline
def _shape_density(em, surf, e, s, part, n_canonical):
    """World-area density of the sample at a point of part `part` of shape s with unit canonical normal n:
    P(part) / (A_part · J), J = |det M|·|M⁻ᵀ n|; and the world unit normal there."""
    m = surf.shape_xform[s]
    n_w = xform_normal(m, n_canonical)  # M⁻ᵀ n: object_from_world's transpose
    slot = em.emit_slot[e]
    jac = em.emit_geom[slot, 3, 0] * length(n_w)
    kind = surf.shape_info[s, INFO_KIND]
    if not jac > 0.0:
        return 0.0, (0.0, 0.0, 1.0)
    return em.emit_parts[slot, part] / (_part_area(kind, part) * jac), normalize(n_w)


@njit_inline
def sample_emitter(em, lit, surf, p, n, u_pick, u1, u2, time):
    """One light sample for the point p with unit shading normal n: (wi, dist, le_d, le_s, pdf, delta).

    wi is the unit direction to the sampled point at distance dist (T_FAR-like for directional lights); le_d and
    le_s the radiance that reaches p along wi before the BSDF (for delta lights: the irradiance factor π·I/att,
    split into the diffuse Id and specular Is of the classic model); pdf the density of the sample (solid angle,
    times the probability of picking the emitter; for delta lights the probability alone). pdf = 0: no sample.
    """
    e, pmf = select_emitter(em, p, n, u_pick)
    if not pmf > 0.0:
        return _NO_SAMPLE
    kind = em.emit_kind[e]
    ref = em.emit_ref[e]
    if kind == EMIT_LIGHT:
        wi, dist, w = sample_light(lit, ref, p, u1, u2)
        if not w > 0.0:
            return _NO_SAMPLE
        vecs = lit.light_vecs[ref]
        if lit.light_kind[ref] <= LIGHT_DIRECTIONAL:
            f = math.pi * w
            return wi, dist, mul(row3(vecs, LV_DIFFUSE), f), mul(row3(vecs, LV_SPECULAR), f), pmf, True
        return wi, dist, row3(vecs, LV_DIFFUSE), row3(vecs, LV_SPECULAR), pmf / (math.pi * w), False
    if kind == EMIT_ENV:
        wi, pdf = env_sample(em, u1, u2)
        if not pdf > 0.0:
            return _NO_SAMPLE
        le = env_radiance(em, wi)
        return wi, config.T_FAR, le, le, pmf * pdf, False
    if kind == EMIT_SPHERE:
        g = em.emit_geom[em.emit_slot[e]]
        wi, dist, solid_angle = sphere_cone((g[3, 0], g[3, 1], g[3, 2]), g[3, 3], p, u1, u2)
        if not solid_angle > 0.0:
            return _NO_SAMPLE
        mat = np.int64(surf.shape_info[ref, INFO_MATERIAL])
        le = row3(lit.materials[mat:mat + 1, MAT_EMISSION:MAT_EMISSION + 3], 0)
        return wi, dist, le, le, pmf / solid_angle, False
    if kind == EMIT_TRIANGLE:
        v = surf.tri_verts
        su = math.sqrt(u1)
        b1 = 1.0 - su
        b2 = u2 * su
        v0 = (np.float64(v[ref, 0]), np.float64(v[ref, 1]), np.float64(v[ref, 2]))
        e1 = (v[ref, 3] - v0[0], v[ref, 4] - v0[1], v[ref, 5] - v0[2])
        e2 = (v[ref, 6] - v0[0], v[ref, 7] - v0[1], v[ref, 8] - v0[2])
        y = (v0[0] + b1 * e1[0] + b2 * e2[0], v0[1] + b1 * e1[1] + b2 * e2[1], v0[2] + b1 * e1[2] + b2 * e2[2])
        n_y = normalize(cross(e1, e2))
        density = 1.0 / em.emit_area[e]
        mat = np.int64(surf.tri_info[ref, INFO_MATERIAL])
    else:  # EMIT_SHAPE: a part by its probability, then a point uniform over its canonical area
        row = em.emit_parts[em.emit_slot[e]]
        part = EMIT_PARTS - 1
        acc = 0.0
        for k in range(EMIT_PARTS):
            acc += row[k]
            if u1 < acc:
                part = k
                u1 = min((u1 - (acc - row[k])) / row[k], 1.0 - 1e-12)  # reuse u1 within the part
                break
        kind_s = surf.shape_info[ref, INFO_KIND]
        q, n_c = _canonical_point(kind_s, part, u1, u2)
        y = xform_point(em.emit_geom[em.emit_slot[e]], q)
        m = surf.shape_xform[ref]
        if m[3, 3] != 0.0:  # a moving shape
            y = (y[0] + time * m[3, 0], y[1] + time * m[3, 1], y[2] + time * m[3, 2])
        density, n_y = _shape_density(em, surf, e, ref, part, n_c)
        mat = np.int64(surf.shape_info[ref, INFO_MATERIAL])
    to = sub(y, p)
    d2 = dot(to, to)
    if not (d2 > 0.0 and density > 0.0):
        return _NO_SAMPLE
    dist = math.sqrt(d2)
    wi = mul(to, 1.0 / dist)
    cos_y = dot(n_y, wi)  # < 0: p is on the side the emitter's normal faces
    if lit.materials[mat, MAT_ONE_SIDED] != 0.0 and cos_y >= 0.0:
        return _NO_SAMPLE  # p is behind a one-sided emitter
    cos_y = abs(cos_y)
    if not cos_y > 0.0:
        return _NO_SAMPLE
    le = row3(lit.materials[mat:mat + 1, MAT_EMISSION:MAT_EMISSION + 3], 0)
    return wi, dist, le, le, pmf * density * d2 / cos_y, False


@njit_inline
def emitter_pdf(em, lit, surf, e, p, n, wi, dist, n_geo, ref, part, time):
    """The density (solid angle at p, times the probability of picking entry e at p with unit shading normal n)
    with which `sample_emitter` would have drawn the direction wi that reaches, at distance dist, the point of
    emitter entry e with geometric unit normal n_geo (hit record ref, part); 0 for delta lights."""
    kind = em.emit_kind[e]
    if kind == EMIT_LIGHT and lit.light_kind[em.emit_ref[e]] <= LIGHT_DIRECTIONAL:
        return 0.0
    pmf = selection_pmf(em, e, p, n)
    if not pmf > 0.0:
        return 0.0
    r = em.emit_ref[e]
    if kind == EMIT_LIGHT:
        lk = lit.light_kind[r]
        if lk <= LIGHT_DIRECTIONAL:
            return 0.0
        sc = lit.light_scalars[r]
        if lk == LIGHT_SPHERE:
            omega = sphere_cone_solid_angle(row3(lit.light_vecs[r], LV_POSITION), sc[LS_RADIUS], p)
            return pmf / omega if omega > 0.0 else 0.0
        cos_y = abs(dot(row3(lit.light_vecs[r], LV_DIRECTION), wi))
        return pmf * dist * dist / (cos_y * sc[LS_AREA]) if cos_y > 0.0 else 0.0
    if kind == EMIT_SPHERE:
        g = em.emit_geom[em.emit_slot[e]]
        omega = sphere_cone_solid_angle((g[3, 0], g[3, 1], g[3, 2]), g[3, 3], p)
        return pmf / omega if omega > 0.0 else 0.0
    cos_y = abs(dot(n_geo, wi))
    if not cos_y > 0.0:
        return 0.0
    if kind == EMIT_TRIANGLE:
        return pmf * dist * dist / (cos_y * em.emit_area[e])
    # a shape: the canonical normal at the hit point
    m = surf.shape_xform[r]
    y = (p[0] + dist * wi[0], p[1] + dist * wi[1], p[2] + dist * wi[2])
    if m[3, 3] != 0.0:
        y = (y[0] - time * m[3, 0], y[1] - time * m[3, 1], y[2] - time * m[3, 2])
    n_c = _canonical_normal(surf.shape_info[r, INFO_KIND], part, xform_point(m, y))
    density, n_w = _shape_density(em, surf, e, r, part, n_c)
    return pmf * density * dist * dist / cos_y


@njit
def _canonical_normal(kind, part, q):
    """The unit outward normal of the canonical shape at its point q on part `part`."""
    if kind == SHAPE_SPHERE:
        return normalize(q)
    if kind == SHAPE_BOX:
        axis = part // 2
        s = 1.0 if part % 2 == 1 else -1.0
        if axis == 0:
            return (s, 0.0, 0.0)
        if axis == 1:
            return (0.0, s, 0.0)
        return (0.0, 0.0, s)
    if (kind == SHAPE_CYLINDER or kind == SHAPE_CONE) and part == 0:
        rho = math.sqrt(q[0] * q[0] + q[1] * q[1])
        if rho == 0.0:
            return (0.0, 0.0, 1.0)
        if kind == SHAPE_CYLINDER:
            return (q[0] / rho, q[1] / rho, 0.0)
        k = 1.0 / math.sqrt(2.0)
        return (q[0] / rho * k, q[1] / rho * k, k)
    if part == 1:
        return (0.0, 0.0, -1.0)
    return (0.0, 0.0, 1.0)
