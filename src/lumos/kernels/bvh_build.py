"""Binned SAH BVH construction (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies").

Top-down and iterative: each node's primitives are binned by centroid into `n_bins` buckets on all three axes in
one pass, the split with the least surface-area cost is taken, and the index range is partitioned in place. The
two children of a node are stored next to each other, so traversal tests both boxes from one cache line.
Nodes with more than `PARALLEL_MIN` primitives are binned in parallel chunks.
"""

import numpy as np

from .jit import njit, njit_parallel, prange

#: SAH cost of one traversal step relative to one primitive test.
COST_TRAVERSAL = 1.0
#: Trees deeper than this make leaves (the traversal stack is 64 entries; one push per level at most).
MAX_DEPTH = 60
PARALLEL_MIN = 1 << 16
_CHUNKS = 16


@njit
def _area(bmin0, bmin1, bmin2, bmax0, bmax1, bmax2):
    dx = bmax0 - bmin0
    dy = bmax1 - bmin1
    dz = bmax2 - bmin2
    if dx < 0.0:
        return 0.0
    return dx * dy + dy * dz + dz * dx


@njit
def _bin_range(order, start, end, bounds, cent, cmin, scale, n_bins, bin_box, bin_count):
    """Accumulate primitives order[start:end] into per-axis bins (bin_box (3, n_bins, 6), bin_count (3, n_bins))."""
    for i in range(start, end):
        p = order[i]
        for a in range(3):
            b = int((cent[p, a] - cmin[a]) * scale[a])
            if b >= n_bins:
                b = n_bins - 1
            elif b < 0:
                b = 0
            bin_count[a, b] += 1
            for k in range(3):
                if bounds[p, k] < bin_box[a, b, k]:
                    bin_box[a, b, k] = bounds[p, k]
                if bounds[p, 3 + k] > bin_box[a, b, 3 + k]:
                    bin_box[a, b, 3 + k] = bounds[p, 3 + k]


@njit
def _empty_bins(n_bins):
    box = np.empty((3, n_bins, 6))
    box[:, :, :3] = np.inf
    box[:, :, 3:] = -np.inf
    return box, np.zeros((3, n_bins), np.int64)


@njit_parallel
def _bin_parallel(order, start, end, bounds, cent, cmin, scale, n_bins):
    boxes = np.empty((_CHUNKS, 3, n_bins, 6))
    counts = np.zeros((_CHUNKS, 3, n_bins), np.int64)
    step = (end - start + _CHUNKS - 1) // _CHUNKS
    for c in prange(_CHUNKS):
        boxes[c, :, :, :3] = np.inf
        boxes[c, :, :, 3:] = -np.inf
        lo = start + c * step
        hi = min(end, lo + step)
        if lo < hi:
            _bin_range(order, lo, hi, bounds, cent, cmin, scale, n_bins, boxes[c], counts[c])
    box, count = _empty_bins(n_bins)
    for c in range(_CHUNKS):
        count += counts[c]
        for a in range(3):
            for b in range(n_bins):
                for k in range(3):
                    box[a, b, k] = min(box[a, b, k], boxes[c, a, b, k])
                    box[a, b, 3 + k] = max(box[a, b, 3 + k], boxes[c, a, b, 3 + k])
    return box, count


@njit
def _best_split(bin_box, bin_count, n_bins, extent):
    """Sweep the bins; returns (cost, axis, split bin) minimising A_L·N_L + A_R·N_R (not yet divided by A)."""
    best_cost = np.inf
    best_axis = -1
    best_split = 0
    right_area = np.empty(n_bins)
    right_count = np.empty(n_bins, np.int64)
    for a in range(3):
        if extent[a] <= 0.0:
            continue
        lo = np.array([np.inf, np.inf, np.inf])
        hi = np.array([-np.inf, -np.inf, -np.inf])
        n = 0
        for b in range(n_bins - 1, 0, -1):
            n += bin_count[a, b]
            for k in range(3):
                lo[k] = min(lo[k], bin_box[a, b, k])
                hi[k] = max(hi[k], bin_box[a, b, 3 + k])
            right_area[b] = _area(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2])
            right_count[b] = n
        lo[:] = np.inf
        hi[:] = -np.inf
        n = 0
        for b in range(n_bins - 1):
            n += bin_count[a, b]
            for k in range(3):
                lo[k] = min(lo[k], bin_box[a, b, k])
                hi[k] = max(hi[k], bin_box[a, b, 3 + k])
            if n == 0 or right_count[b + 1] == 0:
                continue
            cost = _area(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]) * n + right_area[b + 1] * right_count[b + 1]
            if cost < best_cost:
                best_cost, best_axis, best_split = cost, a, b + 1
    return best_cost, best_axis, best_split


