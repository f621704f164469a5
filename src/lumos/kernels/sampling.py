"""Sample placement: stratified 2D points and the concentric disk mapping."""

import math

from .jit import njit


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
