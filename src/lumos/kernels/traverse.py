"""BVH traversal: closest hit, any hit and shadow-ray transmittance, with a fixed stack supplied by the caller (one
per thread/row).

The walk is over the wide tree (`layout.WIDE_*`: WIDE children per node, collapsed from the binary SAH tree at
compile time): at an interior node all the child boxes are tested at once with explicit SIMD
(`simd.wide_box_test`), the children hit are pushed with their entry distances sorted so that the nearest is
visited next, and a popped entry is skipped once a closer hit is known. A stack entry is a wide node index, or
~(WIDE·node + slot) for a leaf child, whose primitives are tested in place; the any-order walk of shadow rays
(`_pass_through`) tests a leaf child where it finds it and stacks interior nodes only. Unbounded shapes (planes)
are tested before the tree. A csg object is one shape whose test (`kernels.csg`) also fills b1 and b2 of the hit record.
"""

import numpy as np

from .csg import intersect_csg, solid_span
from .intersect import NO_HIT, box_setup, intersect_shape, intersect_triangle, triangle_setup
from .jit import njit_inline
from .layout import (
    FLAG_CAPPED,
    INFO_FLAGS,
    INFO_KIND,
    INFO_LIGHT,
    INFO_MATERIAL,
    LEAF_BASE,
    LEAF_MASK,
    LEAF_PACKED,
    MAT_CUTOUT,
    MAT_KT,
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CSG,
    SHAPE_CYLINDER,
    SHAPE_SPHERE,
    WIDE,
    WIDE_CHILD,
    WIDE_COUNT,
    WIDE_SHIFT,
)
from .simd import lowest_bit, tri4_test, wide_box_mask, wide_box_test, wide_setup
from .vec import xform_point, xform_vector

#: Transmittance below which a shadow ray counts as blocked.
SHADOW_CUTOFF = 1e-4


@njit_inline
def _shape_hit(geo, s, o, d, t_min, t_max, time):
    """(t, part, b1, b2) of shape s; b1 and b2 are 0 except for csg objects (see `kernels.csg`)."""
    info = geo.shape_info[s]
    m = geo.shape_xform[s]
    if m[3, 3] != 0.0:  # a moving shape: at `time` it is displaced by time·motion, so the ray moves back
        o = (o[0] - time * m[3, 0], o[1] - time * m[3, 1], o[2] - time * m[3, 2])
    if info[INFO_KIND] == SHAPE_CSG:  # its solids share its motion: they see the same moved origin
        return _csg_hit(geo.csg_nodes, geo, s, o, d, t_min, t_max)
    t, part = intersect_shape(info[INFO_KIND], info[INFO_FLAGS] & FLAG_CAPPED, m, o, d, t_min, t_max)
    return t, part, 0.0, 0.0


@njit_inline
def _csg_hit(nodes, geo, s, o, d, t_min, t_max):
    """`csg.intersect_csg`, compiled only where the scene has csg objects: `nodes` (geo's csg_nodes) is None in
    the arrays of a scene without any (`compile.features.lean_arrays`), and Numba then prunes the call."""
    if nodes is None:
        return NO_HIT, 0, 0.0, 0.0
    return intersect_csg(geo, s, o, d, t_min, t_max)


@njit_inline
def _triangle_setup_if(geo, d):
    """The watertight test's per-ray constants, or a stand-in when the scene has no triangles (a division and
    the axis choice saved per ray)."""
    if geo.tri_verts.shape[0] == 0:
        return 0, 1, 2, 0.0, 0.0, 1.0
    return triangle_setup(d)


@njit_inline
def leaf_of(link, node):
    """(first, count) of the leaf child that stack entry node = ~(WIDE·wide node + slot) names: a prim_ref range,
    or (its packed row, LEAF_PACKED)."""
    q = ~node
    w, k = q >> WIDE_SHIFT, q & (WIDE - 1)
    return np.int64(link[w, WIDE_CHILD + k]), link[w, WIDE_COUNT + k]


@njit_inline
def packed_leaf(geo, row, kx, ky, kz, sx, sy, sz, okx, oky, okz, t_max):
    """`simd.tri4_test` of packed leaf `row`, its mask limited to the lanes that hold triangles."""
    mask, t0, t1, t2, t3, u0, u1, u2, u3, w0, w1, w2, w3 = tri4_test(geo.leaf_tris, row, kx, ky, kz, sx, sy, sz,
                                                                       okx, oky, okz, t_max)
    return mask & geo.leaf_link[row, LEAF_MASK], t0, t1, t2, t3, u0, u1, u2, u3, w0, w1, w2, w3


