"""How kernels run on several cores: serial `nogil` kernels over a range of rows (or chunks), called on Python threads.

A top-level kernel (`jit.njit_serial`) computes rows k0 … k1−1 of its output and releases the GIL; `parallel_for`
hands out runs of rows to `numba.get_num_threads()` threads (the caller's included) as each finishes its last, so a
slow row does not hold up a thread that was given a fixed share. Each row is computed by itself, whoever runs it,
so the result is the same on any number of threads.

Why not `parallel=True` and `prange`: Numba lowers a parallel loop's body into a function of its own and optimises
it, with every callee inlined, apart from the kernel around it, which about doubles LLVM's share of the compile
(`benchmarks/bench_compile.py`: the path tracer's `_pass_rows` 32 → 23 s, ray casting's 24 → 19 s).
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numba

_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()


def _executor() -> ThreadPoolExecutor:
    global _pool
    with _pool_lock:
        if _pool is None:
            _pool = ThreadPoolExecutor(max(1, numba.config.NUMBA_NUM_THREADS - 1), thread_name_prefix="lumos")
        return _pool


def parallel_for(body, lo: int, hi: int, grain: int | None = None, threads: int | None = None) -> None:
    """Call body(k0, k1) over runs of [lo, hi) that cover it once, on `threads` threads (default: Numba's
    thread count for the calling thread, which `--threads` sets), the calling thread among them. Runs are `grain`
    long (default: a quarter of an even share, so the last runs even out the threads' loads).

    Safe to nest and to call from several threads at once: the caller works through the runs itself, and a
    helper that has not started by the time the runs are gone is cancelled, never waited for."""
    n = hi - lo
    if n <= 0:
        return
    workers = min(threads or numba.get_num_threads(), n)
    if workers <= 1:
        body(lo, hi)
        return
    grain = grain or max(1, n // (4 * workers))
    starts = iter(range(lo, hi, grain))
    take = threading.Lock()
    errors: list[BaseException] = []

    def work():
        while not errors:
            with take:
                k0 = next(starts, None)
            if k0 is None:
                return
            try:
                body(k0, min(hi, k0 + grain))
            except BaseException as exc:  # re-raised in the caller
                errors.append(exc)

    helpers = [_executor().submit(work) for _ in range(workers - 1)]
    work()
    for helper in helpers:
        if not helper.cancel():
            helper.result()
    if errors:
        raise errors[0]
