"""The public Python API: render a scene with any method, get an `Image` back.

    scene = lumos.load_scene("scene.yaml")            # or a dict
    img = lumos.render(scene, method="raycast", width=320, height=240, spp=4)
    img.array        # float32 (H, W, 3) linear radiance
    img.save("out.exr")

Methods are found by name in `METHODS` (one module each under `lumos.methods`).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, Callable

from .errors import LumosError
from .scene.model import RenderSettings, Scene

if TYPE_CHECKING:
    from .image import Image

#: name -> "module:function" of each method's single public entry point (imported on first use).
METHODS: dict[str, str] = {
    "raycast": "lumos.methods.raycast:render_raycast",
    "raster": "lumos.methods.raster:render_raster",
    "whitted": "lumos.methods.whitted:render_whitted",
}

_SETTING_KEYS = tuple(RenderSettings.model_fields)


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
    merged.update({k: v for k, v in overrides.items() if v is not None})
    try:
        settings = RenderSettings.model_validate(merged)
    except ValidationError as exc:
        raise LumosError(format_validation_error(exc, source="settings", prefix=("render",))) from None
    if settings.method not in METHODS:
        raise LumosError(f"render.method: unknown method {settings.method!r} (choose from {', '.join(METHODS)})")
    return settings


def _entry_point(name: str) -> Callable:
    import importlib

    module, func = METHODS[name].split(":")
    return getattr(importlib.import_module(module), func)


def render(scene: Scene | dict | str, progress: bool | Callable[[float], None] = False, **settings) -> "Image":
    """Render `scene` (a Scene, a dict or a path) and return an `Image`.

    `settings` override the scene's `render:` block: method, width, height, spp, max_depth, seed, shading,
    exposure, threads, aov. `progress=True` shows a progress bar on stderr for renders that take over about
    a second; a callable receives the finished fraction instead.
    """
    from .compile import compile_scene
    from .image import Image
    from .progress import make_progress
    from .scene.loader import load_scene

    t0 = time.perf_counter()
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    t_load = time.perf_counter()
    cfg = resolve_settings(scene, settings)
    try:
        compiled = compile_scene(scene, cfg)
    except LumosError as exc:  # the compile step knows the key path, not the file: name it
        if scene.source is not None and not str(exc).startswith(str(scene.source)):
            raise LumosError(f"{scene.source}: {exc}") from None
        raise
    t_build = time.perf_counter()
    with make_progress(progress) as report:
        film = _entry_point(cfg.method)(compiled, scene.camera, cfg, progress=report)
    t_render = time.perf_counter()
    stats = {
        "method": cfg.method,
        "width": cfg.width,
        "height": cfg.height,
        "spp": cfg.spp,
        "threads": film.threads,
        "load_s": t_load - t0,
        "build_s": t_build - t_load,
        "bvh_build_s": compiled.bvh_build_s,
        "render_s": t_render - t_build,
        "total_s": t_render - t0,
        "rays": int(film.rays),
        "primary_rays": int(film.primary_rays),
        "mrays_per_s": film.rays / max(t_render - t_build, 1e-9) / 1e6,
    }
    return Image(film.radiance, aovs=film.aovs, stats=stats, exposure=cfg.exposure)


def scene_info(scene: Scene) -> dict:
    """What a scene holds, for `lumos info`: objects and lights by type, triangles, BVH size and depth, bounds."""
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
    return {
        "objects": dict(Counter(obj.type for obj in scene.objects)),
        "triangles": compiled.n_triangles,
        "lights": dict(lights),
        "materials": len(scene.materials),
        "bvh_nodes": int(len(compiled.arrays.node_box)),
        "bvh_depth": int(compiled.bvh_depth),
        "bvh_build_s": compiled.bvh_build_s,
        "bounds": (tuple(map(float, compiled.bounds[0])), tuple(map(float, compiled.bounds[1]))),
        "camera": camera,
        "render": scene.render.model_dump(),
    }
