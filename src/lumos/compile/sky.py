"""A daylight sky for a user with no HDR file: Preetham, Shirley & Smits's analytic model, tabulated once into a
lat-long image that the environment machinery then reads as any other (`compile.environment`).

    image = sky_image(sky)      # float32 (W/2, W, 3) linear sRGB radiance, the sun's disk included

The model (A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic Model for Daylight", SIGGRAPH 1999):
the sky's luminance Y and chromaticity x, y in a direction at zenith angle θ, at angle γ from the sun (itself at
zenith angle θs), are each a zenith value times Perez et al.'s distribution,

    F(θ, γ) = (1 + A·exp(B / cos θ)) · (1 + C·exp(D·γ) + E·cos²γ),     Y = Y_z · F(θ, γ) / F(0, θs)

with A..E linear in the turbidity T (the haze: 2 a clear day, 10 a hazy one) and Y_z (kcd/m²), x_z, y_z from the
paper's fitted formulas (its appendix; the tables below). xyY goes to XYZ and then to linear sRGB (D65).

The sun is a disk of angular radius 0.2667° whose luminance is the sun's outside the atmosphere (1.9·10⁹ cd/m²,
128 klx at normal incidence) times the transmittance of the air mass m along its direction (Kasten and Young's
m), per channel from Rayleigh scattering and the haze's (Ångström) aerosol scattering at a wavelength per channel,
as Preetham's appendix computes them without the gases' absorption bands. Low suns are dimmer and redder.

Below the horizon lies a diffuse ground of albedo `ground`, lit by the sky and the sun: L = ρ·E_h/π, E_h the
irradiance on a horizontal plane.

The image is scaled so that a white (albedo 1) horizontal plane in the open shows radiance 1 (display white at
exposure 1): E_h = π. The environment's `scale` multiplies that; the ratio of sun to sky and every colour are the
model's. The physical luminance of the image's radiance 1 is reported by `sky_luminance_unit` (cd/m²).
"""

from __future__ import annotations

import math

import numpy as np

from ..mesh.directions import lat_long_directions

#: Perez coefficients (A, B, C, D, E) as (slope, intercept) in the turbidity, for Y, x and y (the paper's appendix)
_PEREZ_Y = ((0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771), (-0.0670, 0.3703))
_PEREZ_X = ((-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989), (-0.0033, 0.0452))
_PEREZ_YC = ((-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537), (-0.0109, 0.0529))
#: zenith chromaticity: rows T², T, 1; columns θs³, θs², θs, 1
_ZENITH_X = ((0.00166, -0.00375, 0.00209, 0.0), (-0.02903, 0.06377, -0.03202, 0.00394),
             (0.11693, -0.21196, 0.06052, 0.25886))
_ZENITH_Y = ((0.00275, -0.00610, 0.00317, 0.0), (-0.04214, 0.08970, -0.04153, 0.00516),
             (0.15346, -0.26756, 0.06670, 0.26688))
#: linear sRGB (D65) from CIE XYZ (IEC 61966-2-1)
_RGB_FROM_XYZ = np.array([[3.2404542, -1.5371385, -0.4985314],
                          [-0.9692660, 1.8760108, 0.0415560],
                          [0.0556434, -0.2040259, 1.0572252]])

SUN_RADIUS_DEG = 0.2667  # the sun's mean angular radius
SUN_LUMINANCE = 1.9e9  # cd/m², outside the atmosphere (128 klx over the disk's solid angle)
_SUN_WAVELENGTHS_UM = (0.61, 0.55, 0.465)  # the channels' wavelengths for the sun's transmittance (μm)


def _perez(coefficients, turbidity: float, cos_theta, gamma):
    a, b, c, d, e = (s * turbidity + i for s, i in coefficients)
    cos_gamma = np.cos(gamma)
    return (1.0 + a * np.exp(b / cos_theta)) * (1.0 + c * np.exp(d * gamma) + e * cos_gamma * cos_gamma)


