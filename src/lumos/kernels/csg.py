"""Ray–csg intersection: the nearest point where a ray crosses the boundary of a combined solid.

A csg object is one shape of kind `SHAPE_CSG` in the BVH. Its solids (leaves) are ordinary shapes kept out of
the BVH: canonical spheres, boxes, capped cylinders and cones, or `SHAPE_MESH_SOLID` (closed meshes, whose
world-space triangles are `tri_verts[INFO_REF : INFO_REF + INFO_COUNT]`, tested by brute force).

Layout (`csg_nodes`, int32 (n, 4)); a csg object with L leaves owns 2L − 1 consecutive rows:

    root − (L − 2) .. root     the L − 1 operator nodes in post-order (children before parents, root last):
                               (op, left, right, parent); a child >= 0 is a node row, < 0 is ~shape of a
                               leaf; parent is -1 at the root
    root + 1 .. root + L       one row per leaf, in shape order: (CSG_LEAF, ~shape, parent, 0)

The csg shape has INFO_REF = root and INFO_COUNT = L; its leaves are L consecutive shapes. All of them share
the csg node's motion, so the origin that `traverse._shape_hit` moved back by time·motion serves every leaf.

Method (the ray-casting CSG of Roth 1982, "Ray casting for modeling solids", CGIP 18(2)): gather every
boundary crossing of every leaf along the WHOLE line, sort them, sweep from −∞ (where the line is outside
every leaf) toggling each leaf's inside state at its crossings, re-evaluate the boolean tree along the path
from that leaf to the root (stopping as soon as a node keeps its value), and report the first crossing in
(t_min, t_max) where the root changes. Crossings at the same t are one event, so coincident faces (a box
minus a box sharing a face) cancel instead of flickering. A hit found again from the same origin with t_min
set to the previous hit's t is the next crossing: no epsilon is needed to walk through a csg object.

Limits: the sweep holds CSG_CROSSINGS crossings at a time; a line that crosses more boundaries takes further
passes (each re-intersects every leaf), so there is no hard limit, only a slower path. Leaves: at most 2^24 per
csg object. Each test allocates three small scratch arrays (the crossings, and the inside states sized by the
leaf count); a ray that reaches a 23-solid die costs ~1 µs, the allocations a small part of it. Mesh solids cost
two triangle tests per triangle (both directions) for every ray that reaches the csg object's box; they must be
closed (parity decides inside), and a ray through a shared edge or vertex, reported by several triangles at the
same t and in the same direction, counts once (within one sweep pass).

Hit record (what `closest_hit` returns for a csg hit): ref = ~csg shape, part = leaf shape · CSG_PART_STRIDE
+ the leaf's part (box face, cylinder side/cap…; 0 for mesh solids), b1 = +1.0 where the ray enters the
combined solid and −1.0 where it leaves, b2 = the triangle index (as a float) on a mesh solid, else 0.
"""

import numpy as np

from .intersect import (
    NO_HIT,
    quadratic_roots,
    axial_quadratic,
    box_span,
    intersect_triangle,
    sphere_roots,
    triangle_setup,
)
from .jit import njit, njit_alloc, njit_inline
from .layout import (
    INFO_COUNT,
    INFO_KIND,
    INFO_REF,
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_MESH_SOLID,
    SHAPE_SPHERE,
)
from .vec import xform_point, xform_vector

# csg_nodes column 0
CSG_UNION = 0
CSG_INTERSECTION = 1
CSG_DIFFERENCE = 2
CSG_LEAF = 3

#: a csg hit's part = leaf shape · CSG_PART_STRIDE + the leaf's own part
CSG_PART_STRIDE = 16
#: crossings held per sweep pass
CSG_CROSSINGS = 64
#: crossing codes: (leaf part or triangle) << 25 | direction bit << 24 | leaf number
_LEAF_BITS = 24
_LEAF_MASK = (1 << _LEAF_BITS) - 1
#: two hits of one mesh solid in the same direction closer than this (relative to t) are one crossing
_SAME_T = 1e-9
_FAR = 1e300  # "no bound" on a leaf's span (finite: see DESIGN.md's Numba notes)


@njit
def csg_leaf(part):
    """(leaf shape index, the leaf's own part) of a csg hit's `part`."""
    return part // CSG_PART_STRIDE, part % CSG_PART_STRIDE


# --------------------------------------------------------------------------------- spans of convex solids


@njit
def _sphere_span(o, d):
    """(t_in, part_in, t_out, part_out) of the line through the unit sphere; t_in = t_out = 0 if it misses."""
    t0, t1 = sphere_roots(o, d)
    if not (t0 < t1):  # no roots (nan) or a tangent
        return 0.0, 0, 0.0, 0
    return t0, 0, t1, 0


@njit
def _box_span(o, d):
    """The slab test over the whole line through [0, 1]^3 (`intersect.box_span`); all 0 if it misses."""
    t_in, p_in, t_out, p_out = box_span(o, d)
    if not (t_in < t_out) or t_in == -_FAR or t_out == _FAR:
        return 0.0, 0, 0.0, 0
    return t_in, p_in, t_out, p_out


