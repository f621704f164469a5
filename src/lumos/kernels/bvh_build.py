"""Binned SAH BVH construction (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies").

Top-down and iterative. At each node the primitives are binned by centroid into `n_bins` buckets on all three
axes in one pass; the split with the least surface-area cost is taken; the index range is partitioned in place,
and the same pass gathers both children's centroid bounds (their boxes come from the bins). The two children of
a node are stored next to each other, so traversal tests both boxes from one cache line.

Parallelism: the top of the tree is built first; every node below `task_size` primitives becomes a task, and the
tasks are built into their own node regions (a subtree of n primitives needs at most 2n − 1 nodes), which are
compacted at the end. `build_nodes` builds a run of tasks and releases the GIL, so `compile.bvh.build` runs the
tasks on Python threads. (As `parallel=True` kernels the builder took 16 s to compile, against 10 s now: Numba
optimises each parallel loop body, with everything inlined into it, as a module of its own; the tree is the same.)
"""

import numpy as np

from .jit import njit_alloc, njit_serial
from .layout import LEAF_PACKED, WIDE

#: Trees deeper than this make leaves (the traversal stack, `config.BVH_STACK`, is sized for this depth).
MAX_DEPTH = 60


@njit_alloc
def _half_area(b):
    dx = b[3] - b[0]
    dy = b[4] - b[1]
    dz = b[5] - b[2]
    if dx < 0.0:
        return 0.0
    return dx * dy + dy * dz + dz * dx


@njit_alloc
def _reset(box):
    """Set (..., 6) boxes empty: +inf minimum, -inf maximum."""
    box[..., :3] = np.inf
    box[..., 3:] = -np.inf


@njit_alloc
def _grow(dst, src):
    for k in range(3):
        if src[k] < dst[k]:
            dst[k] = src[k]
        if src[3 + k] > dst[3 + k]:
            dst[3 + k] = src[3 + k]


@njit_alloc
def _bin_range(order, start, end, bounds, cent, cbox, scale, first_shape, bin_box, bin_count):
    """Accumulate primitives order[start:end] into per-axis bins (bin_box (3, B, 6), bin_count (3, B) of their
    `_weight`s)."""
    n_bins = bin_count.shape[1]
    for i in range(start, end):
        p = order[i]
        w = _weight(p, first_shape)
        for a in range(3):
            b = int((cent[p, a] - cbox[a]) * scale[a])
            b = min(max(b, 0), n_bins - 1)
            bin_count[a, b] += w
            _grow(bin_box[a, b], bounds[p])


@njit_alloc
def _blocks(n):
    """SAH cost of testing primitives of total `_weight` n in a leaf: the packed leaf test (`simd.tri4_test`)
    takes four triangles at the price of one, so the cost counts blocks of four, ceil(n / 4), not primitives
    (Embree's SAH does the same for its four-wide leaves). With a traversal step costing one block, every node
    of at most four triangles becomes a leaf, and leaves come out full."""
    return (n + 3) // 4


@njit_alloc
def _weight(p, first_shape):
    """Primitive p's share of a leaf-test block: a triangle (p < first_shape) a quarter, an analytic shape, tested
    on its own, a whole block (4), so that the SAH keeps the walls of a room out of one leaf that every ray
    entering the room would test in full."""
    return 4 if p >= first_shape else 1


@njit_alloc
def _best_split(bin_box, bin_count, cbox, right_area, acc):
    """Sweep the bins; returns (cost, axis, split bin) minimising A_L·B(N_L) + A_R·B(N_R) (not yet divided by
    A), B(N) the number of four-triangle blocks the leaf test needs (`_blocks`; N the primitives' weight)."""
    n_bins = bin_count.shape[1]
    best_cost = np.inf
    best_axis = -1
    best_split = 0
    for a in range(3):
        if cbox[3 + a] <= cbox[a]:
            continue
        _reset(acc)
        for b in range(n_bins - 1, 0, -1):
            _grow(acc, bin_box[a, b])
            right_area[b] = _half_area(acc)
        _reset(acc)
        n_left = 0
        n_right = 0
        for b in range(n_bins):
            n_right += bin_count[a, b]
        for b in range(n_bins - 1):
            n_left += bin_count[a, b]
            n_right -= bin_count[a, b]
            _grow(acc, bin_box[a, b])
            if n_left == 0 or n_right == 0:
                continue
            cost = _half_area(acc) * _blocks(n_left) + right_area[b + 1] * _blocks(n_right)
            if cost < best_cost:
                best_cost, best_axis, best_split = cost, a, b + 1
    return best_cost, best_axis, best_split


