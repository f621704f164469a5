"""Ray–primitive intersection: triangles (watertight), canonical analytic shapes, and the slab test for boxes.

Conventions: a ray is `origin + t·direction` with `direction` not necessarily unit length; a hit is reported only
for `t_min < t < t_max`. Analytic shapes are intersected in their canonical object space (see `layout.SHAPE_*`):
the ray is mapped there by the affine `object_from_world` matrix, which preserves the parameter t, so the t found
in object space is the world-space t. Each shape test returns `(t, part)`, where `part` says which face was hit
(needed for normals and UVs); t = -1 means no hit.
"""

import math

import numpy as np

from .jit import njit, njit_inline
from .layout import (
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CYLINDER,
    SHAPE_DISK,
    SHAPE_PLANE,
    SHAPE_RECT,
    SHAPE_SPHERE,
)
from .vec import xform_point, xform_vector

NO_HIT = -1.0
f64 = np.float64

# ------------------------------------------------------------------------------------------------ triangles


@njit
def triangle_setup(d):
    """Per-ray constants of the watertight test (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle
    Intersection", JCGT 2(1)): the axis kz where |d| is largest, kx and ky after it (swapped to keep the
    winding), and the shear that maps d onto +z."""
    ax, ay, az = abs(d[0]), abs(d[1]), abs(d[2])
    if ax >= ay and ax >= az:
        kz = 0
    elif ay >= az:
        kz = 1
    else:
        kz = 2
    kx = kz + 1 if kz < 2 else 0
    ky = kx + 1 if kx < 2 else 0
    if d[kz] < 0.0:
        kx, ky = ky, kx
    sz = 1.0 / d[kz]
    return kx, ky, kz, d[kx] * sz, d[ky] * sz, sz


@njit
def intersect_triangle(o, setup, v, i, t_max):
    """Watertight ray–triangle test against triangle i of `v` (float32 (n, 9): v0, v1, v2).

    Returns (t, b1, b2) with barycentrics of v1 and v2, or (-1, 0, 0). The edge functions of an edge shared by
    two triangles are computed from the same sheared vertices, so they are exact negatives of each other: a ray
    through the edge hits at least one of the two triangles (no cracks), whatever the rounding.
    """
    kx, ky, kz, sx, sy, sz = setup
    ax = float(v[i, kx]) - o[kx]
    ay = float(v[i, ky]) - o[ky]
    az = float(v[i, kz]) - o[kz]
    bx = float(v[i, 3 + kx]) - o[kx]
    by = float(v[i, 3 + ky]) - o[ky]
    bz = float(v[i, 3 + kz]) - o[kz]
    cx = float(v[i, 6 + kx]) - o[kx]
    cy = float(v[i, 6 + ky]) - o[ky]
    cz = float(v[i, 6 + kz]) - o[kz]
    # shear and scale the vertices into the ray's space (the ray becomes the +z axis)
    ax = ax - sx * az
    ay = ay - sy * az
    bx = bx - sx * bz
    by = by - sy * bz
    cx = cx - sx * cz
    cy = cy - sy * cz
    # scaled barycentric coordinates (2D edge functions)
    e0 = cx * by - cy * bx
    e1 = ax * cy - ay * cx
    e2 = bx * ay - by * ax
    if (e0 < 0.0 or e1 < 0.0 or e2 < 0.0) and (e0 > 0.0 or e1 > 0.0 or e2 > 0.0):
        return NO_HIT, 0.0, 0.0
    det = e0 + e1 + e2
    if det == 0.0:
        return NO_HIT, 0.0, 0.0
    t_scaled = (e0 * az + e1 * bz + e2 * cz) * sz
    if det < 0.0:
        if t_scaled >= 0.0 or t_scaled < t_max * det:
            return NO_HIT, 0.0, 0.0
    elif t_scaled <= 0.0 or t_scaled > t_max * det:
        return NO_HIT, 0.0, 0.0
    inv = 1.0 / det
    return t_scaled * inv, e1 * inv, e2 * inv


# ------------------------------------------------------------------------------------------------ boxes (BVH)


#: 1 + 2·γ(3) for float64 (γ(n) = n·u / (1 − n·u), u = 2^-53): scaling t_far by it makes the slab test
#: conservative (Ize 2013, "Robust BVH Ray Traversal", JCGT 2(2)).
ROBUST_FAR = 1.0 + 2.0 * (3.0 * 2.0**-53) / (1.0 - 3.0 * 2.0**-53)


