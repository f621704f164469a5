"""Maps between directions and image coordinates, in NumPy: lumos's lat-long environment and pbrt-v4's equal-area
octahedral one.

    d = lat_long_directions(h, w)          # (h, w, 3): the direction at each lat-long pixel's centre
    row, col = lat_long_pixel(d, h, w)     # the pixel each direction falls in (kernels.environment's twin)
    rgb = lat_long_bilinear(pixels, d)     # the image seen along each direction, bilinear (env_bilinear's twin)
    d = equal_area_square_to_sphere(u, v)  # (..., 3) of a point of [0, 1]² (Clarberg's map, as pbrt-v4 has it)
    u, v = equal_area_sphere_to_square(d)  # its inverse

lumos's lat-long image (`scene.lights.Environment`): the top row is +y, a direction (x, y, z) reads the pixel at
u = 1/2 + atan2(x, −z)/2π, v = acos(y)/π.

pbrt-v4's image infinite lights store radiance in an equal-area octahedral square (P. Clarberg, "Fast
equal-area mapping of the (hemi)sphere using SIMD", 2008; pbrt-v4 `EqualAreaSquareToSphere`): every pixel covers
the same solid angle 4π/N²; the square's centre is +z, its corners −z; the point (u, v) is read at pixel
(row v·N, column u·N) of the image as stored.
"""

from __future__ import annotations

import numpy as np


def lat_long_directions(height: int, width: int) -> np.ndarray:
    """(H, W, 3) the unit direction at each lat-long pixel's centre."""
    theta = (np.arange(height) + 0.5) / height * np.pi
    phi = ((np.arange(width) + 0.5) / width - 0.5) * 2.0 * np.pi
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    return np.stack(np.broadcast_arrays(st * np.sin(phi)[None, :], ct, -st * np.cos(phi)[None, :]), axis=-1)


def lat_long_pixel(d, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) int64 of the lat-long pixel each unit direction d (..., 3) falls in, as the kernels find it
    (`kernels.environment`, which also turns d back by the environment's rotation first)."""
    d = np.asarray(d, float)
    col = np.clip(((0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi)) * width).astype(np.int64), 0,
                  width - 1)
    row = np.minimum((np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi * height).astype(np.int64), height - 1)
    return row, col


def lat_long_bilinear(pixels: np.ndarray, d) -> np.ndarray:
    """(..., C) float64: the lat-long image `pixels` (H, W, C) seen along unit directions d (..., 3), bilinear
    between the four nearest pixel centres, around the seam in u and held at the poles in v (the twin of
    `kernels.environment.env_bilinear`, which also turns d back by the environment's rotation first)."""
    d = np.asarray(d, float)
    h, w = pixels.shape[:2]
    x = (0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi)) * w - 0.5
    y = np.clip(np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi * h - 0.5, 0.0, h - 1.0)
    j = np.floor(x).astype(np.int64)
    i = np.minimum(y.astype(np.int64), max(h - 2, 0))
    fx, fy = (x - j)[..., None], (y - i)[..., None]
    j0, j1, i1 = j % w, (j + 1) % w, np.minimum(i + 1, h - 1)
    p = pixels.astype(np.float64)
    return ((1 - fy) * ((1 - fx) * p[i, j0] + fx * p[i, j1]) + fy * ((1 - fx) * p[i1, j0] + fx * p[i1, j1]))


def equal_area_square_to_sphere(u, v) -> np.ndarray:
    """(..., 3): the unit direction of the point (u, v) of [0, 1]²."""
    u, v = 2.0 * np.asarray(u, float) - 1.0, 2.0 * np.asarray(v, float) - 1.0
    up, vp = np.abs(u), np.abs(v)
    signed = 1.0 - (up + vp)  # signed distance from the diagonal: > 0 inside the inner diamond (z > 0)
    r = 1.0 - np.abs(signed)
    with np.errstate(invalid="ignore", divide="ignore"):
        phi = np.where(r == 0.0, 1.0, (vp - up) / r + 1.0) * np.pi / 4.0
    z = np.copysign(1.0 - r * r, signed)
    cos_phi, sin_phi = np.copysign(np.cos(phi), u), np.copysign(np.sin(phi), v)
    s = r * np.sqrt(np.maximum(2.0 - r * r, 0.0))
    return np.stack([cos_phi * s, sin_phi * s, z], axis=-1)


def equal_area_sphere_to_square(d) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) in [0, 1]² of unit directions d (..., 3): the inverse of `equal_area_square_to_sphere`."""
    d = np.asarray(d, float)
    x, y, z = np.abs(d[..., 0]), np.abs(d[..., 1]), np.abs(d[..., 2])
    r = np.sqrt(np.maximum(1.0 - z, 0.0))
    a, b = np.maximum(x, y), np.minimum(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        b = np.where(a == 0.0, 0.0, b / a)
    phi = np.arctan(b) * 2.0 / np.pi
    phi = np.where(x < y, 1.0 - phi, phi)
    v = phi * r
    u = r - v
    below = d[..., 2] < 0.0
    u, v = np.where(below, 1.0 - v, u), np.where(below, 1.0 - u, v)
    u, v = np.copysign(u, d[..., 0]), np.copysign(v, d[..., 1])
    return 0.5 * (u + 1.0), 0.5 * (v + 1.0)
