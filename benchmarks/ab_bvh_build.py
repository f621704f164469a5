"""The BVH build of two lumos source trees, each in processes of its own, alternating (as `ab_process.py` does for
renders): the binary tree of trimesh's icosphere (1,310,720 triangles by default), best of `--repeats` per round.

    python benchmarks/ab_bvh_build.py BASE_SRC WORK_SRC [--subdivisions 8] [--rounds 4] [--repeats 3] [--threads N]

Also checks that both trees build the same tree (node boxes, links, order and depth).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import icosphere, machine  # noqa: E402

CHILD = """
import hashlib, json, sys, time
import numpy as np
from lumos.compile.bvh import build
bounds = np.load(sys.argv[1])
build(bounds[:5000])  # compiled (or loaded) before the clock starts
times = []
for _ in range(int(sys.argv[2])):
    t = time.perf_counter()
    tree = build(bounds)
    times.append(time.perf_counter() - t)
digest = hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in tree[:3]) + str(tree[3]).encode())
print(json.dumps({"best": min(times), "tree": digest.hexdigest(), "nodes": len(tree[0])}))
"""


def run(src: Path, cache: str, bounds_file: str, repeats: int, threads: int | None) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), LUMOS_CACHE_DIR=cache)
    if threads:
        env["NUMBA_NUM_THREADS"] = str(threads)
    out = subprocess.run([sys.executable, "-c", CHILD, bounds_file, str(repeats)], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base", type=Path)
    ap.add_argument("work", type=Path)
    ap.add_argument("--subdivisions", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int)
    args = ap.parse_args()
    import numpy as np

    v, f = icosphere(args.subdivisions)
    tri = v[f]
    bounds = np.concatenate([tri.min(axis=1), tri.max(axis=1)], axis=1)
    with tempfile.TemporaryDirectory() as tmp:
        bounds_file = os.path.join(tmp, "bounds.npy")
        np.save(bounds_file, bounds)
        caches = {name: os.path.join(tmp, name) for name in ("base", "work")}
        times = {"base": [], "work": []}
        trees = {}
        for r in range(args.rounds):
            order = ("base", "work") if r % 2 == 0 else ("work", "base")
            for name in order:
                got = run(getattr(args, name), caches[name], bounds_file, args.repeats, args.threads)
                times[name].append(got["best"])
                trees[name] = (got["tree"], got["nodes"])
    print(f"# {machine()}; BVH build of {len(bounds):,} triangles, {args.rounds} rounds, best of {args.repeats}")
    for name in ("base", "work"):
        t = times[name]
        print(f"  {name}: {min(t):.3f} / {statistics.median(t):.3f} / {max(t):.3f} s (min / median / max), "
              f"{trees[name][1]:,} nodes")
    ratios = [w / b for w, b in zip(times["work"], times["base"])]
    print(f"  work / base: median of per-round ratios {statistics.median(ratios):.3f} "
          f"(min {min(ratios):.3f}, max {max(ratios):.3f})")
    print(f"  same tree: {trees['base'][0] == trees['work'][0]}")


if __name__ == "__main__":
    main()
