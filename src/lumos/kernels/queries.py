"""Kernels of the ray-query API (`lumos.RayCaster`): closest hits with their surface, every crossing of a ray,
and camera rays for picked pixels. Each runs over runs of rays on threads (`threads.parallel_for`), each run with
its own fixed traversal stack and scratch buffers; each ray's answer depends on that ray alone (deterministic, any thread
count), and the GIL is released.

Every crossing (`crossings`): the ray's line is clipped to the scene's (padded) bounds [t0, t1], outside which
it is outside every closed solid; the origin is moved to o + t0·d (so every crossing has t' >= 0 and one
forward triangle test serves) and the wide BVH is walked in any order, collecting:

    triangles                       each hit (t, object, face); the same crossing reported by two triangles
                                    sharing an edge or vertex (same object, same side, |Δt| <= 1e-9·|t|) counts once
    sphere, box, capped cyl/cone    both ends of the line's span through the solid (`csg.solid_span`), exact
    open cylinder / cone            each root of the side quadric with 0 <= z <= 1
    disk, rect, plane               the one crossing of its plane inside it
    csg                             the boundary crossings of the combined solid, walked one after another with
                                    `csg.intersect_csg` from t = −∞ (each gives its own in/out flag)

sorted by t. "Entering" is exact for analytic solids and csg; on a closed mesh it is the Jordan parity swept
from t0 (where the line is outside), so it does not depend on the winding of the faces; on open surfaces it is
dot(d, n) < 0 for the surface's normal (a triangle's (v1 − v0) × (v2 − v0)).
"""

import numpy as np

from .. import config
from .camera import camera_ray_at
from .csg import csg_leaf, intersect_csg, solid_span
from .intersect import (
    NO_HIT,
    quadratic_roots,
    axial_quadratic,
    box_setup,
    intersect_triangle,
    triangle_setup,
)
from .jit import njit, njit_inline, njit_serial
from .layout import (
    FLAG_CAPPED,
    FLAG_UVS,
    INFO_FLAGS,
    INFO_KIND,
    INFO_OBJECT,
    INFO_REF,
    LEAF_FACE,
    LEAF_OBJECT,
    LEAF_PACKED,
    LEAF_UVS,
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CSG,
    SHAPE_CYLINDER,
    SHAPE_DISK,
    SHAPE_PLANE,
    SHAPE_RECT,
    SHAPE_SPHERE,
)
from .simd import wide_box_mask, wide_setup
from .surface import surface_at
from .traverse import closest_hit, leaf_of, packed_leaf, push_children
from .vec import cross, madd, normalize, xform_point, xform_vector
from .threads import parallel_for
from .views import geometry_of, surfaces_of

_CHUNK = 256
#: two triangle hits of one mesh on the same side closer than this (relative to |t|) are one crossing
_SAME_T = 1e-9
_FAR = 1e300
#: crossing codes
_ENTER = 1  # the crossing enters a solid (or, on an open surface, meets its front)
_MESH = 2  # a triangle hit: its "entering" is decided by parity (closed meshes) after the sweep
_DROP = 4  # a repeat of the crossing before it


# ------------------------------------------------------------------------------------------- input checks


@njit
def bad_rays(origins, directions):
    """(first ray with a non-finite origin, first with a non-finite direction, first with a zero direction), each
    -1 if there is none: one pass over float64 (n, 3) + (n, 3), instead of NumPy's temporary arrays."""
    bad_o, bad_d, zero = -1, -1, -1
    for i in range(origins.shape[0]):
        ox, oy, oz = origins[i, 0], origins[i, 1], origins[i, 2]
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        if bad_o < 0 and not (np.isfinite(ox) and np.isfinite(oy) and np.isfinite(oz)):
            bad_o = i
        if bad_d < 0 and not (np.isfinite(dx) and np.isfinite(dy) and np.isfinite(dz)):
            bad_d = i
        if zero < 0 and dx == 0.0 and dy == 0.0 and dz == 0.0:
            zero = i
    return bad_o, bad_d, zero


# ------------------------------------------------------------------------------------------- closest hits


