"""Render every figure of docs/methods/radiosity.md from the scenes in this folder.

    python examples/radiosity/figures.py                       # writes docs/images/radiosity/*.png; ~2 min
    python examples/radiosity/figures.py --threads 1           # on one thread (the solutions do not depend on
                                                               # the thread count, only the times)
    python examples/radiosity/figures.py --only stochastic     # some figures only

Each figure loads a scene (`lumos.load_scene`), solves it with `lumos.radiosity.solve(scene, settings)` (a
setting or two of its `render.radiosity` block changed) and draws the solution with `lumos.render(scene,
solution=...)`, so that one solution can be drawn twice (flat and Gouraud) without solving again. Renders that
are compared sit side by side with a caption under each (as examples/path/figures.py does). Every number in a
caption is measured here and printed too:

- `cornell.png`: cornell.yaml (adaptive subdivision on) beside Mitsuba 3's converged path-traced image of the
  same box (tests/data/cornell_mitsuba/ref_depthinf_256.npy: unbounded depth), with the error of the first
  against the second: the mean relative error over 8x8-pixel blocks, as tests/methods/test_radiosity.py measures it.
- `display.png`: one solution (2,352 patches) drawn with `display: flat` and `display: gouraud`.
- `form_factors.png`: ray-cast against hemicube form factors (resolutions 128 and 32), same patches.
- `subdivision.png`: coarse patches (0.25) with adaptive subdivision off and on: flat, each element's level of
  refinement in false colour, and Gouraud.
- `mirror.png`: cornell_mirror.yaml: the diffuse solution alone (pass 1), the two-pass display, and the path
  tracer on the same scene.
- `room.png`: room.yaml (a point light, boxes, a sphere, a cylinder, a mesh), Gouraud and flat, and the
  path tracer on the same scene.
- `progressive.png`, `progressive_plot.png`: progressive refinement stopped after 12, 100 and 1,000 shots
  and converged; the unshot power and the error against a converged Gauss–Seidel solution of the same patches,
  against the number of shots.
- `sweeps_plot.png`: Jacobi against Gauss–Seidel: the largest change of each sweep (what the solver's `say`
  callback reports: "sweep N: largest change X of the mean radiance").
- `stochastic_plot.png`: stochastic radiosity: error against rays on log-log axes with the 1/sqrt(N) slope.

Errors of a solution against another are over the elements that are lit and do not emit, weighted by area:
the relative RMS `sqrt(Σ A·(L − L_ref)²) / sqrt(Σ A·L_ref²)` (L the mean of the RGB channels). The plots need
matplotlib (`pip install matplotlib`), imported for them only; without it they are skipped and the numbers are
still printed.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import sys
import time
from pathlib import Path

import numpy as np

import lumos

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # examples/: the figure scripts' shared kit
from figure_kit import compose, png8, save_image, shown  # noqa: E402
from lumos.api import resolve_settings
from lumos.radiosity import solve

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OUT = ROOT / "docs" / "images" / "radiosity"
REFERENCE = ROOT / "tests" / "data" / "cornell_mitsuba" / "ref_depthinf_256.npy"


#: Set by main(): worker threads of every solve and render.
THREADS: int | None = None
#: Solutions that more than one figure uses, made once.
_cache: dict = {}
#: (figure, what, value) rows, printed at the end.
MEASURED: list[tuple[str, str, str]] = []


# ------------------------------------------------------------------------------------------------ helpers


def load(name: str):
    return lumos.load_scene(HERE / name)


def solved(scene, label: str, say=None, seed=None, **radiosity):
    """The radiosity solution of `scene` with its render.radiosity block overridden by `radiosity` (and its
    seed by `seed`), and the seconds it took (meshing, form factors and solving)."""
    settings = resolve_settings(scene, {"method": "radiosity", "threads": THREADS, "seed": seed,
                                        "radiosity": radiosity})
    t0 = time.perf_counter()
    sol = solve(scene, settings, say=say)
    seconds = time.perf_counter() - t0
    s = sol.stats
    print(f"  {label}: {s['solver']}, {s['form_factors']} form factors, {s['patches']:,} patches, "
          f"{s['elements']:,} elements, {s['iterations']:,} iterations, residual {s['residual']:.2e}, "
          f"{s['rays']:,} rays, {seconds:.2f} s", flush=True)
    return sol, seconds


def draw(scene, sol, **settings) -> lumos.Image:
    """The solution drawn from the scene's camera (display and two-pass as the settings say)."""
    radiosity = {"display": settings.pop("display")} if "display" in settings else {}
    return lumos.render(scene, method="radiosity", solution=sol, threads=THREADS, radiosity=radiosity,
                        **settings)


