"""pbrt-v4 light sources as lumos lights (and the background).

    lights, background = light_items("point", params, world, ctx, where)

Units. pbrt's point and spot lights have radiant intensity I (irradiance I·cosθ/d² at distance d), its distant
light gives irradiance L·cosθ, its area and infinite lights emit radiance L. A lumos point light of intensity I′
delivers irradiance π·I′·cosθ/att(d) (DESIGN.md §3), so the same light is I′ = I/π with `attenuation: [0, 0, 1]`
(and a directional light of I′ = L/π); radiance is radiance. Each value is pbrt's spectrum as RGB (a spectrum or
blackbody at luminance 1, as pbrt-v4 normalises them) times `scale`, and, where `power` (or `illuminance`) is
given, times pbrt's factor for it: point power/4π, spot power/(2π((1 − cos θ₁) + (cos θ₁ − cos θ₀)/2)),
distant illuminance, infinite illuminance/π.

- `point` (I, from): lumos `point`, intensity I/π, position from, attenuation [0, 0, 1].
- `spot` (I, from, to, coneangle θ₀, conedeltaangle δ): `spot`, intensity I/π, direction to − from, angle θ₀,
  inner_angle θ₀ − δ (between them lumos eases with s², pbrt with a smoothstep).
- `distant` (L, from, to): `directional`, intensity L/π, direction to − from.
- `infinite` (L): the scene's `environment` of that colour; with `filename`, pbrt-v4's equal-area octahedral
  map (square) resampled into lumos's lat-long image (`lat_long_environment`) through the light's transform,
  `illuminance` scaling it as pbrt does (the illuminance on a surface facing the light's +z). Several infinite
  lights add up into one environment.
- `goniometric`, `projection`: a `point` light of the same I, with a warning.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from ..mesh.directions import equal_area_sphere_to_square, equal_area_square_to_sphere, lat_long_directions
from .pbrt_textures import Context, Tex, color, tidy
from .pbrt_tokens import Params, Where

_WHITE = Tex((1.0, 1.0, 1.0))


def _vector(world: np.ndarray, v) -> list:
    out = world[:3, :3] @ np.asarray(v, dtype=np.float64)
    return [float(c) for c in out]


def _point(world: np.ndarray, p) -> list:
    return [float(c) for c in world[:3, :3] @ np.asarray(p, dtype=np.float64) + world[:3, 3]]


def _rgb(tex: Tex, factor: float) -> list:
    return [tidy(c * factor) for c in tex.mean]


def light_items(kind: str, ps: Params, world: np.ndarray, ctx: Context, where: Where
                ) -> tuple[list[dict], "Optional[tuple | EnvironmentMap]"]:
    """The lumos lights of one LightSource, and the radiance it adds to the background (infinite lights)."""
    scale = ps.float("scale", 1.0)
    if kind in ("point", "goniometric", "projection"):
        if kind != "point":
            ctx.warn.once(("light", kind), where, f"LightSource '{kind}' is not supported: a point light of its "
                          f"intensity stands in")
            ps.ignore("filename", "fov")
        power = ps.float("power", -1.0)
        factor = scale * (power / (4.0 * math.pi) if power > 0 else 1.0) / math.pi
        light = {"type": "point", "position": _point(world, ps.point("from", (0, 0, 0))),
                 "intensity": _rgb(color(ps, "I", "illuminant", ctx, _WHITE), factor), "attenuation": [0, 0, 1]}
        return [light], None
    if kind == "spot":
        return [_spot(ps, world, ctx, where, scale)], None
    if kind == "distant":
        direction = np.subtract(ps.point("to", (0, 0, 1)), ps.point("from", (0, 0, 0)))
        if not np.any(direction):
            raise where.error("LightSource 'distant': from and to are the same point")
        illuminance = ps.float("illuminance", -1.0)
        factor = scale * (illuminance if illuminance > 0 else 1.0) / math.pi
        return [{"type": "directional", "direction": _vector(world, direction),
                 "intensity": _rgb(color(ps, "L", "illuminant", ctx, _WHITE), factor)}], None
    if kind == "infinite":
        return [], _infinite(ps, ctx, where, scale, world)
    ctx.warn.once(("light", kind), where, f"LightSource '{kind}' is unknown: left out")
    ps.ignore(*ps.params)
    return [], None


def _spot(ps: Params, world: np.ndarray, ctx: Context, where: Where, scale: float) -> dict:
    start, end = ps.point("from", (0, 0, 0)), ps.point("to", (0, 0, 1))
    direction = np.subtract(end, start)
    if not np.any(direction):
        raise where.error("LightSource 'spot': from and to are the same point")
    cone = ps.float("coneangle", 30.0)
    delta = ps.float("conedeltaangle", 5.0)
    angle = min(max(cone, 1e-3), 90.0)
    if cone > 90.0:
        ctx.warn.once(("spot-wide",), where, f"LightSource 'spot': coneangle {cone:g} > 90: lumos spots reach 90°")
    inner = min(max(cone - delta, 0.0), angle)
    power = ps.float("power", -1.0)
    factor = scale / math.pi
    if power > 0:
        cos_end, cos_start = math.cos(math.radians(cone)), math.cos(math.radians(cone - delta))
        factor *= power / (2.0 * math.pi * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0))
    return {"type": "spot", "position": _point(world, start), "direction": _vector(world, direction),
            "angle": angle, "inner_angle": inner, "attenuation": [0, 0, 1],
            "intensity": _rgb(color(ps, "I", "illuminant", ctx, _WHITE), factor)}


def _infinite(ps: Params, ctx: Context, where: Where, scale: float, world: np.ndarray):
    """An infinite light: its radiance as an RGB tuple (`L`), or an `EnvironmentMap` (`filename`)."""
    illuminance = ps.float("illuminance", -1.0)
    filename = ps.string("filename", None)
    if ps.get("portal") is not None:
        ctx.warn.once(("portal",), where, "LightSource 'infinite': \"portal\" is not read (the whole sky lights)")
    if filename and ps.has("L"):
        raise where.error("LightSource 'infinite': both \"L\" and \"filename\" given")
    if not filename:
        factor = scale * (illuminance / math.pi if illuminance > 0 else 1.0)
        return tuple(_rgb(color(ps, "L", "illuminant", ctx, _WHITE), factor))
    path = ctx.folder / filename
    if not path.is_file():
        raise where.error(f"LightSource 'infinite': no such file '{filename}'")
    from .image_files import read_image

    try:
        image = read_image(path).astype(np.float64)
    except Exception as exc:  # noqa: BLE001 - a map that cannot be read is bad input, said in one line
        raise where.error(f"LightSource 'infinite': {exc}") from None
    if image.shape[0] != image.shape[1]:
        raise where.error(f"LightSource 'infinite': '{filename}' is {image.shape[1]}x{image.shape[0]}: pbrt-v4's "
                          "environment maps are square (equal-area octahedral)")
    factor = scale
    if illuminance > 0:  # scaled so that a surface facing the light's +z receives this illuminance (pbrt-v4)
        n = image.shape[0]
        u, v = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n)
        up = np.maximum(equal_area_square_to_sphere(u, v)[..., 2], 0.0)
        k = float((image @ _LUMINANCE * up).sum() * 4.0 * math.pi / (n * n))
        factor *= illuminance / k if k > 0 else 0.0
    return EnvironmentMap(image * factor, np.asarray(world, float)[:3, :3])


#: the luminance of a linear sRGB triple
_LUMINANCE = np.array([0.2126729, 0.7151522, 0.0721750])


class EnvironmentMap:
    """One image infinite light: its equal-area octahedral radiance (N, N, 3) and the 3×3 linear part of its
    light-to-world transform."""

    def __init__(self, image: np.ndarray, to_world: np.ndarray):
        self.image, self.to_world = image, to_world


def lat_long_environment(maps: list[EnvironmentMap], constant) -> np.ndarray:
    """float32 (N, 2N, 3): lumos's lat-long environment of the image infinite lights `maps` (N the largest map's
    side) plus a constant radiance: each lat-long pixel takes the mean of 2×2 points, each read at the nearest
    pixel of each map (as pbrt-v4's `ImageLe` reads it) along the direction turned back into the map's frame."""
    n = max(m.image.shape[0] for m in maps)
    sub = lat_long_directions(2 * n, 4 * n)  # 2×2 points per pixel of the (n, 2n) image
    out = np.zeros((2 * n, 4 * n, 3)) + np.asarray(constant, float)
    for m in maps:
        d = sub @ np.linalg.inv(m.to_world).T  # world -> the map's own frame
        d /= np.linalg.norm(d, axis=-1)[..., None]
        u, v = equal_area_sphere_to_square(d)
        side = m.image.shape[0]
        rows = np.clip((v * side).astype(np.int64), 0, side - 1)
        cols = np.clip((u * side).astype(np.int64), 0, side - 1)
        out += m.image[rows, cols]
    return out.reshape(n, 2, 2 * n, 2, 3).mean(axis=(1, 3)).astype(np.float32)
