"""Render every figure of docs/methods/path.md from the scenes in this folder (and examples/showcase.yaml).

    python examples/path/figures.py                      # writes docs/images/path/*.png; ~10 min on one core
    python examples/path/figures.py --threads 1          # the figures of the guide were made so (the images
                                                         # do not depend on the thread count, only the times)
    python examples/path/figures.py --quick              # 1/16 of the samples, written to a temporary folder
    python examples/path/figures.py --only veach noise   # some figures only

Each figure loads a scene (`lumos.load_scene`), renders it with `lumos.render` (a setting or two given as
keywords), and, where it compares renders, puts them side by side with a caption under each (as
examples/raster/figures.py does). Every number in a caption is measured here and printed too:

- `cornell.png`, `cornell_spheres.png`, `showcase.png`, `glowing_bunny.png`: the renders, with their times.
- `veach_mis.png`: sampling light / bsdf / mis at equal spp, each caption with the RMSE over the plates' pixels
  against a 1024-spp MIS render of the same scene, of the displayed values (radiance clamped to [0, 1], as the
  PNG shows it: the highlights of the small lights reach 500, and unclamped their few pixels would decide the
  figure alone); the linear RMSE is printed beside it.
- `noise.png` and `noise_plot.png`: the Cornell box at 4, 16, 64, 256 spp, and RMSE against Mitsuba 3's
  converged image (tests/data/cornell_mitsuba/ref_depth8_256.npy: 16384 spp, Mitsuba max_depth 8 = lumos 6)
  for 1 to 256 spp with the Sobol and the independent sampler, on log-log axes with a 1/sqrt(N) line. The
  plot needs matplotlib (`pip install matplotlib`), imported for that figure only; without it the plot is
  skipped and the numbers are still printed.
- `denoise.png`: 16 spp before and after `denoise: true` (Intel Open Image Denoise: `pip install pyoidn`), the
  1024-spp render and Mitsuba's reference, with the RMSE of each against the reference. Skipped without pyoidn.
- `helmet.png`: DamagedHelmet under the courtyard (helmet.yaml) beside three.js's render of the same file
  (helmet_three.png, from helmet_viewer.py), with the mean difference over the helmet's pixels.
- `material_grid.png`: material_grid.yaml, the principled material's metallic × roughness grid.
- `variance.png`: the spheres box and its `variance` AOV, shown as the standard error of each pixel (of the
  variance averaged over 3x3 pixels).

RMSE is over every pixel and channel of the linear image; "off the lamp" leaves out the pixels within one
pixel of the directly seen ceiling light (radiance 18 against at most 1 elsewhere, so its edge pixels, which
measure pixel anti-aliasing rather than light transport, weigh most in the plain RMSE), as
benchmarks/bench_path.py does.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import lumos

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # examples/: the figure scripts' shared kit
from figure_kit import compose, png8, save_image, shown  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OUT = ROOT / "docs" / "images" / "path"
REFERENCE = ROOT / "tests" / "data" / "cornell_mitsuba" / "ref_depth8_256.npy"


#: Set by main(): worker threads of every render, and the fraction of the samples (--quick: 1/16).
THREADS: int | None = None
SCALE = 1.0
#: Renders that more than one figure uses, made once.
_cache: dict = {}
#: (figure, what, value) rows, printed at the end.
MEASURED: list[tuple[str, str, str]] = []


# ------------------------------------------------------------------------------------------------ helpers


def load(name: str):
    path = HERE / name if (HERE / name).exists() else ROOT / "examples" / name
    return lumos.load_scene(path)


def spp(n: int) -> int:
    """n samples per pixel, or 1/16 of them with --quick (at least 1)."""
    return max(1, int(round(n * SCALE)))


def render(scene, label: str, **settings) -> lumos.Image:
    img = lumos.render(scene, threads=THREADS, **settings)
    s = img.stats
    print(f"  {label}: {s['width']}x{s['height']}, {s['spp']} spp, render {s['render_s']:.2f} s "
          f"({s['threads']} thread{'s' if s['threads'] > 1 else ''}), {s['rays']:,} rays, "
          f"{s['mrays_per_s']:.2f} Mrays/s, {s.get('discarded_samples', 0)} non-finite samples dropped", flush=True)
    return img


def save(page, name: str) -> None:
    save_image(page, OUT / name, ROOT)


def _shown(path: Path) -> str:
    return shown(path, ROOT)


def measured(figure: str, what: str, value: str) -> None:
    MEASURED.append((figure, what, value))
    print(f"  = {what}: {value}", flush=True)


def rmse(a: np.ndarray, b: np.ndarray, keep: np.ndarray | None = None) -> float:
    """Root mean square error over the pixels (all, or those where `keep`) and channels."""
    if keep is not None:
        a, b = a[keep], b[keep]
    return float(np.sqrt(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2)))


def off_the_lamp(ref: np.ndarray) -> np.ndarray:
    """True for the pixels more than one pixel away from a pixel that sees the lamp (reference radiance above 1
    in some channel: nothing else in the Cornell box is that bright); benchmarks/bench_path.py's "no light"."""
    lit = (ref > 1.0).any(axis=-1)
    grown = lit.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            grown |= np.roll(np.roll(lit, dy, axis=0), dx, axis=1)
    return ~grown