def save(page, name: str) -> None:
    save_image(page, OUT / name, ROOT)


def save_plot(fig, name: str) -> None:
    import matplotlib.pyplot as plt

    path = OUT / name
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    print(f"{_shown(path)}: {path.stat().st_size // 1024} KB", flush=True)


def pyplot():
    """matplotlib.pyplot with the Agg backend, or None (and a note) without matplotlib."""
    try:
        import matplotlib
    except ImportError:
        print("  plot skipped (pip install matplotlib to draw it)")
        return None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _shown(path: Path) -> str:
    return shown(path, ROOT)


def measured(figure: str, what: str, value: str) -> None:
    MEASURED.append((figure, what, value))
    print(f"  = {what}: {value}", flush=True)


def block_error(img: np.ndarray, ref: np.ndarray, k: int = 8) -> float:
    """Mean relative error over k×k-pixel blocks (and channels) where the reference is lit: the measure of
    tests/methods/test_radiosity.py's Cornell test."""
    def blocks(a):
        h, w = a.shape[:2]
        return a.reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))

    ours, theirs = blocks(img.astype(np.float64)), blocks(ref.astype(np.float64))
    lit = theirs > 1e-3
    return float(np.mean(np.abs(ours - theirs)[lit] / theirs[lit]))


def solution_error(sol, ref) -> float:
    """Relative RMS error of a solution's element radiance against a reference solution of the same elements,
    area-weighted, over the lit elements that do not emit."""
    L, R = sol.element_radiance.mean(axis=1), ref.element_radiance.mean(axis=1)
    keep = (ref.element_emission.max(axis=1) <= 0) & (R > 1e-3)
    a = ref.element_area[keep]
    return float(np.sqrt(np.sum(a * (L[keep] - R[keep]) ** 2) / np.sum(a * R[keep] ** 2)))


def surface_power(sol) -> float:
    """Σ A·L over the elements that do not emit (mean of the channels): the light the surfaces send out, /π."""
    keep = sol.element_emission.max(axis=1) <= 0
    return float(np.sum(sol.element_area[keep] * sol.element_radiance[keep].mean(axis=1)))


def reference() -> np.ndarray:
    return np.load(REFERENCE).astype(np.float32)


def cornell_plain():
    """cornell.yaml with subdivision off: its 2,352 default patches, progressive, ray-cast (made once)."""
    if "plain" not in _cache:
        _cache["plain"] = solved(load("cornell.yaml"), "cornell.yaml, subdivide off", subdivide=False)
    return _cache["plain"]


def gauss_seidel_reference():
    """The same patches solved by Gauss–Seidel to 1e-6 (made once), and the sweeps it reported."""
    if "gs" not in _cache:
        lines: list[str] = []
        sol, seconds = solved(load("cornell.yaml"), "cornell.yaml, gauss_seidel to 1e-6", say=lines.append,
                              subdivide=False, solver="gauss_seidel", tolerance=1e-6)
        _cache["gs"] = (sol, seconds, lines)
    return _cache["gs"]


def sweeps(lines: list[str]) -> list[float]:
    """The largest change of each sweep, from the solver's say() lines."""
    pattern = re.compile(r"sweep (\d+): largest change ([0-9.e+-]+)")
    return [float(m.group(2)) for m in map(pattern.match, lines) if m]


# ------------------------------------------------------------------------------------------------ figures


