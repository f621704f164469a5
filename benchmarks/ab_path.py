"""Two versions of lumos's path tracer, timed side by side in one process: the working tree against a git revision.

    python benchmarks/ab_path.py REV [--spp 32] [--threads 2] [--rounds 8] [--scene examples/path/cornell.yaml]

On a shared machine the speed of a render drifts by ±10-20% from minute to minute, far more than most changes to
a kernel are worth, so two versions timed one after the other in separate runs cannot be told apart. Here both are
imported into one process (the revision's `src/lumos`, from `git archive`, as the package `lumos_base`; the working
tree's as `lumos_work`), compiled, and rendered alternately, round by round, each round starting with the other
one; the ratio of each round's two times cancels the drift that both see. Reported: min / median / max time of
each and the median of the per-round ratios (work / base, below 1 is faster), and whether the last round's two
images are the same.

Both compile into a fresh temporary NUMBA_CACHE_DIR (about a minute each), so neither loads kernels the other or an
earlier run cached. The second version in one process can read a few per cent slower for identical code (an A/A
run of whitted read 1.06): for effects that small, `ab_process.py` runs each version in processes of its own.
"""

from __future__ import annotations

import argparse
import importlib
import io
import os
import shutil
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def package_tree(tree: Path, name: str, source: Path | None = None, rev: str | None = None) -> None:
    """lumos's source, from the working tree or a revision, as package `name` in `tree`."""
    target = tree / name
    if rev is None:
        shutil.copytree(source, target, ignore=shutil.ignore_patterns("__pycache__"))
    else:
        blob = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src/lumos"], check=True,
                              capture_output=True).stdout
        with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
            tar.extractall(tree / "_archive", filter="data")
        shutil.move(tree / "_archive" / "src" / "lumos", target)
    # the method table names its modules absolutely; everything else imports relatively
    api = target / "api.py"
    api.write_text(api.read_text().replace('"lumos.methods', f'"{name}.methods'))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("rev", help="git revision to compare the working tree against (e.g. HEAD, a commit)")
    parser.add_argument("--spp", type=int, default=32)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=8)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--max-depth", type=int, default=6)
    parser.add_argument("--scene", default=str(ROOT / "examples" / "path" / "cornell.yaml"))
    args = parser.parse_args()

    tree = Path(tempfile.mkdtemp(prefix="lumos-ab-"))
    try:
        os.environ["NUMBA_CACHE_DIR"] = str(tree / "numba_cache")  # before numba is imported
        package_tree(tree, "lumos_base", rev=args.rev)
        package_tree(tree, "lumos_work", source=ROOT / "src" / "lumos")
        sys.path.insert(0, str(tree))
        versions = {name: importlib.import_module(f"lumos_{name}") for name in ("base", "work")}
        scenes = {name: module.load_scene(args.scene) for name, module in versions.items()}
        settings = dict(method="path", width=args.size, height=args.size, max_depth=args.max_depth,
                        threads=args.threads)
        for name, module in versions.items():
            t0 = time.perf_counter()
            module.render(scenes[name], spp=1, **settings)
            print(f"{name}: compiled and warm in {time.perf_counter() - t0:.0f} s", flush=True)
        times = {name: [] for name in versions}
        images = {}
        for r in range(args.rounds):
            order = ["base", "work"] if r % 2 == 0 else ["work", "base"]
            for name in order:
                t0 = time.perf_counter()
                image = versions[name].render(scenes[name], spp=args.spp, seed=r, **settings)
                times[name].append(time.perf_counter() - t0)
                images[name] = image.array
        print(f"{Path(args.scene).name}, {args.size}x{args.size}, {args.spp} spp, max_depth {args.max_depth}, "
              f"{args.threads} threads, {args.rounds} rounds; base = {args.rev}, work = the working tree")
        for name in versions:
            ts = times[name]
            print(f"  {name}: {min(ts):.3f} / {statistics.median(ts):.3f} / {max(ts):.3f} s (min / median / max)")
        ratios = [w / b for w, b in zip(times["work"], times["base"])]
        print(f"  work / base: median of per-round ratios {statistics.median(ratios):.3f} "
              f"(min {min(ratios):.3f}, max {max(ratios):.3f})")
        diff = np.abs(images["work"].astype(np.float64) - images["base"]).max()
        print("  last round's images: " + ("identical" if diff == 0 else f"differ, max |work - base| = {diff:.3g}"))
    finally:
        shutil.rmtree(tree, ignore_errors=True)


if __name__ == "__main__":
    main()