def closest_kernel(sa, tri_prim, origins, directions, t_max, t_out, object_out, prim_out, point_out, normal_out,
                   uv_out):
    """Nearest hit of each ray (float64 (n, 3) origins and directions, t_max (n,)) with its surface: t_out (n,)
    (inf on a miss), object_out / prim_out int64 (n,) (-1 on a miss), point_out / normal_out (n, 3) and uv_out
    (n, 2) (NaN on a miss). The normal is the unit geometric normal, outward (not turned towards the ray).
    Runs of rays go to threads (`threads.parallel_for`)."""
    parallel_for(lambda i0, i1: _closest_rays(sa, tri_prim, origins, directions, t_max, t_out, object_out, prim_out,
                                              point_out, normal_out, uv_out, i0, i1),
                 0, origins.shape[0], grain=_CHUNK)


@njit_serial
def _closest_rays(sa, tri_prim, origins, directions, t_max, t_out, object_out, prim_out, point_out, normal_out,
                  uv_out, i0, i1):
    _closest_band(sa, tri_prim, origins, directions, t_max, t_out, object_out, prim_out, point_out, normal_out,
                  uv_out, i0, i1, np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK))


@njit
def _closest_band(sa, tri_prim, origins, directions, t_max, t_out, object_out, prim_out, point_out, normal_out,
                  uv_out, i0, i1, stack, stack_t):
    geo, surf = geometry_of(sa), surfaces_of(sa)
    for i in range(i0, i1):
        o = (origins[i, 0], origins[i, 1], origins[i, 2])
        d = (directions[i, 0], directions[i, 1], directions[i, 2])
        t, ref, b1, b2, part = closest_hit(geo, o, d, 0.0, t_max[i], stack, stack_t, 0.0)
        if t == NO_HIT:
            t_out[i] = np.inf
            object_out[i] = -1
            prim_out[i] = -1
            for k in range(3):
                point_out[i, k] = np.nan
                normal_out[i, k] = np.nan
            uv_out[i, 0] = np.nan
            uv_out[i, 1] = np.nan
            continue
        if ref >= 0 and part >= 0:  # a triangle of a packed leaf: its record is in the row just tested
            p, n_geo, u, v, obj, prim = _packed_record(geo, surf, o, d, t, ref, b1, b2, part)
        elif ref >= 0:  # another triangle: only what the hit record holds (no shading normal)
            p, n_geo, u, v, obj = _triangle_record(surf, o, d, t, ref, b1, b2)
            prim = np.int64(tri_prim[ref])
        else:
            p, n_geo, n_sh, u, v, mat, obj, light = surface_at(surf, o, d, t, ref, b1, b2, part, 0.0)
            prim = _prim_of(sa, tri_prim, ref, part)
        t_out[i] = t
        object_out[i] = obj
        prim_out[i] = prim
        for k in range(3):
            point_out[i, k] = p[k]
            normal_out[i, k] = n_geo[k]
        uv_out[i, 0] = u
        uv_out[i, 1] = v


@njit_inline
def _triangle_record(surf, o, d, t, ref, b1, b2):
    """(point, unit geometric normal, u, v, object id) of a hit on triangle ref: `surface_at`'s answer without
    the shading normal, which a ray query does not report (one cache line fewer per incoherent hit)."""
    vt = surf.tri_verts
    v0 = (np.float64(vt[ref, 0]), np.float64(vt[ref, 1]), np.float64(vt[ref, 2]))
    e1 = (vt[ref, 3] - v0[0], vt[ref, 4] - v0[1], vt[ref, 5] - v0[2])
    e2 = (vt[ref, 6] - v0[0], vt[ref, 7] - v0[1], vt[ref, 8] - v0[2])
    info = surf.tri_info[ref]
    u, v = b1, b2
    if info[INFO_FLAGS] & FLAG_UVS:
        uv = surf.tri_uvs
        b0 = 1.0 - b1 - b2
        u = b0 * uv[ref, 0] + b1 * uv[ref, 2] + b2 * uv[ref, 4]
        v = b0 * uv[ref, 1] + b1 * uv[ref, 3] + b2 * uv[ref, 5]
    return madd(o, d, t), normalize(cross(e1, e2)), u, v, info[INFO_OBJECT]


