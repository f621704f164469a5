"""The BVH build step: a thin wrapper that validates input and calls the compiled binned-SAH builder."""

from __future__ import annotations

import numpy as np

from .. import config
from ..kernels.bvh_build import build_bvh
from .memory import aligned_copy, aligned_zeros


def build(prim_bounds: np.ndarray, first_shape: int | None = None):
    """BVH over boxes float64 (n, 6): triangles, then (from `first_shape` on; default: none) analytic shapes,
    which the SAH weighs as four triangles' test each (`kernels.bvh_build._weight`). Returns (node_box float32
    (nn, 6), node_link int32 (nn, 2), order int64 (n,), depth). An empty scene gives an empty tree."""
    if len(prim_bounds) == 0:
        return np.zeros((0, 6), np.float32), np.zeros((0, 2), np.int32), np.zeros(0, np.int64), 0
    bounds = np.ascontiguousarray(prim_bounds, dtype=np.float64)
    first = len(bounds) if first_shape is None else first_shape
    return build_bvh(bounds, np.int64(first), config.BVH_MAX_LEAF, config.BVH_BINS, float(config.BVH_COST_TRAVERSAL))


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
    n = pack_leaves(wide_link, WIDE_CHILD, WIDE_COUNT, prim_ref, tri_verts, packed, packed.view(np.int32),
                    LEAF_BASE, LEAF_MASK, np.ascontiguousarray(tri_object, np.int32),
                    np.ascontiguousarray(tri_face, np.int32), np.ascontiguousarray(tri_uvs, np.bool_),
                    LEAF_OBJECT, LEAF_FACE, LEAF_UVS)
    packed = aligned_copy(packed[:n])
    return packed, packed.view(np.int32)
