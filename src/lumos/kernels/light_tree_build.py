"""The light tree's build (pbrt-v4's BVHLightSampler::buildBVH, *Physically Based Rendering*, 4th ed., §12.6.3),
run once at compile time by `compile.light_tree`; `kernels.light_tree` walks the tree it makes.

    build_light_tree(items, nodes, link, leaf_of)
"""

import math

import numpy as np

from .jit import njit, njit_serial
from .layout import TREE_COS_E, TREE_COS_O, TREE_FIRST, TREE_ITEM, TREE_MAX, TREE_MIN, TREE_PARENT, TREE_PHI, TREE_SIZE
from .layout import TREE_TWO_SIDED, TREE_W

#: Buckets per axis of the build's split search (pbrt's 12).
N_BUCKETS = 12
#: Radians added to a merged normal cone, so that rounding never leaves a member's normal outside it.
CONE_SLACK = 1e-9
#: A node of more items than this prices its splits on this many of them, evenly spread through its order (the
#: partition then moves all of them): a 1.3M-triangle mesh builds in seconds instead of tens of seconds.
SPLIT_SAMPLE = 1024


@njit
def _cone_union(ax, ay, az, cos_a, bx, by, bz, cos_b):
    """The normal cone (axis, cos θ) bounding cones a and b (pbrt's DirectionCone Union), widened by CONE_SLACK."""
    theta_a = math.acos(min(max(cos_a, -1.0), 1.0))
    theta_b = math.acos(min(max(cos_b, -1.0), 1.0))
    d = min(max(ax * bx + ay * by + az * bz, -1.0), 1.0)
    theta_d = math.acos(d)
    if min(theta_d + theta_b, math.pi) <= theta_a:
        return ax, ay, az, cos_a
    if min(theta_d + theta_a, math.pi) <= theta_b:
        return bx, by, bz, cos_b
    theta_o = 0.5 * (theta_a + theta_d + theta_b) + CONE_SLACK
    if theta_o >= math.pi:
        return 0.0, 0.0, 1.0, -1.0
    theta_r = theta_o - theta_a
    kx, ky, kz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx  # rotate a's axis towards b's about a × b
    kl = math.sqrt(kx * kx + ky * ky + kz * kz)
    if kl == 0.0:
        return 0.0, 0.0, 1.0, -1.0
    kx, ky, kz = kx / kl, ky / kl, kz / kl
    c, s = math.cos(theta_r), math.sin(theta_r)
    # Rodrigues' rotation of a (⟂ k): a·cos θr + (k × a)·sin θr
    tx, ty, tz = ky * az - kz * ay, kz * ax - kx * az, kx * ay - ky * ax
    wx, wy, wz = ax * c + tx * s, ay * c + ty * s, az * c + tz * s
    wl = math.sqrt(wx * wx + wy * wy + wz * wz)
    return wx / wl, wy / wl, wz / wl, math.cos(theta_o)


@njit
def _union_into(dst, i, src, j):
    """Row i of dst (TREE_SIZE columns, empty when its φ is 0) becomes its union with row j of src."""
    if src[j, TREE_PHI] == 0.0:
        return
    if dst[i, TREE_PHI] == 0.0:
        for c in range(TREE_SIZE):
            dst[i, c] = src[j, c]
        return
    for a in range(3):
        dst[i, TREE_MIN + a] = min(dst[i, TREE_MIN + a], src[j, TREE_MIN + a])
        dst[i, TREE_MAX + a] = max(dst[i, TREE_MAX + a], src[j, TREE_MAX + a])
    w = _cone_union(dst[i, TREE_W], dst[i, TREE_W + 1], dst[i, TREE_W + 2], dst[i, TREE_COS_O],
                    src[j, TREE_W], src[j, TREE_W + 1], src[j, TREE_W + 2], src[j, TREE_COS_O])
    dst[i, TREE_W], dst[i, TREE_W + 1], dst[i, TREE_W + 2], dst[i, TREE_COS_O] = w
    dst[i, TREE_PHI] += src[j, TREE_PHI]
    dst[i, TREE_COS_E] = min(dst[i, TREE_COS_E], src[j, TREE_COS_E])
    dst[i, TREE_TWO_SIDED] = max(dst[i, TREE_TWO_SIDED], src[j, TREE_TWO_SIDED])


