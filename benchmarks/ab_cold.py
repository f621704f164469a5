"""Cold first renders of two versions of lumos, alternating: what a change does to the first render on an empty
kernel cache (an editable install that never ran `lumos warmup`).

    python benchmarks/ab_cold.py BASE/src WORK/src [--methods raycast,raster,whitted,path] [--rounds 2]
                                 [--base-env NAME=VALUE ...] [--work-env NAME=VALUE ...]

Each run is one whole process, `lumos render S --method M --width 160 --height 120 --spp 1` with `PYTHONPATH` the
version's `src/` and `LUMOS_CACHE_DIR` a fresh empty folder (S: the showcase; path and radiosity their Cornell
boxes, as `bench_first_image.py`), timed around the process; its `--stats` give the time spent compiling. Base and
work run back to back, method by method, round by round, so that the machine's drift falls on both; the images of
each pair are compared byte for byte. Prints each pair and the ratios work / base. `--base-env` and `--work-env`
set an environment variable for one side's processes: one tree against itself, e.g. without its helper process
(LUMOS_COMPILE_HELPER=0) and with the general kernels against those for plain scenes (LUMOS_LEAN_KERNELS=0 on the
base side).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = {"path": "path/cornell.yaml", "radiosity": "radiosity/cornell.yaml"}


def cold_render(src: Path, method: str, work: Path, extra_env: dict) -> tuple[float, float, bytes]:
    """(whole process seconds, compiling seconds, the PNG's bytes) of one cold render with lumos from `src`, with
    `extra_env` in its environment."""
    cache = Path(tempfile.mkdtemp(dir=work))
    out, stats = work / "out.png", work / "stats.json"
    env = {**os.environ, **extra_env, "PYTHONPATH": str(src), "LUMOS_CACHE_DIR": str(cache)}
    env.pop("NUMBA_CACHE_DIR", None)
    scene = ROOT / "examples" / SCENES.get(method, "showcase.yaml")
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "lumos", "render", str(scene), "--method", method, "--width", "160",
                    "--height", "120", "--spp", "1", "-o", str(out), "--stats", str(stats)], env=env, check=True,
                   capture_output=True)
    wall = time.perf_counter() - t0
    return wall, json.loads(stats.read_text())["jit_s"], out.read_bytes()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base", type=Path, help="the base version's src/ folder")
    ap.add_argument("work", type=Path, help="the new version's src/ folder")
    ap.add_argument("--methods", default="raycast,raster,whitted,path")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--base-env", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--work-env", action="append", default=[], metavar="NAME=VALUE")
    args = ap.parse_args()
    sides = [(args.base, dict(v.split("=", 1) for v in args.base_env)),
             (args.work, dict(v.split("=", 1) for v in args.work_env))]
    ratios: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory(prefix="lumos-ab-cold-") as tmp:
        for r in range(1, args.rounds + 1):
            for method in args.methods.split(","):
                (b_wall, b_jit, b_png), (w_wall, w_jit, w_png) = (
                    cold_render(src.resolve(), method, Path(tmp), env) for src, env in sides)
                same = "same image" if b_png == w_png else "IMAGES DIFFER"
                print(f"round {r} {method:9s} base {b_wall:6.2f} s ({b_jit:5.2f})  work {w_wall:6.2f} s "
                      f"({w_jit:5.2f})  {w_wall / b_wall:.3f}  {same}", flush=True)
                ratios.setdefault(method, []).append(w_wall / b_wall)
    for method, values in ratios.items():
        print(f"{method:9s} work / base: {', '.join(f'{v:.3f}' for v in values)}")


if __name__ == "__main__":
    main()
