"""Telling kernel compilation apart from rendering.

Numba compiles each kernel the first time it runs with a new signature and keeps the machine code in its
on-disk cache (`NUMBA_CACHE_DIR`, or `__pycache__` beside the sources), so only a first run after installing
(or after a change to lumos's sources) compiles. `watch_compiles` measures the time spent compiling, so that
a render's figures exclude it, and calls `on_first` when the first compilation starts.

    with watch_compiles(on_first=lambda: print("compiling...")) as watch:
        render()
    watch.seconds
"""

from __future__ import annotations

import contextlib
import time
from typing import Callable, Iterator, Optional

from numba.core import event

#: About how long a first run compiles, per method, on two cores (BENCHMARKS.md, time to first image, cold):
#: the BVH builder (~11 s) and the method's kernels.
ESTIMATE_S = {"raycast": 30, "raster": 25, "whitted": 40, "path": 45}


class CompileWatch(event.Listener):
    """Listens to Numba's "numba:compile" events (sent only when a kernel is compiled, not when it is loaded
    from the cache); nested compilations of callees count once."""

    def __init__(self, on_first: Optional[Callable[[], None]] = None):
        self.seconds = 0.0
        self.compiles = 0
        self._depth = 0
        self._t0 = 0.0
        self._on_first = on_first

    def on_start(self, event) -> None:
        if self._depth == 0:
            if self.compiles == 0 and self._on_first is not None:
                self._on_first()
            self._t0 = time.perf_counter()
            self.compiles += 1
        self._depth += 1

    def on_end(self, event) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._t0


@contextlib.contextmanager
def watch_compiles(on_first: Optional[Callable[[], None]] = None) -> Iterator[CompileWatch]:
    watch = CompileWatch(on_first)
    event.register("numba:compile", watch)
    try:
        yield watch
    finally:
        event.unregister("numba:compile", watch)