@njit_inline
def push_children(stack, sp, link, node, mask):
    """Push the children of wide node `node` whose bits are set in mask, in slot order (an any-order walk);
    returns the new stack size."""
    while mask != 0:
        k = lowest_bit(mask)
        mask &= mask - 1
        stack[sp] = _child(link, node, k)
        sp += 1
    return sp


@njit_inline
def _child(link, node, k):
    """The stack entry of child slot k of wide node `node`: its wide node index, or ~(WIDE·node + k) for a leaf."""
    return np.int64(link[node, WIDE_CHILD + k]) if link[node, WIDE_COUNT + k] == 0 else ~(WIDE * node + k)


@njit_inline
def _lane(x0, x1, x2, x3, k):
    """x_k for a runtime lane number k (0-3)."""
    return x0 if k == 0 else (x1 if k == 1 else (x2 if k == 2 else x3))


@njit_inline
def closest_hit(geo, o, d, t_min, t_max, stack, stack_t, time):
    """Nearest intersection with t_min < t < t_max at shutter time `time`; `geo` is a `layout.Geometry`.
    `closest_hit_of` with the shapes' tests compiled in.

    Returns (t, ref, b1, b2, part): ref is a triangle index (>= 0) or ~shape index (< 0); b1, b2 are the
    barycentrics of a triangle hit, part the face of a shape hit (csg hits: see `kernels.csg`) and, for a
    triangle hit, 4·row + lane of the packed leaf row that holds it (-1 when it is not in one), so that the
    caller can read the hit's record from the row just loaded (`layout.LEAF_*`). t = -1 when nothing is hit.
    stack (int64) and stack_t (float64) are the caller's, of equal length (`config.BVH_STACK`); the top WIDE
    entries of stack_t hold the entry distances of the node just tested, so the walk itself stays below them.
    """
    return closest_hit_of(geo, geo, o, d, t_min, t_max, stack, stack_t, time)


