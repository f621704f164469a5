"""Record the compile plans a cold first render shares with a helper process (`methods.compile_plan`).

    python -m lumos.tools.plans                     # raycast, raster, whitted, path, from a checkout (it renders
                                                    # its examples)
    python -m lumos.tools.plans --methods path,path-lean

For each method, a child process renders the method's example at 160×120, 1 spp, on an empty kernel cache, with
no helper, and listens to Numba's compile events: every function compiled under the method's top-level kernel,
in order, with its own (exclusive) compile time, and which device function calls which. `choose` then picks the
subtrees a helper process compiles meanwhile and those the render compiles first (simulating both processes on
those times), and the plan is written to `src/lumos/methods/plans/<method>.json`. `<method>-lean` is recorded on
the same scene, a plain one, with the kernels compiled for its lean arrays (`compile.features`); `<method>` with
the general kernels (LUMOS_LEAN_KERNELS=0). Run it again after changing kernels: roots whose sources changed are
skipped by the helper until then (the renders stay right, only slower to compile).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ..methods.common import LEAN_METHODS
from ..methods.compile_plan import LEAN, PLAN_DIR, encode_args, resolve

#: what each planned method's first render is recorded on (bench_first_image's scenes): the methods whose first
#: render compiles beside a helper (`api.WITH_HELPER`)
SCENES = {"raycast": "showcase.yaml", "raster": "showcase.yaml", "whitted": "showcase.yaml",
          "path": "path/cornell.yaml"}
#: the plans recorded: each method's, and a plain scene's for the methods whose kernels compile to it
PLANS = tuple(SCENES) + tuple(m + LEAN for m in SCENES if m in LEAN_METHODS)
#: the modules of the BVH build's kernels, which the helper compiles after its share (`lumos warmup --methods bvh`)
BVH_MODULES = ("lumos.kernels.bvh_build",)
#: the helper's first compile starts this much later than the render's (the render starts it after its imports
#: and the scene's; then its own interpreter, imports, plan and Numba's first compile: measured from both
#: processes' compile events), and loading an entry another process compiled costs about this (seconds)
HELPER_START_S = 1.3
LOAD_S = 0.01


def record(name: str, examples: Path) -> dict:
    """What a cold first render for plan `name` compiles, in this process: {order: [[module, name], ...] in the order
    their compiles finished, excl: seconds each, calls: [[caller, callee], ...] (indices into order), args:
    {index: encoded argument types} for the device functions, top: the top-level kernel that took longest,
    top_arg: the type of its first argument (the scene arrays, general or lean) as a 1-tuple, bvh_s:
    the compile time of the BVH build's kernels (which the helper compiles after its share), left out of the
    rest}."""
    from numba.core import event

    from .. import load_scene, render
    from ..kernels.jit import DeviceDispatcher

    tops: dict[tuple, float] = {}  # the top-level kernels, and their whole compile
    stack: list[list] = []  # [key, start, nested]
    order: list[tuple] = []
    excl: dict[tuple, float] = {}
    args: dict[tuple, str] = {}
    calls: set[tuple] = set()
    outside = [0.0]
    inside = [False]

    def key_of(dispatcher) -> tuple:
        return dispatcher.py_func.__module__, dispatcher.py_func.__qualname__

    class Compiles(event.Listener):
        def on_start(self, ev):
            key = key_of(ev.data["dispatcher"])
            if not stack and key[0] not in BVH_MODULES:
                inside[0] = True
                tops.setdefault(key, 0.0)
            stack.append([key, time.perf_counter(), 0.0])

        def on_end(self, ev):
            key, start, nested = stack.pop()
            took = time.perf_counter() - start
            if stack:
                stack[-1][2] += took
            if not inside[0]:
                if not stack:
                    outside[0] += took
                return
            if key not in excl:
                order.append(key)
                excl[key] = 0.0
                dispatcher = ev.data["dispatcher"]
                if isinstance(dispatcher, DeviceDispatcher):
                    try:
                        args[key] = encode_args(ev.data["args"])
                    except Exception:  # (a type that does not pickle: never a root)
                        pass
            excl[key] += took - nested
            if not stack:
                inside[0] = False
                tops[key] += took

    plain_template = DeviceDispatcher.get_call_template

    def get_call_template(self, call_args, kws):
        if inside[0] and stack:
            calls.add((stack[-1][0], key_of(self)))
        return plain_template(self, call_args, kws)

    DeviceDispatcher.get_call_template = get_call_template
    event.register("numba:compile", Compiles())
    method = name.removesuffix(LEAN)
    render(load_scene(examples / SCENES[method]), method=method, width=160, height=120, spp=1)
    index = {key: i for i, key in enumerate(order)}
    top = max(tops, key=tops.get)
    return {"order": [list(k) for k in order], "excl": [excl[k] for k in order],
            "calls": sorted([index[a], index[b]] for a, b in calls if a in index and b in index),
            "args": {str(index[k]): v for k, v in args.items()}, "top": list(top),
            "top_arg": encode_args(next(iter(resolve(*top).overloads))[:1]), "bvh_s": outside[0]}


def _closures(n: int, calls: list) -> list[list[int]]:
    """Each function's callees, transitively, itself included, in compile order (a function's callees finish
    before it does, so the recorded order is the order a compile of any one of them takes them in)."""
    kids: dict[int, list[int]] = {}
    for a, b in calls:
        kids.setdefault(a, []).append(b)
    out = []
    for i in range(n):
        seen, todo = {i}, [i]
        while todo:
            for c in kids.get(todo.pop(), ()):
                if c not in seen:
                    seen.add(c)
                    todo.append(c)
        out.append(sorted(seen))
    return out


def simulate(first: list[int], roots: list[int], excl: list[float], closures: list[list[int]],
             start: float = HELPER_START_S, load: float = LOAD_S) -> tuple[float, float]:
    """When the render's compile and the helper's share end (seconds) if the render compiles the closures of
    `first` in that order and then everything else in the recorded order, while the helper, from `start`,
    compiles the closures of `roots` in that order. Each loads what the other has finished when it gets there,
    waits for what the other is compiling (`cache`'s claims), and compiles the rest."""
    inf = float("inf")
    order, seen = [], set()
    for k in [k for r in first for k in closures[r]] + list(range(len(excl))):
        if k not in seen:
            seen.add(k)
            order.append(k)

    def walk(keys, t, other_start, other_done):
        began, done = {}, {}
        for k in keys:
            if k in done:
                continue
            if other_done.get(k, inf) <= t:
                t += load
            elif other_start.get(k, inf) <= t:
                t = other_done[k] + load  # claimed over there: wait for it
            else:
                began[k] = t
                t += excl[k]
            done[k] = t
        return t, began, done

    helper_keys = [k for r in roots for k in closures[r]]
    main_began: dict[int, float] = {}
    main_done: dict[int, float] = {}
    t_main = t_helper = 0.0
    for _ in range(4):  # each side's timeline depends on the other's: a few rounds settle it
        t_helper, helper_began, helper_done = walk(helper_keys, start, main_began, main_done)
        t_main, main_began, main_done = walk(order, 0.0, helper_began, helper_done)
    return t_main, t_helper


def choose(excl: list[float], calls: list, candidates: set[int], bvh_s: float):
    """Which subtrees the render compiles first (before its top-level kernel, in compile order) and which the helper
    compiles meanwhile (in compile order or against it, whichever is quicker; then the BVH build's kernels), to shorten
    max(the render's compile, the helper's share + the BVH build's compile): a local search from nothing, whose
    moves give a function's subtree to one side, take a root away, or hand it to the other side, taking the best
    move until none helps. Returns (first, roots, that time, the render's compile alone)."""
    closures = _closures(len(excl), calls)
    alone = sum(excl)

    def tidy(picked, reverse):
        picked = sorted(set(picked), reverse=reverse)
        return [r for r in picked if not any(r != o and r in closures[o] for o in picked)]

    def cost(first, roots):
        t_main, t_helper = simulate(first, roots, excl, closures)
        return max(t_main, t_helper + bvh_s)

    first, roots = [], []
    best = cost(first, roots)
    while True:
        moves = []
        for c in sorted(candidates):
            moves.append((tidy(first + [c], False), roots))
            moves += [(first, tidy(roots + [c], order)) for order in (False, True)]
        for r in first:
            rest = [o for o in first if o != r]
            moves += [(rest, roots)] + [(rest, tidy(roots + [r], order)) for order in (False, True)]
        for r in roots:
            rest = [o for o in roots if o != r]
            moves += [(first, rest), (tidy(first + [r], False), rest)]
        pick = min(moves, key=lambda m: cost(*m), default=None)
        if pick is None or cost(*pick) >= best - 1e-3:
            return first, roots, best, alone
        first, roots = pick
        best = cost(first, roots)


def plan_of(method: str, rec: dict) -> dict:
    """The plan JSON object for `method` from a `record`ing."""
    from ..kernels.cache import closure_stamp

    candidates = {int(i) for i in rec["args"]}
    first, roots, finish, alone = choose(rec["excl"], rec["calls"], candidates, rec["bvh_s"])

    def entries(picked):
        out = []
        for r in picked:
            module, name = rec["order"][r]
            out.append({"module": module, "name": name, "stamp": closure_stamp(resolve(module, name).py_func),
                        "args": rec["args"][str(r)]})
        return out

    return {"method": method, "top": rec["top"], "top_arg": rec["top_arg"],
            "recorded": {"date": time.strftime("%Y-%m-%d"), "machine": platform.processor() or platform.machine(),
                         "compile_alone_s": round(alone, 2), "bvh_s": round(rec["bvh_s"], 2),
                         "predicted_s": round(finish, 2), "functions": len(rec["order"])},
            "first": entries(first), "roots": entries(roots)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(PLANS), help="plans to record (default: %(default)s)")
    ap.add_argument("--examples", type=Path, default=Path(__file__).resolve().parents[3] / "examples",
                    help="the checkout's examples folder (default: %(default)s)")
    ap.add_argument("--child", metavar="METHOD", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(record(args.child, args.examples)))
        return 0
    for method in args.methods.split(","):
        with tempfile.TemporaryDirectory(prefix="lumos-plan-") as cache:
            env = {**os.environ, "LUMOS_CACHE_DIR": cache, "NUMBA_CACHE_DIR": cache,
                   "LUMOS_COMPILE_HELPER": "0", "LUMOS_LEAN_KERNELS": "1" if method.endswith(LEAN) else "0"}
            out = subprocess.run([sys.executable, "-m", "lumos.tools.plans", "--child", method, "--examples",
                                  str(args.examples)], env=env, capture_output=True, text=True, check=True)
        plan = plan_of(method, json.loads(out.stdout.strip().splitlines()[-1]))
        PLAN_DIR.mkdir(exist_ok=True)
        (PLAN_DIR / f"{method}.json").write_text(json.dumps(plan, indent=1) + "\n")
        rec = plan["recorded"]
        print(f"{method}: {rec['functions']} functions, {rec['compile_alone_s']} s alone; about "
              f"{rec['predicted_s']} s with {len(plan['first'])} subtrees first and {len(plan['roots'])} in the helper "
              f"(then the BVH build's {rec['bvh_s']} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
