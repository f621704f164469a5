"""3-vectors as tuples of floats: no allocation, everything inlines."""

import math

from .jit import njit


@njit
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit
def mul(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


@njit
def hadamard(a, b):
    return (a[0] * b[0], a[1] * b[1], a[2] * b[2])


@njit
def madd(a, b, s):
    """a + s·b"""
    return (a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2])


@njit
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit
def length(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@njit
def normalize(a):
    n = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    if n == 0.0:
        return (0.0, 0.0, 0.0)
    inv = 1.0 / n
    return (a[0] * inv, a[1] * inv, a[2] * inv)


@njit
def row3(arr, i):
    """Row i of an (n, 3) array as a float64 tuple."""
    return (float(arr[i, 0]), float(arr[i, 1]), float(arr[i, 2]))


@njit
def xform_point(m, p):
    """m (3, 4) affine matrix applied to point p."""
    return (
        m[0, 0] * p[0] + m[0, 1] * p[1] + m[0, 2] * p[2] + m[0, 3],
        m[1, 0] * p[0] + m[1, 1] * p[1] + m[1, 2] * p[2] + m[1, 3],
        m[2, 0] * p[0] + m[2, 1] * p[1] + m[2, 2] * p[2] + m[2, 3],
    )


@njit
def xform_vector(m, d):
    """Linear part of m (3, 4) applied to direction d."""
    return (
        m[0, 0] * d[0] + m[0, 1] * d[1] + m[0, 2] * d[2],
        m[1, 0] * d[0] + m[1, 1] * d[1] + m[1, 2] * d[2],
        m[2, 0] * d[0] + m[2, 1] * d[1] + m[2, 2] * d[2],
    )


@njit
def xform_normal(m_object_from_world, n):
    """A normal from object to world space: the transpose of object_from_world's linear part (inverse transpose
    of world_from_object), so normals stay perpendicular under non-uniform scale."""
    m = m_object_from_world
    return (
        m[0, 0] * n[0] + m[1, 0] * n[1] + m[2, 0] * n[2],
        m[0, 1] * n[0] + m[1, 1] * n[1] + m[2, 1] * n[2],
        m[0, 2] * n[0] + m[1, 2] * n[1] + m[2, 2] * n[2],
    )


@njit
def orthonormal_basis(n):
    """Two unit vectors perpendicular to unit n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited")."""
    sign = 1.0 if n[2] >= 0.0 else -1.0
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    return (1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]), (b, sign + n[1] * n[1] * a, -n[1])