def cornell_figure():
    """cornell.yaml as its file says (subdivide on) beside Mitsuba's converged image, with the block error;
    the error without subdivision and with smaller patches too (the accuracy table of the guide)."""
    scene = load("cornell.yaml")
    ref = reference()
    sol, seconds = solved(scene, "cornell.yaml")
    img = draw(scene, sol)
    e = block_error(img.array, ref)
    measured("cornell", "subdivide on: patches / elements, solve s, block error vs Mitsuba",
             f"{sol.stats['patches']:,} / {sol.stats['elements']:,}, {seconds:.1f}, {e:.2%}")
    plain, plain_s = cornell_plain()
    e_plain = block_error(draw(scene, plain).array, ref)
    measured("cornell", "subdivide off: patches, solve s, block error vs Mitsuba",
             f"{plain.stats['patches']:,}, {plain_s:.1f}, {e_plain:.2%}")
    fine, fine_s = solved(scene, "cornell.yaml, patch_size 0.1", subdivide=False, patch_size=0.1)
    e_fine = block_error(draw(scene, fine).array, ref)
    measured("cornell", "patch_size 0.1, subdivide off: patches, solve s, block error vs Mitsuba",
             f"{fine.stats['patches']:,}, {fine_s:.1f}, {e_fine:.2%}")
    save(compose([(f"radiosity: {sol.stats['elements']:,} elements, {seconds:.1f} s\n"
                   f"block error vs Mitsuba {e:.1%}", png8(img.array)),
                  ("Mitsuba 3, path traced\n(converged, unbounded depth)", png8(ref))], 2), "cornell.png")


def display_figure():
    """One solution of the default patches drawn flat and Gouraud."""
    scene = load("cornell.yaml")
    sol, _ = cornell_plain()
    n = sol.stats["patches"]
    panels = [(f"display: flat\n{n:,} patches, one colour each", png8(draw(scene, sol, display="flat").array)),
              ("display: gouraud\nradiance averaged to the corners", png8(draw(scene, sol).array))]
    save(compose(panels, 2), "display.png")


def form_factor_figure():
    """The default patches with ray-cast and with hemicube form factors (resolution 128 and 32)."""
    scene = load("cornell.yaml")
    ref = reference()
    raycast, _ = cornell_plain()
    panels = []
    for label, sol in (("raycast", raycast),
                       ("hemicube 128", solved(scene, "hemicube 128", subdivide=False, form_factors="hemicube")[0]),
                       ("hemicube 32", solved(scene, "hemicube 32", subdivide=False, form_factors="hemicube",
                                              hemicube_resolution=32)[0])):
        img = draw(scene, sol)
        e = block_error(img.array, ref)
        ff = sol.stats["form_factor_s"]
        measured("form_factors", f"{label}: form factor s, block error vs Mitsuba", f"{ff:.2f}, {e:.2%}")
        panels.append((f"{label}: form factors {ff:.1f} s\nblock error {e:.1%}", png8(img.array)))
    save(compose(panels, 3), "form_factors.png")


def subdivision_figure():
    """Coarse patches (0.25) with subdivision off and on: flat (the elements), the level of each element in
    false colour, and Gouraud."""
    scene = load("cornell.yaml")
    ref = reference()
    off, off_s = solved(scene, "patch_size 0.25, subdivide off", patch_size=0.25, subdivide=False)
    on, on_s = solved(scene, "patch_size 0.25, subdivide on", patch_size=0.25, subdivide=True)
    e_off, e_on = (block_error(draw(scene, s).array, ref) for s in (off, on))
    img = draw(scene, on)
    for word, sol, seconds, e in (("off", off, off_s, e_off), ("on", on, on_s, e_on)):
        measured("subdivision", f"subdivide {word}: patches / elements, solve s, block error",
                 f"{sol.stats['patches']:,} / {sol.stats['elements']:,}, {seconds:.1f}, {e:.2%}")
    levels = refinement_levels(on)
    counts = np.bincount(levels, minlength=3)
    measured("subdivision", "elements at level 0 / 1 / 2", " / ".join(f"{c:,}" for c in counts))
    panels = [(f"subdivide off, flat\n{off.stats['patches']:,} patches, block error {e_off:.1%}",
               png8(draw(scene, off, display="flat").array)),
              (f"subdivide on, flat\n{on.stats['elements']:,} elements", png8(draw(scene, on, display="flat").array)),
              ("the elements' levels: grey 0,\nyellow 1 (1/4 patch), red 2 (1/16)",
               png8(draw(scene, level_colours(on, levels), display="flat").array)),
              (f"subdivide on, gouraud\nblock error {e_on:.1%}", png8(img.array))]
    save(compose(panels, 4), "subdivision.png")


