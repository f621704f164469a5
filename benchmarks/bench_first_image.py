"""Time to first image: the whole `lumos render` process, from a cold and from a warm Numba cache.

    python benchmarks/bench_first_image.py [--repeats 3] [--width 320] [--height 240]

For each scene, `lumos render SCENE -o out.png --width 320 --height 240 --stats stats.json` runs as a child
process, timed with `time.perf_counter` around `subprocess.run`:

    cold  NUMBA_CACHE_DIR is a fresh empty folder, so every kernel compiles (a user's very first render)
    warm  the same folder again, now filled by the cold run; best of `--repeats`

The scenes are `examples/showcase.yaml` (every primitive and light, the 69k-triangle bunny; rendered at its own
`spp`) and a one-sphere, one-light scene. Besides the wall time of the process, the table shows the figures
the process reports itself (`--stats`): load (parse, validate, read meshes), build (flatten + BVH; includes
compiling the BVH builder when cold), render (includes compiling the render kernels when cold), and startup,
which is the wall time not covered by the command's own `total_s` (interpreter start, imports).
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

from common import machine

ROOT = Path(__file__).resolve().parent.parent

SPHERE = """\
camera: {position: [0, 0, 4], look_at: [0, 0, 0], fov: 40}
lights:
  - {type: point, position: [2, 3, 4], intensity: 1}
objects:
  - {type: sphere, center: [0, 0, 0], radius: 1, material: {kd: 0.8, ks: 0.3, shininess: 20}}
"""


def lumos_command() -> list[str]:
    """The `lumos` script of this Python environment (else `python -m lumos`)."""
    script = Path(sys.executable).parent / "lumos"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "lumos"]


def render_once(scene: Path, cache: Path, work: Path, width: int, height: int, method: str) -> dict:
    """Run one `lumos render` process; returns its `--stats` figures plus `wall_s` (the whole process)."""
    out, stats = work / "out.png", work / "stats.json"
    stats.unlink(missing_ok=True)
    cmd = lumos_command() + ["render", str(scene), "-o", str(out), "--width", str(width), "--height", str(height),
                             "--stats", str(stats), "--quiet", "--method", method]
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr}")
    figures = json.loads(stats.read_text())
    figures["wall_s"] = wall
    figures["startup_s"] = wall - figures["total_s"]
    return figures


def measure(scene: Path, width: int, height: int, repeats: int, method: str) -> tuple[dict, dict]:
    """(cold run, best warm run) for one scene, each with its own fresh cache folder."""
    with tempfile.TemporaryDirectory(prefix="lumos-first-image-") as tmp:
        cache, work = Path(tmp) / "numba_cache", Path(tmp) / "work"
        cache.mkdir()
        work.mkdir()
        cold = render_once(scene, cache, work, width, height, method)
        warm = min((render_once(scene, cache, work, width, height, method) for _ in range(repeats)),
                   key=lambda f: f["wall_s"])
    return cold, warm


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--repeats", type=int, default=3, help="warm runs; the best is reported")
    ap.add_argument("--method", default="raycast", help="rendering method (raycast, raster)")
    args = ap.parse_args()

    with tempfile.TemporaryDirectory(prefix="lumos-sphere-") as tmp:
        sphere = Path(tmp) / "sphere.yaml"
        sphere.write_text(SPHERE)
        scenes = [("showcase.yaml", ROOT / "examples" / "showcase.yaml"), ("one sphere", sphere)]
        print(f"machine: {machine()}")
        print(f"command: {' '.join(lumos_command())} render SCENE -o out.png --width {args.width} "
              f"--height {args.height} --method {args.method}  (NUMBA_CACHE_DIR: fresh empty folder, then the same "
              "folder again)")
        print(f"warm = best of {args.repeats}; load/build/render/startup from the process's own --stats\n")
        header = f"{'scene':<14} {'cache':<5} {'wall s':>7} {'startup':>8} {'load':>6} {'build':>6} {'render':>7}"
        print(header)
        print("-" * len(header))
        ratios = []
        for name, path in scenes:
            cold, warm = measure(path, args.width, args.height, args.repeats, args.method)
            for label, f in (("cold", cold), ("warm", warm)):
                print(f"{name:<14} {label:<5} {f['wall_s']:>7.2f} {f['startup_s']:>8.2f} {f['load_s']:>6.2f} "
                      f"{f['build_s']:>6.2f} {f['render_s']:>7.2f}")
            ratios.append((name, cold["wall_s"] / warm["wall_s"], cold["spp"]))
        print()
        for name, ratio, spp in ratios:
            print(f"{name}: cold / warm = {ratio:.1f}x  ({spp} spp)")


if __name__ == "__main__":
    main()
