"""A preview session: one scene, edited live and rendered progressively, its images sent to whoever subscribes.
No web code: the server (`preview.server`) turns page messages into calls here and frames into PNGs.

    session = Session.from_file("examples/showcase.yaml")          # renders at once, in a thread of its own
    session.subscribe(lambda event: print(event[0]))                # ("frame", Frame), ("state", dict), ...
    session.handle({"type": "material", "name": "red", "key": "kd", "value": 0.3})
    session.set_display(exposure=2.0)                               # the last image again, brighter: no render
    session.save("showcase-edited.yaml")                            # a new file beside the scene
    session.close()

Rendering, in the session's render thread: every change bumps `generation`. A render takes its generation's
scene and settings and renders a quick pass (a quarter of the size, one sample per pixel), then the full preview
size (path: pass by pass, one sample per pixel first). Between bands of rows it checks the generation and drops
the render (`_Stale`) when an edit made it stale; the thread then starts on the newest one. Pixel explanations
(`explain`) run on the same thread, between bands, so no two kernels ever run at once.

Publishing (`publish.Publisher`): frames go out at most four a second while a render refines, except the first
frame after a change (the quick pass), the last of a render and a change of display, which go at once.
Subscribers are called on the session's threads and must return quickly (the server hands each event to its
event loop).

Viewer sessions (`Session.viewer`) show a render made elsewhere (`lumos render --preview`): `show(image)` publishes
it; there is nothing to edit.
"""

from __future__ import annotations

import copy
import itertools
import threading
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Callable, Optional

from ..api import METHODS, resolve_settings
from ..errors import LumosError
from ..scene.loader import load_scene, parse_yaml
from ..scene.model import PATH_AOVS, TERM_AOVS
from ..tools.explain import EXPLAINED, explain, format_text
from . import edits
from .display import TONEMAPS, Display
from .publish import Frame, Publisher
from .renderer import Renderer
from .scenefile import SCENE_SUFFIXES, save_new_scene

#: The preview's size: the scene's, scaled down so that its larger side is at most this (pixels).
PREVIEW_SIDE = 320
#: The quick first pass: this fraction of the preview's size, one sample per pixel.
QUICK_SCALE = 4
#: Samples per pixel the path tracer refines to when the scene is not a path-traced one (its spp is meant for
#: the classic methods' anti-aliasing).
PATH_PREVIEW_SPP = 256
SHADINGS = ("flat", "gouraud", "phong")
#: The views every method gives, those of the methods that compute the classic terms, and path's own.
COMMON_VIEWS = ("image", "albedo", "normal", "depth", "object_id", "samples")
#: The render-block keys the preview sets itself or leaves out: path's time limit and denoising are for final
#: renders (the preview refines until `spp`), and its AOVs are the one view shown.
PREVIEW_DROPS = ("time_limit", "denoise", "aov")
PATH_ONLY_KEYS = ("filter", "sampling", "sampler", "light_selection")
#: Samples per pixel at most, and the bounces, of whitted's account of a pixel of path or radiosity (`explain`).
EXPLAIN_STAND_IN_SPP, EXPLAIN_STAND_IN_DEPTH = 4, 5
#: Pixels that may wait to be explained (more are refused: a page clicks one at a time).
MAX_EXPLAINS_WAITING = 8


class _Stale(Exception):
    """Raised between bands of a render that a newer edit made useless."""


