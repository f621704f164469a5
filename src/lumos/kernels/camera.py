"""Primary rays (DESIGN.md §3): pixel (x, y) sampled at (x + jx, y + jy), row 0 at the top.

    sx = 2(x + jx)/W − 1,  sy = 1 − 2(y + jy)/H,  a = W/H
    perspective:   o = position,  d = normalize(sx·a·t·u + sy·t·v − w),  t = tan(fov/2)
    orthographic:  o = position + sx·a·(size/2)·u + sy·(size/2)·v,  d = −w
    thin lens:     o = position + aperture·(lx·u + ly·v), aimed at the pinhole ray's point at focus_distance

With one sample per pixel the pixel centre is used (jx = jy = 0.5); otherwise `spp` stratified jittered points,
uniform over the pixel (the box filter) or drawn from the Gaussian filter about its centre (σ = 0.5 pixel,
truncated at 2: Mitsuba's `gaussian`), each by inverting the filter's CDF at a stratified point, so that every
sample weighs the same (filter importance sampling, as `path` does). Random dimensions 0–1 place the sample in the
pixel, 2–3 on the lens.

Texture filtering in the ray methods follows each camera ray's cone (`camera_cone`; Akenine-Möller et al. 2019,
"Texture Level of Detail Strategies for Real-Time Ray Tracing"): perspective, width 0 at the eye and spread
2·tan(fov/2)/H radians, one pixel; orthographic, the width of a pixel, 2·(size/2)/H, and no spread. With `spp` > 1
each sample's cone is narrowed by max(1/8, 1/√spp), as pbrt scales its ray differentials, so that the samples
resolve what lies within the pixel.
"""

import math

import numpy as np

from .jit import njit_inline
from .layout import CAM_APERTURE, CAM_FILTER, CAM_FOCUS, CAM_HALF_SIZE, CAM_ORTHO, CAM_TAN_HALF_FOV
from .rng import rand01
from .sampling import concentric_disk, stratified_2d, truncated_gaussian
from .vec import madd, mul, normalize, row3, sub


#: Pixel filters (cam_params[CAM_FILTER]); the Gaussian's standard deviation and radius in pixels (Mitsuba's)
FILTER_BOX, FILTER_GAUSSIAN = 0, 1
GAUSSIAN_SIGMA = 0.5
GAUSSIAN_RADIUS = 2.0


@njit_inline
def filter_offset(kind, u):
    """Where in (or about) its pixel a sample lands along one axis, from u ∈ [0, 1): u itself (box), or the
    Gaussian filter's inverse CDF about the centre."""
    if kind == FILTER_GAUSSIAN:
        return 0.5 + truncated_gaussian(u, GAUSSIAN_SIGMA, GAUSSIAN_RADIUS)
    return u


@njit_inline
def camera_ray(cam_vecs, cam_params, width, height, x, y, sample, spp, seed, pixel):
    """Origin and unit direction of sample `sample` of pixel (x, y)."""
    if spp == 1:
        jx, jy = 0.5, 0.5
    else:
        jx, jy = stratified_2d(sample, spp, rand01(seed, pixel, sample, 0), rand01(seed, pixel, sample, 1))
        kind = np.int64(cam_params[CAM_FILTER])
        jx, jy = filter_offset(kind, jx), filter_offset(kind, jy)
    lx, ly = 0.5, 0.5
    if cam_params[CAM_APERTURE] != 0.0:
        lx, ly = rand01(seed, pixel, sample, 2), rand01(seed, pixel, sample, 3)
    return camera_ray_at(cam_vecs, cam_params, width, height, x + jx, y + jy, lx, ly)


@njit_inline
def camera_cone(cam_params, height, spp, on):
    """(width at the origin, spread angle) of a camera ray's cone (module doc); (0, 0), no filtering, unless
    `on`."""
    if not on:
        return 0.0, 0.0
    scale = max(0.125, 1.0 / math.sqrt(spp))
    if cam_params[CAM_ORTHO] != 0.0:
        return 2.0 * cam_params[CAM_HALF_SIZE] / height * scale, 0.0
    return 0.0, 2.0 * cam_params[CAM_TAN_HALF_FOV] / height * scale


@njit_inline
def camera_ray_at(cam_vecs, cam_params, width, height, fx, fy, lx, ly):
    """The ray through the image point (fx, fy) in pixel units (pixel (x, y) spans [x, x+1) × [y, y+1)), through
    the point (lx, ly) ∈ [0, 1)² of the lens (mapped onto the aperture disk; unused by a pinhole)."""
    sx = 2.0 * fx / width - 1.0
    sy = 1.0 - 2.0 * fy / height
    aspect = width / height
    pos = row3(cam_vecs, 0)
    u = row3(cam_vecs, 1)
    v = row3(cam_vecs, 2)
    w = row3(cam_vecs, 3)
    if cam_params[CAM_ORTHO] != 0.0:
        half = cam_params[CAM_HALF_SIZE]
        o = madd(madd(pos, u, sx * aspect * half), v, sy * half)
        return o, mul(w, -1.0)
    t = cam_params[CAM_TAN_HALF_FOV]
    d = normalize(madd(madd(mul(w, -1.0), u, sx * aspect * t), v, sy * t))
    aperture = cam_params[CAM_APERTURE]
    if aperture == 0.0:
        return pos, d
    # thin lens: every ray through the lens meets the pinhole ray on the plane of focus
    cos_axis = -(d[0] * w[0] + d[1] * w[1] + d[2] * w[2])
    focus = madd(pos, d, cam_params[CAM_FOCUS] / cos_axis)
    dx, dy = concentric_disk(lx, ly)
    o = madd(madd(pos, u, aperture * dx), v, aperture * dy)
    return o, normalize(sub(focus, o))