@njit
def _axial_span(o, d, cone):
    """The whole line through a capped canonical cylinder or cone: the span inside the side surface (an
    infinite cylinder, or the lower nappe of the double cone, both convex) clipped by the slab 0 <= z <= 1.
    Parts: 0 side, 1 cap z = 0, 2 cap z = 1."""
    a, half_b, c = axial_quadratic(o, d, cone)
    # inside the side surface: q(t) = a·t² + 2·half_b·t + c <= 0
    lo, hi = -_FAR, _FAR
    if a == 0.0:
        if half_b == 0.0:  # parallel to the cylinder's axis
            if c > 0.0:
                return 0.0, 0, 0.0, 0
        elif half_b > 0.0:  # along a cone's generator: q is linear, inside on one side of its root
            hi = -c / (2.0 * half_b)
        else:
            lo = -c / (2.0 * half_b)
    else:
        t0, t1 = quadratic_roots(a, half_b, c)
        if not (t0 <= t1):
            return 0.0, 0, 0.0, 0
        if a > 0.0:
            lo, hi = t0, t1
        elif d[2] > 0.0:  # (cone) q <= 0 outside the roots; the lower nappe is the part with z -> -inf
            hi = t0
        else:
            lo = t1
    p_lo, p_hi = 0, 0
    # clip by the slab
    if d[2] == 0.0:
        if o[2] < 0.0 or o[2] > 1.0:
            return 0.0, 0, 0.0, 0
    else:
        z0 = (0.0 - o[2]) / d[2]
        z1 = (1.0 - o[2]) / d[2]
        pz0, pz1 = 1, 2
        if z0 > z1:
            z0, z1 = z1, z0
            pz0, pz1 = pz1, pz0
        if z0 > lo:
            lo, p_lo = z0, pz0
        if z1 < hi:
            hi, p_hi = z1, pz1
    if not (lo < hi) or lo == -_FAR or hi == _FAR:  # (a span in the cone's upper nappe lies above z = 1)
        return 0.0, 0, 0.0, 0
    return lo, p_lo, hi, p_hi


@njit_inline
def solid_span(kind, o, d):
    """(t_in, part_in, t_out, part_out) of the whole line o + t·d (object space) through a canonical convex
    solid: a sphere, a box, or a capped cylinder or cone; t_in = t_out = 0 if it misses."""
    if kind == SHAPE_SPHERE:
        return _sphere_span(o, d)
    if kind == SHAPE_BOX:
        return _box_span(o, d)
    return _axial_span(o, d, kind == SHAPE_CONE)


# ------------------------------------------------------------------------------------------- the crossings


@njit
def _insert(ts, codes, n, t, code, dropped):
    """Insert (t, code) into the sorted buffers holding n crossings, keeping the smallest; returns (n, dropped):
    dropped is the smallest t let go for want of room (inf when none)."""
    cap = ts.shape[0]
    if n == cap:
        if t >= ts[cap - 1]:
            return n, min(dropped, t)
        dropped = min(dropped, ts[cap - 1])
        n -= 1
    k = n
    while k > 0 and ts[k - 1] > t:
        ts[k] = ts[k - 1]
        codes[k] = codes[k - 1]
        k -= 1
    ts[k] = t
    codes[k] = code
    return n + 1, dropped


@njit
def _is_repeat(ts, codes, n, t, code):
    """True if the buffers already hold a crossing of the same mesh solid, in the same direction, at (almost)
    the same t: the same crossing reported by a neighbouring triangle (a ray through an edge or a vertex)."""
    key = code & ((1 << (_LEAF_BITS + 1)) - 1)  # leaf number and direction bit
    tol = _SAME_T * abs(t)
    for k in range(n):
        if (codes[k] & ((1 << (_LEAF_BITS + 1)) - 1)) == key and abs(ts[k] - t) <= tol:
            return True
    return False