def box_mean(a: np.ndarray, r: int) -> np.ndarray:
    """The mean of `a` (H, W) over the (2r+1)² pixels around each pixel (edges repeated)."""
    p = np.pad(a, r, mode="edge")
    h, w = a.shape
    return sum(p[dy:dy + h, dx:dx + w] for dy in range(2 * r + 1) for dx in range(2 * r + 1)) / (2 * r + 1) ** 2


def reference() -> np.ndarray:
    return np.load(REFERENCE).astype(np.float32)


def cornell_converged() -> lumos.Image:
    """The Cornell box at 1024 spp (made once: the Cornell figure and the denoising figure show it)."""
    if "cornell" not in _cache:
        _cache["cornell"] = render(load("cornell.yaml"), "cornell.yaml", spp=spp(1024))
    return _cache["cornell"]


# ------------------------------------------------------------------------------------------------ figures


def cornell_figure():
    """cornell.yaml (Mitsuba's Cornell box) at 1024 spp, with its RMSE against Mitsuba's converged image."""
    img = cornell_converged()
    ref = reference()
    keep = off_the_lamp(ref)
    a = rmse(img.array, ref)
    b = rmse(img.array, ref, keep)
    measured("cornell", f"{img.stats['spp']} spp render_s", f"{img.stats['render_s']:.1f}")
    measured("cornell", f"{img.stats['spp']} spp RMSE vs Mitsuba (all / off the lamp)", f"{a:.5f} / {b:.5f}")
    save(png8(img.array), "cornell.png")


def spheres_figure():
    """cornell_spheres.yaml at 1024 spp; the same render's variance AOV as the standard error of each pixel."""
    scene = load("cornell_spheres.yaml")
    img = render(scene, "cornell_spheres.yaml", spp=spp(1024), aov=["variance"])
    measured("cornell_spheres", f"{img.stats['spp']} spp render_s", f"{img.stats['render_s']:.1f}")
    save(png8(img.array), "cornell_spheres.png")
    # the variance AOV is the variance of each pixel's mean (its estimator's): its square root is the noise
    # left in the pixel. The variance is itself estimated from the pixel's samples and one firefly makes it
    # jump, so it is averaged over 3x3 pixels first; shown as grey, white = the 99.5th percentile of the
    # standard error, through the sRGB curve like the image.
    sigma = np.sqrt(box_mean(np.maximum(img.aovs["variance"], 0.0).mean(axis=2), 1))
    top = float(np.percentile(sigma, 99.5))
    grey = png8(np.repeat((sigma / top)[:, :, None], 3, axis=2))
    q = {p: float(np.percentile(sigma, p)) for p in (50, 99)}
    measured("variance", "standard error (3x3): median / 99th percentile / 99.5th",
             f"{q[50]:.4f} / {q[99]:.4f} / {top:.4f}")
    page = compose([(f"cornell_spheres.yaml, {img.stats['spp']} spp\n", png8(img.array)),
                    ("variance AOV: standard error (3x3 mean)\nwhite = its 99.5th percentile", grey)], 2)
    save(page, "variance.png")


def showcase_figure():
    """examples/showcase.yaml (method raycast in its file) rendered with whitted and with path, side by side."""
    scene = load("showcase.yaml")
    size = {"width": 400, "height": 300}
    w = render(scene, "showcase.yaml whitted", method="whitted", spp=16, **size)
    p = render(scene, "showcase.yaml path", method="path", spp=spp(256), **size)
    measured("showcase", f"whitted 16 spp / path {p.stats['spp']} spp render_s",
             f"{w.stats['render_s']:.2f} / {p.stats['render_s']:.2f}")
    save(compose([(f"whitted, 16 spp, {w.stats['render_s']:.1f} s", png8(w.array, w.exposure)),
                  (f"path, {p.stats['spp']} spp, {p.stats['render_s']:.1f} s", png8(p.array, p.exposure))], 2),
         "showcase.png")