@njit_inline
def _packed_record(geo, surf, o, d, t, ref, b1, b2, part):
    """`_triangle_record` plus the face id, of a hit on lane part & 3 of packed leaf row part >> 2, read from that
    row (`layout.LEAF_*`): the hit test has just loaded it, so an incoherent hit costs no further cache misses
    (the triangle's rows in tri_verts, tri_info and the face table would be three). Bit for bit the same answer:
    the row holds the same float32 corners."""
    row, lane = part >> 2, part & 3
    lt, ll = geo.leaf_tris, geo.leaf_link
    v0 = (np.float64(lt[row, lane]), np.float64(lt[row, 4 + lane]), np.float64(lt[row, 8 + lane]))
    e1 = (lt[row, 12 + lane] - v0[0], lt[row, 16 + lane] - v0[1], lt[row, 20 + lane] - v0[2])
    e2 = (lt[row, 24 + lane] - v0[0], lt[row, 28 + lane] - v0[1], lt[row, 32 + lane] - v0[2])
    u, v = b1, b2
    if ll[row, LEAF_UVS] & (1 << lane):
        uv = surf.tri_uvs
        b0 = 1.0 - b1 - b2
        u = b0 * uv[ref, 0] + b1 * uv[ref, 2] + b2 * uv[ref, 4]
        v = b0 * uv[ref, 1] + b1 * uv[ref, 3] + b2 * uv[ref, 5]
    return (madd(o, d, t), normalize(cross(e1, e2)), u, v, ll[row, LEAF_OBJECT + lane],
            np.int64(ll[row, LEAF_FACE + lane]))


@njit_inline
def _prim_of(sa, tri_prim, ref, part):
    """The primitive id of a hit: a triangle's face in its own mesh, a csg solid's number in its object, or an
    analytic shape's part (box face 2·axis + max side; cylinder/cone 0 side, 1 base cap, 2 top cap; else 0)."""
    if ref >= 0:
        return np.int64(tri_prim[ref])
    s = ~ref
    if sa.shape_info[s, INFO_KIND] == SHAPE_CSG:
        leaf, _ = csg_leaf(part)
        root = np.int64(sa.shape_info[s, INFO_REF])
        return np.int64(leaf - ~sa.csg_nodes[root + 1, 1])
    return np.int64(part)


# ------------------------------------------------------------------------------------------- every crossing


@njit
def _insert(ts, objs, prims, codes, n, t, obj, prim, code):
    """Insert a crossing into the buffers (sorted by t, n held); returns the new n, or -1 when they are full."""
    if n == ts.shape[0]:
        return -1
    k = n
    while k > 0 and ts[k - 1] > t:
        ts[k] = ts[k - 1]
        objs[k] = objs[k - 1]
        prims[k] = prims[k - 1]
        codes[k] = codes[k - 1]
        k -= 1
    ts[k] = t
    objs[k] = obj
    prims[k] = prim
    codes[k] = code
    return n + 1


@njit
def _scene_span(bounds, o, d):
    """(t0, t1) of the line o + t·d inside the box bounds (float64 (2, 3)); t0 > t1 when it misses."""
    t0, t1 = -_FAR, _FAR
    for a in range(3):
        if d[a] == 0.0:
            if o[a] < bounds[0, a] or o[a] > bounds[1, a]:
                return 1.0, -1.0
            continue
        ta = (bounds[0, a] - o[a]) / d[a]
        tb = (bounds[1, a] - o[a]) / d[a]
        if ta > tb:
            ta, tb = tb, ta
        t0 = max(t0, ta)
        t1 = min(t1, tb)
    return t0, t1