@njit_alloc
def _partition(order, start, end, cent, axis, cbox, scale, split, n_bins, left_cbox, right_cbox):
    """Move primitives whose bin is below `split` to the front; gather both sides' centroid bounds."""
    _reset(left_cbox)
    _reset(right_cbox)
    i, j = start, end - 1
    while i <= j:
        p = order[i]
        b = int((cent[p, axis] - cbox[axis]) * scale[axis])
        b = min(max(b, 0), n_bins - 1)
        if b < split:
            for k in range(3):
                left_cbox[k] = min(left_cbox[k], cent[p, k])
                left_cbox[3 + k] = max(left_cbox[3 + k], cent[p, k])
            i += 1
        else:
            for k in range(3):
                right_cbox[k] = min(right_cbox[k], cent[p, k])
                right_cbox[3 + k] = max(right_cbox[3 + k], cent[p, k])
            order[i], order[j] = order[j], p
            j -= 1
    return i


@njit_alloc
def _range_bounds(order, start, end, bounds, cent, box, cbox):
    _reset(box)
    _reset(cbox)
    for i in range(start, end):
        p = order[i]
        _grow(box, bounds[p])
        for k in range(3):
            cbox[k] = min(cbox[k], cent[p, k])
            cbox[3 + k] = max(cbox[3 + k], cent[p, k])


@njit_alloc
def _store_box(node_box, node, box):
    """Round the float64 box outward to float32 (a relative widening larger than one float32 ulp)."""
    for k in range(3):
        lo, hi = box[k], box[3 + k]
        node_box[node, k] = lo - (abs(lo) * 4e-7 + 1e-30)
        node_box[node, 3 + k] = hi + (abs(hi) * 4e-7 + 1e-30)


@njit_alloc
def _build_from(root, start, end, depth, root_box, root_cbox, first_free, order, bounds, cent, first_shape, max_leaf,
                n_bins, cost_traversal, task_size, node_box, node_link, tasks, n_tasks):
    """Build the subtree of node `root` over order[start:end], allocating nodes from `first_free` upward.

    Nodes with fewer than `task_size` primitives (when > 0) are not built but appended to `tasks` as
    (node, start, end, depth). Returns (next free node, number of tasks, deepest level reached).
    """
    stack_i = np.empty((MAX_DEPTH + 4, 4), np.int64)
    stack_f = np.empty((MAX_DEPTH + 4, 12))
    bin_box = np.empty((3, n_bins, 6))
    bin_count = np.zeros((3, n_bins), np.int64)
    right_area = np.empty(n_bins)
    acc = np.empty(6)
    scale = np.empty(3)
    left_box = np.empty(6)
    right_box = np.empty(6)
    box = np.empty(6)
    cbox = np.empty(6)
    stack_i[0] = (root, start, end, depth)
    stack_f[0, :6] = root_box
    stack_f[0, 6:] = root_cbox
    sp = 1
    next_free = first_free
    max_depth = depth
    while sp > 0:
        sp -= 1
        node, start, end, depth = stack_i[sp, 0], stack_i[sp, 1], stack_i[sp, 2], stack_i[sp, 3]
        box[:] = stack_f[sp, :6]
        cbox[:] = stack_f[sp, 6:]
        count = end - start
        _store_box(node_box, node, box)
        max_depth = max(max_depth, depth)
        if 0 < task_size and count < task_size and node != root:
            tasks[n_tasks] = (node, start, end, depth)
            n_tasks += 1
            continue
        # stage 1: bin the centroids and find the cheapest split
        axis = -1
        split = 0
        cost = np.inf
        weight = count
        if count > 1 and depth < MAX_DEPTH:
            for a in range(3):
                ext = cbox[3 + a] - cbox[a]
                scale[a] = n_bins / ext * (1.0 - 1e-9) if ext > 0.0 else 0.0
            _reset(bin_box)
            bin_count[:] = 0
            _bin_range(order, start, end, bounds, cent, cbox, scale, first_shape, bin_box, bin_count)
            cost, axis, split = _best_split(bin_box, bin_count, cbox, right_area, acc)
            weight = bin_count[0].sum()
        # stage 2: a leaf when splitting does not pay (SAH) or is impossible; a leaf holds at most max_leaf
        # weight, four triangles or one shape: shapes are tested one by one, so each gets a box of its own
        area = _half_area(box)
        split_cost = cost_traversal + (cost / area if area > 0.0 else 0.0)
        leaf = count == 1 or depth >= MAX_DEPTH or (weight <= max_leaf and (axis < 0 or _blocks(weight) <= split_cost))
        if leaf:
            node_link[node, 0] = start
            node_link[node, 1] = count
            continue
        # stage 3: partition; children boxes come from the bins, centroid boxes from the partition pass
        if axis >= 0:
            # the left child goes to stack slot sp + 1 (built first), the right to slot sp
            mid = _partition(order, start, end, cent, axis, cbox, scale, split, n_bins, stack_f[sp + 1, 6:],
                             stack_f[sp, 6:])
            _reset(left_box)
            _reset(right_box)
            for b in range(n_bins):
                _grow(left_box if b < split else right_box, bin_box[axis, b])
            stack_f[sp, :6] = right_box
            stack_f[sp + 1, :6] = left_box
        else:
            mid = (start + end) // 2  # all centroids coincide: halve the range
            _range_bounds(order, mid, end, bounds, cent, right_box, acc)
            stack_f[sp, :6] = right_box
            stack_f[sp, 6:] = acc
            _range_bounds(order, start, mid, bounds, cent, left_box, acc)
            stack_f[sp + 1, :6] = left_box
            stack_f[sp + 1, 6:] = acc
        left = next_free
        next_free += 2
        node_link[node, 0] = left
        node_link[node, 1] = 0
        stack_i[sp] = (left + 1, mid, end, depth + 1)  # right child, built after the left
        stack_i[sp + 1] = (left, start, mid, depth + 1)
        sp += 2
    return next_free, n_tasks, max_depth