@njit
def _node_bounds(order, start, end, bounds, cent):
    box = np.array([np.inf, np.inf, np.inf, -np.inf, -np.inf, -np.inf])
    cmin = np.array([np.inf, np.inf, np.inf])
    cmax = np.array([-np.inf, -np.inf, -np.inf])
    for i in range(start, end):
        p = order[i]
        for k in range(3):
            box[k] = min(box[k], bounds[p, k])
            box[3 + k] = max(box[3 + k], bounds[p, 3 + k])
            cmin[k] = min(cmin[k], cent[p, k])
            cmax[k] = max(cmax[k], cent[p, k])
    return box, cmin, cmax


@njit
def _partition(order, start, end, cent, axis, cmin, scale, split, n_bins):
    i, j = start, end - 1
    while i <= j:
        b = int((cent[order[i], axis] - cmin[axis]) * scale[axis])
        b = min(max(b, 0), n_bins - 1)
        if b < split:
            i += 1
        else:
            order[i], order[j] = order[j], order[i]
            j -= 1
    return i


@njit
def _store_box(node_box, node, box):
    """Round the float64 box outward to float32 (a relative widening larger than one float32 ulp)."""
    for k in range(3):
        lo, hi = box[k], box[3 + k]
        node_box[node, k] = lo - (abs(lo) * 4e-7 + 1e-30)
        node_box[node, 3 + k] = hi + (abs(hi) * 4e-7 + 1e-30)


@njit
def build_bvh(bounds, max_leaf, n_bins):
    """Build a BVH over primitive boxes `bounds` float64 (n, 6) (min xyz, max xyz).

    Returns (node_box float32 (nn, 6), node_link int32 (nn, 2), order int64 (n,), depth). A leaf's primitives
    are order[first:first + count].
    """
    n = bounds.shape[0]
    order = np.arange(n)
    cent = (bounds[:, :3] + bounds[:, 3:]) * 0.5
    node_box = np.empty((max(2 * n - 1, 1), 6), np.float32)
    node_link = np.zeros((max(2 * n - 1, 1), 2), np.int32)
    # work stack of (node, start, end, depth)
    stack = np.empty((4 * MAX_DEPTH + 8, 4), np.int64)
    stack[0] = (0, 0, n, 0)
    sp = 1
    n_nodes = 1
    max_depth = 0
    scale = np.empty(3)
    while sp > 0:
        sp -= 1
        node, start, end, depth = stack[sp, 0], stack[sp, 1], stack[sp, 2], stack[sp, 3]
        max_depth = max(max_depth, depth)
        count = end - start
        box, cmin, cmax = _node_bounds(order, start, end, bounds, cent)
        _store_box(node_box, node, box)
        extent = cmax - cmin
        split_axis = -1
        split = 0
        if count > 1 and depth < MAX_DEPTH:
            for a in range(3):
                scale[a] = n_bins / extent[a] * (1.0 - 1e-9) if extent[a] > 0.0 else 0.0
            if count >= PARALLEL_MIN:
                bin_box, bin_count = _bin_parallel(order, start, end, bounds, cent, cmin, scale, n_bins)
            else:
                bin_box, bin_count = _empty_bins(n_bins)
                _bin_range(order, start, end, bounds, cent, cmin, scale, n_bins, bin_box, bin_count)
            cost, split_axis, split = _best_split(bin_box, bin_count, n_bins, extent)
            area = _area(box[0], box[1], box[2], box[3], box[4], box[5])
            split_cost = COST_TRAVERSAL + (cost / area if area > 0.0 else 0.0)
            if count <= max_leaf and (split_axis < 0 or count <= split_cost):
                split_axis = -2  # a leaf is cheaper
        if split_axis == -2 or count == 1 or (split_axis == -1 and count <= max_leaf) or depth >= MAX_DEPTH:
            node_link[node, 0] = start
            node_link[node, 1] = count
            continue
        if split_axis >= 0:
            mid = _partition(order, start, end, cent, split_axis, cmin, scale, split, n_bins)
        else:
            mid = (start + end) // 2  # all centroids coincide: split the range in half
        if mid == start or mid == end:
            mid = (start + end) // 2
        left = n_nodes
        n_nodes += 2
        node_link[node, 0] = left
        node_link[node, 1] = 0
        stack[sp] = (left + 1, mid, end, depth + 1)
        stack[sp + 1] = (left, start, mid, depth + 1)
        sp += 2
    return node_box[:n_nodes].copy(), node_link[:n_nodes].copy(), order, max_depth
