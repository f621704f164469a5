"""Render a scene for the preview, reusing what an edit left unchanged.

`lumos.render` loads, compiles and renders every time: at the preview's size the compile step (the flattened
scene and its BVH: 0.2 s of the showcase's 0.25 s at 320x240) is most of the cost. `Renderer` keeps the last
compiled scene, keyed on what it depends on: everything in the scene but the camera (for raster, whose
tessellation of planes follows the camera, the camera too; for the ray methods only its shutter interval), the
method and the settings its compile step reads. Orbiting the camera, changing the size or the samples, or
switching between raycast and whitted (the same compiled scene) recompiles nothing; a radiosity solution is
view-independent and kept in the same way, so orbiting a radiosity scene draws the solution again without
solving.

Each render calls `check` between bands of rows (and between path's passes): the preview's session raises there
to drop a render an edit made stale. Given `on_pass`, path shows each pass, and raycast and whitted their image
band by band (`BANDS` bands of rows, each rendered with the method's `rows=`; every pixel is computed by itself,
so the image is the one a whole render gives).
"""

from __future__ import annotations

import json
import time
from typing import Callable, Optional

import numpy as np

from ..api import entry_point
from ..image import Image
from ..methods import compile_for

#: The render settings each method's compile step reads (besides the scene): its cache key.
COMPILE_SETTINGS = {"raster": ("tessellation", "shadows"), "radiosity": ("radiosity", "seed")}
#: Methods whose compiled scene is the same (`methods.compile_for` does nothing method-specific for them).
SHARED_COMPILE = {"raycast": "rays", "whitted": "rays"}
#: Bands of rows raycast and whitted show one after another while they render for the page.
BANDS = 8


class Renderer:
    """Renders (scene, settings) to an `Image`, keeping the compiled scene and radiosity's solution between
    renders while their keys hold. Not thread-safe: one session's render thread owns it."""

    def __init__(self):
        self._compiled: tuple[Optional[str], object] = (None, None)
        self._solution: tuple[Optional[str], object] = (None, None)
        self.compiles = 0  # how many times the scene was compiled (the tests count them)
        self.solves = 0

    def render(self, data: dict, scene, cfg, check: Callable[[float], None],
               on_pass: Optional[Callable[[Image], None]] = None) -> Image:
        """`scene` (validated from the dict `data`) rendered with `cfg`; `check(fraction)` after each band,
        `on_pass(image)` after each of path's passes but the last."""
        key = compile_key(data, cfg)
        compiled = self._compile(key, scene, cfg)
        kwargs = {}
        if cfg.method == "radiosity":
            kwargs["solution"] = self._solve(key, compiled, cfg, check)
        if cfg.method == "path" and on_pass is not None:
            started = time.perf_counter()
            kwargs["on_pass"] = lambda film: on_pass(_image(film, cfg, time.perf_counter() - started))
        t0 = time.perf_counter()
        if cfg.method in SHARED_COMPILE and on_pass is not None:
            return self._by_bands(compiled, scene.camera, cfg, check, on_pass)
        film = entry_point(cfg.method)(compiled, scene.camera, cfg, progress=check, **kwargs)
        return _image(film, cfg, time.perf_counter() - t0)

    def _by_bands(self, compiled, camera, cfg, check, on_pass) -> Image:
        """raycast or whitted band by band: on_pass(the image so far) after each band but the last."""
        from ..methods.common import Film, row_bands

        render = entry_point(cfg.method)
        started = time.perf_counter()
        radiance = np.zeros((cfg.height, cfg.width, 3), np.float32)
        aovs: dict = {}
        rays = 0
        bands = row_bands(cfg.height, BANDS)
        for k, (y0, y1) in enumerate(bands):
            part = render(compiled, camera, cfg, rows=(y0, y1))
            radiance[y0:y1] = part.radiance[y0:y1]
            for name, buf in part.aovs.items():
                aovs.setdefault(name, np.zeros_like(buf))[y0:y1] = buf[y0:y1]
            rays += part.rays
            check((k + 1) / len(bands))
            film = Film(radiance, aovs, rays)
            if k + 1 < len(bands):
                on_pass(_image(film, cfg, time.perf_counter() - started))
        return _image(film, cfg, time.perf_counter() - started)

    def _compile(self, key: str, scene, cfg):
        if self._compiled[0] != key:
            # an edit of materials or lights keeps the BVH (compile_scene's `reuse`: same geometry, same bits)
            previous = self._compiled[1] if cfg.method != "raster" else None
            self._compiled = (None, None)  # a failed compile leaves nothing stale behind
            self._compiled = (key, compile_for(scene, cfg, reuse=previous))
            self.compiles += 1
        return self._compiled[1]

    def _solve(self, key: str, compiled, cfg, check):
        from ..radiosity.solve import solve_compiled

        if self._solution[0] != key:
            self._solution = (None, None)
            self._solution = (key, solve_compiled(compiled, cfg, check))
            self.solves += 1
        return self._solution[1]


def compile_key(data: dict, cfg) -> str:
    """What the compiled scene of `data` with settings `cfg` depends on, as one string."""
    camera = data.get("camera") if isinstance(data.get("camera"), dict) else {}
    parts = {
        "scene": {k: v for k, v in data.items() if k not in ("camera", "render")},
        "camera": camera if cfg.method == "raster" else camera.get("shutter"),
        "method": SHARED_COMPILE.get(cfg.method, cfg.method),
        "settings": {name: getattr(cfg, name) for name in COMPILE_SETTINGS.get(cfg.method, ())},
    }
    return json.dumps(parts, sort_keys=True, default=_plain)


def _plain(value):
    return value.model_dump() if hasattr(value, "model_dump") else str(value)


def _image(film, cfg, render_s: float) -> Image:
    """The film as an `Image` with the figures the page's status line shows."""
    stats = {"method": cfg.method, "width": cfg.width, "height": cfg.height, "spp": cfg.spp, "render_s": render_s,
             "rays": int(film.rays), "mrays_per_s": film.rays / max(render_s, 1e-9) / 1e6}
    stats.update({k: v for k, v in film.extra.items() if k in ("spp", "passes", "stopped")})
    return Image(film.radiance, aovs=film.aovs, stats=stats, exposure=cfg.exposure)
