"""Compile every kernel once, ahead of the first render: `lumos warmup`, and the wheel build of `pip install .`.

    lumos warmup                          # every family, in parallel processes, with a progress bar
    lumos warmup --methods raycast,path   # only these families
    warmup.run(["path"], jobs=1)          # from Python: a FamilyResult per family

A *family* is the set of kernels one method reaches (`FAMILIES`): each is warmed by rendering small built-in
scenes (no files needed, so the wheel build can run it) in a process of its own, so that families compile side by
side on every core; the kernels they share with others (the BVH build) are compiled first, once. A family whose
kernels are all in the cache loads them and reports `0 compiled`: `lumos warmup` is also the check that an
install is warm. What each family compiled and how long it took is kept beside the kernels (`timings.json`),
which is where a render's "compiling kernels: about N s" estimate comes from.
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable, Iterable, Optional

#: family -> what it covers (`lumos warmup --help` lists them)
FAMILIES = {
    "bvh": "the BVH build every method shares",
    "raycast": "ray casting",
    "raster": "scan-line rendering, flat, Gouraud and Phong",
    "whitted": "Whitted ray tracing, supersampled and adaptive",
    "path": "path tracing",
    "radiosity": "radiosity: form factors, the solver, the display",
    "queries": "lumos.RayCaster's ray queries",
    "explain": "lumos explain: one pixel's ray tree and terms (raycast, whitted, raster)",
}
#: families compiled first, in this process (the others, in their own processes, load what they share)
FIRST = ("bvh",)
#: families warmed only when named (`lumos warmup --methods explain`): lumos explain's one-pixel kernels take
#: about a fifth of the whole warm-up (the integrators compiled again with the ray log), for a teaching tool that
#: compiles them on its first use instead (BENCHMARKS.md, "Time to first image")
ON_REQUEST = ("explain",)
SMALL = {"width": 48, "height": 36, "spp": 1}


def _scene() -> dict:
    """Every kind of shape and light, a procedural texture and a small mesh: the arrays every scene compiles to."""
    mesh_v = [[-0.4, 0, -0.4], [0.4, 0, -0.4], [0.4, 0, 0.4], [-0.4, 0, 0.4], [0, 0.6, 0]]
    mesh_f = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 2, 1], [0, 3, 2]]
    return {
        "camera": {"position": [0, 1.5, 6], "look_at": [0, 0.8, 0], "fov": 45},
        "ambient": 0.05,
        "background": [0.1, 0.1, 0.12],
        "lights": [
            {"type": "point", "position": [-3, 5, 4], "intensity": 1.0},
            {"type": "directional", "direction": [0.3, -1, -0.2], "intensity": 0.3},
            {"type": "area", "shape": "rect", "corner": [-0.5, 3, -0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1],
             "radiance": 4.0, "samples": 2},
        ],
        "materials": {
            "matte": {"ka": 0.5, "kd": 0.6},
            "shiny": {"ka": 0.2, "kd": 0.3, "ks": 0.5, "shininess": 40, "kr": 0.3},
            "glass": {"kd": 0.05, "ks": 0.5, "shininess": 100, "kt": 0.8, "ior": 1.5, "fresnel": True},
            "board": {"ks": 0.1, "texture": {"type": "checker", "colors": [[0.8, 0.1, 0.1], [0.9, 0.8, 0.1]],
                                             "scale": [4, 4], "apply_to": ["ka", "kd"]}},
        },
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": "board"},
            {"type": "sphere", "center": [-1.5, 0.6, 0], "radius": 0.6, "material": "shiny"},
            {"type": "sphere", "center": [0, 0.6, 1], "radius": 0.5, "material": "glass"},
            {"type": "box", "min": [0.8, 0, -0.5], "max": [1.6, 0.8, 0.3], "material": "matte"},
            {"type": "cylinder", "base": [-2.5, 0, -1], "top": [-2.5, 1.2, -1], "radius": 0.3, "material": "matte"},
            {"type": "cone", "base": [2.4, 0, -1], "top": [2.4, 1.2, -1], "radius": 0.4, "material": "shiny"},
            {"type": "disk", "center": [0, 0.01, -2], "normal": [0, 1, 0], "radius": 0.5, "material": "matte"},
            {"type": "triangle", "vertices": [[-1, 0, -2], [-0.5, 1, -2], [0, 0, -2]], "material": "matte"},
            {"type": "mesh", "vertices": mesh_v, "faces": mesh_f, "material": "shiny",
             "transform": {"translate": [1.2, 0.8, 1]}},
            {"type": "csg", "op": "difference", "material": "matte",
             "left": {"type": "box", "min": [-0.4, 0, -3.4], "max": [0.4, 0.8, -2.6]},
             "right": {"type": "sphere", "center": [0, 0.8, -3], "radius": 0.5}},
        ],
    }


def _box() -> dict:
    """A closed diffuse box with a rect light: what path tracing and radiosity read physically."""
    def rect(corner, u, v, material):
        return {"type": "rect", "corner": corner, "edge_u": u, "edge_v": v, "material": material}

    return {
        "camera": {"position": [0, 0, 3.9], "look_at": [0, 0, 0], "fov": 39},
        "lights": [{"type": "area", "shape": "rect", "corner": [-0.25, 0.99, -0.2], "edge_u": [0.5, 0, 0],
                    "edge_v": [0, 0, 0.4], "radiance": 15.0}],
        "materials": {"white": {"kd": 0.75}, "red": {"kd": [0.6, 0.05, 0.05]}, "glossy": {"kd": 0.3, "ks": 0.4,
                                                                                          "shininess": 30}},
        "objects": [
            rect([-1, -1, 1], [2, 0, 0], [0, 0, -2], "white"), rect([-1, 1, -1], [2, 0, 0], [0, 0, 2], "white"),
            rect([-1, -1, -1], [2, 0, 0], [0, 2, 0], "white"), rect([-1, -1, 1], [0, 0, -2], [0, 2, 0], "red"),
            rect([1, -1, -1], [0, 0, 2], [0, 2, 0], "white"),
            {"type": "box", "min": [-0.6, -1, -0.5], "max": [-0.1, -0.3, 0.0], "material": "glossy"},
        ],
    }


def _render(scene: dict, method: str, **settings) -> None:
    from .. import api

    api.render(scene, method=method, progress=False, **{**SMALL, **settings})


def _warm_bvh() -> None:
    from ..compile import compile_scene
    from ..scene.loader import load_scene

    compile_scene(load_scene(_scene()))


def _warm_raycast() -> None:
    _render(_scene(), "raycast")
    _render(_scene(), "raycast", aov=["depth"])  # the kernel compiled with the surface AOV stores (methods.raycast)


def _warm_raster() -> None:
    for shading in ("flat", "gouraud", "phong"):
        _render(_scene(), "raster", shading=shading)


def _warm_whitted() -> None:
    _render(_scene(), "whitted")
    _render(_scene(), "whitted", antialias="adaptive", adaptive_depth=1)


def _warm_path() -> None:
    scene = _box()  # with a second light, so that the light tree is built (`kernels.light_tree_build`)
    scene["lights"].append({"type": "area", "shape": "sphere", "center": [0.5, 0.5, 0.3], "radius": 0.1,
                            "radiance": 2.0})
    _render(scene, "path")


def _warm_radiosity() -> None:
    _render(_box(), "radiosity", radiosity={"subdivide": True})  # a refined level inherits the kept form factors
    # a point light (its direct light is gathered apart) and a mirror (the two-pass extension traces it)
    scene = _box()
    scene["lights"].append({"type": "point", "position": [0.3, 0.8, 0.3], "intensity": 0.5})
    scene["materials"]["mirror"] = {"kr": 0.9}
    scene["objects"][-1]["material"] = "mirror"
    scene.pop("background", None)
    scene["environment"] = {"color": [0.2, 0.2, 0.25]}  # gathered as a sky light (kernels.radiosity.sky_light)
    _render(scene, "radiosity", radiosity={"solver": "stochastic", "rays": 2000})
    # the matrix solvers, hemicube form factors, adaptive subdivision and the flat display (on coarse patches: the
    # kernels are the same, the solve a tenth)
    for solver in ("gauss_seidel", "jacobi"):
        _render(_box(), "radiosity", radiosity={"solver": solver, "form_factors": "hemicube", "patch_size": 0.4,
                                                "hemicube_resolution": 16, "subdivide": True, "display": "flat"})


def _warm_queries() -> None:
    import numpy as np

    from ..queries import RayCaster

    rc = RayCaster(_scene())
    rng = np.random.default_rng(0)
    o = rng.normal(size=(16, 3)) * 0.1 + [0.0, 1.5, 6.0]
    d = rng.normal(size=(16, 3)) * 0.1 + [0.0, -0.1, -1.0]
    rc.closest(o, d)
    rc.occluded(o, d, 10.0)
    rc.all_hits(o, d)
    rc.contains(o)
    rc.path_length(o, d, 20.0)


def _warm_explain() -> None:
    from .explain import explain

    for method in ("raycast", "whitted", "raster"):
        explain(_scene(), SMALL["width"] // 2, SMALL["height"] // 2, method=method, **SMALL)
    explain(_scene(), 3, 3, method="whitted", antialias="adaptive", adaptive_depth=1, **SMALL)


_WORK: dict[str, Callable[[], None]] = {
    "bvh": _warm_bvh, "raycast": _warm_raycast, "raster": _warm_raster, "whitted": _warm_whitted,
    "path": _warm_path, "radiosity": _warm_radiosity, "queries": _warm_queries, "explain": _warm_explain,
}


@dataclass
class FamilyResult:
    family: str
    compiled: int  # top-level kernels compiled (0: everything came from the cache)
    compile_s: float  # time Numba spent compiling
    wall_s: float  # the whole warm-up of the family, loading and rendering included
    error: str = ""


def warm_family(family: str) -> FamilyResult:
    """Run one family's warm-up in this process; returns what it compiled."""
    from ..jitwatch import watch_compiles

    t0 = time.perf_counter()
    try:
        with _warming(), watch_compiles() as watch:
            _WORK[family]()
    except Exception as exc:  # reported, not raised: the other families still warm
        return FamilyResult(family, 0, 0.0, time.perf_counter() - t0, f"{type(exc).__name__}: {exc}")
    return FamilyResult(family, watch.compiles, watch.seconds, time.perf_counter() - t0)