def refinement_levels(sol) -> np.ndarray:
    """How many times each element's patch was cut to make it: log4 of the patch's area over the element's."""
    patch_area = np.bincount(sol.element_patch, sol.element_area)
    return np.rint(np.log(patch_area[sol.element_patch] / sol.element_area) / np.log(4.0)).astype(np.int64)


def level_colours(sol, levels):
    """The solution with each element's radiance replaced by a colour for its level (grey, yellow, red),
    shaded by its own brightness so that the box stays recognisable; emitters stay white."""
    palette = np.array([[0.55, 0.55, 0.55], [1.0, 0.62, 0.04], [0.95, 0.05, 0.03], [0.5, 0.1, 0.9]])
    lum = sol.element_radiance.mean(axis=1)
    emits = sol.element_emission.max(axis=1) > 0
    shade = 0.25 + 0.75 * np.sqrt(np.clip(lum / max(float(lum[~emits].max(initial=1e-9)), 1e-9), 0.0, 1.0))
    colours = palette[np.minimum(levels, len(palette) - 1)] * shade[:, None]
    colours[emits] = 1.0
    return dataclasses.replace(sol, element_radiance=colours)


def mirror_figure():
    """cornell_mirror.yaml: its diffuse solution drawn without the second pass, with it, and path-traced."""
    scene = load("cornell_mirror.yaml")
    sol, seconds = solved(scene, "cornell_mirror.yaml")
    # the first pass alone: the same solution with its mirrors and glass taken out (kr = kt = 0)
    optics = sol.element_optics.copy()
    optics[:, :6] = 0.0
    diffuse = draw(scene, dataclasses.replace(sol, element_optics=optics))
    two = draw(scene, sol)
    spp = 256
    path = lumos.render(scene, method="path", spp=spp, threads=THREADS)
    measured("mirror", "patches, solve s, two-pass draw s, path render s",
             f"{sol.stats['patches']:,}, {seconds:.1f}, {two.stats['render_s']:.2f}, {path.stats['render_s']:.1f}")
    save(compose([("the solution alone (pass 1)\nmirror and glass: kd 0, black", png8(diffuse.array)),
                  (f"two-pass, {seconds + two.stats['render_s']:.1f} s\nno caustic, dark glass shadow",
                   png8(two.array)),
                  (f"path, {spp} spp, {path.stats['render_s']:.1f} s\nthe caustic under the glass",
                   png8(path.array))], 3), "mirror.png")


def room_figure():
    """room.yaml as its file says, Gouraud and flat, and the path tracer on the same scene."""
    scene = load("room.yaml")
    sol, seconds = solved(scene, "room.yaml")
    s = sol.stats
    img = draw(scene, sol)
    spp = 64
    path = lumos.render(scene, method="path", spp=spp, threads=THREADS)
    ratio = img.array.mean(axis=(0, 1)) / path.array.mean(axis=(0, 1))
    measured("room", "patches / elements, iterations, solve s, path render s",
             f"{s['patches']:,} / {s['elements']:,}, {s['iterations']:,}, {seconds:.1f}, {path.stats['render_s']:.1f}")
    measured("room", "mean image radiance, radiosity / path (r, g, b)", ", ".join(f"{r:.3f}" for r in ratio))
    save(compose([(f"radiosity, {seconds:.1f} s", png8(img.array)),
                  (f"flat: {s['patches']:,} patches, {s['elements']:,} elements",
                   png8(draw(scene, sol, display="flat").array)),
                  (f"path, {spp} spp, {path.stats['render_s']:.1f} s", png8(path.array))], 3), "room.png")


