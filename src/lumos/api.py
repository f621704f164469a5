"""The public Python API: render a scene with any method, get an `Image` back.

    scene = lumos.load_scene("scene.yaml")            # or a dict
    img = lumos.render(scene, method="raycast", width=320, height=240, spp=4)
    img.array        # float32 (H, W, 3) linear radiance
    img.save("out.exr")

Methods are found by name in `METHODS` (one module each under `lumos.methods`).
"""

from __future__ import annotations

import sys
import time
import warnings
from typing import TYPE_CHECKING, Any, Callable, Optional

from .errors import LumosError, LumosWarning
from .methods.capabilities import check_settings
from .scene.from_model import PATH_SPP as MODEL_PATH_SPP
from .scene.model import RenderSettings, Scene

if TYPE_CHECKING:
    from .image import Image

#: name -> "module:function" of each method's single public entry point (imported on first use).
METHODS: dict[str, str] = {
    "raycast": "lumos.methods.raycast:render_raycast",
    "raster": "lumos.methods.raster:render_raster",
    "whitted": "lumos.methods.whitted:render_whitted",
    "path": "lumos.methods.path:render_path",
    "radiosity": "lumos.methods.radiosity:render_radiosity",
}

_SETTING_KEYS = tuple(RenderSettings.model_fields)
#: Samples per pixel of the supersampling that stands in for whitted's adaptive anti-aliasing in the other methods
#: (adaptive_depth 3 spends 1 ray per pixel on flat areas and up to 64 on edges; 4 jittered samples per pixel is
#: about its cost on the Whitted examples), when a scene asks for adaptive and another method is chosen.
ADAPTIVE_STAND_IN_SPP = 4


def method_names() -> tuple[str, ...]:
    return tuple(METHODS)


def resolve_settings(scene: Scene, overrides: dict[str, Any]) -> RenderSettings:
    """The scene's `render:` block with non-None `overrides` applied, validated again as a whole."""
    from pydantic import ValidationError

    from .scene.loader import format_validation_error

    unknown = sorted(set(overrides) - set(_SETTING_KEYS))
    if unknown:
        raise LumosError(f"render(): unknown setting {unknown[0]!r} (known: {', '.join(_SETTING_KEYS)})")
    merged = scene.render.model_dump()
    for key, value in overrides.items():
        if value is None:
            continue
        if isinstance(value, dict) and isinstance(merged.get(key), dict):  # a nested block: override its keys
            merged[key] = {**merged[key], **{k: v for k, v in value.items() if v is not None}}
        else:
            merged[key] = value
    try:
        settings = RenderSettings.model_validate(merged)
    except ValidationError as exc:
        raise LumosError(format_validation_error(exc, source="settings", prefix=("render",))) from None
    if settings.method not in METHODS:
        raise LumosError(f"render.method: unknown method {settings.method!r} (choose from {', '.join(METHODS)})")
    if (settings.antialias == "adaptive" and settings.method != "whitted" and overrides.get("antialias") is None
            and overrides.get("method") is not None):
        # the scene file asks for whitted's adaptive anti-aliasing and the caller chose another method: that
        # method supersamples at about adaptive's cost instead (as `lumos sheet` does); given as a setting of its
        # own, adaptive with another method is still refused below
        spp = settings.spp if overrides.get("spp") is not None else max(settings.spp, ADAPTIVE_STAND_IN_SPP)
        settings = settings.model_copy(update={"antialias": "supersample", "spp": spp})
        warnings.warn(LumosWarning(f"render.antialias: the scene's adaptive anti-aliasing is whitted's; "
                                   f"{settings.method} supersamples at {spp} spp instead"))
    if (scene.made_for_model and settings.method == "path" and overrides.get("spp") is None
            and settings.spp < MODEL_PATH_SPP):
        # a bare model file: its made-up render block holds whitted's 4 spp; a path-traced image of it is not
        # to be speckled
        settings = settings.model_copy(update={"spp": MODEL_PATH_SPP})
    if scene.made_for_model and settings.method == "path" and overrides.get("denoise") is None and not settings.denoise:
        import importlib.util

        if importlib.util.find_spec("pyoidn") is not None:  # denoised where Open Image Denoise is installed
            settings = settings.model_copy(update={"denoise": True})
    check_settings(settings)
    return settings


def entry_point(name: str) -> Callable:
    """The render function of method `name` (`METHODS`)."""
    import importlib

    module, func = METHODS[name].split(":")
    return getattr(importlib.import_module(module), func)


#: The methods whose first run compiles its kernels beside a helper process (`compile_with_helper`); radiosity
#: builds its trees in its solve, whose kernels wait on them.
WITH_HELPER = ("raycast", "raster", "whitted", "path")


