"""Microfacet reflection and refraction for the path tracer: the GGX (Trowbridge–Reitz) distribution of normals,
Smith's masking, sampling of the visible normals, the Fresnel factors of a conductor and of a dielectric, and the
rough dielectric's two lobes (`eval_ggx_dielectric`, after Walter et al. 2007).

    D(h)  = 1 / (π·αu·αv·((hx/αu)² + (hy/αv)² + hz²)²)          h in the local frame (t, b, n), hz = cos θh
    Λ(w)  = (−1 + sqrt(1 + (αu²·wx² + αv²·wy²)/wz²)) / 2         G1(w, h) = 1/(1 + Λ(w)) where w·h and wz agree
    f     = F(wo·h)·D(h)·G1(wo, h)·G1(wi, h) / (4·cos θo·cos θi)   h = (wo + wi)/|wo + wi|
    pdf   = G1(wo, h)·D(h) / (4·cos θo)                          of wi = reflect(wo, h), h drawn from the normals
                                                                  visible from wo (Heitz 2018)

Shadowing is Smith's separable form G1·G1, as in Mitsuba 3 (pbrt-v4 uses the height-correlated one; they differ
by at most a few per cent at α near 1). The lobe loses the energy of light that would scatter more than once
between microfacets: the white furnace (F = 1) keeps 100% at α → 0 and less as α grows (tests/kernels).
The tangent frame (`tangent_frame`): αu lies along the given tangent (the surface's ∂p/∂u, made perpendicular to
n: Mitsuba's shading frame), or, where none is given (0, 0, 0), along `vec.orthonormal_basis(n)`'s first axis.
"""

import math

from .jit import njit, njit_inline
from .sampling import turn
from .vec import dot, orthonormal_basis

_INV_PI = 1.0 / math.pi


@njit
def fresnel_conductor(cos_i, eta, k):
    """Unpolarised Fresnel reflectance of a conductor of complex index η + ik at incidence cos_i >= 0 (the exact
    formula, e.g. Born & Wolf; pbrt's and Mitsuba's). η = k = 0 stands for a perfect reflector: 1."""
    if eta == 0.0 and k == 0.0:
        return 1.0
    c2 = cos_i * cos_i
    s2 = 1.0 - c2
    t0 = eta * eta - k * k - s2
    a2b2 = math.sqrt(max(t0 * t0 + 4.0 * eta * eta * k * k, 0.0))
    a = math.sqrt(max(0.5 * (a2b2 + t0), 0.0))
    t1 = a2b2 + c2
    t2 = 2.0 * cos_i * a
    rs = (t1 - t2) / (t1 + t2)
    t3 = a2b2 * c2 + s2 * s2
    t4 = t2 * s2
    rp = rs * (t3 - t4) / (t3 + t4)
    return 0.5 * (rs + rp)


