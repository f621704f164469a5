"""Where the traversal's arrays live: on cache-line boundaries, and big ones in transparent huge pages.

An incoherent ray visits nodes and leaves all over a large tree, and with 4 KiB pages nearly every visit also
misses the TLB (a 1.3M-triangle scene's wide nodes and leaf rows span 80 MB: 20,000 pages, ten times what the
second-level TLB of a current x86 core maps). Backed by 2 MiB pages the same arrays take 40 entries. Linux gives
an anonymous mapping huge pages when it is advised to (`MADV_HUGEPAGE`, the default `madvise` setting of
/sys/kernel/mm/transparent_hugepage/enabled), as Embree does for its BVH; measured here, 1M incoherent closest
hits against that scene took 27% less time (BENCHMARKS.md). Elsewhere (no madvise, THP off) the arrays are plain
aligned NumPy memory and nothing else changes.
"""

from __future__ import annotations

import mmap

import numpy as np

HUGE_PAGE = 2 << 20
#: arrays at least this big are put in huge pages (smaller ones are cached well enough, and rounding a small
#: array up to a 2 MiB boundary would waste more than it saves)
HUGE_MIN = 4 << 20


def aligned_zeros(shape, dtype, align: int = 64) -> np.ndarray:
    """A zero-filled C-contiguous array whose first byte lies on an `align`-byte boundary (a 2 MiB one, in memory
    advised as huge pages, when it holds at least HUGE_MIN bytes and the platform has MADV_HUGEPAGE)."""
    dtype = np.dtype(dtype)
    shape = tuple(int(s) for s in np.atleast_1d(shape))
    nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if nbytes >= HUGE_MIN and hasattr(mmap, "MADV_HUGEPAGE"):
        try:  # private and anonymous: shared anonymous memory is shmem, which THP treats separately
            block = mmap.mmap(-1, nbytes + HUGE_PAGE, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
            block.madvise(mmap.MADV_HUGEPAGE)  # before the first touch: the pages are faulted in as huge ones
        except (OSError, ValueError):
            pass
        else:
            raw = np.frombuffer(block, np.uint8)  # the array keeps the mapping alive; it is zero-filled
            skip = -raw.ctypes.data % HUGE_PAGE
            return raw[skip:skip + nbytes].view(dtype).reshape(shape)
    raw = np.zeros(nbytes + align, np.uint8)
    skip = -raw.ctypes.data % align
    return raw[skip:skip + nbytes].view(dtype).reshape(shape)


def aligned_copy(a: np.ndarray, align: int = 64) -> np.ndarray:
    """`a` copied into `aligned_zeros` memory."""
    out = aligned_zeros(a.shape, a.dtype, align)
    out[...] = a
    return out