@njit
def box_setup(o, d):
    """Per-ray constants of the slab test: the origin, 1/d (zero components replaced by a huge finite value, so
    the test never meets 0·inf), and which box columns hold the near and far plane on each axis."""
    ix = 1.0 / d[0] if d[0] != 0.0 else 1e100
    iy = 1.0 / d[1] if d[1] != 0.0 else 1e100
    iz = 1.0 / d[2] if d[2] != 0.0 else 1e100
    nx = 0 if ix >= 0.0 else 3
    ny = 1 if iy >= 0.0 else 4
    nz = 2 if iz >= 0.0 else 5
    return ix, iy, iz, o[0], o[1], o[2], nx, ny, nz, 3 - nx, 5 - ny, 7 - nz


@njit
def intersect_node_box(box, j, rb, t_max):
    """Slab test of the ray (constants `rb` from `box_setup`) against box j of `box` (float32 (n, >= 6)).

    Returns the entry distance (clamped to 0), or -1 if the box is missed or lies beyond t_max. Each slab
    distance is (plane − origin)·(1/d), whose relative rounding error is bounded, and t_far is scaled by
    1 + 2γ(3), so a ray that touches the box is never reported as missing it — not even along an edge that
    lies exactly on a box face (which watertight meshes depend on).
    """
    ix, iy, iz, ox, oy, oz, nx, ny, nz, fx, fy, fz = rb
    # np.float64(): promote the float32 bounds before any arithmetic, compiled or interpreted (NumPy keeps
    # float32 · float in float32 under NEP 50, and the 1e100 stand-in for 1/0 would overflow)
    t_near = max(max((f64(box[j, nx]) - ox) * ix, (f64(box[j, ny]) - oy) * iy),
                 max((f64(box[j, nz]) - oz) * iz, 0.0))
    t_far = min(min((f64(box[j, fx]) - ox) * ix, (f64(box[j, fy]) - oy) * iy),
                (f64(box[j, fz]) - oz) * iz) * ROBUST_FAR
    if t_near <= min(t_far, t_max):
        return t_near
    return NO_HIT


# ------------------------------------------------------------------------------------- canonical analytic shapes


@njit
def quadratic_roots(a, half_b, c):
    """Roots of a·t² + 2·half_b·t + c = 0, smaller first, in the numerically stable form. (nan, nan) if none."""
    if a == 0.0:
        # linear: a ray parallel to a cone's generator meets the (double) cone once
        if half_b == 0.0:
            return math.nan, math.nan
        t = -c / (2.0 * half_b)
        return t, t
    disc = half_b * half_b - a * c
    if disc < 0.0:
        return math.nan, math.nan
    s = math.sqrt(disc)
    q = -(half_b + s) if half_b >= 0.0 else -(half_b - s)
    if q == 0.0:
        return 0.0, 0.0
    r0 = q / a
    r1 = c / q
    return min(r0, r1), max(r0, r1)


@njit
def sphere_roots(o, d):
    """Both roots along the whole line through the unit sphere, smaller first; (nan, nan) if it misses."""
    return quadratic_roots(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], o[0] * d[0] + o[1] * d[1] + o[2] * d[2],
                            o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 1.0)


@njit
def _sphere(o, d, t_min, t_max):
    t0, t1 = sphere_roots(o, d)
    if t_min < t0 < t_max:
        return t0, 0
    if t_min < t1 < t_max:
        return t1, 0
    return NO_HIT, 0


@njit
def box_span(o, d):
    """The slab test over the whole line through the cube [0,1]^3: (t_near, near_part, t_far, far_part), part =
    2·axis + (1 if the max face); t_near > t_far when the line misses (±1e300 on an axis it runs along)."""
    t_near = -1e300
    t_far = 1e300
    near_part = 0
    far_part = 0
    for a in range(3):
        if d[a] == 0.0:
            if o[a] < 0.0 or o[a] > 1.0:
                return 1.0, 0, -1.0, 0
            continue
        inv = 1.0 / d[a]
        ta = (0.0 - o[a]) * inv
        tb = (1.0 - o[a]) * inv
        pa, pb = 2 * a, 2 * a + 1
        if ta > tb:
            ta, tb = tb, ta
            pa, pb = pb, pa
        if ta > t_near:
            t_near, near_part = ta, pa
        if tb < t_far:
            t_far, far_part = tb, pb
    return t_near, near_part, t_far, far_part


@njit
def _box(o, d, t_min, t_max):
    """The cube [0,1]^3; part = 2·axis + (1 if the max face). Rays from inside hit the far face."""
    t_near, near_part, t_far, far_part = box_span(o, d)
    if t_near > t_far:
        return NO_HIT, 0
    if t_min < t_near < t_max:
        return t_near, near_part
    if t_min < t_far < t_max:
        return t_far, far_part
    return NO_HIT, 0


