"""Mirror reflection, Snell refraction and Schlick's Fresnel approximation (DESIGN.md §3, recursion).

All directions are unit vectors; `n` is the unit normal on the side the incident direction `d` comes from
(d·n < 0). `eta` is the ratio of refractive indices n_incident / n_transmitted: 1/ior entering a material
from outside, ior leaving it.
"""

import math

from .jit import njit


@njit
def reflect(d, n):
    """d mirrored about n: d − 2(d·n)n."""
    k = 2.0 * (d[0] * n[0] + d[1] * n[1] + d[2] * n[2])
    return (d[0] - k * n[0], d[1] - k * n[1], d[2] - k * n[2])


@njit
def refract(d, n, eta):
    """Snell's law: (ok, t). ok is False on total internal reflection (then t is the mirror direction).

    With cos_i = −d·n and sin²_t = eta²(1 − cos_i²): t = eta·d + (eta·cos_i − cos_t)·n, cos_t = √(1 − sin²_t).
    """
    cos_i = -(d[0] * n[0] + d[1] * n[1] + d[2] * n[2])
    sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i)
    if sin2_t > 1.0:
        return False, reflect(d, n)
    cos_t = math.sqrt(1.0 - sin2_t)
    k = eta * cos_i - cos_t
    t = (eta * d[0] + k * n[0], eta * d[1] + k * n[1], eta * d[2] + k * n[2])
    inv = 1.0 / math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
    return True, (t[0] * inv, t[1] * inv, t[2] * inv)


@njit
def schlick(cos_i, eta, cos_t):
    """Schlick's approximation of the Fresnel reflectance, R0 + (1 − R0)(1 − c)^5 with R0 = ((1−η)/(1+η))²,
    where c is the cosine on the optically thinner side (cos_t when leaving a denser medium)."""
    r0 = (1.0 - eta) / (1.0 + eta)
    r0 = r0 * r0
    c = cos_i if eta <= 1.0 else cos_t
    m = 1.0 - c
    return r0 + (1.0 - r0) * m * m * m * m * m
