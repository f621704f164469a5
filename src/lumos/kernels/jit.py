"""The one place that decides how kernels are compiled.

No `fastmath`: the watertight triangle test relies on exact IEEE products (FMA contraction would break the
antisymmetry of shared-edge tests), and "no hit yet" comparisons must not be folded away.
"""

import numba

#: Device-style helpers: inlined into their callers by LLVM, cached on disk.
njit = numba.njit(cache=True, nogil=True, error_model="numpy")
#: Top-level kernels run with prange over rows or tiles.
njit_parallel = numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
prange = numba.prange
#: For tests that tolerate rounding (ray–box slabs): allow fused multiply-add and ignore the sign of zero.
njit_contract = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract", "nsz"})
