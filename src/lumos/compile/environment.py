"""The environment as the kernels read it (`kernels.environment`): its lat-long image and the 2-D piecewise-constant
distribution the path tracer samples directions from.

    image = environment_image(env)                  # float32 (H, W, 3) radiance, scale applied (1×1 for a colour)
    pixels, marginal, conditional, info = environment_arrays(env)   # = image_arrays(image, env.rotation)
    mean = mean_radiance(image)                     # Ia, and the background of the methods that do not look it up

`compile_scene` reads and tabulates it once (`CompiledScene.environment`); the scene arrays and path's emitter
table share the result.

Pixel (i, j) covers v in [i/H, (i+1)/H) (θ = v·π from +y) and u in [j/W, (j+1)/W); it is drawn with probability
proportional to its mean radiance times sin θ at its centre (the solid angle it covers), then a point uniform in
it; the density per solid angle is p(i, j)·H·W / (2π²·sin θ) (Pharr, Jakob & Humphreys, §12.5).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..errors import LumosError
from ..kernels.layout import ENV_COS, ENV_ENTRY, ENV_HEIGHT, ENV_INFO_SIZE, ENV_PRESENT, ENV_SIN, ENV_WIDTH

#: negative values down to this fraction of the image's mean are compression noise, read as 0 (with a warning)
NEGATIVE_TOLERANCE = 0.01


def environment_image(env) -> np.ndarray:
    """float32 (H, W, 3): the environment's radiance (its image read as linear values, its colour as 1×1, or its
    sky tabulated by `compile.sky`), times its scale."""
    scale = np.asarray(env.scale, np.float32)
    if env.color is not None:
        return (np.asarray(env.color, np.float32) * scale).reshape(1, 1, 3)
    if env.sky is not None:
        from .sky import sky_image

        return np.ascontiguousarray(sky_image(env.sky) * scale, np.float32)
    from ..io.image_files import read_image

    try:
        image = read_image(env._path if env._path is not None else env.file)
    except LumosError as exc:
        raise LumosError(f"environment.file: {exc}") from None
    if not np.isfinite(image).all():
        raise LumosError(f"environment.file: {env.file!r} has NaN or infinite pixels")
    low = float(image.min()) if image.size else 0.0
    if low < 0.0:
        # lossy EXR compression (DWA, as Blender's own HDRIs) leaves a few values a hair below 0: read as 0
        if -low > NEGATIVE_TOLERANCE * max(float(image.mean()), 0.0):
            raise LumosError(f"environment.file: {env.file!r} has negative pixels (down to {low:.3g})")
        import warnings

        from ..errors import LumosWarning

        warnings.warn(f"environment.file: {env.file!r}: {int((image < 0).sum())} values slightly below 0 (down to "
                      f"{low:.2g}, lossy compression) read as 0", LumosWarning, stacklevel=2)
        image = np.maximum(image, 0.0)
    return np.ascontiguousarray(image * scale, np.float32)


def _solid_angle_weights(h: int) -> np.ndarray:
    """sin θ at the centre of each row."""
    return np.sin((np.arange(h) + 0.5) / h * np.pi)


def mean_radiance(image: np.ndarray) -> np.ndarray:
    """The environment's mean radiance over the sphere of directions (rows weighted by their solid angle)."""
    w = _solid_angle_weights(image.shape[0])
    return (image.astype(np.float64) * w[:, None, None]).sum(axis=(0, 1)) / (w.sum() * image.shape[1])


def _row_solid_angles(h: int, w: int) -> np.ndarray:
    """The solid angle of a pixel in each of the h rows of a w-wide lat-long image."""
    edges = np.cos(np.arange(h + 1) / h * np.pi)
    return (edges[:-1] - edges[1:]) * 2.0 * np.pi / w


