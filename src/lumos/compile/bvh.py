"""The BVH build step: a thin wrapper that validates input and calls the compiled binned-SAH builder."""

from __future__ import annotations

import numpy as np

from .. import config
from ..kernels.bvh_build import MAX_DEPTH, build_nodes
from ..kernels.threads import parallel_for
from .memory import aligned_copy, aligned_zeros


def build(prim_bounds: np.ndarray, first_shape: int | None = None, threads: int | None = None):
    """BVH over boxes float64 (n, 6): triangles, then (from `first_shape` on; default: none) analytic shapes,
    which the SAH weighs as four triangles' test each (`kernels.bvh_build._weight`). Returns (node_box float32
    (nn, 6), node_link int32 (nn, 2), order int64 (n,), depth). An empty scene gives an empty tree.

    The top of the tree is built first; its small subtrees (tasks) are then built on `threads` Python threads
    (`threads.parallel_for`; default: Numba's thread count), each task into a node region of its own, and the
    regions closed up in task order, so the tree is the same on any number of threads."""
    n = len(prim_bounds)
    if n == 0:
        return np.zeros((0, 6), np.float32), np.zeros((0, 2), np.int32), np.zeros(0, np.int64), 0
    bounds = np.ascontiguousarray(prim_bounds, dtype=np.float64)
    first = np.int64(n if first_shape is None else first_shape)
    order = np.arange(n, dtype=np.int64)
    cent = np.ascontiguousarray((bounds[:, :3] + bounds[:, 3:]) * 0.5)
    settings = (first, np.int64(config.BVH_MAX_LEAF), np.int64(config.BVH_BINS), float(config.BVH_COST_TRAVERSAL))
    task_size = max(1024, n // 64) if n >= 4096 else 0  # small trees: one task, the whole tree
    node_box = np.empty((2 * n + 2, 6), np.float32)
    node_box[1] = 0.0  # node 1 is padding: sibling pairs start at even indices, a pair of 32-byte nodes per line
    node_link = np.zeros((2 * n + 2, 2), np.int32)
    root = np.zeros((1, 4), np.int64)
    root[0, 2] = n
    top_end, depth = np.zeros(1, np.int64), np.zeros(1, np.int64)
    # nodes of >= task_size primitives number at most (2n / task_size)·MAX_DEPTH; each yields at most two tasks
    tasks = np.empty((2 * (2 * (n // task_size) + 2) * (MAX_DEPTH + 1) if task_size else 1, 4), np.int64)
    n_tasks = build_nodes(root, np.array([2], np.int64), np.int64(0), np.int64(1), order, bounds, cent, *settings,
                          np.int64(task_size), node_box, node_link, top_end, depth, tasks)
    top_end, depth = int(top_end[0]), int(depth[0])
    if n_tasks == 0:
        return node_box[:top_end].copy(), node_link[:top_end].copy(), order, depth
    tasks = tasks[:n_tasks]
    # task k's region starts at bases[k]: room for the 2·count − 1 nodes of its subtree (and one spare)
    sizes = 2 * (tasks[:, 2] - tasks[:, 1])
    bases = top_end + np.concatenate(([0], np.cumsum(sizes)[:-1])).astype(np.int64)
    big_box = np.empty((top_end + int(sizes.sum()), 6), np.float32)
    big_link = np.zeros((len(big_box), 2), np.int32)
    big_box[:top_end], big_link[:top_end] = node_box[:top_end], node_link[:top_end]
    ends, depths = np.empty(n_tasks, np.int64), np.empty(n_tasks, np.int64)

    parallel_for(lambda k0, k1: build_nodes(tasks, bases, np.int64(k0), np.int64(k1), order, bounds, cent, *settings,
                                            np.int64(0), big_box, big_link, ends, depths, tasks),
                 0, n_tasks, grain=1, threads=threads)  # build_nodes releases the GIL
    # close the gaps between regions, shifting the child links that point into a region
    used = ends - bases
    shift = bases - (top_end + np.concatenate(([0], np.cumsum(used)[:-1])))
    out_box = np.empty((top_end + int(used.sum()), 6), np.float32)
    out_link = np.empty((len(out_box), 2), np.int32)
    out_box[:top_end], out_link[:top_end] = big_box[:top_end], big_link[:top_end]
    for k in range(n_tasks):
        root, lo, hi, s = tasks[k, 0], bases[k], ends[k], shift[k]
        if big_link[root, 1] == 0:  # the task's root (in the top region) links to its first child, in the region
            out_link[root, 0] = big_link[root, 0] - s
        links = big_link[lo:hi]
        out_box[lo - s:hi - s] = big_box[lo:hi]
        out_link[lo - s:hi - s, 1] = links[:, 1]
        out_link[lo - s:hi - s, 0] = np.where(links[:, 1] == 0, links[:, 0] - s, links[:, 0])
    return out_box, out_link, order, max(depth, int(depths.max()))


def pack_nodes(node_box: np.ndarray, node_link: np.ndarray):
    """Interleave bounds and links into 32-byte nodes: (float32 (nn, 8), its int32 view) — see kernels.layout."""
    from ..kernels.layout import NODE_COUNT, NODE_FIRST

    packed = np.zeros((len(node_box), 8), np.float32)
    packed[:, :6] = node_box
    links = packed.view(np.int32)
    links[:, NODE_FIRST] = node_link[:, 0]
    links[:, NODE_COUNT] = node_link[:, 1]
    return packed, links


def wide_nodes(node_box: np.ndarray, node_link: np.ndarray):
    """The wide tree of a packed binary one, packed into nodes of WIDE_SIZE float32 (whole cache lines) on 64-byte
    boundaries (in huge pages when large, `compile.memory`): (float32 (nw, WIDE_SIZE), its int32 view) — see
    `kernels.layout.WIDE_*` and `kernels.simd`."""
    from ..kernels.bvh_build import collapse_wide
    from ..kernels.layout import NODE_COUNT, NODE_FIRST, WIDE, WIDE_CHILD, WIDE_COUNT, WIDE_SIZE

    if len(node_box) == 0:  # an empty tree: no kernel to run (or to compile, on a first run)
        packed = aligned_zeros((0, WIDE_SIZE), np.float32)
        return packed, packed.view(np.int32)
    boxes, child, count = collapse_wide(node_box, node_link, NODE_FIRST, NODE_COUNT)
    n = len(boxes)
    packed = aligned_zeros((n, WIDE_SIZE), np.float32)
    packed[:, :6 * WIDE] = boxes.reshape(n, 6 * WIDE)
    links = packed.view(np.int32)
    links[:, WIDE_CHILD:WIDE_CHILD + WIDE] = child
    links[:, WIDE_COUNT:WIDE_COUNT + WIDE] = count
    return packed, links


def packed_leaves(wide_link: np.ndarray, prim_ref: np.ndarray, tri_verts: np.ndarray, tri_object: np.ndarray,
                  tri_face: np.ndarray, tri_uvs: np.ndarray):
    """Packed rows for the wide tree's triangle leaves (`kernels.bvh_build.pack_leaves`; rewrites those slots of
    `wide_link` in place): (float32 (nl, 48) on 64-byte boundaries, its int32 view) — see `kernels.layout.LEAF_*`.
    tri_object, tri_face (int (nt,)) and tri_uvs (bool (nt,)) are each triangle's object id, face in its own mesh
    and whether it has uvs, in the triangles' (leaf) order."""
    from ..kernels.bvh_build import pack_leaves
    from ..kernels.layout import LEAF_BASE, LEAF_FACE, LEAF_MASK, LEAF_OBJECT, LEAF_UVS, WIDE, WIDE_CHILD, WIDE_COUNT

    packed = aligned_zeros((WIDE * len(wide_link), 48), np.float32)  # room for every slot; pages untouched stay free
    if len(wide_link) == 0:  # an empty tree
        return packed, packed.view(np.int32)
    n = pack_leaves(wide_link, WIDE_CHILD, WIDE_COUNT, prim_ref, tri_verts, packed, packed.view(np.int32),
                    LEAF_BASE, LEAF_MASK, np.ascontiguousarray(tri_object, np.int32),
                    np.ascontiguousarray(tri_face, np.int32), np.ascontiguousarray(tri_uvs, np.bool_),
                    LEAF_OBJECT, LEAF_FACE, LEAF_UVS)
    packed = aligned_copy(packed[:n])
    return packed, packed.view(np.int32)