def compile_with_helper(scene, cfg) -> None:
    """On a first run with something to compile, compile the method's kernels while a second process compiles, on
    another core, `lumos warmup --plan METHOD --methods bvh`: first the device functions the method's compile plan gives
    it (`methods.compile_plan`: the general kernels' plan, or `METHOD-lean` where the render compiles its kernels for a
    plain scene, `compile.features`; when the method's kernel is not cached), which this compile loads as it reaches
    them, then the BVH build's kernels (when they are not cached and the method traces rays: raster only with shadow
    rays). Meanwhile this process compiles the plan's `first` subtrees, so that the two start apart, and then the
    method's kernels, which need the scene's array types, not its tree: against the scene compiled with an empty one
    (`compile_for(..., tree=False)`), rendered at 2×2 and thrown away. The compile that follows loads the BVH build's
    kernels, and the render finds its own compiled: the same image (BENCHMARKS.md, 2026-12-05, seventh and eighth
    sessions). `LUMOS_COMPILE_HELPER=0` compiles everything in this process."""
    import os
    import subprocess

    from .kernels.bvh_build import build_nodes
    from .kernels.cache import has_entries
    from .methods import compile_for
    from .methods import compile_plan as plan

    if (os.cpu_count() or 1) < 2 or os.environ.get("LUMOS_COMPILE_HELPER") == "0":
        return
    bvh = (cfg.method != "raster" or cfg.shadows) and not has_entries(build_nodes)
    if not bvh and plan.top_cached(cfg.method):  # the general kernels are there: every render takes them
        return
    small = cfg.model_copy(update={"width": 2, "height": 2})
    try:
        compiled = compile_for(scene, small, tree=False)
    except Exception:  # a scene the real compile refuses says why there
        return
    name = plan.plan_for(cfg.method, compiled.arrays)  # the general kernels' plan, or a plain scene's (-lean)
    share = bool(plan.load(name)["roots"]) and not plan.top_cached(name)
    if not (share or bvh):
        return
    command = [sys.executable, "-m", "lumos", "warmup", "--jobs", "1", "--quiet"]
    command += (["--plan", name] if share else []) + (["--methods", "bvh"] if bvh else [])
    try:
        helper = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
    except OSError:  # no process to be had here: everything compiles in this one, as it would have
        return
    try:
        if share:
            plan.compile_share(name, "first")
        entry_point(cfg.method)(compiled, scene.camera, small)
    except Exception:  # a kernel not compiled here compiles there
        pass
    finally:
        try:
            helper.wait(timeout=600)
        except subprocess.TimeoutExpired:  # (never seen: the helper's compile takes seconds)
            helper.kill()


