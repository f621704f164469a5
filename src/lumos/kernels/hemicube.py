"""Hemicube form factors (Cohen & Greenberg 1985, "The hemi-cube: a radiosity solution for complex environments").

The form factor from a point x with unit normal n to a patch is the share of the cosine-weighted hemisphere
above x that the patch fills, seen through the other polygons. A unit hemicube around x (a top face one unit
along n, four side faces one unit along the tangents) is rasterised like five camera images with a z-buffer and
an item buffer holding, per pixel, the patch seen; each pixel adds its delta form factor (the form factor of
the pixel's square, `delta_form_factors`) to the patch it shows.

The scan conversion is the raster method's own (`kernels.raster`: `setup_edges`, `first_covered_row`,
`fill_polygon`, inlined), so a pixel is covered when its centre is (top-left rule) and two polygons that share an
edge cover each pixel on it once.

Layout. The five faces are stacked into one image of 3·res rows by res columns (the "atlas"), which is the shape
of the z-buffer, the item buffer and the ΔF table:

    rows [0, res)                          the top face, res × res pixels, looking along n
    rows [res + k·res/2, res + (k+1)·res/2)  side face k = 0..3, looking along +t1, −t1, +t2, −t2, res × res/2

Side faces: only the upper half of each side face is above the base plane (the tangent plane of x), so only
that half exists. Each side face's buffer is res columns by res/2 rows, from its top edge (one unit above the base
plane) down to the base plane; polygons are clipped against the base plane (Y >= 0 in the face's frame) as
against the face's other three edges, so nothing below the base plane is scanned, and the ΔF table has no
entries there. (Cohen & Greenberg allocate the whole side face and use half of it; nothing else differs.)

Clipping. Each face is a 90° perspective frustum with its apex at x. A polygon is transformed into the face's
clip space (X right, Y up, D forward; the screen point is (X/D, Y/D) in [−1, 1]²), rejected when all its corners
lie outside one frustum plane (D >= near, X <= D, X >= −D, Y <= D, and Y >= −D on the top face or Y >= 0 on the
side faces), and clipped (Sutherland–Hodgman, in clip space, where positions are linear) against each plane
that some of its corners are outside of. So polygons behind x, crossing the base plane, or passing beside x all
reach the scan converter as the part of them inside the face, with D >= near (no division by ~0). The depth key
is 1/D (linear in screen space; larger is nearer), as in the raster method's perspective views.

Rotation. The tangents t1, t2 are `vec.orthonormal_basis(n)` turned by φ about n. A fixed hemicube aliases (the
same small patch always falls on the same pixels); turning it at random per shot, as the progressive solver of
Graphics Gems II (Chen, "Implementing progressive radiosity with user-provided polygon display routines",
rad.c) does, turns that aliasing into noise that averages out over shots. Only the aliasing across the
rotation averages out: a turn about n never moves a patch's elevation relative to the pixel rows of the side
faces (nor its distance from the top face's centre), so a patch a few pixels across keeps a bias of a few
percent in that direction (measured: 5% for a 3-pixel square on a side face at res 32; 0.4% for a 1.6-pixel
square on the top face, against 20% from a single fixed hemicube).

Near plane. `near` must be far below the caller's offset of x off its surface (geometry closer to x than `near`
along a face's axis is cut away) and far above rounding: 1e-3 of the offset, say.

Which side is seen. Polygon p shows side_patch[p, 0] when x is on its front side (dot(x − corner, normal) > 0),
else side_patch[p, 1]; a side that is no patch (-1, e.g. the inside of a closed solid) still occludes, and its
pixels add nothing, as do pixels that see nothing.
"""

import math

import numpy as np

from .jit import njit, njit_alloc, njit_inline, njit_serial
from .threads import parallel_for
from .raster import MAX_VERTS, edge_scratch, fill_polygon, first_covered_row, setup_edges
from .vec import orthonormal_basis

#: Faces of the hemicube, in atlas order.
N_FACES = 5
#: The pixel sample point within a pixel: its centre, where the ΔF table is evaluated.
_JX = 0.5
_JY = 0.5
#: Points per run of `form_factor_matrix` handed to a thread (the scratch buffers are allocated once per run).
_CHUNK = 8


