"""Low-discrepancy sample points for the path tracer: padded, Owen-scrambled 2-D Sobol points.

    u, v = sobol_2d(pixel_key, spp, sample, dim)      # the `sample`-th of the pixel's `spp` points, dimension pair `dim`
    sobol_block(seeds, spp, s0, count, points, walk)   # a renderer's form: many samples and pairs in one vector loop

Each pair of dimensions (the position in the pixel, a BSDF direction, a point on a light...) gets its own copy of
the first two dimensions of the Sobol sequence, a (0, 2)-sequence in base 2: any 2^k consecutive points of it
stratify the unit square into 2^k elementary intervals of every shape. The copies are decorrelated from one
another by shuffling the sample index with a per-pixel, per-pair random permutation of [0, spp) (`shuffle`: for a
power of two, a nested uniform scramble of the index, as Burley 2020 shuffles; otherwise Kensler 2013's hashed
permutation of any length, "Correlated Multi-Jittered Sampling"), and each point is Owen-scrambled
(nested uniform scrambling of its binary digits) with hash-based Laine–Karras permutations (Burley 2020,
"Practical Hash-based Owen Scrambling", JCGT 9(4)) — the "padded Sobol" sampler of pbrt-v4.

Owen scrambling makes every point uniformly distributed in the square on its own, so every sample is an
unbiased estimate, whatever subset of the spp samples is taken (a render stopped early by a time limit keeps an
unbiased image, only less stratified); together, the spp points of a pixel keep the Sobol stratification, which
is where the lower error at equal samples comes from. Everything is a function of (pixel key, spp, sample, dim),
so images stay independent of threads and passes.

All arithmetic is on 64-bit unsigned integers masked to 32 bits (Numba types mixed signed/unsigned integer
arithmetic as float, so every constant is a np.uint64).
"""

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic, overload

from .jit import njit
from .rng import mix64

_U32 = np.uint64(0xFFFFFFFF)
_ONE = np.uint64(1)
_INV_2_32 = 1.0 / 4294967296.0
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_GOLDEN_1D = np.uint64(0xD1B54A32D192ED03)
_S1 = np.uint64(1)
_S2 = np.uint64(2)
_S4 = np.uint64(4)
_S5 = np.uint64(5)
_S8 = np.uint64(8)
_S11 = np.uint64(11)
_S16 = np.uint64(16)
_S23 = np.uint64(23)
_S27 = np.uint64(27)
_S32 = np.uint64(32)


def _reverse_bits(x):
    """The 32 low bits of x in reverse order (LLVM's bitreverse when compiled: a byte swap and three mask-and-shift
    steps)."""
    x = ((x >> _S1) & np.uint64(0x55555555)) | ((x & np.uint64(0x55555555)) << _S1)
    x = ((x >> _S2) & np.uint64(0x33333333)) | ((x & np.uint64(0x33333333)) << _S2)
    x = ((x >> _S4) & np.uint64(0x0F0F0F0F)) | ((x & np.uint64(0x0F0F0F0F)) << _S4)
    x = ((x >> _S8) & np.uint64(0x00FF00FF)) | ((x & np.uint64(0x00FF00FF)) << _S8)
    return ((x >> _S16) | (x << _S16)) & _U32


@overload(_reverse_bits, inline="always")
def _reverse_bits_jit(x):
    def impl(x):
        return _bitreverse32(x)

    return impl


@intrinsic
def _bitreverse32(typingctx, x):
    sig = types.uint64(types.uint64)

    def codegen(context, builder, signature, args):
        i32 = ir.IntType(32)
        fn = builder.module.declare_intrinsic("llvm.bitreverse", [i32], ir.FunctionType(i32, [i32]))
        return builder.zext(builder.call(fn, [builder.trunc(args[0], i32)]), ir.IntType(64))

    return sig, codegen


# bit m of _SUPERSET_i is set where bit i of m is not: the positions the i-th step of `_pascal_reversed` updates
_SUPERSET_0 = np.uint64(0x55555555)
_SUPERSET_1 = np.uint64(0x33333333)
_SUPERSET_2 = np.uint64(0x0F0F0F0F)
_SUPERSET_3 = np.uint64(0x00FF00FF)
_SUPERSET_4 = np.uint64(0x0000FFFF)