@njit
def _shape_crossings(sa, geo, s, o, d, t0, ts, objs, prims, codes, n):
    """Add every crossing of the line o + t·d (t relative to the moved origin; stored as t0 + t) with shape s;
    returns n, or -1 when the buffers overflow."""
    info = sa.shape_info[s]
    kind = info[INFO_KIND]
    obj = info[INFO_OBJECT]
    m = sa.shape_xform[s]
    if kind == SHAPE_CSG:
        root = np.int64(info[INFO_REF])
        first_leaf = ~np.int64(sa.csg_nodes[root + 1, 1])
        t_prev = -_FAR
        while n >= 0:
            t, part, b1, b2 = intersect_csg(geo, s, o, d, t_prev, _FAR)
            if t == NO_HIT:
                break
            leaf, _ = csg_leaf(part)
            n = _insert(ts, objs, prims, codes, n, t0 + t, obj, leaf - first_leaf, _ENTER if b1 > 0.0 else 0)
            t_prev = t
        return n
    oc = xform_point(m, o)
    dc = xform_vector(m, d)
    capped = (info[INFO_FLAGS] & FLAG_CAPPED) != 0
    if kind == SHAPE_SPHERE or kind == SHAPE_BOX or ((kind == SHAPE_CYLINDER or kind == SHAPE_CONE) and capped):
        t_in, p_in, t_out, p_out = solid_span(kind, oc, dc)
        if t_in < t_out:
            n = _insert(ts, objs, prims, codes, n, t0 + t_in, obj, p_in, _ENTER)
            if n >= 0:
                n = _insert(ts, objs, prims, codes, n, t0 + t_out, obj, p_out, 0)
        return n
    if kind == SHAPE_CYLINDER or kind == SHAPE_CONE:  # open: the side surface between z = 0 and z = 1
        cone = kind == SHAPE_CONE
        a, half_b, c = axial_quadratic(oc, dc, cone)
        r0, r1 = quadratic_roots(a, half_b, c)
        for j in range(2):
            t = r0 if j == 0 else r1
            if not (t == t) or (j == 1 and r1 == r0):  # no root (nan), or the single root of a linear case
                continue
            p = (oc[0] + t * dc[0], oc[1] + t * dc[1], oc[2] + t * dc[2])
            if 0.0 <= p[2] <= 1.0:
                nz = 1.0 - p[2] if cone else 0.0
                front = p[0] * dc[0] + p[1] * dc[1] + nz * dc[2] < 0.0
                n = _insert(ts, objs, prims, codes, n, t0 + t, obj, 0, _ENTER if front else 0)
                if n < 0:
                    return n
        return n
    if kind == SHAPE_DISK or kind == SHAPE_RECT or kind == SHAPE_PLANE:
        if dc[2] == 0.0:
            return n
        t = -oc[2] / dc[2]
        x = oc[0] + t * dc[0]
        y = oc[1] + t * dc[1]
        if kind == SHAPE_DISK and x * x + y * y > 1.0:
            return n
        if kind == SHAPE_RECT and not (0.0 <= x <= 1.0 and 0.0 <= y <= 1.0):
            return n
        return _insert(ts, objs, prims, codes, n, t0 + t, obj, 0, _ENTER if dc[2] < 0.0 else 0)
    return n


@njit
def _triangle_crossing(sa, tri_prim, o, setup, d, r, t0, t_far, ts, objs, prims, codes, n):
    t, b1, b2 = intersect_triangle(o, setup, sa.tri_verts, r, t_far)
    if t == NO_HIT:
        return n
    v = sa.tri_verts
    v0 = (np.float64(v[r, 0]), np.float64(v[r, 1]), np.float64(v[r, 2]))
    e1 = (v[r, 3] - v0[0], v[r, 4] - v0[1], v[r, 5] - v0[2])
    e2 = (v[r, 6] - v0[0], v[r, 7] - v0[1], v[r, 8] - v0[2])
    dn = ((e1[1] * e2[2] - e1[2] * e2[1]) * d[0] + (e1[2] * e2[0] - e1[0] * e2[2]) * d[1]
          + (e1[0] * e2[1] - e1[1] * e2[0]) * d[2])
    code = _MESH | (_ENTER if dn < 0.0 else 0)
    return _insert(ts, objs, prims, codes, n, t0 + t, sa.tri_info[r, INFO_OBJECT], tri_prim[r], code)


