"""Counter-based random numbers: every sample is a pure function of (seed, pixel, sample index, dimension).

No state is carried between pixels or threads, so images do not depend on the thread count. The mixer is the
SplitMix64 finaliser (Steele, Lea & Flood 2014), applied once per key component.
"""

import numpy as np

from .jit import njit

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_INV_2_53 = 1.0 / 9007199254740992.0


@njit
def mix64(z):
    z = z + _GOLDEN
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit
def rand01(seed, pixel, sample, dim):
    """A uniform float64 in [0, 1) for the key (seed, pixel, sample, dim); all four are non-negative ints."""
    h = mix64(np.uint64(seed))
    h = mix64(h ^ np.uint64(pixel))
    h = mix64(h ^ np.uint64(sample))
    h = mix64(h ^ np.uint64(dim))
    return float(h >> _S11) * _INV_2_53


@njit
def sample_key(seed, pixel, sample):
    """The hash of (seed, pixel, sample) that `rand01` starts from: `rand_key(sample_key(s, p, i), d)` equals
    `rand01(s, p, i, d)`, at a quarter of the cost when one sample draws many dimensions (a path tracer)."""
    return pixel_sample_key(pixel_hash(seed, pixel), sample)


@njit
def pixel_hash(seed, pixel):
    """The part of `sample_key` that one pixel's samples share: hash it once per pixel, then
    `pixel_sample_key(pixel_hash(seed, pixel), sample)` is `sample_key(seed, pixel, sample)` for one hash a sample."""
    return mix64(mix64(np.uint64(seed)) ^ np.uint64(pixel))


@njit
def pixel_sample_key(pixel_h, sample):
    """`sample_key` from the pixel's `pixel_hash`."""
    return mix64(np.uint64(pixel_h) ^ np.uint64(sample))


@njit
def rand_key(key, dim):
    """A uniform float64 in [0, 1) for dimension `dim` of the sample whose `sample_key` is `key`."""
    return float(mix64(key ^ np.uint64(dim)) >> _S11) * _INV_2_53


_U32 = np.uint64(0xFFFFFFFF)
_S32 = np.uint64(32)
_INV_2_32 = 1.0 / 4294967296.0


@njit
def rand2_key(key, dim):
    """Two uniform numbers in [0, 1) (32 bits each) from one hash: dimension pair `dim` of the sample `key`."""
    h = mix64(key ^ np.uint64(dim))
    return float(h >> _S32) * _INV_2_32, float(h & _U32) * _INV_2_32