@njit_serial
def build_nodes(tasks, bases, k0, k1, order, bounds, cent, first_shape, max_leaf, n_bins, cost_traversal, task_size,
                node_box, node_link, ends, depths, new_tasks):
    """Build the subtrees of tasks[k0:k1] (rows (node, start, end, depth) over order[start:end]), task k's nodes
    from bases[k] upward, into node_box float32 (nn, 6) and node_link int32 (nn, 2) (see `_build_from`); ends[k]
    and depths[k] get the node after its last and its deepest level.

    With `task_size` > 0, nodes below that many primitives are not built but appended to `new_tasks`; returns how
    many were. The whole tree is the root task (0, 0, n, 0) with base 2, built with a task size and then its
    tasks without: `compile.bvh.build` does that, the tasks on threads."""
    box = np.empty(6)
    cbox = np.empty(6)
    n_new = 0
    for k in range(k0, k1):
        node, start, end, depth = tasks[k, 0], tasks[k, 1], tasks[k, 2], tasks[k, 3]
        _range_bounds(order, start, end, bounds, cent, box, cbox)
        ends[k], n_new, depths[k] = _build_from(node, start, end, depth, box, cbox, bases[k], order, bounds, cent,
                                                first_shape, max_leaf, n_bins, cost_traversal, task_size, node_box,
                                                node_link, new_tasks, n_new)
    return n_new


# ------------------------------------------------------------------------------------------- the wide tree