@njit_alloc
def delta_form_factors(res, normalise=True):
    """The delta form factors of a unit hemicube whose top face has res × res pixels (res even): float64
    (3·res, res) in the atlas layout (module docstring).

    Top face pixel centred at (x, y) (the face is [−1, 1]² one unit above x): ΔF = Δa / (π (x² + y² + 1)²).
    Side face pixel centred at (y, z) (y across, z in (0, 1) the height above the base plane):
    ΔF = z·Δa / (π (y² + z² + 1)²). Δa = (2/res)². They are the midpoint rule for each pixel's exact form factor,
    whose total is 1; the raw sum exceeds 1 by the rule's O(1/res²) truncation error (1.3e-4 at res 64, 3.3e-5 at
    128). With `normalise` the table is scaled to sum to 1, so a point enclosed on every side sees a total of
    exactly 1 (up to rounding): what energy conservation in a closed scene needs."""
    if res < 2 or res % 2 != 0:
        raise ValueError("hemicube resolution must be even")
    half = res // 2
    table = np.zeros((3 * res, res))
    da = (2.0 / res) ** 2
    for r in range(res):
        y = 1.0 - (r + 0.5) * 2.0 / res
        for c in range(res):
            x = (c + 0.5) * 2.0 / res - 1.0
            s = x * x + y * y + 1.0
            table[r, c] = da / (math.pi * s * s)
    for k in range(4):
        for r in range(half):
            z = 1.0 - (r + 0.5) * 2.0 / res
            for c in range(res):
                y = (c + 0.5) * 2.0 / res - 1.0
                s = y * y + z * z + 1.0
                table[res + k * half + r, c] = z * da / (math.pi * s * s)
    if normalise:
        table /= table.sum()
    return table


@njit_alloc
def hemicube_scratch(res):
    """The working buffers of one hemicube (`hemicube_form_factors`), one set per thread: a tuple
    (zbuf float64 (3·res, res), item buffer int32 (3·res, res), corners float64 (MAX_VERTS, 3),
    clip_a and clip_b float64 (MAX_VERTS, 3), px and py float64 (MAX_VERTS,), vertex values float64
    (MAX_VERTS, 2), an empty G-buffer float32 (1, 1, 0), and the scan converter's `edges` tuple)."""
    kf = 2  # depth key 1/D and q = 1; no attributes
    edges = edge_scratch(kf)
    return (np.empty((3 * res, res)), np.empty((3 * res, res), np.int32), np.empty((MAX_VERTS, 3)),
            np.empty((MAX_VERTS, 3)), np.empty((MAX_VERTS, 3)), np.empty(MAX_VERTS), np.empty(MAX_VERTS),
            np.empty((MAX_VERTS, kf)), np.empty((1, 1, 0), np.float32), edges)


@njit_inline
def _face_clip(face, l0, l1, l2):
    """(X, Y, D) of a point with hemicube coordinates (l0, l1, l2) = along (t1, t2, n), in face `face`'s clip
    space: D along the face's axis, Y up (n on the side faces, t2 on the top), X = right = forward × up."""
    if face == 0:
        return -l0, l1, l2
    if face == 1:
        return -l1, l2, l0
    if face == 2:
        return l1, l2, -l0
    if face == 3:
        return l0, l2, l1
    return -l0, l2, -l1


@njit_inline
def _only_face(nc, corners, near):
    """The face whose frustum holds the whole polygon (all its corners, strictly inside: the frustum is convex),
    or -1 when it may reach several faces or needs clipping. Most small polygons lie inside one face."""
    face = -1
    for k in range(nc):
        l0, l1, l2 = corners[k, 0], corners[k, 1], corners[k, 2]
        a0, a1 = abs(l0), abs(l1)
        if l2 > a0 and l2 > a1:
            f, d = 0, l2
        elif a0 > a1 and a0 > l2 > 0.0:
            f, d = (1 if l0 > 0.0 else 2), a0
        elif a1 > a0 and a1 > l2 > 0.0:
            f, d = (3 if l1 > 0.0 else 4), a1
        else:
            return -1  # on a face boundary or at/below the base plane
        if d < near or (face >= 0 and f != face):
            return -1
        face = f
    return face


@njit_inline
def _plane_distance(plane, top, near, X, Y, D):
    """Signed distance-like value of clip point (X, Y, D) to a frustum plane, >= 0 inside: 0 near (D >= near),
    1 right, 2 left, 3 top edge, 4 bottom edge (Y >= −D on the top face, the base plane Y >= 0 on the sides)."""
    if plane == 0:
        return D - near
    if plane == 1:
        return D - X
    if plane == 2:
        return D + X
    if plane == 3:
        return D - Y
    return D + Y if top else Y


