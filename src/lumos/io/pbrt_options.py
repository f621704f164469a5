"""pbrt-v4's scene-wide options (Camera, Film, Sampler, Integrator, PixelFilter) as lumos's camera and render block.

    mirror = world_mirror(camera.ctm)           # pbrt's camera is left-handed: see below
    camera_dict(camera, mirror, width, height, ctx), render_dict(options, ctx)

**Handedness.** pbrt's LookAt makes a camera whose image x axis is cross(up, view) (pbrt/util/transform.cpp), the
mirror image of a right-handed camera's (lumos's, Mitsuba's): the same LookAt shows the scene left–right flipped
in pbrt. So when the camera transform keeps handedness (det > 0, as a plain LookAt does), the whole scene is read
mirrored in x (`mirror` = diag(−1, 1, 1), applied to every position, direction and shape, and to the camera),
which makes lumos's image pbrt's; a file whose camera transform already mirrors (the `Scale -1 1 1` that
exporters from right-handed tools write before LookAt) is read as it is.

**Field of view.** pbrt's `fov` spans the shorter image axis; lumos's is vertical: for an image taller than wide
(W < H), lumos fov = 2·atan(tan(fov/2)·H/W). `lensradius` is lumos's `aperture` (a radius, in scene units) and
`focaldistance` its `focus_distance`. Orthographic: pbrt's screen window spans 2 units on the shorter axis, so
lumos `size` = 2 (W ≥ H) or 2·H/W.

**Samples.** `pixelsamples` (stratified: `xsamples`·`ysamples`) is `spp`; every pbrt sampler is read as lumos's
Sobol points. pbrt's default pixel filter is a Gaussian (σ = 0.5 pixel), which is lumos's `filter: gaussian`
(every method's supersampling honours it but whitted's adaptive anti-aliasing, which needs `--filter box`).

**Depth.** pbrt's `maxdepth` counts scattering events: 1 is direct light only (PathIntegrator::Li ends the path
when `depth++ == maxDepth`, before sampling a light), lumos's `max_depth` counts the bounces after the first hit
(0 is direct light only): lumos max_depth = maxdepth − 1 (pbrt's default 5 is 4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .pbrt_textures import Context, tidy
from .pbrt_tokens import Params, Where

_PATH_INTEGRATORS = ("path", "volpath")
_OTHER_INTEGRATORS = ("bdpt", "mlt", "sppm", "lightpath", "simplepath", "simplevolpath", "randomwalk",
                      "ambientocclusion", "aov")


@dataclass
class Option:
    """One scene-wide directive: its type, parameters and place (and, for the camera, the CTM it was given with)."""

    kind: str
    params: Params
    where: Where
    ctm: Optional[np.ndarray] = None


@dataclass
class Options:
    camera: Optional[Option] = None
    others: dict = field(default_factory=dict)  # "Film", "Sampler", "Integrator", "PixelFilter" → Option


def world_mirror(camera: Optional[Option]) -> np.ndarray:
    """diag(−1, 1, 1, 1) when pbrt's camera transform keeps handedness (its image is then the mirror of a
    right-handed camera's), else the identity."""
    mirror = np.eye(4)
    if camera is None or np.linalg.det(camera.ctm[:3, :3]) > 0:
        mirror[0, 0] = -1.0
    return mirror


def resolution(options: Options) -> tuple[int, int]:
    film = options.others.get("Film")
    if film is None:
        return 1280, 720
    w, h = film.params.int("xresolution", 1280), film.params.int("yresolution", 720)
    if w < 1 or h < 1:
        raise film.where.error(f"Film: the resolution must be at least 1×1, got {w}×{h}")
    return w, h


def camera_dict(options: Options, mirror: np.ndarray, width: int, height: int, ctx: Context) -> dict:
    """lumos's camera for pbrt's (the default: perspective, fov 90, at the origin looking along +z)."""
    cam = options.camera
    ctm = np.eye(4) if cam is None else cam.ctm
    try:
        world_from_camera = mirror @ np.linalg.inv(ctm)
    except np.linalg.LinAlgError:
        raise cam.where.error("Camera: the transform before it is singular") from None
    position = world_from_camera[:3, 3]
    view = world_from_camera[:3, :3] @ np.array([0.0, 0.0, 1.0])
    up = world_from_camera[:3, :3] @ np.array([0.0, 1.0, 0.0])
    view = view / np.linalg.norm(view)
    out = {"position": _rounded(position), "look_at": _rounded(position + view), "up": _rounded(up)}
    kind = "perspective" if cam is None else cam.kind
    ps = Params({}, Where("", 0)) if cam is None else cam.params
    if kind not in ("perspective", "orthographic"):
        ctx.warn.once(("camera", kind), cam.where, f"Camera '{kind}' is not supported: a perspective camera of fov 90 "
                      f"stands in")
        ps.ignore(*ps.params)
        kind = "perspective"
    for name in ("screenwindow", "frameaspectratio"):
        if ps.get(name) is not None:
            ctx.warn.once(("camera", name), cam.where, f"Camera: \"{name}\" is not read (the image's aspect and a "
                          f"centred window stand in)")
    ps.ignore("shutteropen", "shutterclose")
    wide = width >= height
    if kind == "orthographic":
        out.update(type="orthographic", size=2.0 if wide else 2.0 * height / width)
    else:
        fov = ps.float("fov", 90.0)
        if not 0 < fov < 180:
            raise cam.where.error(f"Camera: fov must be between 0 and 180 degrees, got {fov:g}")
        if not wide:
            fov = math.degrees(2.0 * math.atan(math.tan(math.radians(fov) / 2.0) * height / width))
        out["fov"] = tidy(fov)
    lens = ps.float("lensradius", 0.0)
    focus = ps.float("focaldistance", 1e6)
    if lens > 0:
        out.update(aperture=lens, focus_distance=focus)
    _report(ps, "Camera", kind, ctx)
    return out


