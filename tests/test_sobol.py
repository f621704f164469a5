"""`kernels.sobol`: the padded Owen-scrambled Sobol points are a (0, m, 2)-net per pixel and pair, the shuffle is a
permutation of any length, and the per-pixel pair seeds give the same points as drawing them whole."""

import numpy as np
import pytest

from lumos.kernels.rng import sample_key
from lumos.kernels.sobol import pair_seed, permute, sobol_2d, sobol_2d_seeded


def _points(pixel_key, spp, pair):
    return np.array([sobol_2d(pixel_key, spp, s, pair) for s in range(spp)])


@pytest.mark.parametrize("spp", [16, 64])
@pytest.mark.parametrize("pair", [0, 3])
def test_each_pixels_points_stratify_every_elementary_interval(spp, pair):
    m = spp.bit_length() - 1
    pts = _points(int(sample_key(11, 4321, 1 << 62)), spp, pair)
    assert pts.min() >= 0.0 and pts.max() < 1.0
    for a in range(m + 1):  # intervals of 2^-a by 2^-(m-a): one point in each
        cells = (np.floor(pts[:, 0] * 2**a).astype(int) << (m - a)) + np.floor(pts[:, 1] * 2 ** (m - a)).astype(int)
        assert len(set(cells.tolist())) == spp, a


def test_pairs_of_one_pixel_are_shuffled_apart():
    """Pair k's sample s is not pair j's sample s: the padded sampler decorrelates its copies of the sequence."""
    key = int(sample_key(3, 77, 1 << 62))
    a, b = _points(key, 64, 2), _points(key, 64, 3)
    assert np.abs(np.corrcoef(a[:, 0], b[:, 0])[0, 1]) < 0.4
    assert not np.array_equal(np.sort(a[:, 0]), np.sort(b[:, 0]))  # and scrambled apart


@pytest.mark.parametrize("n", [1, 5, 16, 100])
def test_shuffle_is_a_permutation_of_any_length(n):
    for p in (0, 12345, 0xFFFFFFFF):
        got = sorted(int(permute(np.uint64(i), np.uint64(n), np.uint64(p))) for i in range(n))
        assert got == list(range(n))


def test_seeded_points_are_the_pixels_points():
    key = int(sample_key(5, 999, 1 << 62))
    for pair in range(5):
        h = np.uint64(pair_seed(np.uint64(key), pair))
        for s in (0, 7, 63):
            assert sobol_2d_seeded(h, 64, s) == sobol_2d(np.uint64(key), 64, s, pair)
