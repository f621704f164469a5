"""Path tracing of Mitsuba's Cornell box at 256×256, 64 spp: lumos `path` vs Mitsuba 3 (LLVM and scalar) and Cycles.

    python benchmarks/bench_path.py [--repeats 5] [--spp 64] [--size 256] [--threads 2] [--ref-spp 16384]
                                    [--no-cycles] [--no-equal-error] [--ladder 16,32,64,128,256]
                                    [--big-mesh] [--first-image] [--out /tmp/bench_path]

Setup, besides `pip install -e .`: `pip install mitsuba` (3.9) and, for its LLVM variant, `apt-get install -y
libllvm19` (DRJIT_LIBLLVM_PATH is set to /usr/lib/x86_64-linux-gnu/libLLVM-19.so when unset); optionally
`pip install bpy` (Blender 5.0.1 as a module) for the Cycles column. See /work/shared/PEERS.md and
benchmarks/peers_path.py, which holds the peers' set-up (scene, filter, threads, warm-up, timing).

The scene is `examples/path/cornell.yaml` for lumos and the same `mi.cornell_box()` for Mitsuba (box filter,
black BSDF on the light) and Cycles (built from the same rectangles and cubes with bpy.data meshes). Depth:
Mitsuba max_depth 8 = lumos max_depth 6 = Cycles max_bounces 6 (the last two count bounces after the first hit).
Everything runs in this one process, warm (an untimed render of each configuration first: Numba's, Dr.Jit's and
Cycles' compilation are not timed), with `--threads` threads, `--repeats` times each, alternating (Mitsuba LLVM,
Mitsuba scalar, lumos, Cycles, then again), each render with a new seed. Times are wall seconds around one
render call (`mi.render` + conversion to NumPy, which forces the LLVM variant's evaluation; `lumos.render`, whose
own `stats["render_s"]` is shown beside; `bpy.ops.render.render`). The table gives min / median / max, the ratio
lumos / Mitsuba (median over median) per variant, and each renderer's RMSE against the converged reference.
Because the machine may be shared, each render also records the CPU seconds of this process (all its threads;
2 threads busy = 2x the wall time) and how many cores *other* processes kept busy meanwhile (from /proc/stat);
renders during which they kept fewer than 0.1 cores busy are "quiet", and the ratios use the quiet renders' medians
where there are any. On a shared machine, trust those and the CPU seconds; better, rerun on a quiet one.

The reference is Mitsuba's own converged image (peers_path.reference: `--ref-spp` samples, llvm_ad_rgb, cached as
EXR in benchmarks/.cache/, or tests/data/cornell_mitsuba/ when it has enough samples). RMSE is over every
pixel and channel of the linear image ("all"); since the light's edge pixels (radiance up to 18 against ~0.2
elsewhere) dominate it, and they measure pixel anti-aliasing rather than light transport, it is also given
without the pixels within one pixel of the directly seen light ("no light").

**Time to equal error** (off with --no-equal-error): how long each renderer needs to reach the RMSE that Mitsuba
LLVM reaches at `--spp` (its median over the repeats, "all" and "no light" separately). Each renderer renders
once at every spp count of `--ladder` (warm, new seeds; one render per count), giving points (RMSE, seconds).
Monte Carlo error falls about as spp^-1/2 and time grows about as spp, so log(seconds) is close to linear in
log(RMSE): the time at the target RMSE is interpolated linearly on log-log between the two ladder points that
bracket it (extrapolated from the two nearest ends, marked "~", when none do). Mitsuba LLVM's own figure is a
check: it should be close to its time at `--spp`. The reference's own noise (printed) is a floor: RMSEs near it
would be meaningless, so the target must stay well above it.

`--big-mesh`: samples per second of lumos path (and, for scale, Mitsuba LLVM) on the Cornell box's walls and
light with trimesh's icosphere (subdivisions 8: 1,310,720 triangles, smooth) instead of the two blocks.
`--first-image`: time to first image, the whole process `lumos render examples/path/cornell.yaml --method path
--spp 16 -o OUT.png`, from a fresh empty NUMBA_CACHE_DIR (cold) and again with it filled (warm, best of
`--repeats`), as benchmarks/bench_first_image.py does; with a whole Mitsuba process for comparison (LLVM, its
kernel cache as found).

Until lumos's `path` method exists, its column prints "lumos path: not available" and the rest runs.
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

import numpy as np
from common import machine

import peers_path as peers

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "examples" / "path" / "cornell.yaml"
MI_DEPTH = 8  # Mitsuba's; lumos's is MI_DEPTH - 2
QUIET = 0.1  # a render is "quiet" when other processes kept fewer cores than this busy meanwhile


# ------------------------------------------------------------------------------------------------------- lumos

_lumos_scene = None
_lumos_warm: set = set()


def lumos_path_status() -> str | None:
    """None when lumos's path method renders (a tiny untimed render), else why not, in one line."""
    try:
        import lumos

        lumos.render(lumos.load_scene(SCENE), method="path", width=8, height=8, spp=1, max_depth=1, threads=1)
    except Exception as exc:  # unknown method, module not written yet, not finished...
        return f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
    return None