def sweeps_figure():
    """Gauss–Seidel and Jacobi on the default patches to 1e-6: the largest change of each sweep."""
    scene = load("cornell.yaml")
    _, gs_s, gs_lines = gauss_seidel_reference()
    lines: list[str] = []
    _, jac_s = solved(scene, "cornell.yaml, jacobi to 1e-6", say=lines.append, subdivide=False, solver="jacobi",
                      tolerance=1e-6)
    curves = {"gauss_seidel": sweeps(gs_lines), "jacobi": sweeps(lines)}
    for name, values in curves.items():
        at = {k: values[k - 1] for k in (1, 5, 10) if k <= len(values)}
        measured("sweeps", f"{name}: sweeps to 1e-6; change after sweep 1 / 5 / 10",
                 f"{len(values)}; " + " / ".join(f"{v:.1e}" for v in at.values()))
    gs = gauss_seidel_reference()[0]
    measured("sweeps", "gauss_seidel / jacobi solve s (form factors included); gauss_seidel form factor s",
             f"{gs_s:.1f} / {jac_s:.1f}; {gs.stats['form_factor_s']:.2f}")
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(5.6, 3.6), dpi=100)
    for (name, values), style in zip(curves.items(), ("s-", "o-")):
        ax.semilogy(np.arange(1, len(values) + 1), values, style, markersize=3, label=f"solver: {name}")
    ax.axhline(1e-2, color="k", linestyle="--", linewidth=0.8, label="tolerance 0.01 (the default)")
    ax.set_xlabel("sweep")
    ax.set_ylabel("largest change / mean radiance")
    ax.set_title("Cornell box, 2,352 patches: gathering sweeps", fontsize=10)
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8)
    save_plot(fig, "sweeps_plot.png")


def progressive_figure():
    """Progressive refinement stopped after more and more shots: the images after 12, 100 and 1,000 shots and
    converged, and the unshot power and the error against Gauss–Seidel, against the shots."""
    scene = load("cornell.yaml")
    ref, _, _ = gauss_seidel_reference()
    ladder = [1, 3, 12, 30, 100, 300, 1000, 3000]
    points = []  # (shots, unshot power, error, seconds)
    strip = []
    for shots in ladder:
        sol, seconds = solved(scene, f"{shots} shots", subdivide=False, max_iterations=shots, tolerance=1e-3)
        points.append((sol.stats["iterations"], sol.stats["residual"], solution_error(sol, ref), seconds))
        if shots in (12, 100, 1000):
            strip.append((shots, sol))
    sol, seconds = solved(scene, "to 1e-3", subdivide=False, tolerance=1e-3)
    points.append((sol.stats["iterations"], sol.stats["residual"], solution_error(sol, ref), seconds))
    default, default_s = cornell_plain()
    for n, unshot, err, seconds in points:
        measured("progressive", f"{n:>6,} shots: unshot power, error vs gauss_seidel, solve s",
                 f"{unshot:.2%}, {err:.2%}, {seconds:.2f}")
    d_err = solution_error(default, ref)
    measured("progressive", "tolerance 0.01 (default): shots, error vs gauss_seidel",
             f"{default.stats['iterations']:,}, {d_err:.2%}")
    panels = [(f"{n:,} shots\nunshot {sol.stats['residual']:.0%}, error {solution_error(sol, ref):.1%}",
               png8(draw(scene, sol).array)) for n, sol in strip]
    panels.append((f"{default.stats['iterations']:,} shots (tolerance 0.01)\n"
                   f"unshot {default.stats['residual']:.1%}, error {d_err:.1%}", png8(draw(scene, default).array)))
    save(compose(panels, 4), "progressive.png")
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(5.6, 3.6), dpi=100)
    xs = [p[0] for p in points]
    ax.loglog(xs, [100 * p[1] for p in points], "s-", markersize=3, label="unshot power / power sent")
    ax.loglog(xs, [100 * p[2] for p in points], "o-", markersize=3,
              label="error vs Gauss–Seidel (ambient term included)")
    ax.axhline(1.0, color="k", linestyle="--", linewidth=0.8, label="tolerance 0.01 (the default)")
    ax.set_xlabel("shots (patches shot so far)")
    ax.set_ylabel("%")
    ax.set_title("Cornell box, 2,352 patches: progressive refinement", fontsize=10)
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8)
    save_plot(fig, "progressive_plot.png")


