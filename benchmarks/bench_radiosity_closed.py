"""Radiosity on the closed and simple scenes of issue 28, with default settings: time and error of every solver.

    python benchmarks/bench_radiosity_closed.py [--src DIR] [--timeout 120] [--repeats 3] [--json]

Two scenes with exact answers, each rendered as a user would (48×36 and 48×48) (`lumos.render`, method radiosity, the
default patch size and tessellation, only the solver and form-factor kind chosen):

- the **sphere furnace**: the camera inside a closed unit sphere of ρ = 0.8 emitting 0.5: L = Le/(1 − ρ) = 2.5
  at every pixel (Le/(1 − ρ) holds for any closed enclosure, so for the tessellated sphere too);
- the **parallel plates**: a unit emitter of radiance 1 one unit above a unit receiver of ρ = 0.6 given as a
  two-triangle mesh, an orthographic camera between them seeing the receiver edge to edge: mean ρ·F·Le =
  0.6 × 0.19982 (the worst pixel is no measure here: the radiance varies over the receiver).

For each solver: the wall time of the whole render, warm (one untimed render first, so no compile is timed;
min, median and max of `--repeats`), the mean error and the worst pixel's. Each configuration runs in a child
process of its own, with the lumos tree `--src` first on the path (A/B against an older tree: run the script
once per tree) and a time limit (`--timeout`, per configuration): a configuration that does not finish says so.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

SPHERE = {"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov": 60},
          "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1,
                       "material": {"kd": 0.8, "emission": 0.5}}]}
PLATES = {"camera": {"type": "orthographic", "position": [0.5, 0.5, 0.5], "look_at": [0.5, 0, 0.5],
                     "up": [0, 0, -1], "size": 1.0},
          "lights": [{"type": "area", "shape": "rect", "corner": [0, 1, 0], "edge_u": [1, 0, 0],
                      "edge_v": [0, 0, 1], "radiance": 1.0}],
          "objects": [{"type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]],
                       "faces": [[0, 2, 1], [0, 3, 2]], "material": {"kd": 0.6}}]}
SCENES = {"sphere furnace": (SPHERE, 2.5, 48, 36), "plates": (PLATES, 0.6 * 0.19982, 48, 48)}
SOLVERS = [("auto", "raycast"), ("progressive", "raycast"), ("progressive", "hemicube"),
           ("gauss_seidel", "raycast"), ("gauss_seidel", "hemicube"), ("jacobi", "raycast"),
           ("jacobi", "hemicube"), ("stochastic", "raycast")]

CHILD = """
import json, sys, time, warnings
import numpy as np
import lumos
warnings.simplefilter("ignore")
scene, exact, width, height, solver, ff, repeats = json.loads(sys.argv[1])
def once():
    t = time.perf_counter()
    img = lumos.render(scene, method="radiosity", width=width, height=height, radiosity={"solver": solver, "form_factors": ff})
    return time.perf_counter() - t, img
once()
times = []
for _ in range(repeats):
    t, img = once()
    times.append(t)
a = img.array[..., 0]
print(json.dumps({"times": times, "mean_error": float(a.mean() / exact - 1),
                  "worst_pixel": float(np.abs(a / exact - 1).max()),
                  "stats": {k: v for k, v in img.stats.get("radiosity", {}).items() if k in ("patches", "iterations", "solver")}}))
"""


def run(src: str | None, scene, exact, width, height, solver, ff, repeats, timeout) -> dict:
    env = dict(os.environ)
    if src:
        env["PYTHONPATH"] = os.path.abspath(src) + os.pathsep + env.get("PYTHONPATH", "")
    try:
        out = subprocess.run([sys.executable, "-c", CHILD, json.dumps([scene, exact, width, height, solver, ff, repeats])],
                             capture_output=True, text=True, env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"timeout": timeout}
    if out.returncode != 0:
        return {"failed": out.stderr.strip().splitlines()[-1] if out.stderr.strip() else f"exit {out.returncode}"}
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--src", help="the lumos source tree to measure (default: the installed or current one)")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per configuration (warm-up included)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rows = []
    for name, (scene, exact, width, height) in SCENES.items():
        for solver, ff in SOLVERS:
            t0 = time.perf_counter()
            r = run(args.src, scene, exact, width, height, solver, ff, args.repeats, args.timeout)
            r.update(scene=name, solver=solver, form_factors=ff, wall_s=time.perf_counter() - t0)
            rows.append(r)
            if not args.json:
                if "times" in r:
                    t = sorted(r["times"])
                    print(f"{name:15s} {solver:13s} {ff:9s} {t[len(t) // 2]:7.2f} s ({t[0]:.2f}–{t[-1]:.2f})  "
                          f"mean {r['mean_error']:+.2%}  worst pixel {r['worst_pixel']:.2%}  {r['stats']}", flush=True)
                else:
                    print(f"{name:15s} {solver:13s} {ff:9s} {r}", flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