class Session:
    """The scene, its settings and display, the render thread and the subscribers (see the module's doc)."""

    def __init__(self, data: Optional[dict], path: Optional[Path], *, scene=None, method=None, shading=None,
                 width=None, height=None, spp=None, exposure=None, start=True):
        """`data`: the scene file's dict, edited live (`path` its file); or None and `scene`: a viewer."""
        self.path = path
        self.folder = path.parent.resolve() if path is not None else None
        self.name = path.name if path is not None else "scene"
        self.editable = data is not None
        self._data = data
        self._base = copy.deepcopy(data)
        if self.editable:  # the file's own render block gives the defaults
            scene = load_scene(_preview_dict(data, None), folder=self.folder)
        self._scene = scene  # validated from `_preview_dict(_data, method)`, or the viewer's scene
        self._settings = self._initial_settings(scene, method, shading, width, height, spp)
        self._display = Display(exposure=float(exposure if exposure is not None else scene.render.exposure))
        self._cond = threading.Condition()
        self._generation = 0
        self._edited_at = time.perf_counter()
        self._editing = threading.Lock()  # one change at a time (two pages may send at once)
        self._explains: list = []
        self._publisher = Publisher()
        self._viewer_cfg = None
        self._seq = itertools.count(1)
        self._closed = False
        self._explain_ready = self.editable  # a viewer explains once the render it shows is finished
        self.renderer = Renderer()
        self.renders = 0  # renders started (the tests count them)
        self.notes: list[str] = []  # warnings the scene gave (said once each on the page)
        if self.editable:
            self._scene = self._validate(data)
        self._worker = threading.Thread(target=self._work_loop, name="lumos-preview-render", daemon=True)
        if start:
            self.start()

    # ----------------------------------------------------------------------------------------- constructors

    @classmethod
    def from_file(cls, path, **settings) -> "Session":
        """An editable session on the scene file `path` (.yaml, .yml or .json). `settings`: method, shading,
        width, height, spp, exposure (the preview's; the file's render block otherwise), start."""
        path = Path(path)
        if path.suffix.lower() not in SCENE_SUFFIXES:
            raise LumosError(f"{path}: the preview edits scene files (.yaml, .yml, .json); show another file's "
                             f"render with `lumos render {path.name} --preview`")
        load_scene(path)  # a bad file fails here, with its line numbers
        data, _ = parse_yaml(path.read_text(encoding="utf-8-sig"), str(path))
        return cls(data, path, **settings)

    @classmethod
    def viewer(cls, scene, cfg, path=None, start=True) -> "Session":
        """A session that shows renders made elsewhere (`show`), of `scene` with the settings `cfg`."""
        session = cls(None, Path(path) if path is not None else None, scene=scene, method=cfg.method,
                      shading=cfg.shading, width=cfg.width, height=cfg.height, spp=cfg.spp, exposure=cfg.exposure,
                      start=False)
        session._viewer_cfg = cfg
        if start:
            session.start()
        return session

    def start(self) -> None:
        self._publisher.start()
        if not self._worker.is_alive():
            self._worker.start()

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._generation += 1  # a render under way stops at its next band
            self._cond.notify_all()
        if self._worker.is_alive() and self._worker is not threading.current_thread():
            self._worker.join(timeout=10.0)
        self._publisher.close()

    # -------------------------------------------------------------------------------------------- messages

    def handle(self, message) -> Optional[dict]:
        """Apply one message from the page (a dict with a `type`); returns the reply for its sender, or None.
        A bad message raises `LumosError` with a one-line message and changes nothing."""
        if not isinstance(message, dict):
            raise LumosError(f"expected a JSON object with a 'type', got {type(message).__name__}")
        kind = message.get("type")
        if kind in ("camera", "light", "material"):
            return {"type": "ack", "generation": self.edit(message), "id": message.get("id")}
        if kind == "settings":
            fields = {k: message[k] for k in ("method", "shading", "spp") if k in message}
            return {"type": "ack", "generation": self.set_settings(**fields), "id": message.get("id")}
        if kind == "display":
            fields = {k: message[k] for k in ("exposure", "tonemap", "view") if k in message}
            return {"type": "ack", "generation": self.set_display(**fields), "id": message.get("id")}
        if kind == "save":
            return {"type": "saved", "path": str(self.save(message.get("name"))), "id": message.get("id")}
        if kind == "state":
            return self.state()
        raise LumosError(f"unknown message type {kind!r}")

    def edit(self, message: dict) -> int:
        """Apply a camera, light or material edit (`edits.apply_edit`) and restart the render; returns the new
        generation."""
        self._need_editable()
        with self._editing:
            data = edits.apply_edit(self._data, self._base, message)
            scene = self._validate(data)
            with self._cond:
                self._data, self._scene = data, scene
                return self._bump()

    def set_settings(self, method=None, shading=None, spp=None) -> int:
        """Switch the method or the shading, or set the samples per pixel; restarts the render."""
        self._need_editable()
        with self._editing:
            generation = self._set_settings(method, shading, spp)
        self._publisher.broadcast(("state", self.state()))
        return generation

    def _set_settings(self, method, shading, spp) -> int:
        settings = dict(self._settings)
        if method is not None:
            if method not in METHODS:
                raise LumosError(f"method: unknown method {method!r} (choose from {', '.join(METHODS)})")
            settings["method"] = method
            if spp is None:
                settings["spp"] = self._default_spp(method, self._settings.get("spp_asked"))
        if shading is not None:
            if shading not in SHADINGS:
                raise LumosError(f"shading: unknown shading {shading!r} (choose from {', '.join(SHADINGS)})")
            settings["shading"] = shading
        if spp is not None:
            if isinstance(spp, bool) or not isinstance(spp, int) or not 1 <= spp <= 1 << 16:
                raise LumosError(f"spp: expected a whole number from 1 to {1 << 16}, got {spp!r}")
            settings["spp"] = settings["spp_asked"] = spp
        scene = self._validate(self._data, settings)
        with self._cond:
            self._settings, self._scene = settings, scene
            if self._display.view not in self.views():
                self._display = replace(self._display, view="image")
            return self._bump()

    def set_display(self, exposure=None, tonemap=None, view=None) -> int:
        """Change the exposure, the tone map or the view: the last image is encoded again at once (no render),
        unless the view is an AOV it does not have (then it is rendered with that AOV)."""
        with self._editing:
            return self._set_display(exposure, tonemap, view)

    def _set_display(self, exposure, tonemap, view) -> int:
        display = self._display
        if exposure is not None:
            value = edits.number_in(exposure, (1e-4, 1e4), "exposure")
            display = replace(display, exposure=value)
        if tonemap is not None:
            if tonemap not in TONEMAPS:
                raise LumosError(f"tonemap: unknown tone map {tonemap!r} (choose from {', '.join(TONEMAPS)})")
            display = replace(display, tonemap=tonemap)
        if view is not None:
            if view not in self.views():
                raise LumosError(f"view: {view!r} is not a view of method {self._settings['method']} (choose from "
                                 f"{', '.join(self.views())})")
            display = replace(display, view=view)
        with self._cond:
            self._display = display
            last = self._publisher.last
            rerender = (self.editable and view is not None and view != "image"
                        and (last is None or view not in last.image.aovs))
            generation = self._bump() if rerender else self._generation
        if not rerender and last is not None:
            self._publisher.publish(replace(last, display=display, _png=None, seq=next(self._seq)), urgent=True)
        return generation

    def explain(self, x, y, reply: Callable[[dict], None]) -> None:
        """Explain pixel (x, y) of the preview (`lumos explain`) and call `reply` with the result (or an error)
        from the render thread, between bands of the render under way."""
        for name, v in (("x", x), ("y", y)):
            if isinstance(v, bool) or not isinstance(v, int):
                raise LumosError(f"explain: pixel {name} must be a whole number, got {v!r}")
        with self._cond:
            if len(self._explains) >= MAX_EXPLAINS_WAITING:
                raise LumosError(f"explain: {len(self._explains)} pixels are waiting already; ask again in a moment")
            self._explains.append((x, y, reply))
            self._cond.notify_all()

    def save(self, name) -> Path:
        """Write the edited scene to a new file `name` in the scene's folder (.yaml unless it ends in .yml or
        .json). Refuses a name outside that folder and a file that exists."""
        self._need_editable()
        with self._cond:
            data = copy.deepcopy(self._data)
        return save_new_scene(data, self.folder, name, self.name)

    # ----------------------------------------------------------------------------------------------- state

    def state(self) -> dict:
        """What the page needs to draw its controls."""
        with self._cond:
            settings, display, data = dict(self._settings), self._display, self._data
        return {"type": "state", "scene": self.name, "editable": self.editable, "methods": list(METHODS),
                "shadings": list(SHADINGS), "tonemaps": list(TONEMAPS), "views": self.views(),
                "explained": list(EXPLAINED),
                "settings": {k: settings[k] for k in ("method", "shading", "spp", "width", "height")},
                "display": {"exposure": display.exposure, "tonemap": display.tonemap, "view": display.view},
                "scene_edit": edits.describe(data, self._base) if self.editable else None,
                "generation": self._generation, "notes": list(self.notes)}

    def views(self) -> list[str]:
        """The views the current method gives: the image, the AOVs, the classic terms or path's own."""
        method = self._settings["method"]
        if not self.editable:
            last = self._publisher.last
            image = last.image if last is not None else None
            return ["image"] + (sorted(image.aovs) if image is not None else [])
        views = list(COMMON_VIEWS)
        if method in ("raycast", "raster", "whitted"):
            views += list(TERM_AOVS)
        if method == "path":
            views += [v for v in PATH_AOVS if v != "noisy"]
        return views

    @property
    def generation(self) -> int:
        return self._generation

    @property
    def last_frame(self) -> Optional[Frame]:
        return self._publisher.last

    def subscribe(self, callback: Callable) -> Callable[[], None]:
        """Call `callback(event)` with each ("frame", Frame), ("state", dict), ("busy", dict: a render started),
        ("error", str) and ("note", str: a warning of the scene, once); returns the unsubscribe function. A new
        subscriber gets the last frame at once. Callbacks run on the session's threads: return quickly."""
        return self._publisher.subscribe(callback)

    # ------------------------------------------------------------------------------------------- the viewer

    def show(self, image, final: bool = False) -> None:
        """Viewer sessions: publish `image` (a `lumos.Image`), a pass of the render (or its end: `final`)."""
        stats = image.stats
        status = {"method": stats.get("method", self._settings["method"]), "spp": stats.get("spp"),
                  "spp_target": self._settings.get("spp"), "passes": stats.get("passes"),
                  "elapsed_s": stats.get("render_s", time.perf_counter() - self._edited_at),
                  "mrays_per_s": stats.get("mrays_per_s"), "eta_s": None if final else _eta(stats, self._settings),
                  "done": final}
        frame = Frame(image, self._generation, "shown" if final else "pass", status, self._display,
                      self._edited_at, next(self._seq))
        self._publisher.publish(frame, urgent=final)
        if final:
            with self._cond:
                self._explain_ready = True
                self._cond.notify_all()
            self._publisher.broadcast(("state", self.state()))

    # ------------------------------------------------------------------------------------------- rendering

    def _work_loop(self) -> None:
        rendered = -1
        while True:
            with self._cond:
                while not self._closed and not (self._explains and self._explain_ready) and (
                        not self.editable or self._generation == rendered):
                    self._cond.wait()
                if self._closed:
                    return
                generation = self._generation
            self._serve_explains()
            if self.editable and generation != rendered:
                rendered = generation
                self._render(generation)

    def _render(self, generation: int) -> None:
        with self._cond:
            data, scene, settings = self._data, self._scene, dict(self._settings)
            view, edited_at = self._display.view, self._edited_at
        self.renders += 1
        started = time.perf_counter()
        self._publisher.broadcast(("busy", {"type": "busy", "generation": generation, "method": settings["method"]}))

        def check(fraction=None):
            if self._generation != generation:
                raise _Stale
            self._serve_explains()

        try:
            cfg = self._settings_for(scene, settings, view)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                quick = cfg.model_copy(update={"width": max(1, cfg.width // QUICK_SCALE), "spp": 1,
                                               "height": max(1, cfg.height // QUICK_SCALE), "antialias": "none"})
                image = self.renderer.render(data, scene, quick, check)
                self._frame(image, generation, "quick", cfg, started, edited_at)
                check()
                on_pass = (lambda img: (check(), self._frame(img, generation, "pass", cfg, started, edited_at)))
                image = self.renderer.render(data, scene, cfg, check, on_pass=on_pass)
            self._frame(image, generation, "final", cfg, started, edited_at)
            self._note(caught)
        except _Stale:
            return
        except LumosError as exc:
            self._publisher.broadcast(("error", _one_line(str(exc))))
        except Exception as exc:  # never the end of the render thread: the page says what went wrong
            self._publisher.broadcast(("error", f"render failed: {type(exc).__name__}: {_one_line(str(exc))}"))

    def _frame(self, image, generation, stage, cfg, started, edited_at) -> None:
        if self._generation != generation:
            raise _Stale
        stats = image.stats
        spp = stats.get("spp", cfg.spp) if stage != "quick" else 1
        status = {"method": cfg.method, "shading": cfg.shading, "spp": spp, "spp_target": cfg.spp,
                  "passes": stats.get("passes"), "elapsed_s": time.perf_counter() - started,
                  "mrays_per_s": stats.get("mrays_per_s"), "done": stage == "final",
                  "eta_s": 0.0 if stage == "final" else _eta(stats, {"spp": cfg.spp}) if stage == "pass" else None}
        frame = Frame(image, generation, stage, status, self._display, edited_at, next(self._seq))
        # the first image after a change and the last of a render go at once; the passes between, throttled
        self._publisher.publish(frame, urgent=stage in ("quick", "final"))

    def _settings_for(self, scene, settings: dict, view: str):
        """The RenderSettings of a preview render: the preview's size, method, shading and samples, and the AOV
        of the view shown."""
        overrides = {k: settings[k] for k in ("method", "shading", "spp", "width", "height")}
        overrides["aov"] = [view] if view != "image" else []
        return resolve_settings(scene, overrides)

    def _serve_explains(self) -> None:
        """Explain the pixels asked for (on the render thread, between bands)."""
        while True:
            with self._cond:
                if not self._explains or not self._explain_ready:
                    return
                x, y, reply = self._explains.pop(0)
            try:
                answer = self._explain_pixel(x, y)
            except LumosError as exc:
                text = _one_line(str(exc))
                answer = {"type": "error", "message": text if text.startswith("explain") else f"explain: {text}"}
            except Exception as exc:
                answer = {"type": "error", "message": f"explain failed: {type(exc).__name__}: {_one_line(str(exc))}"}
            try:
                reply(answer)
            except Exception:  # the page that asked has gone
                pass

    def _explain_pixel(self, x: int, y: int) -> dict:
        """`lumos explain` of pixel (x, y) with the preview's scene and settings; path and radiosity explain no
        pixel, so for them whitted's account of it (a few samples, a few bounces) with a note that says so."""
        with self._cond:
            scene, settings = self._scene, dict(self._settings)
        if self._viewer_cfg is not None:
            cfg = self._viewer_cfg
            overrides = {k: getattr(cfg, k) for k in ("method", "shading", "spp", "width", "height", "antialias",
                                                      "max_depth", "seed", "mipmap")}
        else:
            overrides = {k: settings[k] for k in ("method", "shading", "spp", "width", "height")}
        method, note = overrides["method"], None
        if method not in EXPLAINED:
            note = (f"{method} does not explain pixels (it computes global illumination); this is how whitted's "
                    "ray tracing, with the same lights and materials, makes the pixel")
            depth = overrides.get("max_depth", scene.render.max_depth)
            overrides.update(method="whitted", spp=min(overrides["spp"], EXPLAIN_STAND_IN_SPP),
                             max_depth=depth if depth is not None and depth >= 0 else EXPLAIN_STAND_IN_DEPTH)
            if overrides.get("antialias") not in (None, "none", "supersample", "adaptive"):
                overrides.pop("antialias")
            scene = _without_path_settings(scene)
        tree = explain(scene, x, y, **overrides)
        return {"type": "explain", "x": x, "y": y, "method": tree["method"], "note": note,
                "value": tree["value"], "text": format_text(tree)}

    # -------------------------------------------------------------------------------------------- helpers

    def _bump(self) -> int:
        """A new generation (called with the lock held): the render under way is stale."""
        self._generation += 1
        self._edited_at = time.perf_counter()
        self._cond.notify_all()
        return self._generation

    def _need_editable(self) -> None:
        if not self.editable:
            raise LumosError("this page shows a `lumos render --preview`; edit the scene with `lumos serve SCENE`")

    def _validate(self, data: dict, settings: Optional[dict] = None):
        """The scene of the edited dict `data`, checked as a render with the preview's settings would be."""
        settings = self._settings if settings is None else settings
        scene = load_scene(_preview_dict(data, settings["method"]), folder=self.folder)
        if scene.animation is not None:
            from ..scene.animation import scene_at

            scene = scene_at(scene, 0.0)
        self._settings_for(scene, settings, "image")  # a setting the method refuses fails here
        return scene

    def _initial_settings(self, scene, method, shading, width, height, spp) -> dict:
        block = scene.render
        method = method or block.method
        if width is None and height is None:
            scale = min(1.0, PREVIEW_SIDE / max(block.width, block.height))
            width, height = max(1, round(block.width * scale)), max(1, round(block.height * scale))
        elif width is None or height is None:
            given = width or height
            other = round(given * (block.height / block.width if width else block.width / block.height))
            width, height = (given, max(1, other)) if width else (max(1, other), given)
        self._scene_method = block.method
        self._scene_spp = block.spp
        return {"method": method, "shading": shading or block.shading, "width": int(width), "height": int(height),
                "spp": spp or self._default_spp(method, None), "spp_asked": spp}

    def _default_spp(self, method: str, asked) -> int:
        if asked:
            return asked
        if method == "path" and self._scene_method != "path":
            return max(self._scene_spp, PATH_PREVIEW_SPP)
        return self._scene_spp

    def _note(self, caught) -> None:
        new = [str(w.message) for w in caught if str(w.message) not in self.notes]
        if new:
            self.notes.extend(dict.fromkeys(new))
            for text in dict.fromkeys(new):
                self._publisher.broadcast(("note", _one_line(text)))


def _preview_dict(data: dict, method: Optional[str]) -> dict:
    """`data` with the render block the preview renders from: path's final-render keys (time limit,
    denoising) and the file's AOVs left out, and with another method than path, path's own settings."""
    if not isinstance(data, dict):
        raise LumosError("the scene must be a mapping")
    render = data.get("render")
    render = dict(render) if isinstance(render, dict) else {}
    for key in PREVIEW_DROPS + (PATH_ONLY_KEYS if method not in (None, "path") else ()):
        render.pop(key, None)
    if method is not None and method != "whitted" and render.get("antialias") == "adaptive":
        render["antialias"] = "supersample"
    return {**data, "render": render}


def _without_path_settings(scene):
    """`scene` with the path tracer's own render settings at their defaults (whitted refuses them)."""
    render = scene.render.model_copy(update={"time_limit": None, "denoise": False, "filter": "box",
                                             "sampling": "mis", "sampler": "sobol", "light_selection": "tree",
                                             "aov": []})
    return scene.model_copy(update={"render": render})


def _eta(stats: dict, settings: dict) -> Optional[float]:
    """Seconds left to `spp` at the rate so far (path's passes), or None."""
    done, target, spent = stats.get("spp"), settings.get("spp"), stats.get("render_s")
    if not done or not target or spent is None or done >= target:
        return None
    return spent / done * (target - done)


def _one_line(text: str) -> str:
    return " ".join(text.split())