@njit
def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance of a smooth dielectric interface and the cosine of the refracted ray:
    (F, cos_t), with eta = n_incident / n_transmitted and cos_i >= 0 on the incident side (Born & Wolf; F = 1
    and cos_t = 0 under total internal reflection)."""
    sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i)
    if sin2_t >= 1.0:
        return 1.0, 0.0
    cos_t = math.sqrt(1.0 - sin2_t)
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return 0.5 * (rs * rs + rp * rp), cos_t


@njit
def ggx_d(hx, hy, hz, au, av):
    """The GGX density of microfacet normals h (local frame, unit), per unit solid angle projected on the surface."""
    if hz <= 0.0:
        return 0.0
    x = hx / au
    y = hy / av
    t = x * x + y * y + hz * hz
    return _INV_PI / (au * av * t * t)


@njit
def smith_g1(wx, wy, wz, w_dot_h, au, av):
    """Smith's masking of direction w (local frame) by GGX microfacets: 1/(1 + Λ(w)); 0 where w sees the back of
    the microfacet h (w·h and cos θ of different signs)."""
    if w_dot_h * wz <= 0.0:
        return 0.0
    t = (au * au * wx * wx + av * av * wy * wy) / (wz * wz)
    return 2.0 / (1.0 + math.sqrt(1.0 + t))


@njit
def sample_visible_normal(wx, wy, wz, au, av, u1, u2):
    """A microfacet normal drawn from the normals visible from w (local frame, wz > 0), with density
    G1(w, h)·max(0, w·h)·D(h)/cos θ (Heitz 2018, "Sampling the GGX distribution of visible normals")."""
    vx, vy, vz = au * wx, av * wy, wz  # to the hemisphere configuration
    inv = 1.0 / math.sqrt(vx * vx + vy * vy + vz * vz)
    vx, vy, vz = vx * inv, vy * inv, vz * inv
    lensq = vx * vx + vy * vy
    if lensq > 0.0:
        il = 1.0 / math.sqrt(lensq)
        t1 = (-vy * il, vx * il, 0.0)
    else:
        t1 = (1.0, 0.0, 0.0)
    t2 = (vy * t1[2] - vz * t1[1], vz * t1[0] - vx * t1[2], vx * t1[1] - vy * t1[0])
    r = math.sqrt(u1)
    c, s = turn(u2)
    p1 = r * c
    p2 = r * s
    h = 0.5 * (1.0 + vz)
    p2 = (1.0 - h) * math.sqrt(max(0.0, 1.0 - p1 * p1)) + h * p2
    p3 = math.sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2))
    nx = p1 * t1[0] + p2 * t2[0] + p3 * vx
    ny = p1 * t1[1] + p2 * t2[1] + p3 * vy
    nz = p1 * t1[2] + p2 * t2[2] + p3 * vz
    mx, my, mz = au * nx, av * ny, max(nz, 1e-9)  # back to the ellipsoid configuration
    inv = 1.0 / math.sqrt(mx * mx + my * my + mz * mz)
    return mx * inv, my * inv, mz * inv


@njit_inline
def local(v, t, b, n):
    return dot(v, t), dot(v, b), dot(v, n)


@njit_inline
def tangent_frame(n, tangent):
    """(t, b): unit axes perpendicular to unit n, t along `tangent` made perpendicular to n (Gram–Schmidt), b =
    n × t; `vec.orthonormal_basis(n)` where the tangent is (0, 0, 0) or along n."""
    k = dot(tangent, n)
    tx, ty, tz = tangent[0] - k * n[0], tangent[1] - k * n[1], tangent[2] - k * n[2]
    length = math.sqrt(tx * tx + ty * ty + tz * tz)
    if not length > 1e-12:
        return orthonormal_basis(n)
    inv = 1.0 / length
    t = (tx * inv, ty * inv, tz * inv)
    return t, (n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0])


@njit_inline
def eval_ggx(au, av, n, tangent, wo, wi):
    """The GGX lobe for the pair (wo, wi) about the shading normal n (αu along `tangent`: `tangent_frame`),
    without its Fresnel factor:
    (D·G1(wo)·G1(wi)/(4·cos θo·cos θi), the pdf of wi under `sample_ggx`, wo·h) — the caller multiplies by F(wo·h)
    (a conductor's or a dielectric coat's)."""
    t, b = tangent_frame(n, tangent)
    ox, oy, oz = local(wo, t, b, n)
    ix, iy, iz = local(wi, t, b, n)
    if oz <= 0.0 or iz <= 0.0:
        return 0.0, 0.0, 1.0
    hx, hy, hz = ox + ix, oy + iy, oz + iz
    inv = 1.0 / math.sqrt(hx * hx + hy * hy + hz * hz)
    hx, hy, hz = hx * inv, hy * inv, hz * inv
    o_h = ox * hx + oy * hy + oz * hz
    d = ggx_d(hx, hy, hz, au, av)
    g1o = smith_g1(ox, oy, oz, o_h, au, av)
    g = g1o * smith_g1(ix, iy, iz, o_h, au, av)  # (wi·h = wo·h for the reflection half-vector)
    return d * g / (4.0 * oz * iz), g1o * d / (4.0 * oz), o_h


@njit_inline
def sample_ggx(au, av, n, tangent, wo, u1, u2):
    """A direction reflected about a microfacet normal visible from wo; its pdf is `eval_ggx`'s."""
    t, b = tangent_frame(n, tangent)
    ox, oy, oz = local(wo, t, b, n)
    hx, hy, hz = sample_visible_normal(ox, oy, max(oz, 1e-9), au, av, u1, u2)
    k = 2.0 * (ox * hx + oy * hy + oz * hz)
    lx, ly, lz = k * hx - ox, k * hy - oy, k * hz - oz
    return (lx * t[0] + ly * b[0] + lz * n[0], lx * t[1] + ly * b[1] + lz * n[1], lx * t[2] + ly * b[2] + lz * n[2])


@njit_inline
def _to_world(x, y, z, t, b, n):
    return (x * t[0] + y * b[0] + z * n[0], x * t[1] + y * b[1] + z * n[1], x * t[2] + y * b[2] + z * n[2])


