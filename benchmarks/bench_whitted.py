"""Whitted ray tracing of Whitted's 1980 scene at 1024×768: lumos `whitted` vs POV-Ray 3.7, whole processes, one run.

    python benchmarks/bench_whitted.py [--width 1024] [--height 768] [--threads 2] [--repeats 3]
                                       [--out /tmp/bench_whitted] [--lumos-method whitted] [--numba-cache DIR]
                                       [--plain-main]

Setup (Debian, as root), besides `pip install -e .`:

    apt-get install -y povray

which gives POV-Ray 3.7 (`povray`; a warning that it cannot open the user configuration file
~/.povray/3.7/povray.conf is harmless).

The scene is `examples/whitted/classic.yaml` for lumos and `benchmarks/scenes/whitted.pov`, the same scene
written by hand for POV-Ray (a checkered box, a mirror sphere, a glass sphere with Fresnel reflection, two point
lights casting shadows, a sky-blue background; the same camera and framing, 4 bounces after the camera ray,
adaptive anti-aliasing with threshold 0.05 and at most 2 subdivisions). The two are the same kind and amount of
work, not the same image to the pixel: POV-Ray's finishes are close to lumos's illumination model, not equal.

Both renderers run as whole processes (subprocess), timed with `time.perf_counter` around `subprocess.run`,
`--repeats` times each, alternating (POV-Ray, lumos, POV-Ray, lumos…), so both see the machine in the same state:

    povray -D -V +W1024 +H768 +A0.05 +AM2 +R3 +WT2 +O<out>/povray.png benchmarks/scenes/whitted.pov
    lumos render examples/whitted/classic.yaml -o <out>/lumos.png --width 1024 --height 768 --antialias adaptive
          --threads 2 --method whitted --stats <out>/lumos.json -q

(`+AM2` is POV-Ray's recursive adaptive anti-aliasing, `+R3` its depth, which counts the pixel itself: at most two
subdivisions, as lumos's `adaptive_depth: 2`; `+WT2` two render threads.) lumos runs
once untimed first, from a fresh empty `NUMBA_CACHE_DIR` (or `--numba-cache DIR` as found), to compile its
kernels; that cold time is reported too, and the timed runs use the filled cache.

Prints the machine, POV-Ray's version line, a table of the whole-process wall times (median and best) with the
ratio lumos / POV-Ray (median over median), and what each process reports itself: POV-Ray's "Trace Time" and ray
counts (its statistics on stderr), lumos's `render_s` and `rays` (its `--stats` JSON), and how the two images
differ. Writes povray.png, lumos.png and side_by_side.png (POV-Ray on the left) to `--out`.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from common import machine

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "examples" / "whitted" / "classic.yaml"
POV_SCENE = ROOT / "benchmarks" / "scenes" / "whitted.pov"
# POV-Ray's +A and +R. Its depth counts the pixel itself: +R3 subdivides at most twice, lumos's adaptive_depth 2,
# which the lumos scene's render: block says (with adaptive_threshold 0.05).
AA_THRESHOLD, AA_DEPTH = 0.05, 3

# POV-Ray's render statistics (stderr), e.g. "Rays:            1648656   Saved:  102147   Max Level: 5/5"
POV_FIGURES = {
    "pixels": r"Pixels:\s+(\d+)",
    "samples": r"Samples:\s+(\d+)",
    "rays": r"^Rays:\s+(\d+)",
    "shadow_rays": r"Shadow Ray Tests:\s+(\d+)",
    "reflected_rays": r"Reflected Rays:\s+(\d+)",
    "refracted_rays": r"Refracted Rays:\s+(\d+)",
    "trace_s": r"Trace Time:.*\(([\d.]+) seconds\)",
}


#: `--plain-main`: the command's `main` called from `python -c`, so the process keeps Python's cyclic garbage
#: collector and tears the interpreter down at exit, which the `lumos` script (`lumos.cli.run`) skips.
PLAIN_MAIN = [sys.executable, "-c", "import sys; from lumos.cli import main; sys.exit(main(sys.argv[1:]))"]


def lumos_command(plain_main: bool = False) -> list[str]:
    """The `lumos` script of this Python environment (else `python -m lumos`), or PLAIN_MAIN."""
    if plain_main:
        return list(PLAIN_MAIN)
    script = Path(sys.executable).parent / "lumos"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "lumos"]


def povray_version() -> str:
    proc = subprocess.run(["povray", "--version"], capture_output=True, text=True)
    lines = (proc.stdout + proc.stderr).splitlines()
    return next((line.strip() for line in lines if line.startswith("POV-Ray")), "POV-Ray (version unknown)")


def povray_once(out: Path, width: int, height: int, threads: int) -> dict:
    """One `povray` process; returns its statistics (POV_FIGURES) plus `wall_s` (the whole process)."""
    cmd = ["povray", "-D", "-V", f"+W{width}", f"+H{height}", f"+A{AA_THRESHOLD}", "+AM2", f"+R{AA_DEPTH}",
           f"+WT{threads}", f"+O{out / 'povray.png'}", str(POV_SCENE)]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=out)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    figures = {"wall_s": wall, "command": " ".join(cmd)}
    for key, pattern in POV_FIGURES.items():
        m = re.search(pattern, proc.stderr, re.MULTILINE)
        figures[key] = (float(m.group(1)) if key == "trace_s" else int(m.group(1))) if m else None
    return figures


def lumos_once(out: Path, cache: Path, width: int, height: int, threads: int, method: str,
               plain_main: bool = False) -> dict | None:
    """One `lumos render` process; returns its `--stats` figures plus `wall_s`, or None if `method` is unknown."""
    stats = out / "lumos.json"
    stats.unlink(missing_ok=True)
    cmd = lumos_command(plain_main) + ["render", str(SCENE), "-o", str(out / "lumos.png"), "--width", str(width),
                             "--height", str(height), "--antialias", "adaptive", "--threads", str(threads),
                             "--method", method, "--stats", str(stats), "-q"]
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if proc.returncode == 2 and "unknown method" in proc.stderr:
        print(f"\nlumos: method {method!r} is not registered yet ({proc.stderr.strip()}); lumos half skipped. "
              f"Try --lumos-method raycast to exercise this half.")
        return None
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    figures = json.loads(stats.read_text())
    figures["wall_s"] = wall
    figures["command"] = " ".join(cmd)
    return figures


def side_by_side(out: Path) -> dict:
    """Writes povray.png | lumos.png as one image, for looking at both; returns how they differ (lumos.tools.metrics)."""
    from lumos.io.image_files import read_image, write_image
    from lumos.tools.metrics import compare

    left, right = read_image(out / "povray.png"), read_image(out / "lumos.png")
    gap = np.ones((left.shape[0], 8, 3), np.float32)
    write_image(out / "side_by_side.png", np.concatenate([left, gap, right], axis=1))
    return compare(right, left)


def _seconds(values) -> str:
    return ", ".join("?" if v is None else f"{v:.3f}" for v in values)


def _count(n) -> str:
    return "?" if n is None else f"{n:,}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--threads", type=int, default=2, help="render threads of both (POV-Ray +WT, lumos --threads)")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs of each, alternating")
    ap.add_argument("--out", default="/tmp/bench_whitted")
    ap.add_argument("--lumos-method", default="whitted", help="lumos method to time (default whitted)")
    ap.add_argument("--plain-main", action="store_true",
                    help="time lumos through `python -c ... main()` instead of the lumos script: with the cyclic "
                         "GC on and a normal interpreter exit")
    ap.add_argument("--numba-cache", help="NUMBA_CACHE_DIR for lumos (default: a fresh empty folder, so the "
                                          "untimed first run is a cold start)")
    args = ap.parse_args()
    if shutil.which("povray") is None:
        sys.exit("povray not found: apt-get install -y povray")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    W, H, T = args.width, args.height, args.threads

    print(f"machine: {machine()}")
    print(f"{povray_version()}; lumos method {args.lumos_method}; {W}x{H}; {T} threads each; "
          f"{args.repeats} timed runs each, alternating")
    with tempfile.TemporaryDirectory(prefix="lumos-whitted-cache-") as tmp:
        cache = Path(args.numba_cache) if args.numba_cache else Path(tmp)
        state = "as found" if args.numba_cache else "fresh, empty"
        first = lumos_once(out, cache, W, H, T, args.lumos_method)
        if first is not None:
            print(f"lumos first run (Numba cache {state}: {cache}), untimed: wall {first['wall_s']:.2f} s, "
                  f"build_s {first['build_s']:.2f}, render_s {first['render_s']:.2f}")
        povs, lumoses = [], []
        for _ in range(args.repeats):
            povs.append(povray_once(out, W, H, T))
            if first is not None:
                lumoses.append(lumos_once(out, cache, W, H, T, args.lumos_method, args.plain_main))

    print(f"\n$ {povs[0]['command']}")
    print(f"POV-Ray wall s: {_seconds(q['wall_s'] for q in povs)}; its own Trace Time s: "
          f"{_seconds(q['trace_s'] for q in povs)}")
    p = povs[-1]
    # "Pixels" are the rays through the corner grid of each 32x32 block (33x33 of them), "Samples" the extra
    # anti-aliasing rays; "Rays" are those two plus the reflected and refracted rays; shadow rays come apart.
    known = all(p[k] is not None for k in ("pixels", "samples", "rays", "shadow_rays"))
    camera = p["pixels"] + p["samples"] if known else None
    total = p["rays"] + p["shadow_rays"] if known else None
    print(f"POV-Ray counts: {_count(camera)} camera rays ({_count(p['pixels'])} 'pixels' + {_count(p['samples'])} "
          f"'samples'), {_count(p['rays'])} rays with the reflected {_count(p['reflected_rays'])} and refracted "
          f"{_count(p['refracted_rays'])}, + {_count(p['shadow_rays'])} shadow ray tests = {_count(total)} in all")
    pov_med = statistics.median(q["wall_s"] for q in povs)
    rows = [("POV-Ray 3.7", pov_med, min(q["wall_s"] for q in povs), "")]
    if lumoses:
        print(f"\n$ NUMBA_CACHE_DIR={cache} {lumoses[0]['command']}")
        print(f"lumos wall s: {_seconds(q['wall_s'] for q in lumoses)}; its own render_s: "
              f"{_seconds(q['render_s'] for q in lumoses)}; load_s + build_s: "
              f"{_seconds(q['load_s'] + q['build_s'] for q in lumoses)}")
        q = lumoses[-1]
        primary = f"{q['primary_rays']:,} camera rays, " if q.get("primary_rays") else ""  # raycast: 0
        print(f"lumos counts: {primary}{q['rays']:,} rays in all, shadow rays included "
              f"({q['mrays_per_s']:.2f} Mrays/s over render_s), threads {q.get('threads')}")
        lu_med = statistics.median(q["wall_s"] for q in lumoses)
        rows.append((f"lumos {args.lumos_method}", lu_med, min(q["wall_s"] for q in lumoses),
                     f"{lu_med / pov_med:.2f}"))

    print()
    print("| renderer | median wall s | best wall s | lumos / POV-Ray (median) |")
    print("|---|---:|---:|---:|")
    for name, med, best, ratio in rows:
        print(f"| {name} | {med:.3f} | {best:.3f} | {ratio} |")
    print()
    if lumoses:
        figures = side_by_side(out)
        print(f"images (lumos vs POV-Ray, both PNGs decoded as sRGB; not meant to agree to the pixel): RMSE "
              f"{figures['rmse']:.4f}, PSNR {figures['psnr']:.1f} dB, max |diff| {figures['max_abs_error']:.3f}")
        print(f"wrote {out / 'povray.png'}, {out / 'lumos.png'}, {out / 'side_by_side.png'}")
    else:
        print(f"wrote {out / 'povray.png'}")


if __name__ == "__main__":
    main()
