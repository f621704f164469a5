"""`kernels.sobol`: the padded Owen-scrambled Sobol points are a (0, m, 2)-net per pixel and pair, the shuffle is a
permutation of any length, the second coordinate's superset transform is the Sobol matrix product, and the
per-pixel pair seeds and the batched block give the same points as drawing them whole, one by one."""

import numpy as np
import pytest

from lumos.kernels.rng import sample_key
from lumos.kernels.sobol import (
    _WALK_STEPS,
    _next_pow2_mask,
    _pascal_reversed,
    _permute_round,
    pair_seed,
    permute,
    shuffle,
    sobol_2d,
    sobol_2d_seeded,
    sobol_block,
)


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


@pytest.mark.parametrize("n", [1, 2, 5, 16, 64, 100])
@pytest.mark.parametrize("fn", [permute, shuffle])
def test_shuffle_is_a_permutation_of_any_length(n, fn):
    orders = set()
    for p in (0, 12345, 0xFFFFFFFF, 0x9E3779B9):
        order = [int(fn(np.uint64(i), np.uint64(n), np.uint64(p))) for i in range(n)]
        assert sorted(order) == list(range(n))
        orders.add(tuple(order))
    assert n < 5 or len(orders) == 4  # and each seed picks its own


def test_pascal_reversed_is_the_sobol_matrix_product():
    """The superset transform equals the XOR of the reversed direction numbers r_k (r_0 = 1, r_k+1 = r_k ^
    (r_k << 1)) over the set bits k of the index: the second Sobol coordinate, digits reversed."""
    r = [1]
    for _ in range(31):
        r.append((r[-1] ^ (r[-1] << 1)) & 0xFFFFFFFF)
    rng = np.random.default_rng(7)
    for j in list(range(300)) + [int(x) for x in rng.integers(0, 2**32, 300)] + [2**32 - 1]:
        want = 0
        for k in range(32):
            if j >> k & 1:
                want ^= r[k]
        assert int(_pascal_reversed(np.uint64(j))) == want, j


@pytest.mark.parametrize("spp, s0, count", [(64, 0, 64), (64, 10, 30), (100, 0, 64), (7, 3, 4), (1, 0, 1),
                                             (2, 0, 2), (3, 0, 3), (129, 64, 64), (1000, 936, 64), (65537, 3, 61)])
def test_block_is_the_points_one_by_one(spp, s0, count):
    """Every spp, power of two or not (whose cycle walk `sobol_block` takes apart: n just above a power of two
    walks longest, 129 and 65537), gives the points `sobol_2d_seeded` gives one by one."""
    seeds = np.array([pair_seed(np.uint64(int(sample_key(2, 31, 1 << 62))), k) for k in range(5)], np.uint64)
    points = np.full((10, 64), np.nan)
    sobol_block(seeds, spp, s0, count, points, np.empty(64, np.uint64))
    for k in range(5):
        for i in range(count):
            assert (points[2 * k, i], points[2 * k + 1, i]) == sobol_2d_seeded(seeds[k], spp, s0 + i)
    assert np.isnan(points[:, count:]).all()


def test_seeded_points_are_the_pixels_points():
    key = int(sample_key(5, 999, 1 << 62))
    for pair in range(5):
        h = np.uint64(pair_seed(np.uint64(key), pair))
        for s in (0, 7, 63):
            assert sobol_2d_seeded(h, 64, s) == sobol_2d(np.uint64(key), 64, s, pair)


def test_block_cases_walk_past_the_vector_steps():
    """The spp 129 case above has samples whose cycle walk takes more than the `_WALK_STEPS` steps `sobol_block`
    takes for every sample at once, so its scalar rest is exercised (and checked equal)."""
    seeds = [pair_seed(np.uint64(int(sample_key(2, 31, 1 << 62))), k) for k in range(5)]
    n = np.uint64(129)
    w = _next_pow2_mask(n)
    longest = 0
    for h in seeds:
        p = np.uint64(h) & np.uint64(0xFFFFFFFF)
        for i in range(64, 128):
            j, steps = np.uint64(i), 0
            while True:
                j, steps = _permute_round(j, w, p), steps + 1
                if j < n:
                    break
            longest = max(longest, steps)
    assert longest > _WALK_STEPS