def bunny_figure():
    """glowing_bunny.yaml as its file says (400x300, 128 spp)."""
    img = render(load("glowing_bunny.yaml"), "glowing_bunny.yaml", spp=spp(128))
    measured("glowing_bunny", f"{img.stats['spp']} spp render_s", f"{img.stats['render_s']:.1f}")
    save(png8(img.array, img.exposure), "glowing_bunny.png")


def veach_figure():
    """veach_mis.yaml with sampling light, bsdf and mis at its spp (32), and the RMSE of each over the plates'
    pixels against a 1024-spp MIS render."""
    scene = load("veach_mis.yaml")
    ref = render(scene, "veach_mis.yaml reference (mis)", spp=spp(1024), aov=["object_id"])
    plates = (ref.aovs["object_id"] >= 0) & (ref.aovs["object_id"] <= 3)  # objects 0-3 are the plates
    panels = []
    n = spp(scene.render.spp)
    for mode in ("light", "bsdf", "mis"):
        img = render(scene, f"veach_mis.yaml sampling {mode}", sampling=mode, spp=n)
        e_lin = rmse(img.array, ref.array, plates)
        e = rmse(np.clip(img.array, 0, 1), np.clip(ref.array, 0, 1), plates)
        measured("veach_mis", f"sampling {mode}, {n} spp: RMSE on the plates displayed / linear, render_s",
                 f"{e:.4f} / {e_lin:.3f}, {img.stats['render_s']:.2f}")
        panels.append((f"sampling: {mode}, {n} spp\nRMSE on the plates {e:.3f}", png8(img.array)))
    save(compose(panels, 3), "veach_mis.png")