#: the settings a family warms under: no helper process beside each family's first render
#: (`api.compile_with_helper`: the warm-up already runs a process per core, and helpers on top of them made it
#: slower: alternating, fresh cache, 53.7, 55.2 s with them, 50.2, 53.3 s without), and the general kernels,
#: whatever the warm-up's scenes hold (`methods.common.kernel_arrays`): those every scene can use
WARMING = {"LUMOS_COMPILE_HELPER": "0", "LUMOS_LEAN_KERNELS": "0"}


@contextmanager
def _warming():
    """WARMING's settings in the environment, the caller's back afterwards."""
    saved = {name: os.environ.get(name) for name in WARMING}
    os.environ.update(WARMING)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _child(family: str, cache_dir: Optional[str]) -> FamilyResult:
    if cache_dir:
        os.environ["LUMOS_CACHE_DIR"] = cache_dir
    return warm_family(family)


def families_for(methods: Optional[Iterable[str]]) -> list[str]:
    """The families to warm for `methods` (None: all but the ON_REQUEST ones), FIRST ones included; unknown names
    raise ValueError."""
    if methods is None:
        return [f for f in FAMILIES if f not in ON_REQUEST]
    names = [m.strip() for m in methods if m.strip()]
    unknown = [m for m in names if m not in FAMILIES]
    if unknown:
        raise ValueError(f"unknown method or family {unknown[0]!r} (choose from {', '.join(FAMILIES)})")
    return [f for f in FAMILIES if f in FIRST or f in names]