def _rounded(v) -> list:
    """Floats without the last bits of rounding noise (2.0000000000000004 reads badly in `lumos info`)."""
    return [tidy(c, 12) for c in v]


def render_dict(options: Options, ctx: Context) -> dict:
    """lumos's render block: the path tracer at pbrt's resolution, samples, depth and filter."""
    width, height = resolution(options)
    out = {"method": "path", "width": width, "height": height, "spp": 16, "max_depth": 4, "filter": "gaussian"}
    film = options.others.get("Film")
    if film is not None:
        for name in ("cropwindow", "pixelbounds", "iso", "exposuretime", "whitebalance", "sensor"):
            if film.params.get(name) is not None:
                ctx.warn.once(("film", name), film.where, f"Film: \"{name}\" is not read (the whole image, as "
                              f"pbrt's default sensor sees it)")
        film.params.ignore("filename", "savefp16", "diagonal", "maxcomponentvalue", "writefp16")
        _report(film.params, "Film", film.kind, ctx)
    _sampler(options.others.get("Sampler"), out, ctx)
    _integrator(options.others.get("Integrator"), out, ctx)
    _filter(options.others.get("PixelFilter"), out, ctx)
    return out


def _sampler(opt: Optional[Option], out: dict, ctx: Context) -> None:
    if opt is None:
        return
    ps = opt.params
    if opt.kind == "stratified":
        out["spp"] = ps.int("xsamples", 4) * ps.int("ysamples", 4)
        ps.ignore("jitter")
    else:
        out["spp"] = ps.int("pixelsamples", 16)
    if out["spp"] < 1:
        raise opt.where.error(f"Sampler: at least one sample per pixel, got {out['spp']}")
    seed = ps.int("seed", 0)
    if seed:
        out["seed"] = seed % 2 ** 32
    ps.ignore("randomization")
    _report(ps, "Sampler", opt.kind, ctx)


def _integrator(opt: Optional[Option], out: dict, ctx: Context) -> None:
    if opt is None:
        return
    ps = opt.params
    if opt.kind not in _PATH_INTEGRATORS:
        known = opt.kind in _OTHER_INTEGRATORS
        ctx.warn.once(("integrator", opt.kind), opt.where, f"Integrator '{opt.kind}' is "
                      f"{'not supported' if known else 'unknown'}: lumos's path tracer stands in")
        ps.ignore(*ps.params)
    depth = ps.int("maxdepth", 5)
    if depth == 0:
        ctx.warn.once(("maxdepth0",), opt.where, "Integrator: maxdepth 0 (emitters only) is not in lumos: direct "
                      "light (max_depth 0) stands in")
    out["max_depth"] = -1 if depth < 0 else max(depth - 1, 0)
    ps.ignore("regularize", "lightsampler")
    _report(ps, "Integrator", opt.kind, ctx)


def _filter(opt: Optional[Option], out: dict, ctx: Context) -> None:
    """pbrt's `box` (radius 0.5: one pixel) is lumos's box, its `gaussian` (the default, σ = 0.5) lumos's
    gaussian (σ = 0.5 pixel); the other filters stand in as the gaussian."""
    if opt is None:
        return
    ps = opt.params
    if opt.kind == "box":
        out["filter"] = "box"
        radius = ps.floats("radius")
        if radius is not None and any(abs(r - 0.5) > 1e-6 for r in radius):
            ctx.warn.once(("filter-radius",), opt.where, "PixelFilter 'box': lumos's box is one pixel wide (radius "
                          "0.5); the radius given is not read")
    elif opt.kind != "gaussian":
        ctx.warn.once(("filter", opt.kind), opt.where, f"PixelFilter '{opt.kind}' is not supported: lumos's gaussian "
                      f"filter stands in")
    ps.ignore(*ps.params)


def _report(ps: Params, directive: str, kind: str, ctx: Context) -> None:
    for p in ps.unused():
        ctx.warn.once(("param", directive, kind, p.name), p.where, f"{directive} '{kind}': parameter "
                      f"\"{p.type} {p.name}\" is not used")
