"""Form factors by ray casting: from a point of one patch to a whole other patch, visibility by shadow rays.

    F = point_polygon_ff(x, n, corners, k)                          # unoccluded, exact (Lambert)
    V = visibility(geo, x, n, corners, k, samples, key, stack)      # the fraction of it not blocked

The unoccluded form factor from a differential area at x (unit normal n) to a planar polygon is Lambert's
contour integral (Baum, Rushmeier & Winget 1989, eq. 3):

    F = (1/2π) Σ_i γ_i · n · unit(d_i × d_i+1),     d_i = unit(v_i − x),  γ_i = acos(d_i · d_i+1)

over the polygon's edges, after clipping the polygon to the half-space above x's tangent plane (the part
behind x sends it nothing). It is exact however close or large the polygon is, so neighbouring patches, whose
form factors the 1/r² of a point-to-point estimate gets wrong, are right.

Visibility is the kernel-weighted fraction of shadow rays from x to `samples` stratified points y_k of the
polygon that reach it: V = Σ w_k·vis_k / Σ w_k with w_k = cos θ_x cos θ_y / r² (Wallace, Elmquist & Haines
1989, "A ray tracing algorithm for progressive radiosity"); F·V is the form factor with occlusion, exact when
nothing or everything is in the way. Area-to-area form factors average it over points of the receiver.

Polygons are given by their corners as a (4, 3) array with `k` = 3 or 4 of them used, counter-clockwise
about the side that sends light (towards x).
"""

import math

from .. import config
from .jit import njit_inline
from .rng import rand2_key
from .sampling import stratified_2d
from .traverse import any_triangle_hit

_INV_2PI = 0.5 / math.pi
#: The clipping plane sits this far above x (relative to the polygon's size) so a polygon touching x's plane
#: (a neighbour sharing an edge) is not cut into slivers of rounding noise.
_CLIP_EPS = 1e-12
#: Beyond 10 radii of a patch (its farthest corner from its centre), squared, its form factor is a cubature of
#: the point-to-point kernel over it (`patch_ff`), within 3e-5 of A/(π r²) of the exact one there (random
#: parallelograms and triangles against the contour formula) and closer farther out (as r⁻⁴).
_FAR_FIELD = 100.0
#: The 2×2 Gauss–Legendre points on [0, 1], and a triangle's degree-2 rule: barycentrics (2/3, 1/6, 1/6)
#: and their turns, weights 1/3 each.
_GAUSS_LO = 0.5 - 0.5 / math.sqrt(3.0)
_GAUSS_HI = 0.5 + 0.5 / math.sqrt(3.0)


@njit_inline
def _clip_above(x, n, corners, k, out):
    """Sutherland–Hodgman: the part of the polygon corners[:k] with n·(p − x) >= 0, written to out (8, 3);
    returns its corner count (0 when all of it is below)."""
    m = 0
    for i in range(k):
        a = corners[i]
        b = corners[(i + 1) % k]
        da = n[0] * (a[0] - x[0]) + n[1] * (a[1] - x[1]) + n[2] * (a[2] - x[2])
        db = n[0] * (b[0] - x[0]) + n[1] * (b[1] - x[1]) + n[2] * (b[2] - x[2])
        if da >= 0.0:
            out[m, 0], out[m, 1], out[m, 2] = a[0], a[1], a[2]
            m += 1
        if (da >= 0.0) != (db >= 0.0):
            t = da / (da - db)
            out[m, 0] = a[0] + t * (b[0] - a[0])
            out[m, 1] = a[1] + t * (b[1] - a[1])
            out[m, 2] = a[2] + t * (b[2] - a[2])
            m += 1
    return m


