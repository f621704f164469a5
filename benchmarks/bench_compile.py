"""Where a first render's compile time goes: each kernel family compiled on a fresh Numba cache, per top-level kernel.

    python benchmarks/bench_compile.py [--families raycast,raster,...] [--src DIR] [--json OUT.json] [--one-process]

Each family runs in a child process of its own with an empty `NUMBA_CACHE_DIR` (and `LUMOS_CACHE_DIR`), serially,
so nothing is shared between families: the sum of the rows is the whole compile of every family from scratch
(kernels a family shares with another, such as the BVH builder, count in each). `--src DIR` imports lumos from
`DIR` (a checkout's `src/`, for an A/B against another commit: `git worktree add /tmp/base HEAD~1`).

A child listens to Numba's own events: `numba:compile` (a kernel compiled, not loaded from the cache),
`numba:run_pass` (each compiler pass) and `numba:llvm_lock` (time holding LLVM). Times are exclusive: a pass that
triggers the compile of a callee does not count the callee's time, which goes to the callee's own passes. Per
top-level kernel (a compile that no other compile encloses) it reports

    total      wall time of the compile, callees included
    typeinf    Numba's type inference (`nopython_type_inference`), over the kernel and its callees
    lower      lowering to LLVM IR (`native_lowering`, `native_parfor_lowering`), LLVM time taken out
    llvm       time under the LLVM lock (optimisation, code generation, linking)
    other      the other passes (bytecode analysis, rewrites, parfor passes)
    compiles   how many (function, signature) pairs were compiled, callees included
    sigs       how many signatures of that top-level kernel were compiled (one per entry point is the aim)

With `--one-process` every family compiles in one child process, one after the other, on one fresh cache, as
`lumos warmup --jobs 1` (and a program that renders with every method) compiles them: a kernel that families share
(traversal, shading, the BVH build) compiles once, for the first family that reaches it. That is the whole compile
of lumos; the default (a fresh process per family) is what one method's first render costs.

The workloads are small renders through the public API (160×120, 1 spp) that reach every method's kernels: the
general kernels, as `lumos warmup` compiles them (LUMOS_LEAN_KERNELS=0 unless set: the showcase and the Cornell
boxes are plain scenes, whose first render elsewhere compiles the kernels for plain scenes, `compile.features`).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
FAMILIES = ("raycast", "raster", "whitted", "path", "radiosity", "queries")


def workload(family: str) -> None:
    """Render (or query) through the public API so that the family's kernels compile, as a user's first run."""
    import numpy as np

    import lumos

    showcase = lumos.load_scene(EXAMPLES / "showcase.yaml")
    small = dict(width=160, height=120, spp=1)
    if family == "raycast":
        lumos.render(showcase, method="raycast", **small)
    elif family == "raster":
        for shading in ("flat", "gouraud", "phong"):
            lumos.render(showcase, method="raster", shading=shading, **small)
    elif family == "whitted":
        lumos.render(lumos.load_scene(EXAMPLES / "whitted" / "classic.yaml"), method="whitted", **small)
    elif family == "path":
        lumos.render(lumos.load_scene(EXAMPLES / "path" / "cornell.yaml"), method="path", **small)
    elif family == "radiosity":
        lumos.render(lumos.load_scene(EXAMPLES / "radiosity" / "cornell.yaml"), method="radiosity", **small)
    elif family == "queries":
        rc = lumos.RayCaster(showcase)
        rng = np.random.default_rng(0)
        o = rng.normal(size=(64, 3)) * 0.1 + [0.2, 2.1, 8.0]
        d = rng.normal(size=(64, 3)) * 0.1 + [0.0, -0.15, -1.0]
        rc.closest(o, d)
        rc.occluded(o, d, 10.0)
        rc.all_hits(o, d)
        rc.contains(o)
        rc.path_length(o, d, 20.0)
    else:
        raise SystemExit(f"unknown family {family!r} (choose from {', '.join(FAMILIES)})")


class Recorder:
    """Exclusive time per (top-level kernel, category) from Numba's nested compile, pass and LLVM-lock events."""

    def __init__(self):
        self.stack = []  # [kind, name, start, time of nested events]
        self.top = None
        self.rows = defaultdict(lambda: defaultdict(float))
        self.sigs = defaultdict(set)
        self.llvm_depth = 0
        self.llvm_t0 = 0.0

    # numba:compile and numba:run_pass share one stack, so a pass's exclusive time leaves out its callees
    def push(self, kind, name):
        self.stack.append([kind, name, time.perf_counter(), 0.0])

    def pop(self):
        kind, name, t0, nested = self.stack.pop()
        dur = time.perf_counter() - t0
        if self.stack:
            self.stack[-1][3] += dur
        return kind, name, dur, dur - nested

    def compile_start(self, ev):
        disp = ev.data["dispatcher"]
        name = f"{disp.py_func.__module__.removeprefix('lumos.')}.{disp.py_func.__qualname__}"
        if not any(kind == "compile" for kind, *_ in self.stack):
            self.top = name
            self.sigs[name].add(str(ev.data["args"]))
        self.rows[self.top]["compiles"] += 1
        self.push("compile", name)

    def compile_end(self, ev):
        kind, name, dur, _ = self.pop()
        if not any(k == "compile" for k, *_ in self.stack):
            self.rows[name]["total"] += dur

    def pass_start(self, ev):
        self.push("pass", ev.data["name"].split(" [")[0])

    def pass_end(self, ev):
        kind, name, dur, exclusive = self.pop()
        if self.top is None:
            return
        category = {"nopython_type_inference": "typeinf", "native_lowering": "lower",
                    "native_parfor_lowering": "lower"}.get(name, "other")
        self.rows[self.top][category] += exclusive

    def llvm_start(self, ev):
        if self.llvm_depth == 0:
            self.llvm_t0 = time.perf_counter()
        self.llvm_depth += 1

    def llvm_end(self, ev):
        self.llvm_depth -= 1
        if self.llvm_depth == 0 and self.top is not None and self.stack:
            self.rows[self.top]["llvm"] += time.perf_counter() - self.llvm_t0