def run(families: Optional[Iterable[str]] = None, jobs: Optional[int] = None,
        on_done: Optional[Callable[[FamilyResult], None]] = None,
        on_start: Optional[Callable[[str], None]] = None) -> list[FamilyResult]:
    """Warm `families` (default: all): the FIRST ones, then the rest in `jobs` processes (default: one per core;
    1 = in this process, one after the other). Returns one result per family, in FAMILIES's order."""
    from ..jitwatch import read_timings, save_timings
    from ..kernels.cache import cache_dirs

    names = families_for(families)
    jobs = max(1, jobs or os.cpu_count() or 1)
    cache_dir = str(cache_dirs()[0])
    results: dict[str, FamilyResult] = {}

    def done(result: FamilyResult) -> None:
        results[result.family] = result
        if on_done is not None:
            on_done(result)

    first, rest = [f for f in names if f in FIRST], [f for f in names if f not in FIRST]
    for family in first + (rest if jobs == 1 else []):
        if on_start is not None:
            on_start(family)
        done(warm_family(family))
    if jobs > 1 and rest:
        import multiprocessing

        context = multiprocessing.get_context("spawn")  # no fork of a process that holds Numba's LLVM state
        with ProcessPoolExecutor(max_workers=min(jobs, len(rest)), mp_context=context) as pool:
            futures = {}
            # the largest families first, so that the last one to finish is a small one
            timings = read_timings()
            for family in sorted(rest, key=lambda f: -timings.get(f, {}).get("compile_s", 60)):
                futures[pool.submit(_child, family, cache_dir)] = family
                if on_start is not None:
                    on_start(family)
            for future in as_completed(futures):
                try:
                    done(future.result())
                except Exception as exc:  # a worker that died
                    done(FamilyResult(futures[future], 0, 0.0, 0.0, f"{type(exc).__name__}: {exc}"))
    ordered = [results[f] for f in names]
    save_timings({r.family: r.compile_s for r in ordered if r.compiled and not r.error})
    return ordered


