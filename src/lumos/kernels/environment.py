"""The environment in the kernels: its radiance in a direction, directions drawn in proportion to it (the path
tracer), and its glossy reflection (the local methods).

    rgb = env_radiance(em, d)              # the lat-long pixel the world direction d falls in
    rgb = env_bilinear(pixels, info, d)    # bilinear between pixel centres: the image as rays that see it show it
    d, pdf = env_sample(em, u1, u2)        # a direction, and its density per solid angle
    pdf = env_pdf(em, d)                   # the density env_sample draws d with
    rgb = glossy_radiance(amb, r, n)       # seen along r through a Phong lobe of exponent n (the local methods)
    rgb = mirrored_environment(amb, pixels, info, n, V, kr)   # kr·L(R_V): raycast's and raster's mirrors

`em` is the `layout.Emitters` table (its env_* arrays, `compile.environment`). The image's top row is +y, its middle
column −z; the environment is turned about +y by its rotation. A pixel is drawn with the probability the marginal and
conditional CDFs give it, then a point uniform in it, so the density per solid angle is p·W·H/(2π²·sin θ) and
`env_radiance` (constant over the pixel) matches it exactly.
"""

import math

import numpy as np

from .jit import njit, njit_inline
from .layout import AMBIENT_ROWS, ENV_COS, ENV_HEIGHT, ENV_PRESENT, ENV_SIN, ENV_WIDTH, GLOSSY_BASE, GLOSSY_HEADER

_INV_2PI = 0.5 / math.pi


@njit
def _find(cdf, u):
    """The interval k of a CDF (cdf[0] = 0 … cdf[-1] = 1) with cdf[k] <= u < cdf[k+1], skipping empty ones."""
    lo = 0
    hi = cdf.shape[0] - 2
    while lo < hi:
        mid = (lo + hi + 1) >> 1
        if cdf[mid] <= u:
            lo = mid
        else:
            hi = mid - 1
    return lo


@njit_inline
def _uv(info, d):
    """(u, v, sin θ): the lat-long coordinates in [0, 1] of the world direction d."""
    return _uv_turned(info[ENV_COS], info[ENV_SIN], d)


@njit_inline
def _uv_turned(c, s, d):
    """`_uv` for an environment turned by the angle of cosine c and sine s about +y."""
    x = c * d[0] - s * d[2]  # the environment turned back by its rotation
    z = s * d[0] + c * d[2]
    y = min(max(d[1], -1.0), 1.0)
    return 0.5 + math.atan2(x, -z) * _INV_2PI, math.acos(y) / math.pi, math.sqrt(max(0.0, 1.0 - y * y))


@njit_inline
def _pixel(info, d):
    """(row, column, sin θ) of the pixel the world direction d falls in."""
    u, v, sin_t = _uv(info, d)
    w = np.int64(info[ENV_WIDTH])
    h = np.int64(info[ENV_HEIGHT])
    return min(np.int64(v * h), h - 1), min(max(np.int64(u * w), 0), w - 1), sin_t


@njit_inline
def _bilinear_stencil(u, v, w, h):
    """The four texels around lat-long point (u, v) of a w × h image and their bilinear weights: (row i, row i1,
    column j0, column j1, w00, w01, w10, w11), between texel centres, around the seam in u, held at the poles in v."""
    x = u * w - 0.5
    y = min(max(v * h - 0.5, 0.0), h - 1.0)
    j = np.int64(math.floor(x))
    i = min(np.int64(y), h - 2) if h > 1 else 0
    fx, fy = x - j, y - i
    w00, w01 = (1.0 - fy) * (1.0 - fx), (1.0 - fy) * fx
    return i, min(i + 1, h - 1), j % w, (j + 1) % w, w00, w01, fy * (1.0 - fx), fy * fx


@njit
def env_bilinear(pixels, info, d):
    """The image seen along d as a viewer shows it: bilinear between the four nearest pixel centres (around the
    seam in u, held at the poles in v). For rays that see the environment directly (camera rays, and rays
    after mirrors and glass, which no light sample meets); light transport reads `env_radiance`, constant over
    each pixel as the sampling density is."""
    u, v, _ = _uv(info, d)
    i, i1, j0, j1, w00, w01, w10, w11 = _bilinear_stencil(u, v, pixels.shape[1], pixels.shape[0])
    return (w00 * pixels[i, j0, 0] + w01 * pixels[i, j1, 0] + w10 * pixels[i1, j0, 0] + w11 * pixels[i1, j1, 0],
            w00 * pixels[i, j0, 1] + w01 * pixels[i, j1, 1] + w10 * pixels[i1, j0, 1] + w11 * pixels[i1, j1, 1],
            w00 * pixels[i, j0, 2] + w01 * pixels[i, j1, 2] + w10 * pixels[i1, j0, 2] + w11 * pixels[i1, j1, 2])