@njit
def _cost(b, i, kr):
    """pbrt's EvaluateCost: φ · M_Ω (the measure of the directions the cone and θe reach) · Kr · surface area."""
    if b[i, TREE_PHI] == 0.0:
        return 0.0
    cos_o = b[i, TREE_COS_O]
    theta_o = math.acos(min(max(cos_o, -1.0), 1.0))
    theta_e = math.acos(min(max(b[i, TREE_COS_E], -1.0), 1.0))
    theta_w = min(theta_o + theta_e, math.pi)
    sin_o = math.sqrt(max(0.0, 1.0 - cos_o * cos_o))
    m_omega = (2.0 * math.pi * (1.0 - cos_o)
               + 0.5 * math.pi * (2.0 * theta_w * sin_o - math.cos(theta_o - 2.0 * theta_w) - 2.0 * theta_o * sin_o
                                  + cos_o))
    ex = b[i, TREE_MAX] - b[i, TREE_MIN]
    ey = b[i, TREE_MAX + 1] - b[i, TREE_MIN + 1]
    ez = b[i, TREE_MAX + 2] - b[i, TREE_MIN + 2]
    area = 2.0 * (ex * ey + ey * ez + ez * ex)
    return b[i, TREE_PHI] * m_omega * kr * area


@njit_serial
def build_light_tree(items, nodes, link, leaf_of):
    """The light BVH over `items` float64 (m, TREE_SIZE) (each emitter's bounds, every φ > 0), into `nodes` float64
    (2m − 1, TREE_SIZE) and `link` int32 (2m − 1, 3) (layout.TREE_*; node 0 the root, a node's children adjacent),
    and `leaf_of` int32 (m,), each item's leaf. Top-down, as pbrt's BVHLightSampler::buildBVH: a node's items are
    split where the summed cost of the two sides (`_cost`) is least among N_BUCKETS buckets of their centroids along
    each axis (priced on at most SPLIT_SAMPLE of them), or in the middle of their order when no bucket split
    separates them; one item is a leaf. Interior
    nodes are the unions of their children, made bottom-up."""
    m = items.shape[0]
    order = np.arange(m)
    cent = np.empty((m, 3))
    for i in range(m):
        for a in range(3):
            cent[i, a] = 0.5 * (items[i, TREE_MIN + a] + items[i, TREE_MAX + a])
    buckets = np.zeros((N_BUCKETS, TREE_SIZE))
    below = np.zeros((N_BUCKETS, TREE_SIZE))
    above = np.zeros((N_BUCKETS, TREE_SIZE))
    counts = np.zeros(N_BUCKETS, np.int64)
    scratch = np.empty(m, np.int64)
    box = np.empty((4, 3))
    stack = np.empty((2 * m + 2, 4), np.int64)  # (node, start, end, parent)
    stack[0] = (0, 0, m, -1)
    sp = 1
    n_nodes = 1
    while sp > 0:
        sp -= 1
        node, start, end, parent = stack[sp, 0], stack[sp, 1], stack[sp, 2], stack[sp, 3]
        link[node, TREE_PARENT] = parent
        if end - start == 1:
            item = order[start]
            for c in range(TREE_SIZE):
                nodes[node, c] = items[item, c]
            link[node, TREE_FIRST] = -1
            link[node, TREE_ITEM] = item
            leaf_of[item] = node
            continue
        mid = start + 1  # two items: a leaf each, whatever the cost says
        if end - start > 2:
            mid = _split(items, cent, order, start, end, buckets, below, above, counts, scratch, box)
        first = n_nodes
        n_nodes += 2
        link[node, TREE_FIRST] = first
        link[node, TREE_ITEM] = -1
        stack[sp] = (first + 1, mid, end, node)
        stack[sp + 1] = (first, start, mid, node)
        sp += 2
    for k in range(n_nodes - 1, -1, -1):  # children come after their parent: unions bottom-up
        c0 = link[k, TREE_FIRST]
        if c0 >= 0:
            nodes[k, TREE_PHI] = 0.0
            _union_into(nodes, k, nodes, c0)
            _union_into(nodes, k, nodes, c0 + 1)


