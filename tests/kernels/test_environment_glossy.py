"""The environment's glossy reflection in the classic model (`compile.environment.glossy_levels`,
`kernels.environment.glossy_radiance`): L_n(r) = ∫ L(ω)·(n + 1)/(2π)·max(r·ω, 0)^n dω, checked against a direct
sum over the image's pixels (the naive twin), closed forms of a uniform sky and of half a sky, and the image's
own orientation."""

import numpy as np
import pytest

from lumos.compile.environment import GLOSSY_LEVELS, glossy_levels
from lumos.kernels.environment import env_bilinear, glossy_radiance
from lumos.kernels.layout import AMBIENT_ROWS, ENV_COS, ENV_HEIGHT, ENV_INFO_SIZE, ENV_PRESENT, ENV_SIN, ENV_WIDTH


def ambient_of(image, rotation=0.0):
    """The ambient array as the kernels read it: ten rows of irradiance (zeros here), then the glossy levels."""
    return np.concatenate([np.zeros((AMBIENT_ROWS, 3)), glossy_levels(np.asarray(image, np.float32), rotation)])


def texel_directions(h, w):
    """Unit directions (h, w, 3) of the lat-long texel centres (top row +y, the middle column −z)."""
    theta = (np.arange(h) + 0.5) / h * np.pi
    phi = ((np.arange(w) + 0.5) / w - 0.5) * 2 * np.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(t) * np.sin(p), np.cos(t), -np.sin(t) * np.cos(p)], axis=-1)


def naive_glossy(image, r, n):
    """The lobe summed over every pixel of the image (each constant over its area, the lobe taken at its centre,
    times its solid angle), normalised: what the FFT convolution computes, written the slow way."""
    h, w = image.shape[:2]
    d = texel_directions(h, w)
    edges = np.cos(np.arange(h + 1) / h * np.pi)
    omega = ((edges[:-1] - edges[1:]) * 2 * np.pi / w)[:, None]
    k = np.maximum(d @ r, 0.0) ** n * omega
    return (k[..., None] * image).sum(axis=(0, 1)) / k.sum()


def smooth_sky(h=16, w=32, seed=0):
    rng = np.random.default_rng(seed)
    return (0.2 + rng.random((h, w, 3))).astype(np.float32)


def test_each_level_is_the_lobe_summed_over_the_image():
    """At its exponents 4^k and its texel centres the lookup is the level's texel, and the level is the lobe
    summed over the image's pixels (to 1e-9): for a 16×32 image every level keeps the image's resolution."""
    image = smooth_sky()
    amb = ambient_of(image)
    d = texel_directions(16, 32)
    for k in range(GLOSSY_LEVELS):
        n = 4.0 ** k
        for i, j in [(0, 0), (3, 7), (8, 16), (15, 31), (11, 2)]:
            got = glossy_radiance(amb, tuple(d[i, j]), n)
            np.testing.assert_allclose(got, naive_glossy(image, d[i, j], n), rtol=1e-9, err_msg=f"n={n}")


def test_a_uniform_sky_is_itself_at_every_exponent():
    """Each texel's weights sum to one: a uniform radiance comes back at every exponent, between levels and
    beyond the last, in every direction."""
    amb = ambient_of(np.full((64, 128, 3), [0.3, 0.6, 0.9], np.float32))
    rng = np.random.default_rng(1)
    for r in rng.normal(size=(20, 3)):
        r = tuple(r / np.linalg.norm(r))
        for n in (0.0, 1.0, 2.5, 10.0, 300.0, 5000.0, 1e5):
            np.testing.assert_allclose(glossy_radiance(amb, r, n), np.float32([0.3, 0.6, 0.9]), rtol=1e-9)


def test_half_a_sky_is_seen_half_at_the_horizon_and_more_above_it():
    """A sky of 1 above the horizon and 0 below: looking along the horizon the lobe sees half of it, at any
    exponent (symmetry); above the horizon more of it and more as the lobe narrows; L(up) + L(mirrored below) = 1
    (the image is symmetric about the horizon, as the convolution must keep it)."""
    half = np.zeros((64, 128, 3), np.float32)
    half[:32] = 1.0
    amb = ambient_of(half)
    up = (0.0, np.sin(np.radians(20)), -np.cos(np.radians(20)))
    down = (0.0, -up[1], up[2])
    last = 0.5
    for n in (1.0, 4.0, 16.0, 64.0, 256.0):
        np.testing.assert_allclose(glossy_radiance(amb, (1.0, 0.0, 0.0), n), 0.5, atol=1e-9)
        above, below = glossy_radiance(amb, up, n)[0], glossy_radiance(amb, down, n)[0]
        assert above + below == pytest.approx(1.0, abs=1e-9)
        assert above > last, (n, above)
        last = above
    assert last > 0.999  # a lobe of exponent 256 (about 3.6° wide) 20° above the horizon sees sky alone


def test_exponents_between_levels_mix_them_by_the_lobe_width():
    """Between two levels the lookup mixes them linearly in 1/sqrt(n): halfway in width between 16 and 64
    (n = 1/0.1875²) is the mean of the two; below the first level it is the first."""
    image = smooth_sky(seed=2)
    amb = ambient_of(image)
    r = (0.3, 0.5, np.sqrt(1 - 0.34))
    a16, a64 = np.array(glossy_radiance(amb, r, 16.0)), np.array(glossy_radiance(amb, r, 64.0))
    np.testing.assert_allclose(glossy_radiance(amb, r, 1.0 / 0.1875 ** 2), (a16 + a64) / 2, rtol=1e-9)
    np.testing.assert_allclose(glossy_radiance(amb, r, 0.2), glossy_radiance(amb, r, 1.0), rtol=1e-12)


@pytest.mark.parametrize("rotation", [0.0, 37.0, -120.0])
def test_the_glossy_image_turns_with_the_environment(rotation):
    """The narrowest lobe (exponent 4^7, 0.45° wide) on an image of 11° texels is the image itself: it reads
    what `env_bilinear` reads in every direction, with the environment turned."""
    image = smooth_sky(seed=4)
    amb = ambient_of(image, rotation)
    info = np.zeros(ENV_INFO_SIZE)
    info[ENV_PRESENT], info[ENV_COS], info[ENV_SIN] = 1.0, np.cos(np.radians(rotation)), np.sin(np.radians(rotation))
    info[ENV_WIDTH], info[ENV_HEIGHT] = 32, 16
    rng = np.random.default_rng(5)
    for r in rng.normal(size=(30, 3)):
        r = tuple(r / np.linalg.norm(r))
        np.testing.assert_allclose(glossy_radiance(amb, r, 4.0 ** 7), env_bilinear(image, info, r), rtol=2e-3)


def test_levels_are_no_finer_than_the_image_or_the_cap():
    """A 1×1 colour stays one texel at every level; a large image is averaged down to at most 512 texels a row,
    keeping its mean radiance (every pixel weighted by its solid angle)."""
    one = glossy_levels(np.full((1, 1, 3), 2.0, np.float32))
    assert one.shape == (1 + GLOSSY_LEVELS + GLOSSY_LEVELS, 3)
    np.testing.assert_allclose(one[1 + GLOSSY_LEVELS:], 2.0)
    big = glossy_levels(smooth_sky(256, 1024, seed=6))
    widths = big[1:1 + GLOSSY_LEVELS, 1]
    assert widths.max() == 512 and widths.min() == 32 and np.all(np.diff(widths) >= 0)