@njit_inline
def point_polygon_ff(x, n, corners, k, scratch):
    """The unoccluded form factor from the differential area at x (unit normal n) to the polygon corners[:k]
    (float64 (4, 3)), by Lambert's contour formula on its part above x's tangent plane; `scratch` is a float64
    (8, 3) work array. 0 when the polygon is wholly below."""
    m = _clip_above(x, n, corners, k, scratch)
    if m < 3:
        return 0.0
    total = 0.0
    # unit directions to the corners
    for i in range(m):
        dx = scratch[i, 0] - x[0]
        dy = scratch[i, 1] - x[1]
        dz = scratch[i, 2] - x[2]
        inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz + 1e-300)
        scratch[i, 0], scratch[i, 1], scratch[i, 2] = dx * inv, dy * inv, dz * inv
    for i in range(m):
        j = i + 1 if i + 1 < m else 0
        a0, a1, a2 = scratch[i, 0], scratch[i, 1], scratch[i, 2]
        b0, b1, b2 = scratch[j, 0], scratch[j, 1], scratch[j, 2]
        c0 = a1 * b2 - a2 * b1
        c1 = a2 * b0 - a0 * b2
        c2 = a0 * b1 - a1 * b0
        s = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        if s == 0.0:
            continue
        gamma = math.atan2(s, a0 * b0 + a1 * b1 + a2 * b2)  # acos of the dot, accurate near 0 and π
        total += gamma * (n[0] * c0 + n[1] * c1 + n[2] * c2) / s
    return abs(total) * _INV_2PI


@njit_inline
def _kernel(x, n, n_poly, y0, y1, y2):
    """cos θ_x cos θ_y / r² from x (normal n) to the point y of a polygon of normal n_poly."""
    vx, vy, vz = y0 - x[0], y1 - x[1], y2 - x[2]
    r2 = vx * vx + vy * vy + vz * vz
    return (n[0] * vx + n[1] * vy + n[2] * vz) * -(n_poly[0] * vx + n_poly[1] * vy + n_poly[2] * vz) / (r2 * r2)


@njit_inline
def _cubature_ff(x, n, c, k, area, n_poly):
    """(1/π)·∫ cos θ_x cos θ_y / r² dA over the polygon c[:k] (a parallelogram or a triangle), by the 2×2
    Gauss points of the parallelogram or the triangle's degree-2 rule; exact enough only far from it."""
    e1 = (c[1, 0] - c[0, 0], c[1, 1] - c[0, 1], c[1, 2] - c[0, 2])
    if k == 4:
        e2 = (c[3, 0] - c[0, 0], c[3, 1] - c[0, 1], c[3, 2] - c[0, 2])
        total = 0.0
        for a in range(2):
            u = _GAUSS_LO if a == 0 else _GAUSS_HI
            for b in range(2):
                v = _GAUSS_LO if b == 0 else _GAUSS_HI
                total += _kernel(x, n, n_poly, c[0, 0] + u * e1[0] + v * e2[0], c[0, 1] + u * e1[1] + v * e2[1],
                                 c[0, 2] + u * e1[2] + v * e2[2])
        return area * total * (0.25 / math.pi)
    e2 = (c[2, 0] - c[0, 0], c[2, 1] - c[0, 1], c[2, 2] - c[0, 2])
    total = 0.0
    for q in range(3):
        u = 2.0 / 3.0 if q == 1 else 1.0 / 6.0
        v = 2.0 / 3.0 if q == 2 else 1.0 / 6.0
        total += _kernel(x, n, n_poly, c[0, 0] + u * e1[0] + v * e2[0], c[0, 1] + u * e1[1] + v * e2[1],
                         c[0, 2] + u * e1[2] + v * e2[2])
    return area * total / (3.0 * math.pi)