@njit
def _bucket_bounds(items, cent, order, start, end, stride, a, lo, extent, buckets, counts):
    """The bounds of each bucket of the items order[start:end:stride] by their centroids along axis a, to price
    the splits: exact but for the normal cone, which is the one about the mean of the members' axes that holds
    them all (two passes of dot products; `_cone_union` per member would take an arccosine each: most of a large
    build's time)."""
    buckets[:, :] = 0.0
    counts[:] = 0
    for b in range(N_BUCKETS):
        buckets[b, TREE_MIN:TREE_MIN + 3] = np.inf
        buckets[b, TREE_MAX:TREE_MAX + 3] = -np.inf
        buckets[b, TREE_COS_E] = 1.0
    for k in range(start, end, stride):
        i = order[k]
        b = min(int(N_BUCKETS * (cent[i, a] - lo) / extent), N_BUCKETS - 1)
        counts[b] += 1
        for c in range(3):
            buckets[b, TREE_MIN + c] = min(buckets[b, TREE_MIN + c], items[i, TREE_MIN + c])
            buckets[b, TREE_MAX + c] = max(buckets[b, TREE_MAX + c], items[i, TREE_MAX + c])
            buckets[b, TREE_W + c] += items[i, TREE_W + c]
        buckets[b, TREE_PHI] += items[i, TREE_PHI]
        buckets[b, TREE_COS_E] = min(buckets[b, TREE_COS_E], items[i, TREE_COS_E])
        buckets[b, TREE_TWO_SIDED] = max(buckets[b, TREE_TWO_SIDED], items[i, TREE_TWO_SIDED])
    for b in range(N_BUCKETS):
        wl = math.sqrt(buckets[b, TREE_W] ** 2 + buckets[b, TREE_W + 1] ** 2 + buckets[b, TREE_W + 2] ** 2)
        if wl > 1e-12:
            for c in range(3):
                buckets[b, TREE_W + c] /= wl
            buckets[b, TREE_COS_O] = 1.0
        else:
            buckets[b, TREE_W + 2] = 1.0
            buckets[b, TREE_COS_O] = -1.0
    for k in range(start, end, stride):
        i = order[k]
        b = min(int(N_BUCKETS * (cent[i, a] - lo) / extent), N_BUCKETS - 1)
        if buckets[b, TREE_COS_O] == -1.0:
            continue
        # cos(α + θo): α the angle from the bucket's axis to the member's, θo the member's half-angle
        ca = (buckets[b, TREE_W] * items[i, TREE_W] + buckets[b, TREE_W + 1] * items[i, TREE_W + 1]
              + buckets[b, TREE_W + 2] * items[i, TREE_W + 2])
        ca = min(max(ca, -1.0), 1.0)
        co = items[i, TREE_COS_O]
        if ca < -co:  # α + θo > π
            buckets[b, TREE_COS_O] = -1.0
            continue
        cos_sum = ca * co - math.sqrt(1.0 - ca * ca) * math.sqrt(max(0.0, 1.0 - co * co))
        buckets[b, TREE_COS_O] = min(buckets[b, TREE_COS_O], cos_sum)


@njit
def _split(items, cent, order, start, end, buckets, below, above, counts, scratch, box):
    """Reorder order[start:end] into the two children's items and return where the second begins (box: (4, 3)
    scratch for the bounds of their centroids and of their boxes)."""
    lo, hi, blo, bhi = box[0], box[1], box[2], box[3]
    lo[:] = np.inf
    hi[:] = -np.inf
    blo[:] = np.inf
    bhi[:] = -np.inf
    for k in range(start, end):
        i = order[k]
        for a in range(3):
            lo[a] = min(lo[a], cent[i, a])
            hi[a] = max(hi[a], cent[i, a])
            blo[a] = min(blo[a], items[i, TREE_MIN + a])
            bhi[a] = max(bhi[a], items[i, TREE_MAX + a])
    diag_max = max(bhi[0] - blo[0], bhi[1] - blo[1], bhi[2] - blo[2])
    stride = max((end - start) // SPLIT_SAMPLE, 1)
    n_priced = (end - start + stride - 1) // stride
    best_cost = np.inf
    best_axis = -1
    best_bucket = -1
    for a in range(3):
        extent = hi[a] - lo[a]
        if not extent > 0.0:
            continue
        _bucket_bounds(items, cent, order, start, end, stride, a, lo[a], extent, buckets, counts)
        below[:, TREE_PHI] = 0.0
        above[:, TREE_PHI] = 0.0
        for b in range(N_BUCKETS - 1):
            if b > 0:
                for c in range(TREE_SIZE):
                    below[b, c] = below[b - 1, c]
            _union_into(below, b, buckets, b)
        for b in range(N_BUCKETS - 1, 0, -1):
            if b < N_BUCKETS - 1:
                for c in range(TREE_SIZE):
                    above[b, c] = above[b + 1, c]
            _union_into(above, b, buckets, b)
        kr = diag_max / max(bhi[a] - blo[a], 1e-300)
        n_below = 0
        for b in range(N_BUCKETS - 1):
            n_below += counts[b]
            if counts[b] == 0 or n_below == n_priced:
                continue  # (an empty bucket: the same split as the one before it)
            cost = _cost(below, b, kr) + _cost(above, b + 1, kr)
            if cost < best_cost:
                best_cost, best_axis, best_bucket = cost, a, b
    if best_axis < 0:
        return (start + end) // 2
    a = best_axis
    extent = hi[a] - lo[a]
    n_lo = 0
    n_hi = 0
    for k in range(start, end):  # a stable partition: the order stays deterministic
        i = order[k]
        b = min(int(N_BUCKETS * (cent[i, a] - lo[a]) / extent), N_BUCKETS - 1)
        if b <= best_bucket:
            order[start + n_lo] = i
            n_lo += 1
        else:
            scratch[n_hi] = i
            n_hi += 1
    for k in range(n_hi):
        order[start + n_lo + k] = scratch[k]
    if n_lo == 0 or n_hi == 0:  # (only when the priced items were not all of them)
        return (start + end) // 2
    return start + n_lo