def main(methods: Optional[list[str]] = None, jobs: Optional[int] = None, quiet: bool = False) -> int:
    """`lumos warmup`: warm, with a progress bar on stderr, and say where the cache is and what it took."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from ..kernels.cache import cache_dirs

    names = families_for(methods)
    console = Console(file=sys.stderr, quiet=quiet)
    t0 = time.perf_counter()
    running: list[str] = []
    with Progress(TextColumn("lumos: warming kernels"), BarColumn(), MofNCompleteColumn(),
                  TextColumn("{task.description}"), TimeElapsedColumn(), console=console,
                  transient=True) as bar:
        task = bar.add_task("", total=len(names))

        def on_start(family):
            running.append(family)
            bar.update(task, description=", ".join(running))

        def on_done(result: FamilyResult):
            if result.family in running:
                running.remove(result.family)
            bar.update(task, advance=1, description=", ".join(running))
            state = (f"failed: {result.error}" if result.error else
                     f"{result.compiled} compiled in {result.compile_s:.1f} s" if result.compiled else
                     "up to date")
            console.print(f"lumos: {result.family:9} {state} ({result.wall_s:.1f} s)")

        results = run(names, jobs=jobs, on_start=on_start, on_done=on_done)
    wall = time.perf_counter() - t0
    compiled = sum(r.compiled for r in results)
    console.print(f"lumos: kernels {'compiled' if compiled else 'up to date'} in {wall:.1f} s; cache: "
                  f"{cache_dirs()[0]}")
    return 1 if any(r.error for r in results) else 0
