"""The one place that decides how kernels are compiled.

No `fastmath`: the watertight triangle test relies on exact IEEE products (FMA contraction would break the
antisymmetry of shared-edge tests), and "no hit yet" comparisons must not be folded away.
"""

import numba

from .cache import cached


def _cached_njit(**options):
    """`numba.njit(**options)` whose dispatchers keep their code in lumos's kernel cache (`cache.KernelCache`:
    stamped with each kernel's source closure, kept in the package or the user's cache folder)."""
    compile_ = numba.njit(cache=False, **options)

    def decorate(py_func):
        dispatcher = compile_(py_func)
        return cached(dispatcher) if hasattr(dispatcher, "py_func") else dispatcher  # NUMBA_DISABLE_JIT=1

    return decorate


#: Device functions (intersection, traversal, shading: everything on the per-ray path), cached on disk. They are
#: compiled without Numba's runtime (NRT): they allocate nothing, and their callers own every array they see, so
#: they need no reference counts. With the runtime, each call that is not inlined increments and decrements the
#: count of every array in its tuple arguments (30 calls on entry and 30 on exit for `whitted.trace`), which took a
#: quarter of the ray tracers' time (perf: NRT_incref, NRT_decref) and bounced shared counters between cores.
#: (`_nrt` is the option Numba's own `register_jitable(_nrt=False)` uses.) Every decorator here states `_nrt` and
#: `forceinline`: an option a function does not state is inherited from the caller being compiled.
njit = _cached_njit(nogil=True, error_model="numpy", _nrt=False, forceinline=False)
#: Device functions on the per-ray path that are inlined into their callers (LLVM alwaysinline). Numba passes
#: every array of a namedtuple argument as its own fields (`closest_hit` takes 96 machine arguments,
#: `illuminate_coeffs` 220), most of them on the stack, at each call that is not inlined.
njit_inline = _cached_njit(nogil=True, error_model="numpy", _nrt=False, forceinline=True)
#: Helpers that allocate arrays (BVH build, raster bins, scratch buffers, csg crossing lists): with the runtime,
#: said explicitly, since a function called from a device function would otherwise inherit its "no runtime".
njit_alloc = _cached_njit(nogil=True, error_model="numpy", _nrt=True, forceinline=False)
#: Top-level kernels run with prange over rows or tiles.
njit_parallel = _cached_njit(nogil=True, parallel=True, error_model="numpy", _nrt=True,
                           forceinline=False)
prange = numba.prange
