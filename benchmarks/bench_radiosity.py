"""Radiosity against path tracing on the diffuse Cornell box: each solver's time to 5% of the converged image.

    python benchmarks/bench_radiosity.py [--repeats 3] [--threads 2] [--bar 0.05] [--no-large] [--large-only]

Radiosity exists because, for diffuse scenes, it is cheaper than tracing many paths. This script shows how much
cheaper, in one process run, warm (every configuration rendered once untimed first, so Numba's compilation is
not timed), with `--threads` threads:

1. **Time to the bar.** The error of an image is the mean relative error over 8×8-pixel blocks against the
   converged path-traced image (Mitsuba 3's 16,384-spp Cornell box, unbounded depth, tests/data/cornell_mitsuba/;
   `path` matches it, see BENCHMARKS.md) at 256×256: the metric of the issue and of
   tests/methods/test_radiosity.py. For `path`, one render per spp count of a ladder; for each radiosity solver (and
   form-factor method), one render per configuration of a ladder of patch sizes, with and without adaptive
   subdivision (stochastic: ray budgets). A render is the whole `lumos.render` call: meshing, form factors,
   solve, display (Gouraud, 1 sample per pixel). The figure is the least time of a configuration whose error
   is under `--bar` (median over `--repeats`), and its ratio to path's. A configuration whose untimed render
   already takes over 1.5× the best time under the bar so far is skipped (it cannot win).
2. **Form factors per second**: the Gauss–Seidel matrix of the 4,620-patch box by ray casting (n² contour form
   factors, 8 shadow rays each where unoccluded) and by hemicubes (one 128² hemicube per patch); the stochastic
   solver's visibility rays per second per core.
3. **The largest scenes**, each in a subprocess of its own (for its peak memory, `ru_maxrss`): a 10k-patch box
   solved progressively to 1% unshot power (target: under 10 s), a 100k-patch box solved stochastically (target:
   under a minute), the Gauss–Seidel matrix at 10k patches, and the matrix limit of this machine (the solvers
   that store F refuse more patches, naming the ones that do not). Peak memory is the subprocess's VmHWM
   (its whole peak resident set: Python, NumPy, Numba and lumos take ~100 MiB of it before anything runs).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from common import machine  # noqa: E402

CORNELL = str(ROOT / "examples" / "path" / "cornell.yaml")
#: Radiosity's display samples per pixel: 1 (the 8×8-block error does not see anti-aliasing; `spp` 4 adds ~0.05 s)
DISPLAY_SPP = 1
REFERENCE = ROOT / "tests" / "data" / "cornell_mitsuba" / "ref_depthinf_256.npy"


def blocks(a: np.ndarray, k: int = 8) -> np.ndarray:
    h, w = a.shape[:2]
    return a[: h // k * k, : w // k * k].reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))


def block_mre(img: np.ndarray, ref_blocks: np.ndarray) -> float:
    ours = blocks(img[..., :3].astype(np.float64))
    lit = ref_blocks > 1e-3
    return float(np.mean(np.abs(ours - ref_blocks)[lit] / ref_blocks[lit]))


def timed_render(threads: int, **kw):
    import lumos

    t0 = time.perf_counter()
    img = lumos.render(CORNELL, width=256, height=256, threads=threads, **kw)
    return time.perf_counter() - t0, img


def ladder(name: str, configs, threads: int, repeats: int, ref_blocks, bar: float):
    """[(label, median s, min, max, error, elements)] for each configuration, each rendered once untimed first.
    A configuration whose untimed render already takes over 1.5× the best time under the bar so far is skipped."""
    rows = []
    best = None
    for label, kw in configs:
        warm, _ = timed_render(threads, **kw)  # warm: kernels compiled, caches filled
        if best is not None and warm > 1.5 * best and name != "path":
            print(f"  {name:<24} {label:<40} skipped ({warm:.2f} s untimed)", flush=True)
            continue
        times, err, patches = [], None, None
        for r in range(repeats):
            s, img = timed_render(threads, seed=1 + r, **kw)
            times.append(s)
            err = block_mre(img.array, ref_blocks) if err is None else err
            patches = img.stats.get("radiosity", {}).get("elements", patches)
        med = float(np.median(times))
        rows.append((label, med, min(times), max(times), err, patches))
        print(f"  {name:<24} {label:<40} {med:7.2f} s  error {err:6.2%}"
              + (f"  {patches:,} elements" if patches else ""), flush=True)
        if err < bar:
            best = med if best is None else min(best, med)
    return rows


def best_under(rows, bar):
    ok = [r for r in rows if r[4] < bar]
    return min(ok, key=lambda r: r[1]) if ok else None


def part_time_to_bar(args) -> list[str]:
    ref_blocks = blocks(np.load(REFERENCE).astype(np.float64))
    out = ["| renderer | configuration | time to < {:.0%} (median, min–max) | error | elements | vs path |".format(
        args.bar), "|---|---|---|---|---|---|"]
    print(f"time to {args.bar:.0%} block mean relative error, 256×256, {args.threads} threads")
    path_rows = ladder("path", [(f"{n} spp", dict(method="path", spp=n, max_depth=-1)) for n in (2, 4, 6, 8, 12, 16)],
                       args.threads, args.repeats, ref_blocks, args.bar)
    path_best = best_under(path_rows, args.bar)
    if path_best is None:
        raise SystemExit("path did not reach the bar: extend its ladder")
    out.append(f"| path | {path_best[0]} | {path_best[1]:.2f} s ({path_best[2]:.2f}–{path_best[3]:.2f}) | "
               f"{path_best[4]:.1%} | | 1 |")
    plain, refined = (0.3, 0.25, 0.2, 0.17, 0.15, 0.12, 0.1), (0.3, 0.25)
    for solver, ff in (("gauss_seidel", "raycast"), ("jacobi", "raycast"), ("progressive", "raycast"),
                       ("gauss_seidel", "hemicube"), ("progressive", "hemicube"), ("stochastic", "raycast")):
        # the form factors' own accuracy: shadow rays per form factor, or the hemicube's resolution
        quality = ([dict(hemicube_resolution=r) for r in (64, 128)] if ff == "hemicube" else
                   [{}] if solver == "stochastic" else [dict(visibility_samples=k) for k in (4, 8)])
        configs = []
        for size, subdivide in [(p, False) for p in plain] + [(p, True) for p in refined]:
            for q in (quality if not subdivide else quality[-1:]):
                rs = dict(solver=solver, form_factors=ff, patch_size=size, subdivide=subdivide, **q)
                name = (f"patch {size}{', subdivided' if subdivide else ''}"
                        + "".join(f", {k.split('_')[0]} {v}" for k, v in q.items()))
                if solver == "stochastic":
                    for rays in (250_000, 1_000_000):
                        configs.append((f"{name}, {rays / 1e6:g} M rays/iteration",
                                        dict(method="radiosity", spp=DISPLAY_SPP, radiosity=dict(rs, rays=rays))))
                else:
                    configs.append((name, dict(method="radiosity", spp=DISPLAY_SPP, radiosity=rs)))
        rows = ladder(f"{solver}/{ff}", configs, args.threads, args.repeats, ref_blocks, args.bar)
        best = best_under(rows, args.bar)
        if best is None:
            out.append(f"| radiosity {solver}, {ff} | none of the ladder | | {min(r[4] for r in rows):.1%} | | |")
            continue
        out.append(f"| radiosity {solver}, {ff} | {best[0]} | {best[1]:.2f} s ({best[2]:.2f}–{best[3]:.2f}) | "
                   f"{best[4]:.1%} | {best[5]:,} | {best[1] / path_best[1]:.2f} |")
    return out


def part_rates(args) -> list[str]:
    from lumos.radiosity.solve import solve

    import lumos
    from lumos.api import resolve_settings
    from lumos.scene.loader import load_scene

    scene = load_scene(CORNELL)
    out = ["| what | patches | time | rate |", "|---|---|---|---|"]

    def run(**rs):
        st = resolve_settings(scene, {"method": "radiosity", "threads": args.threads, "radiosity": rs})
        solve(scene, st.model_copy(update={"radiosity": st.radiosity.model_copy(update={"patch_size": 0.4})}))
        return solve(scene, st).stats

    s = run(solver="gauss_seidel", form_factors="raycast", patch_size=0.1)
    n = s["patches"]
    out.append(f"| ray-cast form factors (contour formula, 8 shadow rays each) | {n:,} | {s['form_factor_s']:.2f} s "
               f"| {n * n / s['form_factor_s'] / 1e6:.1f} M form factors/s, {s['rays'] / s['form_factor_s'] / 1e6:.1f}"
               f" M rays/s ({args.threads} threads) |")
    s = run(solver="gauss_seidel", form_factors="hemicube", patch_size=0.1, hemicube_resolution=128)
    out.append(f"| hemicubes, 128² (the scan-line fill, an item buffer) | {n:,} | {s['form_factor_s']:.2f} s | "
               f"{n / s['form_factor_s']:,.0f} hemicubes/s, {n * n / s['form_factor_s'] / 1e6:.1f} M form factors/s |")
    s = run(solver="stochastic", patch_size=0.1, rays=4_000_000)
    per_core = s["rays"] / s["solve_s"] / args.threads
    out.append(f"| stochastic Jacobi, visibility rays ({s['iterations']} iterations) | {n:,} | {s['solve_s']:.2f} s | {per_core / 1e6:.2f} M "
               f"rays/s per core (RenderPark's port: 0.85 M) |")
    del lumos
    return out


LARGE = r"""
import json, sys, time
from lumos.api import resolve_settings
from lumos.radiosity.solve import solve
from lumos.scene.loader import load_scene
scene = load_scene(sys.argv[1])
rs = json.loads(sys.argv[2])
warm = resolve_settings(scene, {"method": "radiosity", "threads": int(sys.argv[3]), "radiosity": dict(rs, patch_size=0.5)})
solve(scene, warm)
st = resolve_settings(scene, {"method": "radiosity", "threads": int(sys.argv[3]), "radiosity": rs})
t0 = time.perf_counter()
s = solve(scene, st).stats
s["wall_s"] = time.perf_counter() - t0
# the peak resident memory of this process's own address space (VmHWM; ru_maxrss would carry the parent's
# peak across fork and exec)
s["maxrss_mib"] = next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM")) / 1024
print(json.dumps(s))
"""


def part_large(args) -> list[str]:
    from lumos.radiosity.solvers import matrix_limit

    # the box's patches go as 1/patch_size²: 4,620 at 0.1
    def size_for(n):
        return round(0.1 * (4620 / n) ** 0.5, 4)

    cases = [("progressive, 1% unshot (target < 10 s)", dict(solver="progressive", patch_size=size_for(10_000),
                                                              tolerance=0.01)),
             ("stochastic (target < 60 s)", dict(solver="stochastic", patch_size=size_for(100_000))),
             ("gauss_seidel, ray-cast matrix", dict(solver="gauss_seidel", patch_size=size_for(10_000)))]
    out = ["| solver | patches | solve (whole call) | of it form factors | iterations | residual | peak memory |",
           "|---|---|---|---|---|---|---|"]
    for label, rs in cases:
        res = subprocess.run([sys.executable, "-c", LARGE, CORNELL, json.dumps(rs), str(args.threads)],
                             capture_output=True, text=True, env=dict(os.environ))
        if res.returncode != 0:
            out.append(f"| {label} | failed: {res.stderr.strip().splitlines()[-1] if res.stderr else res.returncode} |")
            continue
        s = json.loads(res.stdout.strip().splitlines()[-1])
        print(f"  {label}: {s['patches']:,} patches, {s['wall_s']:.1f} s, {s['maxrss_mib']:.0f} MiB", flush=True)
        out.append(f"| {label} | {s['patches']:,} | {s['wall_s']:.1f} s | {s['form_factor_s']:.1f} s | "
                   f"{s['iterations']:,} | {s['residual']:.2%} | {s['maxrss_mib']:,.0f} MiB |")
    limit = matrix_limit()
    out.append(f"| gauss_seidel / jacobi limit | {limit:,} | (the float32 matrix, {4 * limit * limit / 2**30:.1f} GiB:"
               f" half of the memory available now; more patches are refused) | | | | |")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--bar", type=float, default=0.05)
    ap.add_argument("--no-large", action="store_true", help="skip the largest-scene runs")
    ap.add_argument("--large-only", action="store_true", help="only the largest-scene runs")
    args = ap.parse_args()
    print(machine(), flush=True)
    t0 = time.perf_counter()
    tables = []
    if not args.large_only:
        tables += [part_time_to_bar(args), [""], part_rates(args)]
    if not args.no_large:
        tables += [[""], part_large(args)]
    print()
    print(f"machine: {machine()}; threads {args.threads}; repeats {args.repeats}; "
          f"bench wall {time.perf_counter() - t0:.0f} s; peak memory of this process "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")
    for t in tables:
        print("\n".join(t))


if __name__ == "__main__":
    main()