def lumos_render(spp: int = 64, max_depth: int = MI_DEPTH, width: int = 256, height: int = 256,
                 seed: int | None = None, threads: int = 2, warm: bool = True, scene=None):
    """lumos path on examples/path/cornell.yaml (or `scene`); max_depth is Mitsuba's (lumos gets max_depth - 2).
    Returns (float32 (H, W, 3) image, wall seconds of `lumos.render`, its stats)."""
    import lumos

    global _lumos_scene
    if scene is None:
        if _lumos_scene is None:
            _lumos_scene = lumos.load_scene(SCENE)
        scene = _lumos_scene
    depth = -1 if max_depth < 0 else max_depth - 2  # -1: unbounded in both
    kwargs = dict(method="path", width=width, height=height, max_depth=depth, threads=threads)
    key = (id(scene), depth, width, height, threads)
    if warm and key not in _lumos_warm:
        lumos.render(scene, spp=spp, seed=0, **kwargs)
        _lumos_warm.add(key)
    seed = peers.next_seed() if seed is None else seed
    c0, t0 = time.process_time(), time.perf_counter()
    img = lumos.render(scene, spp=spp, seed=seed, **kwargs)
    seconds = time.perf_counter() - t0
    peers.LAST["cpu_s"] = time.process_time() - c0
    return np.asarray(img.array, np.float32), seconds, dict(img.stats)


# ------------------------------------------------------------------------------------------------------- load