@njit_inline
def closest_hit_of(geo, shaped, o, d, t_min, t_max, stack, stack_t, time):
    """`closest_hit`, with `shaped` `geo` where the tree may hold analytic shapes and None where it holds
    triangles only (raster's polygons): Numba then prunes the shapes' tests before typing them."""
    best_t = t_max
    best_ref = 0
    best_b1 = 0.0
    best_b2 = 0.0
    best_part = 0
    hit = False
    if shaped is not None:
        for k in range(shaped.unbounded.shape[0]):
            s = np.int64(shaped.unbounded[k])
            t, part, b1, b2 = _shape_hit(shaped, s, o, d, t_min, best_t, time)
            if t != NO_HIT:
                best_t, best_ref, best_b1, best_b2, best_part, hit = t, ~s, b1, b2, part, True
    nodes = geo.wide_nodes
    link = geo.wide_link
    if nodes.shape[0] > 0:
        rb = box_setup(o, d)
        ix, iy, iz, ox, oy, oz = rb[0], rb[1], rb[2], rb[3], rb[4], rb[5]
        nx, ny, nz = wide_setup(rb)  # box_setup's near column (0/3, 1/4, 2/5) -> the node's near row
        setup = _triangle_setup_if(geo, d)
        kx, ky, kz, sx, sy, sz = setup
        okx, oky, okz = o[kx], o[ky], o[kz]
        node = np.int64(0)  # a wide node index (>= 0) or ~(WIDE·node + slot) for a leaf child (int64 throughout)
        scratch = stack_t.shape[0] - WIDE  # the top WIDE entries of stack_t hold a node's child entry distances
        sp = 0
        while True:
            if node >= 0:
                # interior: test all the child boxes at once; push the hit ones, nearest on top
                mask = wide_box_test(nodes, node, nx, ny, nz, ox, oy, oz, ix, iy, iz, best_t, stack_t, scratch)
                base = sp
                while mask != 0:
                    k = lowest_bit(mask)
                    mask &= mask - 1
                    tk = stack_t[scratch + k]
                    ref = _child(link, node, k)
                    # insertion into stack[base:sp] kept sorted by decreasing distance
                    j = sp
                    while j > base and stack_t[j - 1] < tk:
                        stack[j], stack_t[j] = stack[j - 1], stack_t[j - 1]
                        j -= 1
                    stack[j], stack_t[j] = ref, tk
                    sp += 1
                if sp > base:
                    sp -= 1
                    node = stack[sp]
                    continue
            else:
                # leaf: test its primitives, four triangles at once where it has a packed row
                first, count = leaf_of(link, node)
                if count == LEAF_PACKED:
                    mask, t0, t1, t2, t3, u0, u1, u2, u3, w0, w1, w2, w3 = packed_leaf(
                        geo, first, kx, ky, kz, sx, sy, sz, okx, oky, okz, best_t)
                    lane, lane_t = -1, best_t
                    for k in range(4):
                        if mask & (1 << k):
                            tk = _lane(t0, t1, t2, t3, k)
                            if tk > t_min and tk <= lane_t:  # ties: the later triangle, as the scalar loop
                                lane, lane_t = k, tk
                    if lane >= 0:
                        best_t, best_ref, hit = lane_t, np.int64(geo.leaf_link[first, LEAF_BASE]) + lane, True
                        best_b1, best_b2 = _lane(u0, u1, u2, u3, lane), _lane(w0, w1, w2, w3, lane)
                        best_part = 4 * first + lane
                    count = 0
                for k in range(first, first + count):
                    r = geo.prim_ref[k]
                    if r >= 0:
                        t, b1, b2 = intersect_triangle(o, setup, geo.tri_verts, r, best_t)
                        if t > t_min:
                            best_t, best_ref, best_b1, best_b2, best_part, hit = t, r, b1, b2, -1, True
                    elif shaped is not None:
                        t, part, b1, b2 = _shape_hit(shaped, np.int64(~r), o, d, t_min, best_t, time)
                        if t != NO_HIT:
                            best_t, best_ref, best_b1, best_b2, best_part, hit = t, r, b1, b2, part, True
            # pop the next node that may still hold a closer hit
            found = False
            while sp > 0:
                sp -= 1
                if stack_t[sp] < best_t:
                    node = stack[sp]
                    found = True
                    break
            if not found:
                break
    if not hit:
        return NO_HIT, 0, 0.0, 0.0, 0
    return best_t, best_ref, best_b1, best_b2, best_part


@njit_inline
def any_hit(geo, o, d, t_min, t_max, stack, time):
    """True if anything lies on the ray with t_min < t < t_max (hit testing; shadow rays use `transmittance`,
    which lets light through transparent objects)."""
    rgb, settled = _pass_through(geo, None, None, o, d, t_min, t_max, stack, time, geo)
    return rgb[0] == 0.0


@njit_inline
def any_triangle_hit(geo, o, d, t_min, t_max, stack):
    """`any_hit` for a tree of triangles only (`compile.triangle_arrays`: radiosity's patches and occluders): the
    same traversal compiled without the analytic shapes' tests (spheres to csg objects), which such a tree never
    reaches."""
    rgb, settled = _pass_through(geo, None, None, o, d, t_min, t_max, stack, 0.0, None)
    return rgb[0] == 0.0


@njit_inline
def transmittance(geo, tri_info, materials, o, d, t_max, stack, time):
    """What reaches o from t_max along d, through everything on the ray with 0 < t < t_max: ((r, g, b), settled).

    The product of what each primitive lets through (`_shape_factor`; a triangle: its kt if it is crossed, 0 if
    it is opaque), in any order, so one any-order traversal settles it, and it stops at the first opaque
    primitive. settled is False when a primitive only the hit-by-hit walk can count is on the ray (see
    `illumination.shadow_transmittance`), among them an opacity cut-out (`kernels.cutout`: its triangles' factor
    is NaN, which no later factor undoes). `tri_info` and `materials` are the triangles' and materials' arrays."""
    return transmittance_of(geo, geo, tri_info, materials, o, d, t_max, stack, time)


@njit_inline
def transmittance_of(geo, shaped, tri_info, materials, o, d, t_max, stack, time):
    """`transmittance`, with `shaped` `geo`, or None for a tree of triangles only (`_pass_through`)."""
    rgb, settled = _pass_through(geo, tri_info, materials, o, d, 0.0, t_max, stack, time, shaped)
    return rgb, settled and rgb[0] == rgb[0]