def zenith_xyY(turbidity: float, theta_sun: float) -> tuple[float, float, float]:
    """The zenith's chromaticity x, y and luminance Y (kcd/m²) with the sun at zenith angle `theta_sun`
    (radians)."""
    t = turbidity
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2.0 * theta_sun)
    luminance = (4.0453 * t - 4.9710) * math.tan(chi) - 0.2155 * t + 2.4192
    powers_t = np.array([t * t, t, 1.0])
    powers_s = np.array([theta_sun ** 3, theta_sun ** 2, theta_sun, 1.0])
    x = float(powers_t @ np.array(_ZENITH_X) @ powers_s)
    y = float(powers_t @ np.array(_ZENITH_Y) @ powers_s)
    return x, y, float(luminance)


def sky_xyY(turbidity: float, sun: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(..., 3) chromaticity x, y and luminance Y (kcd/m²) of the sky towards unit `directions` (..., 3) (y up),
    the sun towards unit `sun`. Directions below the horizon get the horizon's values."""
    theta_sun = math.acos(min(max(float(sun[1]), -1.0), 1.0))
    cos_theta = np.maximum(directions[..., 1], 1e-3)  # the horizon's value below it (the model ends there)
    gamma = np.arccos(np.clip(directions @ sun, -1.0, 1.0))
    zx, zy, zY = zenith_xyY(turbidity, theta_sun)
    out = np.empty(directions.shape[:-1] + (3,))
    for k, (coefficients, zenith) in enumerate(((_PEREZ_X, zx), (_PEREZ_YC, zy), (_PEREZ_Y, zY))):
        norm = _perez(coefficients, turbidity, 1.0, theta_sun)
        out[..., k] = zenith * _perez(coefficients, turbidity, cos_theta, gamma) / norm
    return out


def rgb_from_xyY(xyY: np.ndarray) -> np.ndarray:
    """Linear sRGB of chromaticity and luminance (..., 3)."""
    x, y, lum = xyY[..., 0], xyY[..., 1], xyY[..., 2]
    xyz = np.stack([x * lum / y, lum, (1.0 - x - y) * lum / y], axis=-1)
    return np.maximum(xyz @ _RGB_FROM_XYZ.T, 0.0)


def air_mass(theta_sun: float) -> float:
    """The relative optical air mass towards zenith angle `theta_sun` (Kasten & Young 1989; 1 at the zenith)."""
    degrees = math.degrees(theta_sun)
    return 1.0 / (math.cos(theta_sun) + 0.50572 * (96.07995 - degrees) ** -1.6364)


def sun_transmittance(turbidity: float, theta_sun: float) -> np.ndarray:
    """(3,) the fraction of the sun's light at each channel's wavelength that reaches the ground directly:
    Rayleigh scattering τ_R = exp(−0.008735·λ^−4.08·m) and the haze's τ_a = exp(−β·λ^−1.3·m), β = 0.04608·T −
    0.04586 (Preetham's appendix; λ in μm)."""
    m = air_mass(theta_sun)
    beta = 0.04608 * turbidity - 0.04586
    lam = np.array(_SUN_WAVELENGTHS_UM)
    return np.exp(-0.008735 * lam ** -4.08 * m) * np.exp(-beta * lam ** -1.3 * m)


def sun_direction(sky) -> np.ndarray:
    """The unit direction towards the sun of a scene-model Sky: its `direction`, or `elevation` above the horizon
    and `azimuth` from −z towards +x (degrees; the environment's `rotation` turns it with the rest)."""
    if sky.direction is not None:
        d = np.asarray(sky.direction, float)
        return d / np.linalg.norm(d)
    el, az = math.radians(sky.elevation), math.radians(sky.azimuth)
    return np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])


def _pixel_solid_angles(height: int, width: int) -> np.ndarray:
    """(H, 1): each pixel's solid angle (exact for the band of rows)."""
    edges = np.cos(np.arange(height + 1) / height * np.pi)
    return ((edges[:-1] - edges[1:]) * 2.0 * np.pi / width)[:, None]


