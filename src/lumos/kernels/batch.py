"""Ray queries over arrays of rays: nearest hit for each (used by ray-query callers, tests and benchmarks)."""

import numpy as np

from .. import config
from .jit import njit, njit_serial
from .threads import parallel_for
from .traverse import any_hit, closest_hit
from .views import geometry_of

#: Rays per run handed to a thread (at least).
_GRAIN = 256


def trace_closest(sa, origins, directions, t_max, t_out, ref_out, b_out):
    """For rays float64 (n, 3) + (n, 3): t_out (n,) (-1 on a miss), ref_out (n,) int64 (triangle index or ~shape),
    b_out (n, 2) barycentrics; one t_max for all. Runs of rays go to threads (`threads.parallel_for`)."""
    n = origins.shape[0]
    parallel_for(lambda i0, i1: _closest_rays(sa, origins, directions, t_max, t_out, ref_out, b_out, i0, i1), 0, n,
                 grain=max(_GRAIN, n // 64))


def trace_any(sa, origins, directions, t_max, hit_out):
    """hit_out (n,) bool: does anything lie on ray i before t_max[i]?"""
    n = origins.shape[0]
    parallel_for(lambda i0, i1: _any_rays(sa, origins, directions, t_max, hit_out, i0, i1), 0, n,
                 grain=max(_GRAIN, n // 64))


@njit_serial
def _closest_rays(sa, origins, directions, t_max, t_out, ref_out, b_out, i0, i1):
    _closest_band(sa, origins, directions, t_max, t_out, ref_out, b_out, i0, i1, np.empty(config.BVH_STACK, np.int64),
                  np.empty(config.BVH_STACK))


@njit
def _closest_band(sa, origins, directions, t_max, t_out, ref_out, b_out, i0, i1, stack, stack_t):
    geo = geometry_of(sa)
    for i in range(i0, i1):
        o = (origins[i, 0], origins[i, 1], origins[i, 2])
        d = (directions[i, 0], directions[i, 1], directions[i, 2])
        t, ref, b1, b2, part = closest_hit(geo, o, d, 0.0, t_max, stack, stack_t, 0.0)
        t_out[i] = t
        ref_out[i] = ref
        b_out[i, 0] = b1
        b_out[i, 1] = b2


@njit_serial
def _any_rays(sa, origins, directions, t_max, hit_out, i0, i1):
    _any_band(sa, origins, directions, t_max, hit_out, i0, i1, np.empty(config.BVH_STACK, np.int64))


@njit
def _any_band(sa, origins, directions, t_max, hit_out, i0, i1, stack):
    geo = geometry_of(sa)
    for i in range(i0, i1):
        o = (origins[i, 0], origins[i, 1], origins[i, 2])
        d = (directions[i, 0], directions[i, 1], directions[i, 2])
        hit_out[i] = any_hit(geo, o, d, 0.0, t_max[i], stack, 0.0)
