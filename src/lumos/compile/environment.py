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
    edges = np.cos(np.arange(h + 1) / h * np.pi)
    omega = ((edges[:-1] - edges[1:]) * 2.0 * np.pi / w)[:, None]  # each pixel's solid angle
    coefficients = np.zeros((9, 3))
    for i0 in range(0, h, 64):  # a block of rows at a time: (9, rows, w) stays small for a large image
        rows = slice(i0, min(i0 + 64, h))
        basis = sh9(x[rows], d[rows, :, 1], z[rows]) * omega[rows]
        coefficients += np.einsum("khw,hwc->kc", basis, pixels[rows].astype(np.float64))
    return coefficients * np.array([1.0] + [2.0 / 3.0] * 3 + [0.25] * 5)[:, None]


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