@njit
def _cap(o, d, z, t_min, t_max):
    """The unit disk in the plane at height z; t or -1."""
    if d[2] == 0.0:
        return NO_HIT
    t = (z - o[2]) / d[2]
    if not (t_min < t < t_max):
        return NO_HIT
    x = o[0] + t * d[0]
    y = o[1] + t * d[1]
    return t if x * x + y * y <= 1.0 else NO_HIT


@njit
def axial_quadratic(o, d, cone):
    """(a, half_b, c) of the side surface along the line o + t·d: a·t² + 2·half_b·t + c = 0 on the infinite
    cylinder x² + y² = 1, or on the double cone x² + y² = (1 − z)²; negative inside."""
    if cone:
        k = 1.0 - o[2]
        a = d[0] * d[0] + d[1] * d[1] - d[2] * d[2]
        half_b = o[0] * d[0] + o[1] * d[1] + k * d[2]
        c = o[0] * o[0] + o[1] * o[1] - k * k
    else:
        a = d[0] * d[0] + d[1] * d[1]
        half_b = o[0] * d[0] + o[1] * d[1]
        c = o[0] * o[0] + o[1] * o[1] - 1.0
    return a, half_b, c


@njit
def _axial(o, d, t_min, t_max, cone, capped):
    """Cylinder (cone=False) or cone of the canonical kind; part 0 = side, 1 = cap z=0, 2 = cap z=1."""
    a, half_b, c = axial_quadratic(o, d, cone)
    best = t_max
    part = -1
    t0, t1 = quadratic_roots(a, half_b, c)
    for t in (t0, t1):
        if t_min < t < best:
            z = o[2] + t * d[2]
            if 0.0 <= z <= 1.0:
                best = t
                part = 0
                break
    if capped:
        t = _cap(o, d, 0.0, t_min, best)
        if t != NO_HIT:
            best, part = t, 1
        if not cone:
            t = _cap(o, d, 1.0, t_min, best)
            if t != NO_HIT:
                best, part = t, 2
    if part < 0:
        return NO_HIT, 0
    return best, part


@njit
def _planar(o, d, t_min, t_max, kind):
    if d[2] == 0.0:
        return NO_HIT, 0
    t = -o[2] / d[2]
    if not (t_min < t < t_max):
        return NO_HIT, 0
    if kind == SHAPE_PLANE:
        return t, 0
    x = o[0] + t * d[0]
    y = o[1] + t * d[1]
    if kind == SHAPE_DISK:
        return (t, 0) if x * x + y * y <= 1.0 else (NO_HIT, 0)
    return (t, 0) if (0.0 <= x <= 1.0 and 0.0 <= y <= 1.0) else (NO_HIT, 0)


@njit
def _planar_world(m, o, d, t_min, t_max, kind):
    """`_planar` on the world-space ray: the canonical z of the origin and direction first (the plane's
    distance), the in-plane coordinates only for a hit within (t_min, t_max) — most tests stop before them."""
    dz = m[2, 0] * d[0] + m[2, 1] * d[1] + m[2, 2] * d[2]
    if dz == 0.0:
        return NO_HIT, 0
    oz = m[2, 0] * o[0] + m[2, 1] * o[1] + m[2, 2] * o[2] + m[2, 3]
    t = -oz / dz
    if not (t_min < t < t_max):
        return NO_HIT, 0
    if kind == SHAPE_PLANE:
        return t, 0
    p = (o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2])
    x = m[0, 0] * p[0] + m[0, 1] * p[1] + m[0, 2] * p[2] + m[0, 3]
    y = m[1, 0] * p[0] + m[1, 1] * p[1] + m[1, 2] * p[2] + m[1, 3]
    if kind == SHAPE_DISK:
        return (t, 0) if x * x + y * y <= 1.0 else (NO_HIT, 0)
    return (t, 0) if (0.0 <= x <= 1.0 and 0.0 <= y <= 1.0) else (NO_HIT, 0)


@njit_inline
def intersect_shape(kind, capped, xform, o_world, d_world, t_min, t_max):
    """Intersect an analytic shape given by its kind and object_from_world matrix (3, 4). Returns (t, part)."""
    if kind == SHAPE_RECT or kind == SHAPE_DISK or kind == SHAPE_PLANE:
        return _planar_world(xform, o_world, d_world, t_min, t_max, kind)
    o = xform_point(xform, o_world)
    d = xform_vector(xform, d_world)
    if kind == SHAPE_SPHERE:
        return _sphere(o, d, t_min, t_max)
    if kind == SHAPE_BOX:
        return _box(o, d, t_min, t_max)
    if kind == SHAPE_CYLINDER:
        return _axial(o, d, t_min, t_max, False, capped)
    if kind == SHAPE_CONE:
        return _axial(o, d, t_min, t_max, True, capped)
    return _planar(o, d, t_min, t_max, kind)
