"""The environment for the path tracer: its radiance in a direction, and directions drawn in proportion to it.

    rgb = env_radiance(em, d)              # the lat-long pixel the world direction d falls in
    rgb = env_bilinear(pixels, info, d)    # bilinear between pixel centres: the image as rays that see it show it
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
def _uv(info, d):
    """(u, v, sin θ): the lat-long coordinates in [0, 1] of the world direction d."""
    c, s = info[ENV_COS], info[ENV_SIN]
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


@njit
def env_bilinear(pixels, info, d):
    """The image seen along d as a viewer shows it: bilinear between the four nearest pixel centres (around the
    seam in u, held at the poles in v). For rays that see the environment directly (camera rays, and rays
    after mirrors and glass, which no light sample meets); light transport reads `env_radiance`, constant over
    each pixel as the sampling density is."""
    u, v, _ = _uv(info, d)
    h, w = pixels.shape[0], pixels.shape[1]
    x = u * w - 0.5
    y = min(max(v * h - 0.5, 0.0), h - 1.0)
    j = np.int64(math.floor(x))
    i = min(np.int64(y), h - 2) if h > 1 else 0
    fx, fy = x - j, y - i
    j0, j1 = j % w, (j + 1) % w
    i1 = min(i + 1, h - 1)
    w00, w01 = (1.0 - fy) * (1.0 - fx), (1.0 - fy) * fx
    w10, w11 = fy * (1.0 - fx), fy * fx
    return (w00 * pixels[i, j0, 0] + w01 * pixels[i, j1, 0] + w10 * pixels[i1, j0, 0] + w11 * pixels[i1, j1, 0],
            w00 * pixels[i, j0, 1] + w01 * pixels[i, j1, 1] + w10 * pixels[i1, j0, 1] + w11 * pixels[i1, j1, 1],
            w00 * pixels[i, j0, 2] + w01 * pixels[i, j1, 2] + w10 * pixels[i1, j0, 2] + w11 * pixels[i1, j1, 2])


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
