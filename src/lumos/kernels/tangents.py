"""Tangent frames at a hit, for bump and normal maps: dp/du and dp/dv of a triangle (from its uvs, or its stored
per-vertex tangents) or of an analytic shape's canonical parameterisation, in world space (`surface_tangents`).
"""

from __future__ import annotations

import math

import numpy as np

from .csg import csg_leaf
from .jit import njit
from .layout import (
    FLAG_UVS,
    INFO_FLAGS,
    INFO_KIND,
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CSG,
    SHAPE_CYLINDER,
    SHAPE_DISK,
    SHAPE_PLANE,
    SHAPE_RECT,
    SHAPE_SPHERE,
)
from .vec import cross, dot, length, normalize, orthonormal_basis, xform_point

#: Tangents whose cross product is below this fraction of |p_u|·|p_v| (sine of their angle) are degenerate.
_DEGENERATE_SINE = 1e-9
_TWO_PI = 2.0 * math.pi


@njit
def surface_tangents(surf, ref, part, p, n, time):
    """World-space (∂p/∂u, ∂p/∂v) at a hit, for the (u, v) that `surface_at` reports there.

    Triangles: from their uvs when present, else from the barycentric parameterisation (u, v) = (b1, b2).
    Analytic shapes: the derivative of the canonical shape's uv map (`surface._canonical_normal_uv`) carried to
    world space by the inverse of `object_from_world`; a csg hit uses the solid it lies on (`csg.csg_leaf`).
    Degenerate cases (poles, apex, zero-area uv triangles) and mesh solids inside csg objects (the hit record's
    triangle is not among the arguments) fall back to an orthonormal pair (t, b) around the unit normal n with
    t × b = n.
    """
    if ref >= 0:
        dpdu, dpdv = _triangle_tangents(surf, ref)
    else:
        s = ~ref
        if surf.shape_info[s, INFO_KIND] == SHAPE_CSG:  # the solid hit inside a csg object
            s, part = csg_leaf(part)
        dpdu, dpdv = _shape_tangents(surf, s, part, p, time)
    c = cross(dpdu, dpdv)
    scale = length(dpdu) * length(dpdv)
    if not (length(c) > _DEGENERATE_SINE * scale):  # also catches NaN
        return orthonormal_basis(normalize(n))
    return dpdu, dpdv


@njit
def _triangle_tangents(surf, ref):
    v = surf.tri_verts
    v0 = (np.float64(v[ref, 0]), np.float64(v[ref, 1]), np.float64(v[ref, 2]))
    e1 = (np.float64(v[ref, 3]) - v0[0], np.float64(v[ref, 4]) - v0[1], np.float64(v[ref, 5]) - v0[2])
    e2 = (np.float64(v[ref, 6]) - v0[0], np.float64(v[ref, 7]) - v0[1], np.float64(v[ref, 8]) - v0[2])
    if (surf.tri_info[ref, INFO_FLAGS] & FLAG_UVS) == 0:
        return e1, e2  # p = v0 + b1·e1 + b2·e2 and (u, v) = (b1, b2)
    uv = surf.tri_uvs
    du1 = np.float64(uv[ref, 2]) - np.float64(uv[ref, 0])
    dv1 = np.float64(uv[ref, 3]) - np.float64(uv[ref, 1])
    du2 = np.float64(uv[ref, 4]) - np.float64(uv[ref, 0])
    dv2 = np.float64(uv[ref, 5]) - np.float64(uv[ref, 1])
    det = du1 * dv2 - dv1 * du2
    if det == 0.0:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)  # degenerate: the caller falls back
    inv = 1.0 / det
    # e1 = du1·p_u + dv1·p_v and e2 = du2·p_u + dv2·p_v, solved for p_u, p_v
    dpdu = ((dv2 * e1[0] - dv1 * e2[0]) * inv, (dv2 * e1[1] - dv1 * e2[1]) * inv, (dv2 * e1[2] - dv1 * e2[2]) * inv)
    dpdv = ((du1 * e2[0] - du2 * e1[0]) * inv, (du1 * e2[1] - du2 * e1[1]) * inv, (du1 * e2[2] - du2 * e1[2]) * inv)
    return dpdu, dpdv


@njit
def _canonical_tangents(kind, part, q):
    """Object-space (∂q/∂u, ∂q/∂v) on a canonical shape at q, inverting `surface._canonical_normal_uv`."""
    if kind == SHAPE_SPHERE:
        # q = (cos θ sin φ, sin θ, cos θ cos φ) with φ = 2π(u − ½), θ = π(v − ½)
        q = normalize(q)
        r = math.sqrt(q[0] * q[0] + q[2] * q[2])
        if r == 0.0:
            return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)  # a pole
        return ((_TWO_PI * q[2], 0.0, -_TWO_PI * q[0]),
                (-math.pi * q[1] * q[0] / r, math.pi * r, -math.pi * q[1] * q[2] / r))
    if kind == SHAPE_BOX:
        axis = part // 2
        if axis == 0:  # (u, v) = (z, y)
            return (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)
        if axis == 1:  # (x, z)
            return (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)
        return (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)  # (x, y)
    if kind == SHAPE_CYLINDER or kind == SHAPE_CONE:
        if part == 1 or part == 2:  # caps: (u, v) = (½ + ½x, ½ + ½y)
            return (2.0, 0.0, 0.0), (0.0, 2.0, 0.0)
        # side: φ = 2π(u − ½), (x, y) = ρ(cos φ, sin φ), z = v with ρ = 1 (cylinder) or 1 − z (cone)
        phi = math.atan2(q[1], q[0])
        c = math.cos(phi)
        s = math.sin(phi)
        if kind == SHAPE_CYLINDER:
            return (-_TWO_PI * s, _TWO_PI * c, 0.0), (0.0, 0.0, 1.0)
        rho = 1.0 - q[2]
        return (-_TWO_PI * rho * s, _TWO_PI * rho * c, 0.0), (-c, -s, 1.0)
    if kind == SHAPE_RECT or kind == SHAPE_PLANE:
        return (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    if kind == SHAPE_DISK:
        return (2.0, 0.0, 0.0), (0.0, 2.0, 0.0)
    return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)  # mesh solids and others: the caller falls back


@njit
def _shape_tangents(surf, s, part, p, time):
    m = surf.shape_xform[s]
    q = p
    if m[3, 3] != 0.0:  # a moving shape, displaced by time·motion
        q = (p[0] - time * m[3, 0], p[1] - time * m[3, 1], p[2] - time * m[3, 2])
    t_u, t_v = _canonical_tangents(surf.shape_info[s, INFO_KIND], part, xform_point(m, q))
    # world_from_object's linear part is the inverse of object_from_world's: its columns are the cross products
    # of the rows of object_from_world over the determinant
    r0 = (m[0, 0], m[0, 1], m[0, 2])
    r1 = (m[1, 0], m[1, 1], m[1, 2])
    r2 = (m[2, 0], m[2, 1], m[2, 2])
    c0 = cross(r1, r2)
    c1 = cross(r2, r0)
    c2 = cross(r0, r1)
    det = dot(r0, c0)
    if det == 0.0:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    inv = 1.0 / det
    return _combine(c0, c1, c2, t_u, inv), _combine(c0, c1, c2, t_v, inv)


@njit
def _combine(c0, c1, c2, t, scale):
    return ((c0[0] * t[0] + c1[0] * t[1] + c2[0] * t[2]) * scale,
            (c0[1] * t[0] + c1[1] * t[1] + c2[1] * t[2]) * scale,
            (c0[2] * t[0] + c1[2] * t[1] + c2[2] * t[2]) * scale)