@njit
def _gather(geo, first_leaf, n_leaves, o, d, t_after, ts, codes):
    """The crossings of every leaf with t > t_after, sorted, the smallest len(ts) of them: (n, dropped)."""
    n = 0
    dropped = np.inf
    setup_fwd = triangle_setup(d)
    setup_back = triangle_setup((-d[0], -d[1], -d[2]))
    for j in range(n_leaves):
        s = first_leaf + j
        kind = geo.shape_info[s, INFO_KIND]
        if kind == SHAPE_MESH_SOLID:
            first = np.int64(geo.shape_info[s, INFO_REF])
            v = geo.tri_verts
            for i in range(first, first + geo.shape_info[s, INFO_COUNT]):
                t_fwd, _, _ = intersect_triangle(o, setup_fwd, v, i, _FAR)
                t_back, _, _ = intersect_triangle(o, setup_back, v, i, _FAR)
                if t_fwd == NO_HIT and t_back == NO_HIT:
                    continue
                # direction bit: does d run along the triangle's normal (v1 − v0) × (v2 − v0)?
                v0 = (np.float64(v[i, 0]), np.float64(v[i, 1]), np.float64(v[i, 2]))
                e1 = (v[i, 3] - v0[0], v[i, 4] - v0[1], v[i, 5] - v0[2])
                e2 = (v[i, 6] - v0[0], v[i, 7] - v0[1], v[i, 8] - v0[2])
                dn = ((e1[1] * e2[2] - e1[2] * e2[1]) * d[0] + (e1[2] * e2[0] - e1[0] * e2[2]) * d[1]
                      + (e1[0] * e2[1] - e1[1] * e2[0]) * d[2])
                code = (i << (_LEAF_BITS + 1)) | ((1 if dn > 0.0 else 0) << _LEAF_BITS) | j
                # a hit behind the origin is a hit of the reversed ray at −t
                t = t_fwd if t_fwd != NO_HIT else -t_back
                if t > t_after and not _is_repeat(ts, codes, n, t, code):
                    n, dropped = _insert(ts, codes, n, t, code, dropped)
            continue
        m = geo.shape_xform[s]
        t_in, p_in, t_out, p_out = solid_span(kind, xform_point(m, o), xform_vector(m, d))
        if t_in < t_out:
            if t_in > t_after:
                n, dropped = _insert(ts, codes, n, t_in, (np.int64(p_in) << (_LEAF_BITS + 1)) | j, dropped)
            if t_out > t_after:
                n, dropped = _insert(ts, codes, n, t_out, (np.int64(p_out) << (_LEAF_BITS + 1)) | j, dropped)
    return n, dropped


# ------------------------------------------------------------------------------------------- the sweep


@njit
def _toggle(nodes, state, first_node, first_leaf, n_leaves, root, j):
    """Flip leaf j's inside state and update its ancestors (state: leaves, then nodes from first_node); returns
    the root's state."""
    state[j] ^= 1
    node = np.int64(nodes[root + 1 + j, 2])
    while node >= 0:
        a = np.int64(nodes[node, 1])
        b = np.int64(nodes[node, 2])
        va = state[n_leaves + a - first_node] if a >= 0 else state[~a - first_leaf]
        vb = state[n_leaves + b - first_node] if b >= 0 else state[~b - first_leaf]
        op = nodes[node, 0]
        if op == CSG_UNION:
            v = va | vb
        elif op == CSG_INTERSECTION:
            v = va & vb
        else:
            v = va & (vb ^ 1)
        k = n_leaves + node - first_node
        if state[k] == v:
            break
        state[k] = v
        node = np.int64(nodes[node, 3])
    return state[n_leaves + root - first_node]


@njit_alloc
def intersect_csg(geo, s, o, d, t_min, t_max):
    """Nearest crossing of csg shape s's boundary with t_min < t < t_max: (t, part, b1, b2) as in the module
    doc, or (-1, 0, 0, 0). `o` is the origin already moved back by time·motion (see `traverse._shape_hit`)."""
    nodes = geo.csg_nodes
    root = np.int64(geo.shape_info[s, INFO_REF])
    n_leaves = np.int64(geo.shape_info[s, INFO_COUNT])
    first_node = root - (n_leaves - 2)
    first_leaf = np.int64(~nodes[root + 1, 1])
    ts = np.empty(CSG_CROSSINGS)
    codes = np.empty(CSG_CROSSINGS, np.int64)
    state = np.zeros(2 * n_leaves - 1, np.int8)  # at −∞ the line is outside every leaf
    inside = np.int8(0)
    t_after = -np.inf
    while True:
        n, dropped = _gather(geo, first_leaf, n_leaves, o, d, t_after, ts, codes)
        end = n
        if dropped < np.inf:  # only the crossings before the first one let go are complete
            end = 0
            while end < n and ts[end] < dropped:
                end += 1
            if end == 0:
                end = n  # more than CSG_CROSSINGS crossings at one t: take those held as the event
        i = 0
        while i < end:
            t = ts[i]
            if t >= t_max:
                return NO_HIT, 0, 0.0, 0.0
            before = inside
            flip = np.int64(-1)
            while i < end and ts[i] == t:  # one event: every crossing at this t
                now = _toggle(nodes, state, first_node, first_leaf, n_leaves, root, codes[i] & _LEAF_MASK)
                if now != inside:
                    inside = now
                    flip = codes[i]
                i += 1
            if inside != before and t > t_min:
                j = flip & _LEAF_MASK
                leaf_part = flip >> (_LEAF_BITS + 1)
                if geo.shape_info[first_leaf + j, INFO_KIND] == SHAPE_MESH_SOLID:
                    return t, (first_leaf + j) * CSG_PART_STRIDE, 1.0 if inside else -1.0, np.float64(leaf_part)
                return t, (first_leaf + j) * CSG_PART_STRIDE + leaf_part, 1.0 if inside else -1.0, 0.0
            t_after = t
        if n < CSG_CROSSINGS or dropped == np.inf:
            return NO_HIT, 0, 0.0, 0.0