def _jiffies() -> tuple[int, int]:
    """(busy clock ticks of the whole machine, clock ticks of this process), from /proc."""
    with open("/proc/stat") as f:
        user, nice, system, idle, iowait, irq, softirq, steal = (int(x) for x in f.readline().split()[1:9])
    with open("/proc/self/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return user + nice + system + irq + softirq + steal, int(fields[11]) + int(fields[12])


class OtherLoad:
    """How many cores other processes kept busy while the block ran (the machine may be shared): with
    OtherLoad() as load: ...; load.cores. 0 where /proc is not readable."""

    def __enter__(self):
        try:
            self._j0, self._t0 = _jiffies(), time.perf_counter()
        except OSError:
            self._j0 = None
        return self

    def __exit__(self, *exc):
        self.cores = 0.0
        if self._j0 is not None:
            (b1, o1), (b0, o0) = _jiffies(), self._j0
            wall = time.perf_counter() - self._t0
            self.cores = max(0.0, ((b1 - b0) - (o1 - o0)) / os.sysconf("SC_CLK_TCK") / max(wall, 1e-9))
        return False


# ------------------------------------------------------------------------------------------------------- error


def light_mask(ref: np.ndarray) -> np.ndarray:
    """True for the pixels kept by the "no light" RMSE: not within one pixel of a pixel that sees the light
    (reference radiance above 1 in some channel; everything else in the box is below 1)."""
    lit = (ref > 1.0).any(axis=-1)
    grown = lit.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            grown |= np.roll(np.roll(lit, dy, axis=0), dx, axis=1)
    return ~grown


def errors(img: np.ndarray, ref: np.ndarray, keep: np.ndarray) -> tuple[float, float]:
    """(RMSE over all pixels, RMSE over the `keep` pixels)."""
    return peers.rmse(img, ref), peers.rmse(img[keep], ref[keep])


def time_at_error(points: list[tuple[float, float]], target: float) -> tuple[float, bool]:
    """Seconds at RMSE `target` from (rmse, seconds) points, linear in log-log between the bracketing points;
    returns (seconds, extrapolated)."""
    pts = sorted((float(e), float(t)) for e, t in points if e > 0 and t > 0)
    if len(pts) < 2:
        return float("nan"), True
    le, lt = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    lg = np.log(target)
    for i in range(len(pts) - 1):
        if le[i] <= lg <= le[i + 1]:
            j, extrapolated = i, False
            break
    else:
        j, extrapolated = (0 if lg < le[0] else len(pts) - 2), True
    slope = (lt[j + 1] - lt[j]) / (le[j + 1] - le[j]) if le[j + 1] != le[j] else 0.0
    return float(np.exp(lt[j] + slope * (lg - le[j]))), extrapolated


# ------------------------------------------------------------------------------------------------------- main


def _fmt3(values) -> str:
    v = sorted(values)
    return f"{v[0]:.3f} / {statistics.median(v):.3f} / {v[-1]:.3f}"


def main_table(args, renderers, ref, keep):
    """Alternating warm renders at args.spp; returns {name: {"times": [...], "rmse": [...], "rmse_nl": [...]}}."""
    results = {name: {"times": [], "cpu": [], "others": [], "rmse": [], "rmse_nl": [], "extra": []}
               for name in renderers}
    S, spp, T = args.size, args.spp, args.threads
    for r in range(args.repeats):
        for name, fn in renderers.items():
            # warm=True: the first call of each configuration renders once untimed before the timed render
            with OtherLoad() as load:
                img, seconds, extra = fn(spp, MI_DEPTH, S, S, T, warm=True)
            e_all, e_nl = errors(img, ref, keep)
            res = results[name]
            res["times"].append(seconds)
            res["cpu"].append(peers.LAST.get("cpu_s", float("nan")))
            res["others"].append(load.cores)
            res["rmse"].append(e_all)
            res["rmse_nl"].append(e_nl)
            res["extra"].append(extra)
            res["last"] = img
        print(f"  repeat {r + 1}/{args.repeats}: " + ", ".join(
            f"{n} {results[n]['times'][-1]:.3f} s (others {results[n]['others'][-1]:.2f} cores)"
            for n in renderers), flush=True)
    return results


def _renderers(args, lumos_ok: bool, cycles_ok: bool) -> dict:
    def mitsuba(variant):
        def fn(spp, depth, w, h, threads, warm):
            img, s = peers.mitsuba_render(variant, spp, depth, w, h, threads=threads, warm=warm)
            return img, s, {}
        return fn

    def lumos_fn(spp, depth, w, h, threads, warm):
        return lumos_render(spp, depth, w, h, threads=threads, warm=warm)

    def cycles_fn(spp, depth, w, h, threads, warm):
        img, s = peers.cycles_render(spp, depth, w, h, threads=threads, warm=warm)
        return img, s, {}

    out = {"Mitsuba llvm_ad_rgb": mitsuba("llvm_ad_rgb"), "Mitsuba scalar_rgb": mitsuba("scalar_rgb")}
    if lumos_ok:
        out["lumos path"] = lumos_fn
    if cycles_ok:
        out["Cycles"] = cycles_fn
    return out


def equal_error(args, renderers, ref, keep, targets):
    ladder = [int(x) for x in args.ladder.split(",")]
    S, T = args.size, args.threads
    print(f"\ntime to equal error: one warm render per spp of {ladder}; target = Mitsuba llvm's median RMSE at "
          f"{args.spp} spp: all {targets[0]:.5f}, no light {targets[1]:.5f}")
    print("  spp: wall s, CPU s, RMSE all/no light (cores other processes kept busy)")
    rows = []
    for name, fn in renderers.items():
        points, line = [], []  # (rmse all, rmse no light, wall s, CPU s)
        for spp in ladder:
            with OtherLoad() as load:
                img, seconds, _ = fn(spp, MI_DEPTH, S, S, T, warm=True)  # an untimed render first where new
            cpu = peers.LAST.get("cpu_s", float("nan"))
            e_all, e_nl = errors(img, ref, keep)
            points.append((e_all, e_nl, seconds, cpu))
            line.append(f"{spp}: {seconds:.2f}, {cpu:.2f}, {e_all:.4f}/{e_nl:.4f} ({load.cores:.2f})")
        print(f"  {name}: " + "; ".join(line), flush=True)
        row = [name]
        for col in (2, 3):  # wall, CPU
            for err, target in ((0, targets[0]), (1, targets[1])):
                row.append(time_at_error([(p[err], p[col]) for p in points], target))
        rows.append(row)
    print()
    print("| renderer | wall s to Mitsuba llvm's RMSE: all | no light | CPU s to it: all | no light |")
    print("|---|---:|---:|---:|---:|")
    for name, *cells in rows:
        print(f"| {name} | " + " | ".join(f"{'~' if x else ''}{t:.3f}" for t, x in cells) + " |")
    print("(~: extrapolated beyond the ladder; CPU s count all threads and are less inflated by other processes)")
    return rows


def big_mesh(args, lumos_ok: bool):
    """Samples per second on the Cornell walls + light with a 1.3M-triangle icosphere."""
    from common import icosphere

    V, F = icosphere(8)
    radius, centre = 0.5, np.array([0.0, -0.5, 0.0])
    V = V * radius + centre
    S, spp, T = args.size, args.big_mesh_spp, args.threads
    print(f"\nbig mesh: Cornell walls + light + icosphere(8), {len(F):,} triangles (radius {radius} at "
          f"{centre.tolist()}, smooth), {S}x{S}, {spp} spp, depth {MI_DEPTH} (lumos {MI_DEPTH - 2}), {T} threads")
    samples = S * S * spp
    if lumos_ok:
        import lumos

        scene_dict = _cornell_dict_with_mesh(V, F)
        scene = lumos.load_scene(scene_dict)
        t0 = time.perf_counter()
        lumos_render(spp, MI_DEPTH, S, S, threads=T, warm=True, scene=scene)  # includes the first BVH build
        first = time.perf_counter() - t0
        times = [lumos_render(spp, MI_DEPTH, S, S, threads=T, warm=False, scene=scene) for _ in range(args.repeats)]
        walls = [t[1] for t in times]
        renders = [t[2].get("render_s", float("nan")) for t in times]
        print(f"  lumos path: first call {first:.2f} s (warm-up); wall {_fmt3(walls)} s; render_s "
              f"{_fmt3(renders)} s; {samples / statistics.median(renders) / 1e6:.3f} M samples/s over render_s, "
              f"{samples / statistics.median(walls) / 1e6:.3f} over the wall")
    else:
        print("  lumos path: not available")
    try:
        import trimesh

        with tempfile.TemporaryDirectory(prefix="bench-path-mesh-") as tmp:
            ply = Path(tmp) / "sphere.ply"
            trimesh.Trimesh(V, F, process=False).export(ply)
            mi, dr = peers._mitsuba("llvm_ad_rgb")
            dr.set_thread_count(T)
            d = peers.mitsuba_scene_dict(spp, MI_DEPTH, S, S)
            del d["small-box"], d["large-box"]
            d["sphere"] = {"type": "ply", "filename": str(ply), "bsdf": {"type": "ref", "id": "white"}}
            t0 = time.perf_counter()
            scene = mi.load_dict(d)
            load = time.perf_counter() - t0
            np.array(mi.render(scene, spp=spp, seed=0))
            walls = []
            for _ in range(args.repeats):
                t0 = time.perf_counter()
                np.array(mi.render(scene, spp=spp, seed=peers.next_seed()))
                walls.append(time.perf_counter() - t0)
        print(f"  Mitsuba llvm_ad_rgb: load_dict {load:.2f} s; render {_fmt3(walls)} s; "
              f"{samples / statistics.median(walls) / 1e6:.3f} M samples/s")
    except Exception as exc:
        print(f"  Mitsuba on the big mesh failed: {type(exc).__name__}: {exc}")


def _cornell_dict_with_mesh(V, F) -> dict:
    """examples/path/cornell.yaml as a dict, the two blocks replaced by the mesh (V, F)."""
    import yaml

    scene = yaml.safe_load(SCENE.read_text())
    scene["objects"] = [o for o in scene["objects"] if o.get("type") != "box"]
    scene["objects"].append({"name": "icosphere", "type": "mesh", "vertices": V, "faces": F, "material": "white"})
    return scene


MITSUBA_PROCESS = """\
import os, sys
os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
sys.path.insert(0, {bench!r})
import numpy as np, drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb"); dr.set_thread_count({threads})
import peers_path
img = mi.render(mi.load_dict(peers_path.mitsuba_scene_dict({spp}, 8, 256, 256)), spp={spp})
mi.util.write_bitmap({out!r}, img)
"""


def first_image(args, lumos_ok: bool):
    from bench_first_image import lumos_command

    spp = 16
    print(f"\ntime to first image (whole processes, {spp} spp, 256x256 as the scene says, {args.threads} threads)")
    with tempfile.TemporaryDirectory(prefix="bench-path-first-") as tmp:
        tmp = Path(tmp)
        if lumos_ok:
            cache = tmp / "numba_cache"
            cache.mkdir()
            cmd = lumos_command() + ["render", str(SCENE), "--method", "path", "--spp", str(spp), "--threads",
                                     str(args.threads), "-o", str(tmp / "x.png"), "--stats", str(tmp / "s.json"),
                                     "--quiet"]
            env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
            runs = []
            for i in range(1 + args.repeats):
                t0 = time.perf_counter()
                proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
                wall = time.perf_counter() - t0
                if proc.returncode != 0:
                    print(f"  lumos failed ({proc.returncode}): {proc.stderr.strip()[-500:]}")
                    break
                stats = json.loads((tmp / "s.json").read_text())
                runs.append((wall, stats))
            if runs:
                print(f"  $ NUMBA_CACHE_DIR=<fresh> {' '.join(cmd)}")
                cold, warm = runs[0], min(runs[1:], key=lambda r: r[0]) if len(runs) > 1 else (float("nan"), {})
                nan = float("nan")
                for label, (wall, st) in (("cold", cold), ("warm", warm)):
                    # startup: interpreter start and imports, the wall time the command's own total_s leaves out
                    print(f"  lumos {label}: wall {wall:.2f} s (startup {wall - st.get('total_s', nan):.2f}, load "
                          f"{st.get('load_s', nan):.2f}, build {st.get('build_s', nan):.2f}, render "
                          f"{st.get('render_s', nan):.2f}, compiling kernels {st.get('jit_s', 0.0):.2f})")
        else:
            print("  lumos path: not available")
        script = tmp / "mitsuba_first.py"
        script.write_text(MITSUBA_PROCESS.format(bench=str(Path(__file__).resolve().parent), threads=args.threads,
                                                 spp=spp, out=str(tmp / "m.exr")))
        walls = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True)
            walls.append(time.perf_counter() - t0)
            if proc.returncode != 0:
                print(f"  Mitsuba process failed: {proc.stderr.strip()[-500:]}")
                return
        print(f"  Mitsuba llvm_ad_rgb whole process (import, load_dict, render, write EXR; its kernel cache as "
              f"found): {_fmt3(walls)} s")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="timed renders of each, alternating")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--size", type=int, default=256, help="width = height")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--ref-spp", type=int, default=16384, help="samples of the converged Mitsuba reference")
    ap.add_argument("--no-cycles", action="store_true", help="leave Cycles out even if bpy imports")
    ap.add_argument("--no-equal-error", action="store_true", help="skip the time-to-equal-error ladder")
    ap.add_argument("--ladder", default="16,32,64,128,256", help="spp counts of the time-to-equal-error ladder")
    ap.add_argument("--big-mesh", action="store_true", help="also: samples/s on a 1.3M-triangle mesh")
    ap.add_argument("--big-mesh-spp", type=int, default=16)
    ap.add_argument("--first-image", action="store_true", help="also: time to first image (whole processes)")
    ap.add_argument("--out", default="/tmp/bench_path", help="folder for the last image of each renderer (EXR)")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    print(f"machine: {machine()}")
    peers._mitsuba("llvm_ad_rgb")
    status = lumos_path_status()
    lumos_ok = status is None
    cycles_ok = not args.no_cycles and peers.cycles_available()
    names = [peers.mitsuba_version() + " (llvm_ad_rgb, scalar_rgb)"]
    names.append("lumos path" if lumos_ok else f"lumos path: not available ({status})")
    names.append(peers.cycles_version() if cycles_ok else "Cycles: not available (bpy does not import)"
                 if not args.no_cycles else "Cycles: left out")
    print("; ".join(names))
    S = args.size
    print(f"Cornell box {S}x{S}, {args.spp} spp, Mitsuba max_depth {MI_DEPTH} = lumos max_depth {MI_DEPTH - 2} = "
          f"Cycles max_bounces {MI_DEPTH - 2}; box filter; {args.threads} threads each; warm; {args.repeats} timed "
          "renders each, alternating, new seed each")

    ref = peers.reference(args.ref_spp, MI_DEPTH, S, S, verbose=True)
    keep = light_mask(ref)
    info = peers.STORED / "info.json"
    entries = json.loads(info.read_text())["files"] if info.is_file() else []
    noise = next((e.get("noise_rmse") for e in entries if e["max_depth"] == MI_DEPTH and e["width"] == S), None)
    print(f"reference: Mitsuba llvm_ad_rgb, {args.ref_spp}+ spp (its own noise, RMSE all: "
          f"{'?' if noise is None else f'{noise:.5f}'}); 'no light' keeps {keep.mean():.1%} of the pixels\n")

    renderers = _renderers(args, lumos_ok, cycles_ok)
    results = main_table(args, renderers, ref, keep)

    def med(res):  # the median of the quiet renders if there are any, else of all
        quiet = [t for t, o in zip(res["times"], res["others"]) if o < QUIET]
        return statistics.median(quiet or res["times"])

    mi_med = {v: med(results[f"Mitsuba {v}"]) for v in peers.VARIANTS}
    print()
    print("| renderer | time s min / median / max | quiet median (n) | CPU s (median) | RMSE all (median) | "
          "RMSE no light (median) | mean RGB / reference's |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    ref_mean = ref.mean(axis=(0, 1))
    for name, res in results.items():
        mean_ratio = res["last"].mean(axis=(0, 1)) / ref_mean
        quiet = [t for t, o in zip(res["times"], res["others"]) if o < QUIET]
        q = f"{statistics.median(quiet):.3f} ({len(quiet)})" if quiet else "- (0)"
        print(f"| {name} | {_fmt3(res['times'])} | {q} | {statistics.median(res['cpu']):.3f} | "
              f"{statistics.median(res['rmse']):.5f} | {statistics.median(res['rmse_nl']):.5f} | "
              f"{' '.join(f'{x:.4f}' for x in mean_ratio)} |")
    busy = max(max(res["others"]) for res in results.values())
    print(f"(quiet: the renders during which other processes kept under {QUIET} cores busy; CPU s: all this "
          f"process's threads; other processes kept at most {busy:.2f} cores busy during a render"
          f"{' -- the machine was shared: trust the quiet medians and CPU s' if busy > QUIET else ''})")
    print()
    for name, res in results.items():
        if name.startswith("Mitsuba"):
            continue
        m = med(res)
        print(f"{name} / Mitsuba: " + ", ".join(f"{m / mi_med[v]:.2f}x {v}" for v in peers.VARIANTS)
              + " (median time over median time, quiet renders where there are any)")
    if lumos_ok:
        rs = [e.get("render_s", float("nan")) for e in results["lumos path"]["extra"]]
        print(f"lumos path stats['render_s']: {_fmt3(rs)} s")
    if not lumos_ok:
        print("lumos path: not available")

    from lumos.io.image_files import write_image

    for name, res in results.items():
        write_image(out / (name.replace(" ", "_") + ".exr"), res["last"])
    write_image(out / "reference.exr", ref)
    print(f"wrote the last image of each and reference.exr to {out}")

    if not args.no_equal_error:
        targets = (statistics.median(results["Mitsuba llvm_ad_rgb"]["rmse"]),
                   statistics.median(results["Mitsuba llvm_ad_rgb"]["rmse_nl"]))
        equal_error(args, renderers, ref, keep, targets)
    if args.big_mesh:
        big_mesh(args, lumos_ok)
    if args.first_image:
        first_image(args, lumos_ok)


if __name__ == "__main__":
    main()