@njit_inline
def _shape_factor(geo, materials, s, o, d, t_min, t_max, time):
    """What shape s lets through along o + t·d, t_min < t < t_max: (kt0, kt1, kt2, settled). An opaque shape
    that the ray meets gives 0; a transparent convex solid (sphere, box, capped cylinder or cone) gives its kt
    where the ray enters it (its span along the whole line starts inside the segment), a transparent planar one
    (plane, disk, rect) its kt where the ray crosses it; an emitter lets everything through. settled is False
    for a transparent shape of another kind on the ray (csg, open cylinder or cone): only the hit-by-hit walk
    knows how often the ray crosses it, or a shape with an opacity cut-out (MAT_CUTOUT) on the ray: only the
    walk looks its holes up. With `materials` None every shape is opaque (`any_hit`)."""
    if materials is None:
        t, part, b1, b2 = _shape_hit(geo, s, o, d, t_min, t_max, time)
        return (1.0, 1.0, 1.0, True) if t == NO_HIT else (0.0, 0.0, 0.0, True)
    info = geo.shape_info[s]
    if info[INFO_LIGHT] >= 0:
        return 1.0, 1.0, 1.0, True
    mat = np.int64(info[INFO_MATERIAL])
    if materials[mat, MAT_CUTOUT] != 0.0:  # an opacity cut-out on the ray: only the walk can look its holes up
        t, part, b1, b2 = _shape_hit(geo, s, o, d, t_min, t_max, time)
        return 1.0, 1.0, 1.0, t == NO_HIT
    kt0, kt1, kt2 = materials[mat, MAT_KT], materials[mat, MAT_KT + 1], materials[mat, MAT_KT + 2]
    kind = info[INFO_KIND]
    convex = kind == SHAPE_SPHERE or kind == SHAPE_BOX or (
        (kind == SHAPE_CYLINDER or kind == SHAPE_CONE) and (info[INFO_FLAGS] & FLAG_CAPPED) != 0)
    if (kt0 > 0.0 or kt1 > 0.0 or kt2 > 0.0) and convex:
        m = geo.shape_xform[s]
        if m[3, 3] != 0.0:  # moving: see _shape_hit
            o = (o[0] - time * m[3, 0], o[1] - time * m[3, 1], o[2] - time * m[3, 2])
        t_in, _, t_out, _ = solid_span(kind, xform_point(m, o), xform_vector(m, d))
        if t_in < t_out and t_min < t_in < t_max:
            return kt0, kt1, kt2, True
        return 1.0, 1.0, 1.0, True
    t, part, b1, b2 = _shape_hit(geo, s, o, d, t_min, t_max, time)
    if t == NO_HIT:
        return 1.0, 1.0, 1.0, True
    if kt0 <= 0.0 and kt1 <= 0.0 and kt2 <= 0.0:
        return 0.0, 0.0, 0.0, True
    return kt0, kt1, kt2, kind != SHAPE_CSG and kind != SHAPE_CYLINDER and kind != SHAPE_CONE


@njit_inline
def _triangle_factor(tri_info, materials, r):
    """What triangle r lets through where a ray crosses it (see `_shape_factor`); NaN for a triangle with an
    opacity cut-out (MAT_CUTOUT), whose holes only the hit-by-hit walk can look up: the product stays NaN
    whatever else the ray crosses, and `transmittance` reports the ray unsettled."""
    if materials is None:
        return 0.0, 0.0, 0.0
    if tri_info[r, INFO_LIGHT] >= 0:
        return 1.0, 1.0, 1.0
    mat = np.int64(tri_info[r, INFO_MATERIAL])
    if materials[mat, MAT_CUTOUT] != 0.0:
        return np.nan, np.nan, np.nan
    return materials[mat, MAT_KT], materials[mat, MAT_KT + 1], materials[mat, MAT_KT + 2]


#: What `_leaf_through` found: go on, the ray is blocked, or a primitive only the hit-by-hit walk can count is on it.
_ON, _BLOCKED, _UNSETTLED = 0, 1, 2