@njit
def _gather(sa, geo, tri_prim, bounds, o, d, ts, objs, prims, codes, stack):
    """Every crossing of the line through o along d (module doc), sorted by t: returns n, or -1 on overflow. The
    walk is `traverse`'s wide one, in any order (every crossing is wanted): all of a node's child boxes per test
    (`simd.wide_box_mask`), four triangles per packed leaf row (`simd.tri4_test`, whose hits are those of the scalar
    test bit for bit), each crossing's facing, object and face read from that row."""
    n = 0
    t0, t1 = _scene_span(bounds, o, d)
    if not (t0 <= t1):
        t0, t1 = 0.0, -1.0  # the line misses every bounded primitive: only planes remain
    om = (o[0] + t0 * d[0], o[1] + t0 * d[1], o[2] + t0 * d[2])  # the moved origin
    for k in range(sa.unbounded.shape[0]):
        n = _shape_crossings(sa, geo, np.int64(sa.unbounded[k]), om, d, t0, ts, objs, prims, codes, n)
        if n < 0:
            return n
    nodes = geo.wide_nodes
    if nodes.shape[0] == 0 or t1 < t0:
        return n
    link = geo.wide_link
    t_far = (t1 - t0) * (1.0 + 1e-9) + 1e-300
    rb = box_setup(om, d)
    ix, iy, iz, ox, oy, oz = rb[0], rb[1], rb[2], rb[3], rb[4], rb[5]
    nx, ny, nz = wide_setup(rb)
    setup = triangle_setup(d)
    kx, ky, kz, sx, sy, sz = setup
    okx, oky, okz = om[kx], om[ky], om[kz]
    node = np.int64(0)  # a wide node, or ~(WIDE·node + slot) for a leaf child (`traverse.closest_hit`)
    sp = 0
    while True:
        if node >= 0:
            mask = wide_box_mask(nodes, node, nx, ny, nz, ox, oy, oz, ix, iy, iz, t_far)
            sp = push_children(stack, sp, link, node, mask)
        else:
            first, count = leaf_of(link, node)
            if count == LEAF_PACKED:
                mask, t_0, t_1, t_2, t_3, u0, u1, u2, u3, w0, w1, w2, w3 = packed_leaf(
                    geo, first, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_far)
                for lane in range(4):
                    if mask & (1 << lane):
                        t = t_0 if lane == 0 else (t_1 if lane == 1 else (t_2 if lane == 2 else t_3))
                        n = _packed_crossing(geo, first, lane, d, t0 + t, ts, objs, prims, codes, n)
                        if n < 0:
                            return n
                count = 0
            for k in range(first, first + count):
                r = sa.prim_ref[k]
                if r >= 0:
                    n = _triangle_crossing(sa, tri_prim, om, setup, d, r, t0, t_far, ts, objs, prims, codes, n)
                else:
                    n = _shape_crossings(sa, geo, np.int64(~r), om, d, t0, ts, objs, prims, codes, n)
                if n < 0:
                    return n
        if sp == 0:
            return n
        sp -= 1
        node = stack[sp]


@njit_inline
def _packed_crossing(geo, row, lane, d, t, ts, objs, prims, codes, n):
    """`_triangle_crossing`'s record of a hit at t on lane `lane` of packed leaf row `row`, from that row."""
    lt = geo.leaf_tris
    v0 = (np.float64(lt[row, lane]), np.float64(lt[row, 4 + lane]), np.float64(lt[row, 8 + lane]))
    e1 = (lt[row, 12 + lane] - v0[0], lt[row, 16 + lane] - v0[1], lt[row, 20 + lane] - v0[2])
    e2 = (lt[row, 24 + lane] - v0[0], lt[row, 28 + lane] - v0[1], lt[row, 32 + lane] - v0[2])
    dn = ((e1[1] * e2[2] - e1[2] * e2[1]) * d[0] + (e1[2] * e2[0] - e1[0] * e2[2]) * d[1]
          + (e1[0] * e2[1] - e1[1] * e2[0]) * d[2])
    code = _MESH | (_ENTER if dn < 0.0 else 0)
    ll = geo.leaf_link
    return _insert(ts, objs, prims, codes, n, t, ll[row, LEAF_OBJECT + lane], ll[row, LEAF_FACE + lane], code)