@njit
def _pascal_reversed(j):
    """The second Sobol coordinate of index j in reversed-digit form: the XOR of r_k over the set bits k of j, where
    r_0 = 1, r_k+1 = r_k ^ (r_k << 1), i.e. r_k = (1 + x)^k over GF(2), whose bit m is C(k, m) mod 2 = [m ⊆ k]
    (Lucas). So bit m of the result is the parity of j's bits at the supersets of m: the superset transform,
    five shift-mask-XOR steps (no table lookups and no loop, so a loop over samples vectorises)."""
    y = j
    y ^= (y >> _S1) & _SUPERSET_0
    y ^= (y >> _S2) & _SUPERSET_1
    y ^= (y >> _S4) & _SUPERSET_2
    y ^= (y >> _S8) & _SUPERSET_3
    y ^= (y >> _S16) & _SUPERSET_4
    return y


@njit
def _laine_karras(x, seed):
    """Burley's improved Laine–Karras hash: a permutation of 32-bit x in which each bit is flipped by a hash of
    the bits below it (applied to bit-reversed digits it is a nested uniform, i.e. Owen, scramble)."""
    x = (x + seed) & _U32
    x ^= (x * np.uint64(0x6C50B47C)) & _U32
    x ^= (x * np.uint64(0xB82F1E52)) & _U32
    x ^= (x * np.uint64(0xC7AFE638)) & _U32
    x ^= (x * np.uint64(0x8D22F6E6)) & _U32
    return x


@njit
def owen_scramble(x, seed):
    """Nested uniform scramble of the binary fraction 0.x (32 digits, most significant first)."""
    return _reverse_bits(_laine_karras(_reverse_bits(x), seed))


@njit
def sobol_index_dims(i):
    """The first two dimensions of the Sobol sequence at index i, as 32-bit binary fractions: the van der Corput
    radical inverse, and the dimension generated by the Pascal matrix (direction numbers v_k+1 = v_k ^ v_k >> 1)."""
    x = _reverse_bits(i)
    y = np.uint64(0)
    v = np.uint64(0x80000000)
    while i != np.uint64(0):
        if i & _ONE:
            y ^= v
        i >>= _ONE
        v ^= v >> _ONE
    return x, y


@njit
def _next_pow2_mask(n):
    """2^m − 1 for the least 2^m >= n (n >= 1)."""
    w = n - _ONE
    w |= w >> _S1
    w |= w >> _S2
    w |= w >> _S4
    w |= w >> _S8
    w |= w >> _S16
    return w


@njit
def _permute_round(i, w, p):
    """One step of `permute`'s cycle walk: Kensler's hash, a bijection on [0, w] (w = 2^m − 1)."""
    i ^= p
    i = (i * np.uint64(0xE170893D)) & _U32
    i ^= p >> _S16
    i ^= (i & w) >> _S4
    i ^= p >> _S8
    i = (i * np.uint64(0x0929EB3F)) & _U32
    i ^= p >> _S23
    i ^= (i & w) >> _S1
    i = (i * (_ONE | (p >> _S27))) & _U32
    i = (i * np.uint64(0x6935FA69)) & _U32
    i ^= (i & w) >> _S11
    i = (i * np.uint64(0x74DCB303)) & _U32
    i ^= (i & w) >> _S2
    i = (i * np.uint64(0x9E501CC3)) & _U32
    i ^= (i & w) >> _S2
    i = (i * np.uint64(0xC860A3DF)) & _U32
    i &= w
    i ^= i >> _S5
    return i


@njit
def permute(i, n, p):
    """Element i of a pseudo-random permutation of [0, n) chosen by the 32-bit seed p (Kensler 2013: a hash
    that is a bijection on the next power of two, cycle-walked until it falls below n)."""
    if n <= np.uint64(1):
        return np.uint64(0)
    w = _next_pow2_mask(n)
    while True:
        i = _permute_round(i, w, p)
        if i < n:
            break
    if n & (n - _ONE) == np.uint64(0):
        return (i + p) & (n - _ONE)  # a power of two: the remainder without a division
    return (i + p) % n


#: Steps of `permute`'s cycle walk that `sobol_block` takes for every sample at once, as selects in a loop LLVM
#: vectorises; a step leaves an index at or above n with probability below 1/2, so after four at most one sample
#: in sixteen walks on, alone.
_WALK_STEPS = 4


@njit
def sobol_2d(pixel_key, spp, sample, dim):
    """Point `sample` of the pixel's `spp` points for dimension pair `dim`: (u, v) in [0, 1)²; the same as
    `sobol_2d_seeded(pair_seed(pixel_key, dim), spp, sample)`, whose seed a renderer hashes once per pixel."""
    return sobol_2d_seeded(pair_seed(pixel_key, dim), spp, sample)