def _sun_solid_angle() -> float:
    return 2.0 * math.pi * (1.0 - math.cos(math.radians(SUN_RADIUS_DEG)))


def _sun_coverage(directions: np.ndarray, sun: np.ndarray, height: int, width: int, sub: int = 8) -> np.ndarray:
    """(H, W) the fraction of each pixel inside the sun's disk, by sub × sub points per pixel near it."""
    cover = np.zeros((height, width))
    cos_r = math.cos(math.radians(SUN_RADIUS_DEG))
    pixel = math.pi / height  # a row's angular height; near the sun only a few pixels can be touched
    near = directions @ sun > math.cos(math.radians(SUN_RADIUS_DEG) + 2.0 * pixel * max(1.0, width / height))
    for i, j in zip(*np.nonzero(near)):
        v = (i + (np.arange(sub) + 0.5) / sub) / height * np.pi
        u = ((j + (np.arange(sub) + 0.5) / sub) / width - 0.5) * 2.0 * np.pi
        st, ct = np.sin(v)[:, None], np.cos(v)[:, None]
        d = np.stack(np.broadcast_arrays(st * np.sin(u)[None, :], ct, -st * np.cos(u)[None, :]), axis=-1)
        w = np.broadcast_to(np.sin(v)[:, None], (sub, sub))  # points weighted by their solid angle
        cover[i, j] = (w * (d @ sun >= cos_r)).sum() / w.sum()
    return cover


def _sky_and_sun(sky, width: int):
    """The model at `width` × width/2: (directions (H, W, 3), sky rgb (H, W, 3) in kcd/m², the sun's direction and
    rgb (kcd/m²), E_h (3,): the irradiance of sky and sun on a horizontal plane, in kcd/m² · sr)."""
    height = width // 2
    sun = sun_direction(sky)
    directions = lat_long_directions(height, width)
    rgb = rgb_from_xyY(sky_xyY(sky.turbidity, sun, directions))
    cos_up = np.maximum(directions[..., 1], 0.0)
    e_sky = (rgb * (cos_up * _pixel_solid_angles(height, width))[..., None]).sum(axis=(0, 1))
    sun_rgb = SUN_LUMINANCE / 1000.0 * sun_transmittance(sky.turbidity, math.acos(float(sun[1])))
    e_sun = sun_rgb * _sun_solid_angle() * max(float(sun[1]), 0.0)
    return directions, rgb, sun, sun_rgb, e_sky + e_sun


def _unit(e_h: np.ndarray) -> float:
    """The model's radiance (kcd/m²) that becomes 1 in the image: the luminance of E_h over π, so that E_h = π
    after scaling."""
    return float(_Y_FROM_RGB @ e_h) / math.pi


#: the luminance Y of a linear sRGB triple (the Y row of XYZ from sRGB)
_Y_FROM_RGB = np.linalg.inv(_RGB_FROM_XYZ)[1]


def sky_image(sky, width: int | None = None) -> np.ndarray:
    """float32 (W/2, W, 3): the sky of a scene-model Sky (turbidity, sun direction, `sun` on or off, `ground`
    albedo, `resolution` W) as lat-long radiance, scaled so that E_h = π (see the module's notes)."""
    width = width or sky.resolution
    directions, rgb, sun, sun_rgb, e_h = _sky_and_sun(sky, width)
    rgb[directions[..., 1] <= 0.0] = np.asarray(sky.ground) * e_h / math.pi
    if sky.sun:
        cover = _sun_coverage(directions, sun, width // 2, width)
        # the disk's pixels hold exactly its solid angle (the sampled coverage is off by a per cent or so)
        cover *= _sun_solid_angle() / (cover * _pixel_solid_angles(width // 2, width)).sum()
        rgb += cover[..., None] * sun_rgb
    return np.ascontiguousarray(rgb / _unit(e_h), np.float32)


def sky_luminance_unit(sky) -> float:
    """The luminance (cd/m²) that radiance 1 in `sky_image(sky)` stands for."""
    return 1000.0 * _unit(_sky_and_sun(sky, 256)[-1])