def irradiance_sh(pixels: np.ndarray, rotation: float = 0.0) -> np.ndarray:
    """(9, 3): the irradiance over π, E(n)/π, of a lat-long radiance image turned `rotation` degrees about +y, as
    coefficients of `kernels.illumination.sh9` (Ramamoorthi & Hanrahan 2001, "An Efficient Representation for
    Irradiance Environment Maps"): the radiance's projection on bands 0-2, each band l scaled by Â_l/π = 1, 2/3,
    1/4 (the clamped cosine's own coefficients), so that a uniform radiance L gives E/π = L everywhere."""
    from ..kernels.illumination import sh9
    from ..mesh.directions import lat_long_directions

    # pixels are constant over their area: a small image is integrated over a finer grid of its own pixels (the
    # midpoint rule per row is then exact to about 1e-5 for the harmonics' polar parts)
    pixels = np.repeat(np.repeat(pixels, -(-256 // pixels.shape[0]), axis=0), -(-512 // pixels.shape[1]), axis=1)
    h, w = pixels.shape[:2]
    d = lat_long_directions(h, w)  # in the image's own frame
    a = np.radians(rotation)
    x, z = np.cos(a) * d[..., 0] + np.sin(a) * d[..., 2], -np.sin(a) * d[..., 0] + np.cos(a) * d[..., 2]  # the world's
    omega = _row_solid_angles(h, w)[:, None]  # each pixel's solid angle
    coefficients = np.zeros((9, 3))
    for i0 in range(0, h, 64):  # a block of rows at a time: (9, rows, w) stays small for a large image
        rows = slice(i0, min(i0 + 64, h))
        basis = sh9(x[rows], d[rows, :, 1], z[rows]) * omega[rows]
        coefficients += np.einsum("khw,hwc->kc", basis, pixels[rows].astype(np.float64))
    return coefficients * np.array([1.0] + [2.0 / 3.0] * 3 + [0.25] * 5)[:, None]


#: the exponents of the glossy levels are GLOSSY_BASE^k for k < GLOSSY_LEVELS: 1, 4, 16, ... 16384 (a Phong
#: lobe of exponent n is about 1/sqrt(n) radians wide: 57° down to 0.45°)
GLOSSY_LEVELS = 8
#: the widest glossy level, in texels (the sharp ones are at most this fine: 0.7° texels)
GLOSSY_MAX_WIDTH = 512


def glossy_levels(pixels: np.ndarray, rotation: float = 0.0) -> np.ndarray:
    """float64 (rows, 3): the environment's glossy reflection as the kernels read it from `layout.GLOSSY_HEADER`
    on (`kernels.environment.glossy_radiance`): for each exponent n = GLOSSY_BASE^k, the lat-long image of

        L_n(r) = ∫ L(ω) · (n + 1)/(2π) · max(r·ω, 0)^n dω,

    the radiance a surface sees in its mirror direction r through a normalised Phong lobe, at a resolution of
    about 2.5 texels per lobe width (GLOSSY_MAX_WIDTH at most, never finer than the image). Each level is the image
    (averaged down to that resolution, every pixel weighted by its solid angle) convolved with the lobe along each
    row by FFT: the lobe between a row at θi and one at θj depends only on their difference in φ. The weights of
    each texel are normalised to sum to one, so a uniform environment gives its radiance at every exponent."""
    from ..kernels.layout import GLOSSY_BASE, GLOSSY_HEADER

    src = np.asarray(pixels, np.float64)
    H, W = src.shape[:2]
    levels = []
    for k in range(GLOSSY_LEVELS):
        n = GLOSSY_BASE ** k
        width = 1 << int(np.ceil(np.log2(2.0 * np.pi * 2.5 * np.sqrt(n))))  # 2.5 texels per lobe width 1/sqrt(n)
        w = min(W, min(max(width, 32), GLOSSY_MAX_WIDTH))
        h = min(H, max(1, w // 2))
        levels.append(_phong_convolve(_average_down(src, h, w), n))
    rows = [np.array([[len(levels), np.cos(np.radians(rotation)), np.sin(np.radians(rotation))]])]
    first = GLOSSY_HEADER + 1 + len(levels)  # (rows of the whole ambient array, which these follow)
    table = np.zeros((len(levels), 3))
    for k, level in enumerate(levels):
        table[k] = first, level.shape[1], level.shape[0]
        first += level.shape[0] * level.shape[1]
    rows.append(table)
    rows.extend(level.reshape(-1, 3) for level in levels)
    return np.concatenate(rows)


def _average_down(src: np.ndarray, h: int, w: int) -> np.ndarray:
    """The lat-long image src averaged down to h × w: each pixel goes wholly to the one its centre falls in,
    weighted by its solid angle."""
    H, W = src.shape[:2]
    if (h, w) == (H, W):
        return src
    rows = ((np.arange(H) + 0.5) * h / H).astype(np.int64)
    cols = ((np.arange(W) + 0.5) * w / W).astype(np.int64)
    weight = np.repeat(_row_solid_angles(H, W)[:, None], W, axis=1)
    index = (rows[:, None] * w + cols[None, :]).ravel()
    total = np.bincount(index, weight.ravel(), minlength=h * w)
    out = np.stack([np.bincount(index, (src[..., c] * weight).ravel(), minlength=h * w) for c in range(3)], axis=-1)
    return (out / np.maximum(total, 1e-300)[:, None]).reshape(h, w, 3)


def _phong_convolve(image: np.ndarray, n: float) -> np.ndarray:
    """L_n (`glossy_levels`) at the centres of the texels of the lat-long image, constant over each of its pixels.
    The lobe is cut where max(r·ω, 0)^n falls below 1e-6 of its peak (rows further from θi take no part)."""
    h, w = image.shape[:2]
    theta = (np.arange(h) + 0.5) / h * np.pi
    omega = _row_solid_angles(h, w)
    cos_dphi = np.cos(np.arange(w) * 2.0 * np.pi / w)
    reach = np.arccos(min(1.0, 1e-6 ** (1.0 / n))) + np.pi / h  # the lobe's extent, and half a row either side
    spectra = np.fft.rfft(image, axis=1)  # (h, w//2 + 1, 3)
    out = np.empty_like(image)
    for i in range(h):
        js = np.nonzero(np.abs(theta - theta[i]) <= reach)[0]
        cos_g = (np.cos(theta[i]) * np.cos(theta[js])[:, None]
                 + np.sin(theta[i]) * np.sin(theta[js])[:, None] * cos_dphi[None, :])
        kernel = np.maximum(cos_g, 0.0) ** n * omega[js][:, None]  # (rows, w): the lobe over Δφ from row i
        total = kernel.sum()
        kernel_spectra = np.fft.rfft(kernel, axis=1)
        row = np.einsum("jf,jfc->fc", kernel_spectra, spectra[js])
        out[i] = np.fft.irfft(row, n=w, axis=0) / total
    return out


def environment_arrays(env) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The arrays of a scene-model Environment (`image_arrays` of its image and rotation); an empty 1×1 black
    environment when `env` is None."""
    if env is None:
        return image_arrays(np.zeros((1, 1, 3), np.float32), None)
    return image_arrays(environment_image(env), env.rotation)


def image_arrays(pixels: np.ndarray, rotation: Optional[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                          np.ndarray]:
    """(pixels float32 (H, W, 3), marginal CDF float64 (H + 1,) over rows, conditional CDFs float64 (H, W + 1)
    within each row, info float64 (ENV_INFO_SIZE,)) of a lat-long radiance image turned `rotation` degrees about
    +y (None: absent, the 1×1 black stand-in)."""
    pixels = np.ascontiguousarray(pixels, np.float32)
    info = np.zeros(ENV_INFO_SIZE)
    info[ENV_ENTRY] = -1.0
    if rotation is not None:
        info[ENV_PRESENT] = 1.0
        a = np.radians(rotation)
        info[ENV_COS], info[ENV_SIN] = np.cos(a), np.sin(a)
    h, w = pixels.shape[:2]
    info[ENV_WIDTH], info[ENV_HEIGHT] = w, h
    weight = pixels.astype(np.float64).mean(axis=2) * _solid_angle_weights(h)[:, None]
    row_sums = weight.sum(axis=1)
    conditional = np.zeros((h, w + 1))
    conditional[:, 1:] = np.cumsum(weight, axis=1)
    nonzero = row_sums > 0
    conditional[nonzero] /= row_sums[nonzero, None]
    conditional[~nonzero, 1:] = np.arange(1, w + 1) / w  # a black row: uniform (never picked)
    conditional[:, -1] = 1.0
    marginal = np.zeros(h + 1)
    marginal[1:] = np.cumsum(row_sums)
    total = marginal[-1]
    marginal = marginal / total if total > 0 else np.arange(h + 1) / h
    marginal[-1] = 1.0
    return pixels, marginal, conditional, info


def environment_power(pixels: np.ndarray, radius: float) -> float:
    """An estimate of the power the environment sends into the scene's bounding sphere of `radius`, for light
    selection (as a directional light's: π·L̄·π·R², L̄ the mean radiance)."""
    return float(np.pi * mean_radiance(pixels).mean() * np.pi * radius * radius)