def child(family: str) -> None:
    from numba.core import event

    rec = Recorder()

    class L(event.Listener):
        def __init__(self, start, end):
            self._s, self._e = start, end

        def on_start(self, ev):
            self._s(ev)

        def on_end(self, ev):
            self._e(ev)

    event.register("numba:compile", L(rec.compile_start, rec.compile_end))
    event.register("numba:run_pass", L(rec.pass_start, rec.pass_end))
    event.register("numba:llvm_lock", L(rec.llvm_start, rec.llvm_end))
    t0 = time.perf_counter()
    walls = {}
    for name in family.split(","):
        t1 = time.perf_counter()
        workload(name)
        walls[name] = time.perf_counter() - t1
    wall = time.perf_counter() - t0
    rows = {}
    for name, row in rec.rows.items():
        row = dict(row)
        # lowering's events enclose the LLVM work done while lowering; report the two apart
        row["lower"] = max(row.get("lower", 0.0) - row.get("llvm", 0.0), 0.0)
        row["sigs"] = len(rec.sigs[name])
        rows[name] = row
    print(json.dumps({"family": family, "wall_s": wall, "walls": walls, "kernels": rows}))


def run_family(family: str, src: Path) -> dict:
    with tempfile.TemporaryDirectory(prefix="lumos-bench-compile-") as tmp:
        env = dict(os.environ, NUMBA_CACHE_DIR=tmp, LUMOS_CACHE_DIR=tmp, PYTHONPATH=str(src),
                   LUMOS_LEAN_KERNELS=os.environ.get("LUMOS_LEAN_KERNELS", "0"))
        proc = subprocess.run([sys.executable, __file__, "--child", family], env=env, capture_output=True,
                              text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{family} failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--src", type=Path, default=ROOT / "src")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--one-process", action="store_true",
                    help="every family in one process, one after the other, on one fresh cache")
    ap.add_argument("--child")
    args = ap.parse_args()
    if args.child:
        return child(args.child)
    if args.one_process:
        return one_process(args)

    sys.path.insert(0, str(Path(__file__).parent))
    from common import machine

    print(f"# {machine()}; lumos from {args.src}; fresh Numba cache per family")
    cols = ("total", "typeinf", "lower", "llvm", "other")
    print(f"{'family':10} {'kernel':46} " + " ".join(f"{c:>8}" for c in cols) + f" {'compiles':>8} {'sigs':>4}")
    results, grand = [], defaultdict(float)
    for family in args.families.split(","):
        res = run_family(family, args.src.resolve())
        results.append(res)
        for name, row in sorted(res["kernels"].items(), key=lambda kv: -kv[1].get("total", 0)):
            print(f"{family:10} {name[:46]:46} " + " ".join(f"{row.get(c, 0):8.2f}" for c in cols)
                  + f" {int(row.get('compiles', 0)):8d} {row['sigs']:4d}", flush=True)
            for c in cols + ("compiles",):
                grand[c] += row.get(c, 0)
        grand["wall"] += res["wall_s"]
        print(f"{family:10} {'(whole workload, wall)':46} {res['wall_s']:8.2f}", flush=True)
    print(f"{'all':10} {'(sum of the families)':46} " + " ".join(f"{grand[c]:8.2f}" for c in cols)
          + f" {int(grand['compiles']):8d}")
    print(f"whole compile, every family, serial: {grand['total']:.1f} s (workloads' wall {grand['wall']:.1f} s)")
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))


def one_process(args) -> None:
    sys.path.insert(0, str(Path(__file__).parent))
    from common import machine

    print(f"# {machine()}; lumos from {args.src}; every family in one process, one fresh Numba cache")
    res = run_family(args.families, args.src.resolve())
    cols = ("total", "typeinf", "lower", "llvm", "other")
    grand = {c: sum(row.get(c, 0.0) for row in res["kernels"].values()) for c in cols + ("compiles",)}
    for name, wall in res["walls"].items():
        print(f"{name:10} {wall:8.2f} s (wall, after the families above it)")
    print(f"{'all':10} " + " ".join(f"{c} {grand[c]:.2f}" for c in cols) + f" compiles {int(grand['compiles'])}")
    print(f"whole compile, every family, serial, one process: {grand['total']:.1f} s of compiling "
          f"(workloads' wall {res['wall_s']:.1f} s)")
    if args.json:
        args.json.write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