@njit
def eval_ggx_dielectric(au, av, eta, n, tangent, wo, wi):
    """The rough dielectric's lobes for the pair (wo, wi) about the shading normal n (wo's side), after Walter et
    al. 2007 as Mitsuba 3's `roughdielectric` reads them in radiance mode; eta = n_t/n_i, the index on the far
    side over the index on wo's side. Returns (f without tint, the pdf of wi under `sample_ggx_dielectric`,
    whether wi is transmitted (below the surface)):

        reflection (cos θi > 0)   h = (wo + wi)/|…|       f = F·D·G/(4·cos θo·cos θi)    pdf = F·G1(wo)·D/(4·cos θo)
        refraction (cos θi < 0)   h = ±(wo + η·wi)/|…|    f = (1 − F)·D·G·|wi·h|·(wo·h)/(cos θo·|cos θi|·(wo·h + η·wi·h)²)
                                                          pdf = (1 − F)·G1(wo)·D·(wo·h)/cos θo · η²·|wi·h|/(wo·h + η·wi·h)²

    F = F(wo·h) the dielectric Fresnel factor, G = G1(wo)·G1(wi) (Smith, separable), h turned to n's side. The
    refracted f is Walter's eq. 21 with η_o² (the index on the viewer's side) over the squared sum: radiance
    compressed by (n_i/n_t)² (Mitsuba's 1/η² factor in radiance mode), so f(wo, wi)/n_o² = f(wi, wo)/n_i²."""
    t, b = tangent_frame(n, tangent)
    ox, oy, oz = local(wo, t, b, n)
    ix, iy, iz = local(wi, t, b, n)
    if oz <= 0.0 or iz == 0.0:
        return 0.0, 0.0, False
    through = iz < 0.0
    e = eta if through else 1.0
    hx, hy, hz = ox + e * ix, oy + e * iy, oz + e * iz
    length = math.sqrt(hx * hx + hy * hy + hz * hz)
    if not length > 0.0:
        return 0.0, 0.0, through
    inv = 1.0 / length if hz >= 0.0 else -1.0 / length
    hx, hy, hz = hx * inv, hy * inv, hz * inv
    o_h = ox * hx + oy * hy + oz * hz
    i_h = ix * hx + iy * hy + iz * hz
    g1o = smith_g1(ox, oy, oz, o_h, au, av)  # 0 where wo or wi sees the back of h
    g = g1o * smith_g1(ix, iy, iz, i_h, au, av)
    if not g > 0.0:
        return 0.0, 0.0, through
    d = ggx_d(hx, hy, hz, au, av)
    F = fresnel_dielectric(o_h, 1.0 / eta)[0]
    if not through:
        return F * d * g / (4.0 * oz * iz), F * g1o * d / (4.0 * oz), False
    s = o_h + eta * i_h
    jacobian = eta * eta * abs(i_h) / (s * s)  # |dh/dwi| of refraction (Walter's eq. 17)
    return ((1.0 - F) * d * g * abs(i_h) * o_h / (oz * -iz * s * s), (1.0 - F) * g1o * d * o_h / oz * jacobian,
            True)


@njit
def sample_ggx_dielectric(au, av, eta, n, tangent, wo, u, u1, u2):
    """A direction from the rough dielectric: a microfacet normal h visible from wo (u1, u2), then reflection
    about h with probability F(wo·h) (u < F), else refraction through it (eta = n_t/n_i). Returns (wi, ok):
    ok is False where the choice leaves its own side of the surface (a reflection below it, a refraction above),
    which `eval_ggx_dielectric` counts as the other lobe: such a sample is dropped, as Mitsuba drops it."""
    t, b = tangent_frame(n, tangent)
    ox, oy, oz = local(wo, t, b, n)
    hx, hy, hz = sample_visible_normal(ox, oy, max(oz, 1e-9), au, av, u1, u2)
    o_h = ox * hx + oy * hy + oz * hz
    F, cos_t = fresnel_dielectric(max(o_h, 0.0), 1.0 / eta)
    if u < F:
        k = 2.0 * o_h
        lx, ly, lz = k * hx - ox, k * hy - oy, k * hz - oz
        return _to_world(lx, ly, lz, t, b, n), lz > 0.0
    r = 1.0 / eta  # Snell about h: −wo/η + (o_h/η − cos_t)·h
    k = r * o_h - cos_t
    lx, ly, lz = k * hx - r * ox, k * hy - r * oy, k * hz - r * oz
    return _to_world(lx, ly, lz, t, b, n), lz < 0.0