@njit
def glossy_radiance(amb, r, n):
    """The environment seen along the unit direction r through a normalised Phong lobe of exponent n, L_n(r) =
    ∫ L(ω)·(n + 1)/(2π)·max(r·ω, 0)^n dω (`compile.environment.glossy_levels`, from row GLOSSY_HEADER of the
    ambient array `amb`): bilinear in the two levels whose exponents bracket n, mixed linearly in the lobe's width
    1/sqrt(n) (the widest level below the first exponent, the sharpest above the last). Called, not inlined (the
    illumination model's untaken branch to it costs the scenes without an environment nothing)."""
    K = np.int64(amb[GLOSSY_HEADER, 0])
    u, v, _ = _uv_turned(amb[GLOSSY_HEADER, 1], amb[GLOSSY_HEADER, 2], r)
    level = math.log(max(n, 1.0)) / math.log(GLOSSY_BASE)
    k = min(np.int64(level), K - 1)
    t = 0.0
    if k < K - 1:  # widths base^(−k/2) and base^(−(k+1)/2) around n^(−1/2)
        wk = GLOSSY_BASE ** (-0.5 * k)
        t = min((wk - 1.0 / math.sqrt(max(n, 1.0))) / (wk - wk / math.sqrt(GLOSSY_BASE)), 1.0)
    r0, g0, b0 = _level_bilinear(amb, GLOSSY_HEADER + 1 + k, u, v)
    if t == 0.0:
        return r0, g0, b0
    r1, g1, b1 = _level_bilinear(amb, GLOSSY_HEADER + 2 + k, u, v)
    return r0 + t * (r1 - r0), g0 + t * (g1 - g0), b0 + t * (b1 - b0)


@njit_inline
def _level_bilinear(amb, entry, u, v):
    """Bilinear between the texel centres of the glossy level described by row `entry` of `amb` (around the
    seam in u, held at the poles in v), as `env_bilinear` reads the image."""
    first = np.int64(amb[entry, 0])
    w = np.int64(amb[entry, 1])
    i, i1, j0, j1, w00, w01, w10, w11 = _bilinear_stencil(u, v, w, np.int64(amb[entry, 2]))
    a, b = first + i * w, first + i1 * w
    return (w00 * amb[a + j0, 0] + w01 * amb[a + j1, 0] + w10 * amb[b + j0, 0] + w11 * amb[b + j1, 0],
            w00 * amb[a + j0, 1] + w01 * amb[a + j1, 1] + w10 * amb[b + j0, 1] + w11 * amb[b + j1, 1],
            w00 * amb[a + j0, 2] + w01 * amb[a + j1, 2] + w10 * amb[b + j0, 2] + w11 * amb[b + j1, 2])


@njit
def mirrored_environment(amb, pixels, info, n, V, kr):
    """kr·L(R_V), the environment in the mirror direction R_V = 2(N·V)N − V as `env_bilinear` shows it, where an
    environment lights the model (`amb` has its glossy rows), else 0: reflection mapping, the mirror of a method
    that traces no reflected rays (raycast, raster), which sees the sky alone where `whitted` also sees the
    scene. (Called, not inlined: inlined into raster's shading loop, even untaken, it cost that loop 4%.)"""
    if amb.shape[0] <= AMBIENT_ROWS or (kr[0] == 0.0 and kr[1] == 0.0 and kr[2] == 0.0):
        return 0.0, 0.0, 0.0
    c = 2.0 * (n[0] * V[0] + n[1] * V[1] + n[2] * V[2])
    r, g, b = env_bilinear(pixels, info, (c * n[0] - V[0], c * n[1] - V[1], c * n[2] - V[2]))
    return kr[0] * r, kr[1] * g, kr[2] * b


@njit_inline
def sky_radiance(pixels, info, background, d):
    """What a ray leaving the scene along d sees: the environment's image there (`env_bilinear`;
    `info[ENV_PRESENT]`), else the background colour."""
    if info[ENV_PRESENT] == 0.0:
        return np.float64(background[0]), np.float64(background[1]), np.float64(background[2])
    return env_bilinear(pixels, info, d)


@njit_inline
def env_radiance(em, d):
    """The environment's radiance arriving from direction d (pointing away from the scene)."""
    i, j, _ = _pixel(em.env_info, d)
    px = em.env_pixels
    return np.float64(px[i, j, 0]), np.float64(px[i, j, 1]), np.float64(px[i, j, 2])


@njit_inline
def env_pdf(em, d):
    """The density per solid angle with which `env_sample` draws d (without the probability of picking the
    environment among the emitters)."""
    i, j, sin_t = _pixel(em.env_info, d)
    if not sin_t > 0.0:
        return 0.0
    m = em.env_marginal
    row = em.env_conditional[i]
    p = (m[i + 1] - m[i]) * (row[j + 1] - row[j])
    return p * em.env_info[ENV_WIDTH] * em.env_info[ENV_HEIGHT] / (2.0 * math.pi * math.pi * sin_t)


@njit_inline
def env_sample(em, u1, u2):
    """A direction drawn in proportion to the environment's radiance (times sin θ), and its density per solid
    angle (0: none)."""
    m = em.env_marginal
    i = _find(m, u1)
    pi_ = m[i + 1] - m[i]
    row = em.env_conditional[i]
    j = _find(row, u2)
    pj = row[j + 1] - row[j]
    if not (pi_ > 0.0 and pj > 0.0):
        return (0.0, 1.0, 0.0), 0.0
    info = em.env_info
    w, h = info[ENV_WIDTH], info[ENV_HEIGHT]
    v = (i + min((u1 - m[i]) / pi_, 1.0 - 1e-9)) / h
    u = (j + min((u2 - row[j]) / pj, 1.0 - 1e-9)) / w
    theta = v * math.pi
    phi = (u - 0.5) * 2.0 * math.pi
    sin_t = math.sin(theta)
    if not sin_t > 0.0:
        return (0.0, 1.0, 0.0), 0.0
    x, y, z = sin_t * math.sin(phi), math.cos(theta), -sin_t * math.cos(phi)
    c, s = info[ENV_COS], info[ENV_SIN]
    d = (c * x + s * z, y, -s * x + c * z)  # turned by the rotation
    return d, pi_ * pj * w * h / (2.0 * math.pi * math.pi * sin_t)
