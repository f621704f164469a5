"""`kernels.rng.rand01`: bit-exact SplitMix64, range, uniformity (χ²) and independence of the key components."""

import numpy as np
import pytest
from naive import chi2_uniform, rand01_ref, splitmix64_stream

from lumos.kernels.rng import mix64, rand01


@pytest.mark.nojit
def test_reference_reproduces_published_splitmix64_vectors():
    # Vigna's splitmix64.c from state 0, and the seed-1234567 vectors used by java.util.SplittableRandom tests.
    assert splitmix64_stream(0, 3) == [0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4, 0x06C45D188009454F]
    assert splitmix64_stream(1234567, 3) == [6457827717110365317, 3203168211198807973, 9817491932198370423]


@pytest.mark.nojit
def test_mix64_is_one_splitmix64_step():
    for z in (0, 1, 1234567, 2**63 + 12345, 2**64 - 1):
        assert int(mix64(np.uint64(z))) == splitmix64_stream(z, 1)[0]


KEYS = [(0, 0, 0, 0), (0, 0, 0, 1), (1, 0, 0, 0), (7, 123, 4, 16), (2**32 - 1, 640 * 480 - 1, 1023, 99),
        (42, 2**40 + 3, 2**20, 2**31)]


@pytest.mark.nojit
@pytest.mark.parametrize("key", KEYS)
def test_rand01_equals_reference(key):
    assert rand01(*key) == rand01_ref(*key)


def _stream(n, seed=3, pixel=None, sample=0, dim=0):
    """n values varying the pixel (or the given component) over 0..n-1."""
    return np.array([rand01(seed, i if pixel is None else pixel, sample, dim) for i in range(n)])


def test_range_and_uniformity_chi2():
    values = np.concatenate([_stream(25000, seed=1), [rand01(9, 17, s, 5) for s in range(25000)]])
    assert values.min() >= 0.0 and values.max() < 1.0
    counts, _ = np.histogram(values, bins=20, range=(0.0, 1.0))
    stat, p = chi2_uniform(counts)
    assert p > 1e-3, (stat, counts)
    # the test is sharp enough to see 5 % of the values moved from the upper half of [0, 1) to the lower
    biased = np.where(values < 0.5, values, np.where(np.arange(len(values)) % 10 == 0, values - 0.5, values))
    assert chi2_uniform(np.histogram(biased, bins=20, range=(0.0, 1.0))[0])[1] < 1e-6


def test_pairs_are_uniform_in_the_unit_square():
    # dims 0 and 1 of the same (pixel, sample) are the (x, y) of a sample: their joint law must be uniform
    xy = np.array([(rand01(5, p, 0, 0), rand01(5, p, 0, 1)) for p in range(20000)])
    counts, _, _ = np.histogram2d(xy[:, 0], xy[:, 1], bins=8, range=[[0, 1], [0, 1]])
    assert chi2_uniform(counts)[1] > 1e-3


@pytest.mark.parametrize(
    "a, b",
    [
        (dict(dim=0), dict(dim=1)),  # neighbouring dimensions
        (dict(sample=0), dict(sample=1)),  # neighbouring samples of the same pixel
        (dict(seed=0), dict(seed=1)),  # neighbouring seeds
    ],
    ids=["dims", "samples", "seeds"],
)
def test_key_components_are_decorrelated(a, b):
    n = 20000
    x = _stream(n, **{"seed": 3, **a})
    y = _stream(n, **{"seed": 3, **b})
    assert not np.array_equal(x, y)
    # the correlation coefficient of independent uniforms has sd 1/sqrt(n) ≈ 0.007
    assert abs(np.corrcoef(x, y)[0, 1]) < 0.035
    # neighbouring pixels too (lag-1 autocorrelation of the per-pixel stream)
    assert abs(np.corrcoef(x[:-1], x[1:])[0, 1]) < 0.035


def test_no_collisions_between_components():
    # swapping which component carries a value must give another number (no symmetric mixing)
    seen = {rand01(1, 2, 3, 4), rand01(1, 3, 2, 4), rand01(1, 4, 3, 2), rand01(2, 1, 3, 4), rand01(1, 2, 4, 3)}
    assert len(seen) == 5


@pytest.mark.nojit
@pytest.mark.parametrize("key", KEYS)
def test_pixel_hash_then_sample_key_is_sample_key(key):
    """The path tracer hashes (seed, pixel) once per pixel: the key it then makes per sample is `sample_key`'s."""
    from lumos.kernels.rng import pixel_hash, pixel_sample_key, sample_key

    seed, pixel, sample, _ = key
    assert pixel_sample_key(np.uint64(pixel_hash(seed, pixel)), sample) == sample_key(seed, pixel, sample)