def stochastic_figure():
    """Stochastic radiosity with 10k to 640k rays per iteration, two seeds each: the error against
    Gauss–Seidel and the noise (the difference between the two seeds, /√2), against all the rays traced."""
    scene = load("cornell.yaml")
    ref, _, _ = gauss_seidel_reference()
    budgets = [10_000, 40_000, 160_000, 640_000]
    points = []  # (rays, error vs gauss_seidel, noise, seconds)
    for rays in budgets:
        runs = []
        for seed in (0, 1):
            runs.append(solved(scene, f"stochastic, {rays:,} rays per iteration, seed {seed}", seed=seed,
                               subdivide=False, solver="stochastic", rays=rays, tolerance=1e-4))
        (a, a_s), (b, _) = runs
        err = float(np.mean([solution_error(s, ref) for s, _ in runs]))
        noise = solution_error(a, b) / np.sqrt(2.0)
        points.append((a.stats["rays"], err, noise, a_s))
        measured("stochastic", f"{rays:>7,} rays/iteration: rays, error vs gauss_seidel, noise, solve s",
                 f"{a.stats['rays']:,}, {err:.2%}, {noise:.2%}, {a_s:.2f}")
    power = float(np.mean([surface_power(s) for s, _ in runs])) / surface_power(ref)
    measured("stochastic", f"{budgets[-1]:,} rays/iteration: power the surfaces send, stochastic / gauss_seidel",
             f"{power:.3f}")
    xs = np.array([p[0] for p in points], float)
    slope = np.polyfit(np.log(xs), np.log([p[2] for p in points]), 1)[0]
    measured("stochastic", "slope of log(noise) against log(rays)", f"{slope:.3f}")
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(5.6, 3.6), dpi=100)
    ax.loglog(xs, [100 * p[1] for p in points], "s-", markersize=4, label="error vs Gauss–Seidel")
    ax.loglog(xs, [100 * p[2] for p in points], "o-", markersize=4, label="noise (seed 0 vs seed 1, /√2)")
    x = xs[[0, -1]]
    ax.loglog(x, 100 * points[0][2] * (x / x[0]) ** -0.5, "k--", linewidth=1, label="1/√N")
    ax.set_xlabel("rays traced N (all iterations)")
    ax.set_ylabel("relative RMS error, %")
    from matplotlib.ticker import FixedLocator, NullFormatter

    ax.yaxis.set_major_locator(FixedLocator([1, 2, 3, 5, 10, 20, 30]))
    ax.yaxis.set_major_formatter(lambda v, _: f"{v:g}")
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_title("Cornell box, 2,352 patches: stochastic radiosity", fontsize=10)
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8)
    save_plot(fig, "stochastic_plot.png")


FIGURES = {"cornell": cornell_figure, "display": display_figure, "form_factors": form_factor_figure,
           "subdivision": subdivision_figure, "mirror": mirror_figure, "room": room_figure,
           "sweeps": sweeps_figure, "progressive": progressive_figure, "stochastic": stochastic_figure}


def main() -> None:
    global THREADS, OUT
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, help="worker threads of every solve and render (default: all cores)")
    parser.add_argument("--only", nargs="+", choices=sorted(FIGURES), help="these figures only")
    parser.add_argument("--out", type=Path, help="folder to write to (default: docs/images/radiosity)")
    args = parser.parse_args()
    THREADS = args.threads
    if THREADS is not None:  # the solver runs on Numba's thread count: set it once for the whole script
        import numba

        numba.set_num_threads(THREADS)
    OUT = args.out or OUT
    OUT.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    for name in args.only or FIGURES:
        print(f"{name}:", flush=True)
        FIGURES[name]()
    print(f"\nmeasured ({THREADS or 'all'} thread(s), {time.perf_counter() - started:.0f} s in all):")
    for figure, what, value in MEASURED:
        print(f"  {figure:13} {what:72} {value}")


if __name__ == "__main__":
    main()