@njit
def pair_seed(pixel_key, dim):
    """The seed of dimension pair `dim`'s shuffle and scrambles in the pixel whose key is `pixel_key`."""
    return mix64(pixel_key ^ (np.uint64(dim) * _GOLDEN))


@njit
def shuffle(i, n, p):
    """Element i of a pseudo-random permutation of [0, n) chosen by the 32-bit seed p. For n = 2^m, the low m bits
    of i's nested uniform scramble (Burley 2020, "shuffled scrambled Sobol"): the scramble flips each bit of i by
    a hash of the bits above it, and below n the bits above the m-th are all 0 and flip alike, so the low m bits
    alone are a permutation. A third of `permute`'s work and free of its cycle-walking loop. Other n: `permute`."""
    if n & (n - _ONE) == np.uint64(0):
        return owen_scramble(i, p) & (n - _ONE)
    return permute(i, n, p)


@njit
def _point(j, h):
    """The Sobol point of (shuffled) index j, Owen-scrambled by the pair seed h: (u, v) in [0, 1)²."""
    x = _reverse_bits(_laine_karras(j, h >> _S32))
    y = _reverse_bits(_laine_karras(_pascal_reversed(j), ((h * _GOLDEN) >> _S32) & _U32))
    return float(x) * _INV_2_32, float(y) * _INV_2_32


@njit
def sobol_2d_seeded(h, spp, sample):
    """Point `sample` of `spp` for the pair seed h (`pair_seed`).

    Worked in reversed-digit form, where an Owen scramble is one Laine–Karras hash: the van der Corput
    coordinate's reversed digits are the index itself, and the second coordinate's are `_pascal_reversed`."""
    h = np.uint64(h)
    return _point(shuffle(np.uint64(sample), np.uint64(spp), h & _U32), h)


@njit
def sobol_block(seeds, spp, s0, count, points, walk):
    """Points of samples s0 … s0+count−1 for every pair seed in `seeds` (`pair_seed`), into points (2·pairs,
    ≥ count): row 2k holds pair k's u, row 2k+1 its v, by sample; `walk` (uint64, ≥ count) is scratch. Equal
    to `sobol_2d_seeded` point by point. For a power-of-two spp the loop over samples has no branch, and LLVM runs
    it several samples to a vector. It takes `shuffle`'s power-of-two test once, outside the loop, rather than
    calling `shuffle` per sample: with the test (and `permute`'s loop) inside, LLVM keeps the loop scalar, 4×
    slower (measured: 1.3 against 5.0 µs a block). Other spp take `permute`'s cycle walk apart (`_WALK_STEPS`),
    so that their loops vectorise too (spp 100: 2.1 against 7.7 µs a block)."""
    n = np.uint64(spp)
    pow2 = n & (n - _ONE) == np.uint64(0)
    mask = n - _ONE
    w = _next_pow2_mask(n)
    for k in range(seeds.shape[0]):
        h = np.uint64(seeds[k])
        p = h & _U32
        if pow2:
            for i in range(count):
                u, v = _point(owen_scramble(np.uint64(s0 + i), p) & mask, h)
                points[2 * k, i] = u
                points[2 * k + 1, i] = v
        else:
            # `permute`, lane by lane the same: the first _WALK_STEPS steps of the cycle walk for every sample
            # (selects, no branch: a vector loop), the rare rest alone, then the remainder (i + p) mod n as
            # i + (p mod n), less n once (a vector loop has no integer division)
            for i in range(count):
                j = _permute_round(np.uint64(s0 + i), w, p)
                for _ in range(_WALK_STEPS - 1):
                    j = _permute_round(j, w, p) if j >= n else j
                walk[i] = j
            for i in range(count):
                j = walk[i]
                while j >= n:
                    j = _permute_round(j, w, p)
                walk[i] = j
            pn = p % n
            for i in range(count):
                j = walk[i] + pn
                j = j - n if j >= n else j
                u, v = _point(j, h)
                points[2 * k, i] = u
                points[2 * k + 1, i] = v


@njit
def sobol_1d(pixel_key, spp, sample, dim):
    """A 1-D point: the Owen-scrambled radical inverse of the permuted sample index (stratified in 1-D)."""
    h = mix64(pixel_key ^ (np.uint64(dim) * _GOLDEN_1D))
    j = shuffle(np.uint64(sample), np.uint64(spp), h & _U32)
    return float(_reverse_bits(_laine_karras(j, h >> _S32))) * _INV_2_32