@njit
def _settle_meshes(ts, objs, codes, n, closed, state):
    """Drop repeated triangle hits and decide "entering" on closed meshes by parity (state: int8 per object,
    all 0 on entry and on return)."""
    for k in range(n):
        if (codes[k] & _MESH) == 0:
            continue
        tol = _SAME_T * max(abs(ts[k]), 1e-300)
        j = k - 1
        while j >= 0 and ts[k] - ts[j] <= tol:
            if (objs[j] == objs[k] and (codes[j] & _MESH) != 0 and (codes[j] & _DROP) == 0
                    and (codes[j] & _ENTER) == (codes[k] & _ENTER)):
                codes[k] |= _DROP
                break
            j -= 1
        if (codes[k] & _DROP) != 0 or closed[objs[k]] == 0:
            continue
        entering = state[objs[k]] == 0
        state[objs[k]] ^= 1
        codes[k] = (codes[k] & ~_ENTER) | (_ENTER if entering else 0)
    for k in range(n):
        state[objs[k]] = 0


def crossings(sa, tri_prim, closed, bounds, origins, directions, t_min, t_max, cap, max_hits, t_out, object_out,
              prim_out, enter_out, count_out, total_out):
    """Every crossing with t_min[i] < t < t_max[i] of each ray (module doc), sorted by t: the first max_hits of
    ray i in row i of t_out (n, max_hits) float64, object_out / prim_out int32, enter_out bool; count_out[i]
    (int64) of them are set, total_out[i] is how many there were in range, or -1 when the line crosses more
    than `cap` boundaries in the scene's box (call again with a larger cap). `closed` int8 (objects,): 1 for a
    closed mesh (parity decides entering). `bounds` float64 (2, 3): the padded scene bounds.
    Runs of rays go to threads (`threads.parallel_for`)."""
    parallel_for(lambda i0, i1: _crossing_rays(sa, tri_prim, closed, bounds, origins, directions, t_min, t_max, cap,
                                               max_hits, t_out, object_out, prim_out, enter_out, count_out,
                                               total_out, i0, i1),
                 0, origins.shape[0], grain=_CHUNK)


@njit_serial
def _crossing_rays(sa, tri_prim, closed, bounds, origins, directions, t_min, t_max, cap, max_hits, t_out, object_out,
                   prim_out, enter_out, count_out, total_out, i0, i1):
    _crossing_band(sa, tri_prim, closed, bounds, origins, directions, t_min, t_max, max_hits, t_out, object_out,
                   prim_out, enter_out, count_out, total_out, i0, i1, np.empty(config.BVH_STACK, np.int64),
                   np.empty(cap), np.empty(cap, np.int32), np.empty(cap, np.int32), np.empty(cap, np.int8),
                   np.zeros(closed.shape[0], np.int8))


@njit
def _crossing_band(sa, tri_prim, closed, bounds, origins, directions, t_min, t_max, max_hits, t_out, object_out,
                   prim_out, enter_out, count_out, total_out, i0, i1, stack, ts, objs, prims, codes, state):
    geo = geometry_of(sa)
    for i in range(i0, i1):
        o = (origins[i, 0], origins[i, 1], origins[i, 2])
        d = (directions[i, 0], directions[i, 1], directions[i, 2])
        m = _gather(sa, geo, tri_prim, bounds, o, d, ts, objs, prims, codes, stack)
        count_out[i] = 0
        if m < 0:
            total_out[i] = -1
            continue
        _settle_meshes(ts, objs, codes, m, closed, state)
        got = 0
        total = 0
        for k in range(m):
            if (codes[k] & _DROP) != 0 or not (t_min[i] < ts[k] < t_max[i]):
                continue
            if got < max_hits:
                t_out[i, got] = ts[k]
                object_out[i, got] = objs[k]
                prim_out[i, got] = prims[k]
                enter_out[i, got] = (codes[k] & _ENTER) != 0
                got += 1
            total += 1
        count_out[i] = got
        total_out[i] = total


