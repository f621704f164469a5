"""The one place that decides how kernels are compiled.

No `fastmath`: the watertight triangle test relies on exact IEEE products (FMA contraction would break the
antisymmetry of shared-edge tests), and "no hit yet" comparisons must not be folded away.
"""

import hashlib
import os
from pathlib import Path

import numba


def _drop_stale_cache() -> None:
    """Numba keys a cached function on the timestamp of its own source file only, so a kernel inlined from a
    file that has since changed would load stale (and possibly out-of-layout) code. Keep a digest of every
    lumos source file next to the cache and wipe lumos's cache entries when it changes."""
    package = Path(__file__).resolve().parent.parent
    digest = hashlib.sha1()
    for path in sorted(package.rglob("*.py")):
        stat = path.stat()
        digest.update(f"{path.relative_to(package)}:{stat.st_mtime_ns}:{stat.st_size};".encode())
    roots = [package] if not numba.config.CACHE_DIR else [Path(numba.config.CACHE_DIR)]
    stamp = roots[0] / ".lumos-sources"
    try:
        if stamp.exists() and stamp.read_text() == digest.hexdigest():
            return
        # under NUMBA_CACHE_DIR, numba names each source folder's cache "<folder name>_<hash of its path>";
        # only these two folders hold compiled code (a shared cache directory keeps other projects' entries)
        folders = {"kernels", "methods"}
        for root in roots:
            for entry in root.rglob("*.nb[ic]"):
                if root == package or entry.parent.name.rsplit("_", 1)[0] in folders:
                    entry.unlink(missing_ok=True)
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError:
        pass  # a read-only install: numba falls back to its own checks


if os.environ.get("NUMBA_DISABLE_JIT", "0") in ("", "0"):
    _drop_stale_cache()

#: Device functions (intersection, traversal, shading: everything on the per-ray path), cached on disk. They are
#: compiled without Numba's runtime (NRT): they allocate nothing, and their callers own every array they see, so
#: they need no reference counts. With the runtime, each call that is not inlined increments and decrements the
#: count of every array in its tuple arguments (30 calls on entry and 30 on exit for `whitted.trace`), which took a
#: quarter of the ray tracers' time (perf: NRT_incref, NRT_decref) and bounced shared counters between cores.
#: (`_nrt` is the option Numba's own `register_jitable(_nrt=False)` uses.) Every decorator here states `_nrt` and
#: `forceinline`: an option a function does not state is inherited from the caller being compiled.
njit = numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=False, forceinline=False)
#: Device functions on the per-ray path that are inlined into their callers (LLVM alwaysinline). Numba passes
#: every array of a namedtuple argument as its own fields (`closest_hit` takes 96 machine arguments,
#: `illuminate_coeffs` 220), most of them on the stack, at each call that is not inlined.
njit_inline = numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=False, forceinline=True)
#: Helpers that allocate arrays (BVH build, raster bins, scratch buffers, csg crossing lists): with the runtime,
#: said explicitly, since a function called from a device function would otherwise inherit its "no runtime".
njit_alloc = numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=True, forceinline=False)
#: Top-level kernels run with prange over rows or tiles.
njit_parallel = numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy", _nrt=True,
                           forceinline=False)
prange = numba.prange