def noise_figure():
    """The Cornell box at 1 … 256 spp with both samplers: crops at 4, 16, 64, 256 (Sobol), and the plot."""
    scene = load("cornell.yaml")
    ref = reference()
    keep = off_the_lamp(ref)
    ladder = [spp(n) for n in (1, 4, 16, 64, 256)]
    ladder = sorted(set(ladder))
    curves = {}
    crops = []
    y0, y1, x0, x1 = 40, 168, 20, 148  # the red wall, the tall block, the back wall and the floor's corner
    for sampler in ("sobol", "independent"):
        points = []
        for n in ladder:
            img = render(scene, f"cornell.yaml {sampler}", spp=n, sampler=sampler)
            a, b = rmse(img.array, ref), rmse(img.array, ref, keep)
            points.append((n, a, b, img.stats["render_s"]))
            measured("noise", f"{sampler} {n:>4} spp: RMSE all / off the lamp, render_s",
                     f"{a:.5f} / {b:.5f}, {img.stats['render_s']:.2f}")
            if sampler == "sobol" and n >= 4:
                crop = np.repeat(np.repeat(png8(img.array[y0:y1, x0:x1]), 2, axis=0), 2, axis=1)
                crops.append((f"{n} spp, RMSE {a:.4f}", crop))
        curves[sampler] = points
    save(compose(crops, len(crops)), "noise.png")
    for i in range(len(ladder)):
        s, r = curves["sobol"][i], curves["independent"][i]
        measured("noise", f"{ladder[i]:>4} spp: independent / sobol RMSE ratio (all, off the lamp)",
                 f"{r[1] / s[1]:.2f}, {r[2] / s[2]:.2f}")
    try:
        import matplotlib
    except ImportError:
        print("noise_plot.png: skipped (pip install matplotlib to draw it)")
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(8.0, 3.4), dpi=100, sharey=True)
    for ax, col, title in ((axes[0], 1, "all pixels"), (axes[1], 2, "off the lamp")):
        for sampler, style in (("independent", "o-"), ("sobol", "s-")):
            xs = [p[0] for p in curves[sampler]]
            ys = [p[col] for p in curves[sampler]]
            ax.loglog(xs, ys, style, label=f"sampler: {sampler}", markersize=4)
        x = np.array([ladder[0], ladder[-1]], float)
        first = curves["independent"][0][col]
        ax.loglog(x, first * (x / x[0]) ** -0.5, "k--", linewidth=1, label="1/√N")
        ax.set_xlabel("samples per pixel N")
        ax.set_title(f"Cornell box, RMSE vs Mitsuba 3 ({title})", fontsize=10)
        ax.set_xticks(ladder)
        ax.set_xticklabels([str(n) for n in ladder])
        ax.grid(True, which="both", linewidth=0.3)
    axes[0].set_ylabel("RMSE (linear radiance)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    path = OUT / "noise_plot.png"
    fig.savefig(path)
    plt.close(fig)
    print(f"{_shown(path)}: {path.stat().st_size // 1024} KB")


def denoise_figure():
    """The Cornell box at 16 spp, raw and denoised, the 1024-spp render and Mitsuba's reference, each with its
    RMSE against the reference."""
    try:
        import pyoidn  # noqa: F401
    except ImportError:
        print("denoise.png: skipped (pip install pyoidn)")
        return
    from lumos.denoise import denoise

    scene = load("cornell.yaml")
    ref = reference()
    keep = off_the_lamp(ref)
    n = spp(16)
    img = render(scene, "cornell.yaml denoised", spp=n, denoise=True, aov=["noisy", "albedo", "normal"])
    t0 = time.perf_counter()
    denoise(img.aovs["noisy"], img.aovs["albedo"], img.aovs["normal"])  # once more, to time the denoiser alone
    oidn_s = time.perf_counter() - t0
    conv = cornell_converged()
    panels = []
    for label, a in ((f"{n} spp", img.aovs["noisy"]), (f"{n} spp, denoise: true", img.array),
                     (f"{conv.stats['spp']} spp", conv.array), ("Mitsuba 3, 16384 spp", ref)):
        e_all, e_off = rmse(a, ref), rmse(a, ref, keep)
        measured("denoise", f"{label}: RMSE all / off the lamp", f"{e_all:.5f} / {e_off:.5f}")
        text = "the reference" if a is ref else f"RMSE {e_all:.4f}, off the lamp {e_off:.4f}"
        panels.append((f"{label}\n{text}", png8(a)))
    measured("denoise", "OIDN alone on the 256x256 image, s", f"{oidn_s:.2f}")
    save(compose(panels, 4), "denoise.png")


def helmet_figure():
    """helmet.yaml as its file says, beside three.js's render of the same glTF file, environment and camera
    (docs/images/path/helmet_three.png, made by examples/path/helmet_viewer.py), with the mean difference of the
    displayed 8-bit values over the helmet's pixels."""
    from PIL import Image

    scene = load("helmet.yaml")
    img = render(scene, "helmet.yaml", spp=spp(scene.render.spp), aov=["object_id"])
    ours = png8(img.array, img.exposure)
    panels = [(f"lumos path, {img.stats['spp']} spp, {img.stats['render_s']:.0f} s", ours)]
    three = ROOT / "docs" / "images" / "path" / "helmet_three.png"
    if three.exists():
        theirs = np.asarray(Image.open(three).convert("RGB"))
        helmet = img.aovs["object_id"] >= 0
        diff = np.abs(ours.astype(float) - theirs.astype(float))[helmet].mean()
        measured("helmet", "mean |lumos - three.js| over the helmet, 8-bit", f"{diff:.1f}")
        panels.append(("three.js r187 (WebGL, image-based lighting)", theirs))
    save(compose(panels, 2), "helmet.png")


def grid_figure():
    """material_grid.yaml as its file says: glTF's metallic (rows) × roughness (columns) under the courtyard."""
    scene = load("material_grid.yaml")
    img = render(scene, "material_grid.yaml", spp=spp(scene.render.spp))
    measured("material_grid", f"{img.stats['spp']} spp render_s", f"{img.stats['render_s']:.1f}")
    save(png8(img.array, img.exposure), "material_grid.png")


FIGURES = {"cornell": cornell_figure, "spheres": spheres_figure, "showcase": showcase_figure,
           "bunny": bunny_figure, "veach": veach_figure, "noise": noise_figure, "denoise": denoise_figure,
           "helmet": helmet_figure, "grid": grid_figure}


def main() -> None:
    global THREADS, SCALE, OUT
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="1/16 of the samples (to check the script)")
    parser.add_argument("--threads", type=int, help="worker threads of every render (default: all cores)")
    parser.add_argument("--only", nargs="+", choices=sorted(FIGURES), help="these figures only")
    parser.add_argument("--out", type=Path, help="folder to write to (default: docs/images/path; with --quick, "
                        "lumos-path-figures-quick in the temporary folder, so the guide's images stay)")
    args = parser.parse_args()
    THREADS = args.threads
    SCALE = 1.0 / 16.0 if args.quick else 1.0
    OUT = args.out or (Path(tempfile.gettempdir()) / "lumos-path-figures-quick" if args.quick else OUT)
    OUT.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    for name in args.only or FIGURES:
        print(f"{name}:", flush=True)
        FIGURES[name]()
    print(f"\nmeasured ({'--quick, ' if args.quick else ''}{THREADS or 'all'} thread(s), "
          f"{time.perf_counter() - started:.0f} s in all):")
    for figure, what, value in MEASURED:
        print(f"  {figure:16} {what:64} {value}")


if __name__ == "__main__":
    main()