def containing_kernel(sa, tri_prim, closed, bounds, points, probes, selected, column, cap, votes, overflow):
    """Point-in-solid votes: for each point and each probe direction (probes float64 (k, 3)), the line through
    the point along it is gathered and settled as `crossings` does, and every selected solid (selected bool
    (objects,)) that holds the point on that line gets a vote in votes[i, column[solid]] (int8 (n, columns)).
    A solid holds the point when its last crossing before it (t < 0) enters and the next one (t > 0) leaves:
    the piece `RayCaster._segments` would report around t = 0. overflow[i] is set where a line crosses more
    than `cap` boundaries (votes of that point are then incomplete: the caller redoes it). With three probes,
    the third line is walked only where the first two disagree on some solid (a majority vote is then settled:
    votes of 0 or 2 out of two stand for 0-1 or 2-3 out of three).
    Runs of points go to threads (`threads.parallel_for`)."""
    parallel_for(lambda i0, i1: _containing_points(sa, tri_prim, closed, bounds, points, probes, selected, column,
                                                   cap, votes, overflow, i0, i1),
                 0, points.shape[0], grain=_CHUNK)


@njit_serial
def _containing_points(sa, tri_prim, closed, bounds, points, probes, selected, column, cap, votes, overflow, i0, i1):
    n_obj = closed.shape[0]
    _containing_band(sa, tri_prim, closed, bounds, points, probes, selected, column, votes, overflow, i0, i1,
                     np.empty(config.BVH_STACK, np.int64), np.empty(cap), np.empty(cap, np.int32),
                     np.empty(cap, np.int32), np.empty(cap, np.int8), np.zeros(n_obj, np.int8),
                     np.full(n_obj, -1, np.int8), np.zeros(n_obj, np.bool_))


@njit
def _containing_band(sa, tri_prim, closed, bounds, points, probes, selected, column, votes, overflow, i0, i1, stack,
                     ts, objs, prims, codes, state, before, done):
    """(`containing_kernel`; before: per solid, -1 for no crossing before the point, else whether it entered)"""
    geo = geometry_of(sa)
    for i in range(i0, i1):
        o = (points[i, 0], points[i, 1], points[i, 2])
        for j in range(probes.shape[0]):
            d = (probes[j, 0], probes[j, 1], probes[j, 2])
            m = _gather(sa, geo, tri_prim, bounds, o, d, ts, objs, prims, codes, stack)
            if m < 0:
                overflow[i] = True
                break
            _settle_meshes(ts, objs, codes, m, closed, state)
            for k in range(m):
                obj = objs[k]
                if (codes[k] & _DROP) != 0 or not selected[obj] or done[obj]:
                    continue
                entering = (codes[k] & _ENTER) != 0
                if ts[k] < 0.0:
                    before[obj] = 1 if entering else 0
                else:
                    done[obj] = True
                    if before[obj] == 1 and not entering and ts[k] > 0.0:
                        votes[i, column[obj]] += 1
            for k in range(m):  # reset what this line touched
                before[objs[k]] = -1
                done[objs[k]] = False
            if j == 1 and probes.shape[0] == 3:  # two lines that agree on every solid decide the majority
                split = False
                for col in range(votes.shape[1]):
                    split = split or votes[i, col] == 1
                if not split:
                    break


# ------------------------------------------------------------------------------------------- camera rays


@njit_serial
def camera_rays_kernel(cam_vecs, cam_params, width, height, fx, fy, origins_out, directions_out):
    """The rays through image points (fx[i], fy[i]) in pixel units (pixel (x, y)'s centre is (x + 0.5, y + 0.5)),
    through the centre of the lens: origins_out, directions_out float64 (n, 3), unit directions."""
    for i in range(fx.shape[0]):
        o, d = camera_ray_at(cam_vecs, cam_params, width, height, fx[i], fy[i], 0.5, 0.5)
        for k in range(3):
            origins_out[i, k] = o[k]
            directions_out[i, k] = d[k]
