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
import json
import os
import time
from pathlib import Path
from typing import Callable, Iterator, Optional

from numba.core import event

#: About how long a first run compiles every kernel of a method on two cores (a first render on a fresh cache, its
#: `jit_s`: BENCHMARKS.md, 2026-12-05, eighth session), when no warm-up has measured it on this machine; raycast,
#: raster, whitted and path share their compile with a helper process on the other core, which also compiles the
#: BVH build's kernels (`api.compile_with_helper`), radiosity compiles in its own process.
ESTIMATE_S = {"raycast": 8, "raster": 8, "whitted": 14, "path": 17, "radiosity": 11}


#: the file beside the kernels where `lumos warmup` keeps what each kernel family took to compile
TIMINGS = "timings.json"


def timings_path() -> Path:
    from .kernels.cache import cache_dirs

    return cache_dirs()[0] / TIMINGS


def read_timings() -> dict:
    """{family: {"compile_s": seconds}} of the last warm-up here that compiled each family."""
    try:
        return json.loads(timings_path().read_text())
    except (OSError, ValueError):
        return {}


def save_timings(compile_s: dict) -> None:
    """Record {family: seconds compiled} (a warm-up's), keeping the other families' figures."""
    timings = read_timings()
    timings.update({family: {"compile_s": round(s, 2)} for family, s in compile_s.items()})
    try:
        path = timings_path()
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(timings, indent=1, sort_keys=True))
        os.replace(tmp, path)
    except OSError:
        pass  # a read-only cache: estimates fall back to ESTIMATE_S


def estimate_s(method: str) -> float:
    """Seconds a first run of `method` compiles: what `lumos warmup` last measured here for the method's kernels
    (its family: each method is one) and the BVH build, else ESTIMATE_S."""
    timings = read_timings()
    if method not in timings:
        return ESTIMATE_S.get(method, 60)
    return timings[method]["compile_s"] + timings.get("bvh", {}).get("compile_s", 0.0)


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