@njit_inline
def _leaf_through(geo, tri_info, materials, first, count, o, d, t_min, t_max, setup, okx, oky, okz, time, tr, tg, tb,
                  shaped):
    """`_pass_through`'s test of one leaf (first, count) (`leaf_of`): (tr, tg, tb) times what its primitives on
    the ray let through, and `_ON`, `_BLOCKED` (the product is as good as 0) or `_UNSETTLED`."""
    kx, ky, kz, sx, sy, sz = setup
    if count == LEAF_PACKED:
        mask, t0, t1, t2, t3, u0, u1, u2, u3, w0, w1, w2, w3 = packed_leaf(geo, first, kx, ky, kz, sx, sy, sz, okx,
                                                                           oky, okz, t_max)
        for k in range(4):
            if mask & (1 << k):
                if _lane(t0, t1, t2, t3, k) <= t_min:
                    continue
                f0, f1, f2 = _triangle_factor(tri_info, materials, np.int64(geo.leaf_link[first, LEAF_BASE]) + k)
                tr, tg, tb = tr * f0, tg * f1, tb * f2
                if max(tr, tg, tb) < SHADOW_CUTOFF:
                    return tr, tg, tb, _BLOCKED
        return tr, tg, tb, _ON
    for k in range(first, first + count):
        r = geo.prim_ref[k]
        if r >= 0:
            t, b1, b2 = intersect_triangle(o, setup, geo.tri_verts, r, t_max)
            if t <= t_min:
                continue
            f0, f1, f2 = _triangle_factor(tri_info, materials, r)
        elif shaped is not None:
            f0, f1, f2, settled = _shape_factor(shaped, materials, np.int64(~r), o, d, t_min, t_max, time)
            if not settled:
                return tr, tg, tb, _UNSETTLED
        else:
            continue
        tr, tg, tb = tr * f0, tg * f1, tb * f2
        if max(tr, tg, tb) < SHADOW_CUTOFF:
            return tr, tg, tb, _BLOCKED
    return tr, tg, tb, _ON


@njit_inline
def _pass_through(geo, tri_info, materials, o, d, t_min, t_max, stack, time, shaped):
    """The traversal behind `transmittance` and `any_hit`: every primitive on the ray with t_min < t < t_max, in
    traversal order, multiplied in; it stops as soon as the product is (as good as) 0. ((r, g, b), settled).
    The leaves among a node's children are tested where they are found, and only its interior children go on
    the stack (the order does not matter: the product is the same). `shaped` is `geo` where the tree may hold
    analytic shapes, and None where it holds triangles only (`any_triangle_hit`): Numba then prunes the shapes'
    branches before typing them, and compiles the triangles' tests alone."""
    tr, tg, tb = 1.0, 1.0, 1.0
    if shaped is not None:
        for k in range(shaped.unbounded.shape[0]):
            f0, f1, f2, settled = _shape_factor(shaped, materials, np.int64(shaped.unbounded[k]), o, d, t_min, t_max,
                                                time)
            if not settled:
                return (tr, tg, tb), False
            tr, tg, tb = tr * f0, tg * f1, tb * f2
            if max(tr, tg, tb) < SHADOW_CUTOFF:
                return (0.0, 0.0, 0.0), True
    nodes = geo.wide_nodes
    link = geo.wide_link
    if nodes.shape[0] == 0:
        return (tr, tg, tb), True
    rb = box_setup(o, d)
    ix, iy, iz, ox, oy, oz = rb[0], rb[1], rb[2], rb[3], rb[4], rb[5]
    nx, ny, nz = wide_setup(rb)
    setup = _triangle_setup_if(geo, d)
    kx, ky, kz = setup[0], setup[1], setup[2]
    okx, oky, okz = o[kx], o[ky], o[kz]
    node = np.int64(0)  # a wide node index: the stack holds interior nodes only
    sp = 0
    while True:
        mask = wide_box_mask(nodes, node, nx, ny, nz, ox, oy, oz, ix, iy, iz, t_max)
        while mask != 0:
            k = lowest_bit(mask)
            mask &= mask - 1
            count = link[node, WIDE_COUNT + k]
            if count == 0:
                stack[sp] = np.int64(link[node, WIDE_CHILD + k])
                sp += 1
                continue
            tr, tg, tb, status = _leaf_through(geo, tri_info, materials, np.int64(link[node, WIDE_CHILD + k]), count,
                                               o, d, t_min, t_max, setup, okx, oky, okz, time, tr, tg, tb, shaped)
            if status == _BLOCKED:
                return (0.0, 0.0, 0.0), True
            if status == _UNSETTLED:
                return (tr, tg, tb), False
        if sp == 0:
            return (tr, tg, tb), True
        sp -= 1
        node = stack[sp]
