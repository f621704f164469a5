"""Ray queries over arrays of rays: nearest hit for each (used by ray-query callers, tests and benchmarks)."""

import numpy as np

from .. import config
from .jit import njit_parallel, prange
from .traverse import any_hit, closest_hit
from .views import geometry_of

_CHUNK = 256


@njit_parallel
def trace_closest(sa, origins, directions, t_max, t_out, ref_out, b_out):
    """For rays float64 (n, 3) + (n, 3): t_out (n,) (-1 on a miss), ref_out (n,) int64 (triangle index or ~shape),
    b_out (n, 2) barycentrics. Rays are processed in chunks of 256 per task."""
    n = origins.shape[0]
    n_chunks = (n + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        geo = geometry_of(sa)  # per task: parfor bodies cannot capture a namedtuple built outside them
        stack = np.empty(config.BVH_STACK, np.int64)
        stack_t = np.empty(config.BVH_STACK)
        for i in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            o = (origins[i, 0], origins[i, 1], origins[i, 2])
            d = (directions[i, 0], directions[i, 1], directions[i, 2])
            t, ref, b1, b2, part = closest_hit(geo, o, d, 0.0, t_max, stack, stack_t, 0.0)
            t_out[i] = t
            ref_out[i] = ref
            b_out[i, 0] = b1
            b_out[i, 1] = b2


@njit_parallel
def trace_any(sa, origins, directions, t_max, hit_out):
    """hit_out (n,) bool: does anything lie on ray i before t_max[i]?"""
    n = origins.shape[0]
    n_chunks = (n + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        geo = geometry_of(sa)  # per task: parfor bodies cannot capture a namedtuple built outside them
        stack = np.empty(config.BVH_STACK, np.int64)
        for i in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            o = (origins[i, 0], origins[i, 1], origins[i, 2])
            d = (directions[i, 0], directions[i, 1], directions[i, 2])
            hit_out[i] = any_hit(geo, o, d, 0.0, t_max[i], stack, 0.0)
