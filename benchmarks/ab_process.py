"""Two lumos source trees, one method, each rendered in processes of its own, alternating: no shared process.

    python benchmarks/ab_process.py BASE_SRC WORK_SRC --method whitted --scene examples/whitted/classic.yaml
                                    [--width 1024] [--height 768] [--spp 1] [--rounds 8] [--set KEY=VALUE ...]

`ab_render.py` imports both versions into one process, which cancels machine drift but not what the process does
to the second version (code placement: an A/A run of identical trees reads 1.03-1.08 for `whitted`). Here each
round starts one process per version (base and work in turn, the order swapped every round), renders once to load
the kernels and then `--repeats` times, and keeps the fastest `render_s`; each tree has its own kernel cache,
filled before the rounds. Reported as ab_render.py does.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = """
import json, sys, lumos
settings = json.loads(sys.argv[2])
scene = lumos.load_scene(sys.argv[1])
lumos.render(scene, **settings)
best = min(lumos.render(scene, **settings).stats["render_s"] for _ in range(int(sys.argv[3])))
print(json.dumps(best))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base")
    ap.add_argument("work")
    ap.add_argument("--method", default="raycast")
    ap.add_argument("--scene", default="examples/showcase.yaml")
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    settings = dict(method=args.method, width=args.width, height=args.height, spp=args.spp)
    for item in args.set:
        key, value = item.split("=", 1)
        settings[key] = json.loads(value) if value[:1].isdigit() or value in ("true", "false") else value
    with tempfile.TemporaryDirectory(prefix="lumos-abp-") as tmp:
        def run(name, src, repeats):
            env = dict(os.environ, PYTHONPATH=str(Path(src).resolve()), LUMOS_CACHE_DIR=f"{tmp}/{name}",
                       NUMBA_CACHE_DIR=f"{tmp}/{name}-numba")
            out = subprocess.run([sys.executable, "-c", CHILD, args.scene, json.dumps(settings), str(repeats)],
                                 env=env, capture_output=True, text=True)
            if out.returncode:
                raise SystemExit(out.stderr[-2000:])
            return json.loads(out.stdout.strip().splitlines()[-1])

        trees = {"base": args.base, "work": args.work}
        for name, src in trees.items():
            run(name, src, 1)  # compile into its cache
        times = {name: [] for name in trees}
        for r in range(args.rounds):
            for name in (["base", "work"] if r % 2 == 0 else ["work", "base"]):
                times[name].append(run(name, trees[name], args.repeats))
    print(f"{args.method}, {Path(args.scene).name}, {args.width}x{args.height}, {args.spp} spp, {args.rounds} rounds "
          f"of one process each, best of {args.repeats}; base = {args.base}, work = {args.work}")
    for name, ts in times.items():
        print(f"  {name}: {min(ts):.3f} / {statistics.median(ts):.3f} / {max(ts):.3f} s render_s (min / median / max)")
    ratios = [w / b for w, b in zip(times["work"], times["base"])]
    print(f"  work / base: median of per-round ratios {statistics.median(ratios):.3f} (min {min(ratios):.3f}, "
          f"max {max(ratios):.3f})")


if __name__ == "__main__":
    main()