def render(scene: Scene | dict | str, progress: bool | Callable[[float], None] = False,
           on_pass: Optional[Callable[["Image"], None]] = None, solution=None, client=None,
           checkpoint: Optional[str] = None, resume: bool = False, live: Any = None, **settings) -> "Image":
    """Render `scene` (a Scene, a dict or a path) and return an `Image`.

    `settings` override the scene's `render:` block: method, width, height, spp, max_depth, seed, shading,
    exposure, threads, aov, and the path tracer's time_limit, filter, sampling and denoise. `progress=True` shows
    a progress bar on stderr for renders that take over about a second (and says so when the kernels are being
    compiled, on a first run); a callable receives the finished fraction instead. `on_pass(image)` (method path)
    receives the image after each pass of samples, e.g. to write checkpoints. `solution` (method radiosity): a
    `lumos.radiosity.Solution` or the path of a saved one, drawn without solving again.

    `client` (a `distributed.Client`): render on its Dask workers, the same image to the bit (`lumos.cluster`).
    `checkpoint` (a folder): keep every finished piece (path: blocks of samples; raycast, whitted: bands of rows)
    there, and with `resume=True` go on from the pieces a stopped run left.

    `live`: watch the image refine (`lumos.live`): True shows it in a Jupyter notebook, updated in place after each
    pass; 'tev' or 'tev:HOST:PORT' streams it to a running tev viewer; or a sink object of yours with
    `update(image, final)` and `close()` (e.g. `lumos.live.TevSink(...)`), which the caller closes. The other methods
    send only the finished image.

    `stats` holds the timings: load_s, build_s (flatten + BVH), render_s and total_s, and jit_s, the time
    Numba spent compiling kernels (a first run only), which build_s and render_s exclude.
    """
    from .jitwatch import estimate_s, watch_compiles
    from .image import Image
    from .live import close_on_error, open_sink
    from .methods import compile_for
    from .progress import make_progress
    from .scene.loader import load_scene

    t0 = time.perf_counter()
    scene = load_scene(scene)  # a Scene built in Python is completed (mesh files, includes), a file or dict loaded
    if scene.animation is not None:  # an animated scene renders its frame 0 (`render_frames` renders the others)
        from .scene.animation import scene_at

        scene = scene_at(scene, 0.0)
    t_load = time.perf_counter()
    cfg = resolve_settings(scene, settings)
    if cfg.denoise:
        from .denoise import require

        require()

    def say_compiling():
        if progress is True:
            print(f"lumos: compiling kernels, once: about {estimate_s(cfg.method):.0f} s (they are cached for the "
                  "next runs; `lumos warmup` compiles them all ahead)", file=sys.stderr, flush=True)

    with watch_compiles(on_first=say_compiling) as watch:
        if cfg.method in WITH_HELPER and solution is None and client is None and checkpoint is None:
            compile_with_helper(scene, cfg)
        try:
            compiled = compile_for(scene, cfg, solved=solution is not None)
        except LumosError as exc:  # the compile step knows the key path, not the file: name it
            if scene.source is not None and not str(exc).startswith(str(scene.source)):
                raise LumosError(f"{scene.source}: {exc}") from None
            raise
        t_build = time.perf_counter()
        jit_build = watch.seconds
        kwargs = {}
        if solution is not None:
            if cfg.method != "radiosity":
                raise LumosError(f"solution: a radiosity solution is drawn by method radiosity, not {cfg.method}")
            kwargs["solution"] = solution
        sink, own_sink = open_sink(live)
        pass_sink = sink if client is None and checkpoint is None else None  # on workers: the final image only
        if (on_pass is not None or pass_sink is not None) and cfg.method == "path":
            def each_pass(film):
                image = Image(film.radiance, aovs=film.aovs, exposure=cfg.exposure, stats=dict(film.extra))
                if on_pass is not None:
                    on_pass(image)
                if pass_sink is not None:
                    pass_sink.update(image, final=False)
            kwargs["on_pass"] = each_pass
        with make_progress(progress) as report, close_on_error(sink, own_sink):
            if client is not None or checkpoint is not None:
                if kwargs:
                    raise LumosError("render: on_pass and solution are for renders in this process, without a "
                                     "cluster or a checkpoint folder")
                from .cluster import render_pieces

                film = render_pieces(client, entry_point(cfg.method), compiled, scene.camera, cfg, progress=report,
                                     checkpoint=checkpoint, resume=resume)
            else:
                film = entry_point(cfg.method)(compiled, scene.camera, cfg, progress=report, **kwargs)
        t_render = time.perf_counter()
    render_s = max(t_render - t_build - (watch.seconds - jit_build), 0.0)
    stats = {
        "method": cfg.method,
        "width": cfg.width,
        "height": cfg.height,
        "spp": cfg.spp,
        "threads": film.threads,
        "load_s": t_load - t0,
        "build_s": max(t_build - t_load - jit_build, 0.0),
        "bvh_build_s": compiled.bvh_build_s,
        "render_s": render_s,
        "jit_s": watch.seconds,
        "total_s": t_render - t0,
        "rays": int(film.rays),
        "primary_rays": int(film.primary_rays),
        "mrays_per_s": film.rays / max(render_s, 1e-9) / 1e6,
    }
    stats.update(film.extra)
    image = Image(film.radiance, aovs=film.aovs, stats=stats, exposure=cfg.exposure)
    if sink is not None:
        try:
            sink.update(image, final=True)
        finally:
            if own_sink:
                sink.close()
    return image


def scene_info(scene: Scene) -> dict:
    """What a scene holds, for `lumos info`: objects and lights by type (and the emissive objects, which the path
    tracer samples as lights), triangles, BVH size and depth, bounds, and the methods that render it."""
    from collections import Counter

    from .compile import compile_scene

    compiled = compile_scene(scene)
    lights = Counter(
        light.type if light.type != "area" else f"area ({light.shape})" for light in scene.lights
    )
    cam = scene.camera
    camera = (
        f"{cam.type} at {tuple(cam.position)} looking at {tuple(cam.look_at)}, "
        + (f"fov {cam.fov:g}" if cam.type == "perspective" else f"size {cam.size:g}")
        + (f", aperture {cam.aperture:g}" if cam.aperture > 0 else "")
    )
    emissive = Counter(obj.type for obj in scene.objects if any(c > 0 for c in scene.material_of(obj).emission))
    return {
        "objects": dict(Counter(obj.type for obj in scene.objects)),
        "emissive_objects": dict(emissive),
        "triangles": compiled.n_triangles,
        "lights": dict(lights),
        "materials": len(scene.materials),
        "bvh_nodes": int(len(compiled.arrays.node_box)),
        "bvh_depth": int(compiled.bvh_depth),
        "bvh_build_s": compiled.bvh_build_s,
        "bounds": (tuple(map(float, compiled.bounds[0])), tuple(map(float, compiled.bounds[1]))),
        "camera": camera,
        "render": scene.render.model_dump(),
        "methods": ", ".join(METHODS),
        **({"included": "; ".join(scene._included)} if scene._included else {}),
    }
