"""Two versions of lumos, one method, timed side by side in one process: the working tree against a git revision.

    python benchmarks/ab_render.py REV --method raycast [--scene examples/showcase.yaml] [--width 640]
                                   [--height 480] [--spp 4] [--rounds 8] [--threads 2] [--set KEY=VALUE ...]

`ab_path.py` for any method: both versions are imported into one process (the revision's `src/lumos` from
`git archive` as `lumos_base`, the working tree's as `lumos_work`), compiled, and rendered alternately, each round
starting with the other one; the per-round ratio of the kernels' own times (`render_s`: the scene compile and the
BVH build are left out) cancels the drift both see. `--set` passes more render settings (`--set shading=flat
--set antialias=adaptive`). Reported: min / median / max `render_s` of each, the median of the per-round ratios
(work / base, below 1 is faster), and whether the last round's images are identical. An A/A run of identical trees
read 1.06 for whitted here; for effects of a few per cent use `ab_process.py`.
"""

from __future__ import annotations

import argparse
import importlib
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ab_path import ROOT, package_tree


def _value(text: str):
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text.lower(), text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("rev", help="git revision to compare the working tree against (e.g. HEAD, a commit)")
    parser.add_argument("--method", default="raycast")
    parser.add_argument("--scene", default=str(ROOT / "examples" / "showcase.yaml"))
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--spp", type=int, default=4)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=8)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()

    tree = Path(tempfile.mkdtemp(prefix="lumos-ab-"))
    try:
        os.environ["NUMBA_CACHE_DIR"] = str(tree / "numba_cache")  # before numba is imported
        package_tree(tree, "lumos_base", rev=args.rev)
        package_tree(tree, "lumos_work", source=ROOT / "src" / "lumos")
        sys.path.insert(0, str(tree))
        versions = {name: importlib.import_module(f"lumos_{name}") for name in ("base", "work")}
        scenes = {name: module.load_scene(args.scene) for name, module in versions.items()}
        settings = dict(method=args.method, width=args.width, height=args.height, spp=args.spp,
                        threads=args.threads)
        settings.update({k: _value(v) for k, v in (s.split("=", 1) for s in args.set)})
        for name, module in versions.items():
            t0 = time.perf_counter()
            module.render(scenes[name], **{**settings, "width": 16, "height": 12})
            print(f"{name}: compiled and warm in {time.perf_counter() - t0:.0f} s", flush=True)
        times = {name: [] for name in versions}
        images = {}
        for r in range(args.rounds):
            order = ["base", "work"] if r % 2 == 0 else ["work", "base"]
            for name in order:
                image = versions[name].render(scenes[name], **settings)
                times[name].append(image.stats["render_s"])
                images[name] = image.array
        extra = "".join(f", {s}" for s in args.set)
        print(f"{args.method}, {Path(args.scene).name}, {args.width}x{args.height}, {args.spp} spp{extra}, "
              f"{args.threads} threads, {args.rounds} rounds; base = {args.rev}, work = the working tree")
        for name in versions:
            ts = times[name]
            print(f"  {name}: {min(ts):.3f} / {statistics.median(ts):.3f} / {max(ts):.3f} s render_s "
                  "(min / median / max)")
        ratios = [w / b for w, b in zip(times["work"], times["base"])]
        print(f"  work / base: median of per-round ratios {statistics.median(ratios):.3f} "
              f"(min {min(ratios):.3f}, max {max(ratios):.3f})")
        diff = np.abs(images["work"].astype(np.float64) - images["base"]).max()
        print("  last round's images: " + ("identical" if diff == 0 else f"differ, max |work - base| = {diff:.3g}"))
    finally:
        shutil.rmtree(tree, ignore_errors=True)


if __name__ == "__main__":
    main()