@njit_alloc
def collapse_wide(node_box, node_link, first_col, count_col):
    """The WIDE-wide BVH (`layout.WIDE`) of a binary one (packed nodes: bounds in columns 0-5, links in
    `first_col`/`count_col` of the int32 view `node_link`): each wide node takes a binary interior node's
    children and keeps opening the largest interior one among them until it holds WIDE (Wald et al. 2008,
    "Getting rid of packets"; Embree's BVH4/BVH8 collapse). Returns (boxes float32 (nw, 6, WIDE): per bound row,
    the children's values; child int32 (nw, WIDE): a wide node index (count 0) or the first prim_ref entry of a
    leaf; count int32 (nw, WIDE): the leaf's
    primitive count, 0 for a wide node, -1 for an empty slot, whose box is inverted (+inf min, -inf max) so that
    every ray misses it). The wide tree is no deeper than the binary one."""
    nn = node_box.shape[0]
    cap = max(nn // 2 + 1, 1)
    boxes = np.empty((cap, 6, WIDE), np.float32)
    child = np.zeros((cap, WIDE), np.int32)
    count = np.full((cap, WIDE), -1, np.int32)
    boxes[:, :3, :] = np.inf
    boxes[:, 3:, :] = -np.inf
    if nn == 0:
        return boxes[:0], child[:0], count[:0]
    todo = np.empty(cap, np.int64)  # binary nodes whose children become wide node todo_w[k]
    todo_w = np.empty(cap, np.int64)
    n_todo = 0
    n_wide = 1
    slots = np.empty(WIDE, np.int64)
    area = np.empty(6)
    if node_link[0, count_col] > 0:  # the whole tree is one leaf
        for r in range(6):
            boxes[0, r, 0] = node_box[0, r]
        child[0, 0] = node_link[0, first_col]
        count[0, 0] = node_link[0, count_col]
        return boxes[:1], child[:1], count[:1]
    todo[0], todo_w[0] = 0, 0
    n_todo = 1
    while n_todo > 0:
        n_todo -= 1
        p, w = todo[n_todo], todo_w[n_todo]
        c = np.int64(node_link[p, first_col])
        slots[0], slots[1] = c, c + 1
        n_slots = 2
        while n_slots < WIDE:  # open the largest interior child
            best, best_area = -1, -1.0
            for s in range(n_slots):
                q = slots[s]
                if node_link[q, count_col] == 0:
                    for r in range(6):
                        area[r] = node_box[q, r]
                    a = _half_area(area)
                    if a > best_area:
                        best, best_area = s, a
            if best < 0:
                break
            q = slots[best]
            cq = np.int64(node_link[q, first_col])
            slots[best] = cq
            slots[n_slots] = cq + 1
            n_slots += 1
        for s in range(n_slots):
            q = slots[s]
            for r in range(6):
                boxes[w, r, s] = node_box[q, r]
            if node_link[q, count_col] > 0:
                child[w, s] = node_link[q, first_col]
                count[w, s] = node_link[q, count_col]
            else:
                child[w, s] = n_wide
                count[w, s] = 0
                todo[n_todo], todo_w[n_todo] = q, n_wide
                n_todo += 1
                n_wide += 1
    return boxes[:n_wide], child[:n_wide], count[:n_wide]


@njit_alloc
def pack_leaves(wide_link, child_col, count_col, prim_ref, tri_verts, packed, packed_link, base_col, mask_col,
                tri_object, tri_face, tri_uvs, object_col, face_col, uvs_col):
    """Give every wide leaf of one to four triangles (and nothing else) its own packed row for `simd.tri4_test`:
    packed float32 (nl, >= 47) rows of four lanes (v0.x, v0.y, v0.z, v1.x, ..., v2.z; spare lanes repeat the
    first triangle), packed_link its int32 view with the first triangle's index in `base_col` (a leaf's triangles
    are consecutive: the compile step numbers them in leaf order), the mask of real lanes in `mask_col`, and per
    lane the triangle's tri_object and tri_face entries in object_col.. and face_col.. and the mask of lanes whose
    tri_uvs is set in `uvs_col`. The slot's count becomes LEAF_PACKED and its child the packed row. Returns the
    number of rows used."""
    n = 0
    for w in range(wide_link.shape[0]):
        for k in range(WIDE):
            count = wide_link[w, count_col + k]
            if count <= 0 or count > 4:
                continue
            first = wide_link[w, child_col + k]
            ok = True
            for i in range(first, first + count):
                if prim_ref[i] < 0 or prim_ref[i] != prim_ref[first] + (i - first):
                    ok = False
            if not ok:
                continue
            base = prim_ref[first]
            uvs = 0
            for lane in range(4):
                r = base + (lane if lane < count else 0)
                for c in range(9):  # vertex c // 3, axis c % 3 -> row c
                    packed[n, 4 * c + lane] = tri_verts[r, c]
                packed_link[n, object_col + lane] = tri_object[r]
                packed_link[n, face_col + lane] = tri_face[r]
                if lane < count and tri_uvs[r]:
                    uvs |= 1 << lane
            packed_link[n, base_col] = base
            packed_link[n, mask_col] = (1 << count) - 1
            packed_link[n, uvs_col] = uvs
            wide_link[w, child_col + k] = n
            wide_link[w, count_col + k] = LEAF_PACKED
            n += 1
    return n

