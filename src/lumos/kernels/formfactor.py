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
from .traverse import any_hit

_INV_2PI = 0.5 / math.pi
#: The clipping plane sits this far above x (relative to the polygon's size) so a polygon touching x's plane
#: (a neighbour sharing an edge) is not cut into slivers of rounding noise.
_CLIP_EPS = 1e-12
#: Beyond (30·√area)² = 900·area from a patch, its form factor is the disk approximation (`patch_ff`). (At
#: 10·√area with the point-to-point formula, every row of a closed cylinder's matrix summed to 1.002 to 1.003:
#: light made from nothing, ×5 in a furnace of ρ = 0.8.)
_FAR_FIELD = 900.0


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
def patch_ff(x, n, corners, k, area, centre, n_poly, scratch):
    """The unoccluded form factor from x (unit normal n) to a patch: Lambert's contour formula near it, and far
    from it (distance over 30·√area) the disk approximation A·cos θ_x cos θ_y / (π r² + A) at its centre
    (Wallace, Elmquist & Haines 1989: exact for a facing disk of area A; the point-to-point A/(π r²) is always
    too large, by about A/(π r²)), within a few 10⁻⁴ there, at a tenth of the cost."""
    dx, dy, dz = centre[0] - x[0], centre[1] - x[1], centre[2] - x[2]
    d2 = dx * dx + dy * dy + dz * dz
    if d2 <= _FAR_FIELD * area:
        return point_polygon_ff(x, n, corners, k, scratch)
    inv = 1.0 / math.sqrt(d2)
    cos_x = (n[0] * dx + n[1] * dy + n[2] * dz) * inv
    cos_y = -(n_poly[0] * dx + n_poly[1] * dy + n_poly[2] * dz) * inv
    if cos_x <= 0.0 or cos_y <= 0.0:
        return 0.0
    return area * cos_x * cos_y / (math.pi * d2 + area)


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
        if not any_hit(geo, x, (wx, wy, wz), 0.0, d * (1.0 - config.RAY_EPSILON), stack, 0.0):
            seen += w
    if not total > 0.0:
        return 0.0, rays
    return seen / total, rays
