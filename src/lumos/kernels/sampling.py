"""Sample placement: stratified 2D points, the concentric disk mapping, and the angle of a uniform turn."""

import math

from .jit import njit, njit_inline

# Taylor coefficients of sin a / a and cos a in a², to a¹⁴: on |a| <= π/4 the first term left out is below
# (π/4)¹⁵/15! < 2.2e-14 (sin) and (π/4)¹⁶/16! < 1.1e-15 (cos)
_S1, _S2, _S3, _S4, _S5, _S6, _S7 = (-1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0,
                                     1.0 / 6227020800.0, -1.0 / 1307674368000.0)
_C1, _C2, _C3, _C4, _C5, _C6, _C7 = (-0.5, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40320.0, -1.0 / 3628800.0,
                                     1.0 / 479001600.0, -1.0 / 87178291200.0)
_HALF_PI = 0.5 * math.pi


@njit_inline
def turn(u):
    """(cos 2πu, sin 2πu) for u in [0, 1), to within 3e-14, without a call to the C library (whose sincos, called
    for every BSDF and light sample, took 8% of a path tracer's time): u in quarter turns is split into the
    nearest whole quarter q and a remainder angle |a| <= π/4, whose sine and cosine are short polynomials, turned
    by q quarters."""
    t = 4.0 * u
    q = math.floor(t + 0.5)
    a = (t - q) * _HALF_PI
    a2 = a * a
    sa = a * (1.0 + a2 * (_S1 + a2 * (_S2 + a2 * (_S3 + a2 * (_S4 + a2 * (_S5 + a2 * (_S6 + a2 * _S7)))))))
    ca = 1.0 + a2 * (_C1 + a2 * (_C2 + a2 * (_C3 + a2 * (_C4 + a2 * (_C5 + a2 * (_C6 + a2 * _C7))))))
    k = int(q) & 3
    if k == 0:
        return ca, sa
    if k == 1:
        return -sa, ca
    if k == 2:
        return -ca, -sa
    return sa, -ca


@njit
def stratified_2d(s, n, r1, r2):
    """The s-th of n stratified points in [0,1)^2: an m×m jittered grid when n is a square, else n strata
    along u with a scrambled order along v (a Latin-hypercube pattern)."""
    m = int(math.sqrt(n) + 0.5)
    if m * m == n:
        return ((s % m) + r1) / m, ((s // m) + r2) / m
    # s -> s·k mod n is a permutation only when k and n are coprime: k = 7919 (prime) unless n is a multiple of
    # it, then the prime 7907 (no n up to 7919·7907 is a multiple of both)
    k = 7919 if n % 7919 != 0 else 7907
    return (s + r1) / n, (((s * k) % n) + r2) / n


@njit
def concentric_disk(u1, u2):
    """Uniform point on the unit disk (Shirley & Chiu 1997, concentric mapping)."""
    a = 2.0 * u1 - 1.0
    b = 2.0 * u2 - 1.0
    if a == 0.0 and b == 0.0:
        return 0.0, 0.0
    if abs(a) > abs(b):
        r, phi = a, (math.pi / 4.0) * (b / a)
    else:
        r, phi = b, math.pi / 2.0 - (math.pi / 4.0) * (a / b)
    return r * math.cos(phi), r * math.sin(phi)


@njit
def erfinv(x):
    """The inverse error function on (−1, 1), Giles' single-precision approximation ("Approximating the erfinv
    function", GPU Computing Gems, 2010): relative error below 4e-7, enough to place a filter sample."""
    w = -math.log(max((1.0 - x) * (1.0 + x), 1e-300))
    if w < 5.0:
        w -= 2.5
        p = 2.81022636e-08
        for c in (3.43273939e-07, -3.5233877e-06, -4.39150654e-06, 0.00021858087, -0.00125372503,
                  -0.00417768164, 0.246640727, 1.50140941):
            p = c + p * w
    else:
        w = math.sqrt(w) - 3.0
        p = -0.000200214257
        for c in (0.000100950558, 0.00134934322, -0.00367342844, 0.00573950773, -0.0076224613, 0.00943887047,
                  1.00167406, 2.83297682):
            p = c + p * w
    return p * x


@njit
def truncated_gaussian(u, sigma, radius):
    """An offset with the normal density of standard deviation sigma truncated to [−radius, radius], by inverting
    its CDF at u ∈ [0, 1): a pixel filter sampled exactly (filter importance sampling), so every sample weighs 1."""
    s = sigma * math.sqrt(2.0)
    x = s * erfinv((2.0 * u - 1.0) * math.erf(radius / s))
    return min(max(x, -radius), radius)
