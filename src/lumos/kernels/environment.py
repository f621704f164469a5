"""The environment for the path tracer: its radiance in a direction, and directions drawn in proportion to it.

    rgb = env_radiance(em, d)              # the lat-long pixel the world direction d falls in
    d, pdf = env_sample(em, u1, u2)        # a direction, and its density per solid angle
    pdf = env_pdf(em, d)                   # the density env_sample draws d with

`em` is the `layout.Emitters` table (its env_* arrays, `compile.environment`). The image's top row is +y, its middle
column −z; the environment is turned about +y by its rotation. A pixel is drawn with the probability the marginal and
conditional CDFs give it, then a point uniform in it, so the density per solid angle is p·W·H/(2π²·sin θ) and
`env_radiance` (constant over the pixel) matches it exactly.
"""

import math

import numpy as np

from .jit import njit, njit_inline
from .layout import ENV_COS, ENV_HEIGHT, ENV_PRESENT, ENV_SIN, ENV_WIDTH

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
def _pixel(info, d):
    """(row, column, sin θ) of the pixel the world direction d falls in."""
    c, s = info[ENV_COS], info[ENV_SIN]
    x = c * d[0] - s * d[2]  # the environment turned back by its rotation
    z = s * d[0] + c * d[2]
    y = min(max(d[1], -1.0), 1.0)
    w = np.int64(info[ENV_WIDTH])
    h = np.int64(info[ENV_HEIGHT])
    u = 0.5 + math.atan2(x, -z) * _INV_2PI
    v = math.acos(y) / math.pi
    return min(np.int64(v * h), h - 1), min(max(np.int64(u * w), 0), w - 1), math.sqrt(max(0.0, 1.0 - y * y))


@njit_inline
def sky_radiance(pixels, info, background, d):
    """What a ray leaving the scene along d sees: the environment's radiance from there (`info[ENV_PRESENT]`),
    else the background colour."""
    if info[ENV_PRESENT] == 0.0:
        return np.float64(background[0]), np.float64(background[1]), np.float64(background[2])
    i, j, _ = _pixel(info, d)
    return np.float64(pixels[i, j, 0]), np.float64(pixels[i, j, 1]), np.float64(pixels[i, j, 2])


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