@njit_inline
def _clip_against(plane, top, near, m, src, dst):
    """Sutherland–Hodgman: the polygon src[:m] (clip space X, Y, D) clipped to the inside of one plane, into
    dst. An edge's crossing is computed from its inside end point, whichever way the polygon runs, so polygons
    sharing the edge agree on it. Returns the output vertex count."""
    out = 0
    for k in range(m):
        j = k + 1 if k + 1 < m else 0
        da = _plane_distance(plane, top, near, src[k, 0], src[k, 1], src[k, 2])
        db = _plane_distance(plane, top, near, src[j, 0], src[j, 1], src[j, 2])
        if da >= 0.0:
            dst[out, 0] = src[k, 0]
            dst[out, 1] = src[k, 1]
            dst[out, 2] = src[k, 2]
            out += 1
        if (da >= 0.0) != (db >= 0.0):
            i_in, i_out, d_in, d_out = (k, j, da, db) if da >= 0.0 else (j, k, db, da)
            t = d_in / (d_in - d_out)
            for c in range(3):
                dst[out, c] = src[i_in, c] + t * (src[i_out, c] - src[i_in, c])
            out += 1
    return out


@njit_inline
def _raster_face(face, res, near, nc, corners, item, scratch):
    """Scan-convert one polygon (its nc corners in hemicube coordinates) into one face of the atlas."""
    zbuf, ids, _, clip_a, clip_b, px, py, F, gbuf, edges = scratch
    top = face == 0
    # clip space, and which planes the corners are outside of (all outside one: nothing to draw)
    for k in range(nc):
        clip_a[k, 0], clip_a[k, 1], clip_a[k, 2] = _face_clip(face, corners[k, 0], corners[k, 1], corners[k, 2])
    crossed = 0
    for plane in range(5):
        inside = 0
        for k in range(nc):
            if _plane_distance(plane, top, near, clip_a[k, 0], clip_a[k, 1], clip_a[k, 2]) >= 0.0:
                inside += 1
        if inside == 0:
            return
        if inside < nc:
            crossed |= 1 << plane
    # clipped to the frustum (only against the planes it crosses)
    m = nc
    src, dst = clip_a, clip_b
    for plane in range(5):
        if crossed & (1 << plane):
            m = _clip_against(plane, top, near, m, src, dst)
            src, dst = dst, src
            if m < 3:
                return
    # screen: x in [0, res], y in the face's rows of the atlas; depth key 1/D
    row0 = 0 if top else res + (face - 1) * (res // 2)
    rows = res if top else res // 2
    y_min = 1e300
    y_max = -1e300
    for k in range(m):
        inv_d = 1.0 / src[k, 2]
        px[k] = (src[k, 0] * inv_d + 1.0) * 0.5 * res
        py[k] = row0 + (1.0 - src[k, 1] * inv_d) * 0.5 * res
        F[k, 0] = inv_d
        F[k, 1] = 1.0
        y_min = min(y_min, py[k])
        y_max = max(y_max, py[k])
    r0 = max(row0, int(math.ceil(y_min - _JY)))
    r1 = min(row0 + rows, int(math.ceil(y_max - _JY)))
    if r1 <= r0:
        return
    ne = setup_edges(m, px, py, edges)
    r, nx = first_covered_row(ne, edges, r0, r1, res, _JX, _JY)
    if r < r1:
        fill_polygon(ne, edges, nx, F, r, r1, res, _JX, _JY, item, zbuf, ids, gbuf, None)


@njit
def hemicube_form_factors(x, n, phi, skip_poly, verts, polys, poly_normal, side_patch, dF, near, scratch, out):
    """Add the hemicube form factors from the point x to every patch into `out`. Allocates nothing.

    x, n      3-tuples of float: the point (already offset a little along n off its surface) and its unit normal
    phi       float: rotation of the hemicube's side faces about n (radians)
    skip_poly int: the polygon x lies on (never drawn), or -1
    verts     float64 (nv, 3): polygon corners
    polys     int32 (np, 4): corner indices, counter-clockwise about the normal; column 3 = -1 for triangles
    poly_normal float64 (np, 3): unit normals
    side_patch int32 (np, 2): patch id of each polygon's front side (the side its normal points to) and back
              side, -1 where that side is no patch (it still occludes)
    dF        float64 (3·res, res): `delta_form_factors(res)`
    near      float: the near plane distance (small against x's offset from its surface, large against rounding)
    scratch   `hemicube_scratch(res)` (overwritten)
    out       float64 (n_patches,): out[patch] += the form factor from x to that patch
    """
    zbuf, ids, corners = scratch[0], scratch[1], scratch[2]
    res = dF.shape[1]
    # the hemicube's frame: t1, t2 turned by phi about n
    b1, b2 = orthonormal_basis(n)
    cs = math.cos(phi)
    sn = math.sin(phi)
    t1 = (cs * b1[0] + sn * b2[0], cs * b1[1] + sn * b2[1], cs * b1[2] + sn * b2[2])
    t2 = (cs * b2[0] - sn * b1[0], cs * b2[1] - sn * b1[1], cs * b2[2] - sn * b1[2])
    for r in range(3 * res):
        for c in range(res):
            zbuf[r, c] = 0.0  # depth key 1/D: 0 is infinitely far
            ids[r, c] = -1
    for p in range(polys.shape[0]):
        if p == skip_poly:
            continue
        nc = 3 if polys[p, 3] < 0 else 4
        # corners in hemicube coordinates (along t1, t2, n); a polygon wholly on or below the base plane is unseen
        above = False
        for k in range(nc):
            v = polys[p, k]
            dx = verts[v, 0] - x[0]
            dy = verts[v, 1] - x[1]
            dz = verts[v, 2] - x[2]
            corners[k, 0] = dx * t1[0] + dy * t1[1] + dz * t1[2]
            corners[k, 1] = dx * t2[0] + dy * t2[1] + dz * t2[2]
            corners[k, 2] = dx * n[0] + dy * n[1] + dz * n[2]
            above |= corners[k, 2] > 0.0
        if not above:
            continue
        # the side of p that x sees: its front where x is on the side its normal points to
        v = polys[p, 0]
        facing = ((x[0] - verts[v, 0]) * poly_normal[p, 0] + (x[1] - verts[v, 1]) * poly_normal[p, 1]
                  + (x[2] - verts[v, 2]) * poly_normal[p, 2])
        item = side_patch[p, 0] if facing > 0.0 else side_patch[p, 1]
        face = _only_face(nc, corners, near)
        if face >= 0:
            _raster_face(face, res, near, nc, corners, item, scratch)
        else:
            for face in range(N_FACES):
                _raster_face(face, res, near, nc, corners, item, scratch)
    # every pixel adds its delta form factor to the patch it shows
    for r in range(3 * res):
        for c in range(res):
            patch = ids[r, c]
            if patch >= 0:
                out[patch] += dF[r, c]


@njit_alloc
def form_factors_from_point(x, n, phi, skip_poly, verts, polys, poly_normal, side_patch, dF, near, n_patches):
    """The single-point entry (progressive radiosity: one shot): float64 (n_patches,) form factors from x.

    x, n float64 (3,); n_patches int (> side_patch.max()); the other arguments as in `hemicube_form_factors`.
    Allocates its scratch buffers; a loop of many shots should call `hemicube_scratch` once and
    `hemicube_form_factors` per shot."""
    out = np.zeros(n_patches)
    hemicube_form_factors((x[0], x[1], x[2]), (n[0], n[1], n[2]), phi, skip_poly, verts, polys, poly_normal,
                          side_patch, dF, near, hemicube_scratch(dF.shape[1]), out)
    return out


def form_factor_matrix(points, normals, phis, skip_polys, verts, polys, poly_normal, side_patch, dF, near, out):
    """Rows of form factors for the full-matrix solvers: out[i, j] = the hemicube form factor from point i to
    patch j (row i from point/patch i to every patch). Runs of _CHUNK points go to threads
    (`threads.parallel_for`), each run with its own scratch.

    points, normals float64 (n_points, 3): the points (offset off their surfaces) and their unit normals
    phis       float64 (n_points,): each hemicube's rotation about its normal (radians)
    skip_polys int32 (n_points,): the polygon each point lies on, or -1
    verts, polys, poly_normal, side_patch, dF, near: as in `hemicube_form_factors`
    out        float32 (n_points, n_patches): overwritten
    """
    parallel_for(lambda c0, c1: _ff_chunks(points, normals, phis, skip_polys, verts, polys, poly_normal, side_patch,
                                           dF, near, out, c0, c1), 0, -(-points.shape[0] // _CHUNK))


@njit_serial
def _ff_chunks(points, normals, phis, skip_polys, verts, polys, poly_normal, side_patch, dF, near, out, c0, c1):
    n_points = points.shape[0]
    n_patches = out.shape[1]
    scratch = hemicube_scratch(dF.shape[1])
    row = np.empty(n_patches)
    for chunk in range(c0, c1):
        for i in range(chunk * _CHUNK, min(n_points, (chunk + 1) * _CHUNK)):
            row[:] = 0.0
            hemicube_form_factors((points[i, 0], points[i, 1], points[i, 2]),
                                  (normals[i, 0], normals[i, 1], normals[i, 2]), phis[i], skip_polys[i], verts,
                                  polys, poly_normal, side_patch, dF, near, scratch, row)
            for j in range(n_patches):
                out[i, j] = row[j]