@njit_inline
def patch_ff(x, n, corners, k, area, centre, n_poly, scratch):
    """The unoccluded form factor from x (unit normal n, in front of the patch) to a patch: Lambert's contour
    formula near it, and far from it (beyond 10 of its radii), when it lies wholly in front of x, the cubature
    `_cubature_ff` (a quarter of the contour's cost; about four form factors in five of the Cornell box's
    adaptive solve). A quad patch is a parallelogram (a grid cell, or a quarter of one); one that is not takes
    the contour formula everywhere."""
    dx, dy, dz = centre[0] - x[0], centre[1] - x[1], centre[2] - x[2]
    d2 = dx * dx + dy * dy + dz * dz
    radius2 = 0.0
    front = True  # every corner above x's tangent plane
    behind = True  # every corner below it: the clip leaves nothing
    for i in range(k):
        cx, cy, cz = corners[i, 0] - centre[0], corners[i, 1] - centre[1], corners[i, 2] - centre[2]
        radius2 = max(radius2, cx * cx + cy * cy + cz * cz)
        height = n[0] * (cx + dx) + n[1] * (cy + dy) + n[2] * (cz + dz)
        front = front and height > 0.0
        behind = behind and height < 0.0
    if behind:
        return 0.0
    if d2 <= _FAR_FIELD * radius2 or not front:
        return point_polygon_ff(x, n, corners, k, scratch)
    if k == 4:  # a parallelogram: corner 0 + corner 2 = corner 1 + corner 3
        sx = corners[0, 0] + corners[2, 0] - corners[1, 0] - corners[3, 0]
        sy = corners[0, 1] + corners[2, 1] - corners[1, 1] - corners[3, 1]
        sz = corners[0, 2] + corners[2, 2] - corners[1, 2] - corners[3, 2]
        if sx * sx + sy * sy + sz * sz > 1e-12 * radius2:
            return point_polygon_ff(x, n, corners, k, scratch)
    return _cubature_ff(x, n, corners, k, area, n_poly)


@njit_inline
def polygon_point(corners, k, u, v):
    """A point of the polygon from (u, v) in [0, 1)²: bilinear over a quad, uniform over a triangle."""
    if k == 3:
        su = math.sqrt(u)
        b1 = su * (1.0 - v)
        b2 = su * v
        return (corners[0, 0] + b1 * (corners[1, 0] - corners[0, 0]) + b2 * (corners[2, 0] - corners[0, 0]),
                corners[0, 1] + b1 * (corners[1, 1] - corners[0, 1]) + b2 * (corners[2, 1] - corners[0, 1]),
                corners[0, 2] + b1 * (corners[1, 2] - corners[0, 2]) + b2 * (corners[2, 2] - corners[0, 2]))
    w0 = (1.0 - u) * (1.0 - v)
    w1 = u * (1.0 - v)
    w2 = u * v
    w3 = (1.0 - u) * v
    return (w0 * corners[0, 0] + w1 * corners[1, 0] + w2 * corners[2, 0] + w3 * corners[3, 0],
            w0 * corners[0, 1] + w1 * corners[1, 1] + w2 * corners[2, 1] + w3 * corners[3, 1],
            w0 * corners[0, 2] + w1 * corners[1, 2] + w2 * corners[2, 2] + w3 * corners[3, 2])


@njit_inline
def visibility(geo, x, n, corners, k, n_poly, samples, key, stack):
    """The kernel-weighted fraction of `samples` stratified shadow rays from x (unit normal n, offset off its
    surface by the caller) to points of the polygon (unit normal n_poly, facing x) that nothing blocks.
    Returns (V, rays traced); V = 1 for samples = 0."""
    if samples <= 0:
        return 1.0, 0
    seen = 0.0
    total = 0.0
    rays = 0
    for s in range(samples):
        r1, r2 = rand2_key(key, s)
        u, v = stratified_2d(s, samples, r1, r2)
        y = polygon_point(corners, k, u, v)
        dx, dy, dz = y[0] - x[0], y[1] - x[1], y[2] - x[2]
        d2 = dx * dx + dy * dy + dz * dz
        if not d2 > 0.0:
            continue
        d = math.sqrt(d2)
        inv = 1.0 / d
        wx, wy, wz = dx * inv, dy * inv, dz * inv
        cos_x = n[0] * wx + n[1] * wy + n[2] * wz
        cos_y = -(n_poly[0] * wx + n_poly[1] * wy + n_poly[2] * wz)
        if cos_x <= 0.0 or cos_y <= 0.0:
            continue
        w = cos_x * cos_y / d2
        total += w
        rays += 1
        if not any_triangle_hit(geo, x, (wx, wy, wz), 0.0, d * (1.0 - config.RAY_EPSILON), stack):
            seen += w
    if not total > 0.0:
        return 0.0, rays
    return seen / total, rays
