"""Time to first image per method: cold (nothing compiled), installed (`pip install .`'s kernels) and warm, beside
Mitsuba 3's cold and warm first image, each a whole process.

    python benchmarks/bench_first_image.py [--installed VENV] [--methods raycast,raster,...] [--repeats 3]
                                           [--width 160] [--height 120] [--install]

Each run is one child process `lumos render examples/showcase.yaml -o out.png --method M --width W --height H
--spp 1 --stats stats.json`, timed with `time.perf_counter` around `subprocess.run` (radiosity renders
examples/radiosity/cornell.yaml, path examples/path/cornell.yaml):

    cold       this Python's lumos with LUMOS_CACHE_DIR a fresh empty folder: every kernel the method needs
               compiles (an editable install that never ran `lumos warmup`)
    installed  VENV's lumos (a venv where `pip install .` ran) with no cache variable set: the kernels the wheel
               build compiled into the package; the first render there, then the best of `--repeats`
    warm       the cold run's folder again, now filled; best of `--repeats`

Mitsuba (if `mitsuba` imports, with `llvm_ad_rgb` when libLLVM 19 is there, else `scalar_rgb`) renders its own
Cornell box at the same size and 1 spp in a whole process: cold with a fresh Dr.Jit kernel cache (`HOME` pointed
at an empty folder: Dr.Jit keeps its cache in ~/.drjit), warm with the filled one.

`--install` also times the README's first command on a fresh venv (`python -m venv`, `pip install .`, the showcase
render) and uses that venv as VENV.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import machine

ROOT = Path(__file__).resolve().parent.parent
METHODS = ("raycast", "raster", "whitted", "path", "radiosity")
SCENES = {"path": ROOT / "examples" / "path" / "cornell.yaml",
          "radiosity": ROOT / "examples" / "radiosity" / "cornell.yaml"}
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
MITSUBA = """\
import os, sys
import mitsuba as mi
variant = "llvm_ad_rgb" if os.path.exists({llvm!r}) and "llvm_ad_rgb" in mi.variants() else "scalar_rgb"
mi.set_variant(variant)
scene = mi.cornell_box()
scene["sensor"]["film"]["width"], scene["sensor"]["film"]["height"] = {width}, {height}
scene["sensor"]["sampler"]["sample_count"] = 1
img = mi.render(mi.load_dict(scene), spp=1)
mi.util.write_bitmap({out!r}, img)
print(variant)
"""


def lumos_command(python: str = sys.executable) -> list[str]:
    """The `lumos` script beside `python` (else `python -m lumos`)."""
    script = Path(python).parent / "lumos"
    return [str(script)] if script.is_file() else [python, "-m", "lumos"]


def render_once(python: str, method: str, work: Path, width: int, height: int, cache) -> dict:
    """One whole `lumos render` process: its --stats figures plus wall_s."""
    out, stats = work / "out.png", work / "stats.json"
    stats.unlink(missing_ok=True)
    scene = SCENES.get(method, ROOT / "examples" / "showcase.yaml")
    cmd = lumos_command(python) + ["render", str(scene), "-o", str(out), "--method", method, "--width", str(width),
                                   "--height", str(height), "--spp", "1", "--stats", str(stats), "--quiet"]
    env = {k: v for k, v in os.environ.items() if k not in ("LUMOS_CACHE_DIR", "NUMBA_CACHE_DIR")}
    if cache is not None:
        env["LUMOS_CACHE_DIR"] = str(cache)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    figures = json.loads(stats.read_text())
    figures["wall_s"] = wall
    return figures


def mitsuba(work: Path, width: int, height: int, repeats: int):
    """(variant, cold wall, warm walls) of whole Mitsuba processes, or None when Mitsuba does not import."""
    if subprocess.run([sys.executable, "-c", "import mitsuba"], capture_output=True).returncode != 0:
        return None
    script = work / "mitsuba_first.py"
    script.write_text(MITSUBA.format(llvm=LLVM, width=width, height=height, out=str(work / "m.exr")))
    home = work / "home"
    home.mkdir()
    env = dict(os.environ, HOME=str(home), DRJIT_LIBLLVM_PATH=LLVM)
    walls, variant = [], ""
    for _ in range(1 + repeats):
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env)
        walls.append(time.perf_counter() - t0)
        if proc.returncode != 0:
            print(f"Mitsuba failed: {proc.stderr[-500:]}")
            return None
        variant = proc.stdout.strip()
    return variant, walls[0], walls[1:]


def install(work: Path) -> tuple[str, float, float]:
    """The README's first command on a fresh venv: (python of the venv, pip install seconds, render seconds)."""
    venv = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = str(venv / "bin" / "python")
    t0 = time.perf_counter()
    subprocess.run([python, "-m", "pip", "install", "-q", str(ROOT)], check=True)
    t_pip = time.perf_counter() - t0
    t0 = time.perf_counter()
    subprocess.run(lumos_command(python) + ["render", str(ROOT / "examples" / "showcase.yaml"), "-o",
                                            str(work / "showcase.png")], check=True, capture_output=True)
    return python, t_pip, time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--installed", metavar="VENV", help="a venv where `pip install .` ran (its bin/python)")
    ap.add_argument("--install", action="store_true", help="time the README's first command on a fresh venv")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--no-cold", action="store_true", help="skip the cold runs (each compiles for a minute)")
    args = ap.parse_args()

    print(f"machine: {machine()}")
    print(f"each figure: one whole process, {args.width}x{args.height}, 1 spp; warm and installed: min / median of "
          f"{args.repeats}\n")
    with tempfile.TemporaryDirectory(prefix="lumos-first-image-") as tmp:
        tmp = Path(tmp)
        python = str(Path(args.installed) / "bin" / "python") if args.installed else None
        if args.install:
            python, t_pip, t_render = install(tmp)
            print(f"README's first command, fresh venv: pip install . {t_pip:.1f} s + showcase render "
                  f"{t_render:.1f} s = {t_pip + t_render:.1f} s\n")
        print(f"{'method':<10} {'cold s':>8} {'(compile)':>9} {'installed first':>15} {'installed':>13} "
              f"{'warm':>13}")
        for method in args.methods.split(","):
            cells = []
            with tempfile.TemporaryDirectory(prefix=f"lumos-{method}-") as wtmp:
                work, cache = Path(wtmp), Path(wtmp) / "cache"
                if args.no_cold:
                    cells += ["-", "-"]
                else:
                    cold = render_once(sys.executable, method, work, args.width, args.height, cache)
                    cells += [f"{cold['wall_s']:.2f}", f"{cold.get('jit_s', 0.0):.1f}"]
                if python:
                    runs = [render_once(python, method, work, args.width, args.height, None)["wall_s"]
                            for _ in range(1 + args.repeats)]
                    cells += [f"{runs[0]:.2f}", f"{min(runs[1:]):.2f} / {statistics.median(runs[1:]):.2f}"]
                else:
                    cells += ["-", "-"]
                if args.no_cold:
                    cells.append("-")
                else:
                    warm = [render_once(sys.executable, method, work, args.width, args.height, cache)["wall_s"]
                            for _ in range(args.repeats)]
                    cells.append(f"{min(warm):.2f} / {statistics.median(warm):.2f}")
            print(f"{method:<10} {cells[0]:>8} {cells[1]:>9} {cells[2]:>15} {cells[3]:>13} {cells[4]:>13}",
                  flush=True)
        peer = mitsuba(tmp, args.width, args.height, args.repeats)
        if peer is None:
            print("\nMitsuba 3: not installed (pip install mitsuba; apt-get install libllvm19 for llvm_ad_rgb)")
        else:
            variant, cold, warm = peer
            print(f"\nMitsuba 3 ({variant}, its Cornell box): cold {cold:.2f} s, warm {min(warm):.2f} / "
                  f"{statistics.median(warm):.2f} s")


if __name__ == "__main__":
    main()
