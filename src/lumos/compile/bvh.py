"""The BVH build step: a thin wrapper that validates input and calls the compiled binned-SAH builder."""

from __future__ import annotations

import numpy as np

from .. import config
from ..kernels.bvh_build import build_bvh


def build(prim_bounds: np.ndarray):
    """BVH over boxes float64 (n, 6). Returns (node_box float32 (nn, 6), node_link int32 (nn, 2), order int64 (n,),
    depth). An empty scene gives an empty tree."""
    if len(prim_bounds) == 0:
        return np.zeros((0, 6), np.float32), np.zeros((0, 2), np.int32), np.zeros(0, np.int64), 0
    bounds = np.ascontiguousarray(prim_bounds, dtype=np.float64)
    return build_bvh(bounds, config.BVH_MAX_LEAF, config.BVH_BINS)
