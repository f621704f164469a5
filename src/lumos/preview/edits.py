"""Live edits of a scene held as the dict its YAML file loads to: orbit the camera, move a light or change its
strength, set a material's classic coefficients. Pure data in, data out: no rendering, no web code.

    data = apply_edit(data, base, {"type": "material", "name": "red", "key": "kd", "value": 0.3})
    data = apply_edit(data, base, {"type": "camera", "yaw": 10, "pitch": -5})

`base` is the scene as it was loaded: a colour set from one slider keeps the hue it had there (`kd: [0.6, 0.08,
0.06]` set to 0.3 becomes `[0.3, 0.04, 0.03]`: the slider is the largest channel). Every value is checked here
(a number, finite, in `RANGES`); the scene model checks the rest when the edited dict is validated.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from ..errors import LumosError

#: The material coefficients the page edits, and the range a slider may set each to.
MATERIAL_KEYS = ("ka", "kd", "ks", "shininess", "kr", "kt", "ior")
RANGES = {"ka": (0.0, 1.0), "kd": (0.0, 1.0), "ks": (0.0, 1.0), "kr": (0.0, 1.0), "kt": (0.0, 1.0),
          "shininess": (0.0, 10000.0), "ior": (1.0, 3.0), "strength": (0.0, 1.0e4)}
#: Colour keys: RGB triples (or a scalar for grey) in the scene file; the slider sets the largest channel.
COLOUR_KEYS = ("ka", "kd", "ks", "kr", "kt")
#: The point each kind of light is placed by, and whether it has a direction: what the page's sliders move.
LIGHT_VECTORS = {"point": ("position",), "spot": ("position", "direction"), "directional": ("direction",),
                 "rect": ("corner",), "disk": ("center",), "sphere": ("center",)}
#: The camera's angle from the up axis stays in this range (degrees) while orbiting, so it never flips over.
PITCH_LIMITS = (2.0, 178.0)
#: The largest coordinate a light may be moved to, and the distances the camera may dolly to (scene units).
MAX_COORDINATE = 1.0e6
DOLLY_LIMITS = (1.0e-3, 1.0e5)
_DEFAULTS = {"ka": 0.0, "kd": 0.0, "ks": 0.0, "kr": 0.0, "kt": 0.0, "shininess": 1.0, "ior": 1.0}


def apply_edit(data: dict, base: dict, message: dict) -> dict:
    """A copy of the scene dict `data` with the edit `message` applied (`camera`, `light` or `material`)."""
    kind = message.get("type")
    edited = copy.deepcopy(data)
    if kind == "camera":
        edited["camera"] = _camera(_mapping(edited, "camera"), _mapping(base, "camera"), message)
    elif kind == "light":
        _light(edited, base, message)
    elif kind == "material":
        _material(edited, base, message)
    else:
        raise LumosError(f"unknown edit {kind!r}")
    return edited


def describe(data: dict, base: dict | None = None) -> dict:
    """What the page offers to edit: the lights (their vectors and strength) and the named materials (their
    coefficients, colours as the largest channel, with a CSS colour for a swatch). `span`: how far the page's
    sliders move a light, from the distance of the camera to what it looks at in `base` (as loaded)."""
    camera = _mapping(base if base is not None else data, "camera")
    span = max(_distance(camera.get("position"), camera.get("look_at")), 1.0)
    lights = []
    for i, light in enumerate(data.get("lights") or []):
        if not isinstance(light, dict):
            continue
        was = _item((base if base is not None else data).get("lights"), i) or light
        kind = light.get("shape") if light.get("type") == "area" else light.get("type")
        keys = [key for key in LIGHT_VECTORS.get(kind, ()) if _vector(light.get(key)) is not None]
        key, colour = _strength_key(light)
        lights.append({"index": i, "label": light.get("name") or f"{i}: {kind}", "kind": kind,
                       "vectors": {k: _vector(light[k]) for k in keys},
                       "base_vectors": {k: _vector(was.get(k)) or _vector(light[k]) for k in keys},
                       "strength": _largest(colour), "base_strength": _largest(_strength_key(was)[1]),
                       "strength_key": key, "colour": _css(colour), "span": span})
    materials = []
    for name, material in (data.get("materials") or {}).items():
        if not isinstance(material, dict):
            continue
        values = {key: (_largest(material.get(key, _DEFAULTS[key])) if key in COLOUR_KEYS
                        else _number_or(material.get(key), _DEFAULTS[key])) for key in MATERIAL_KEYS}
        materials.append({"name": str(name), "values": values, "colour": _css(material.get("kd", 0.0))})
    return {"lights": lights, "materials": materials, "ranges": RANGES}


# -------------------------------------------------------------------------------------------------- camera


def _camera(camera: dict, base: dict, message: dict) -> dict:
    """Orbit (yaw about the up axis, pitch towards it, in degrees), dolly (scale the distance) or reset."""
    if message.get("reset"):
        return copy.deepcopy(base)
    position, look_at = _vector(camera.get("position")), _vector(camera.get("look_at"))
    if position is None or look_at is None:
        raise LumosError("camera: the scene's camera has no position and look_at to orbit about")
    up = np.asarray(_vector(camera.get("up")) or (0.0, 1.0, 0.0), np.float64)
    up /= max(np.linalg.norm(up), 1e-12)
    yaw = math.radians(_number(message, "yaw", default=0.0, limit=360.0))
    pitch = math.radians(_number(message, "pitch", default=0.0, limit=360.0))
    dolly = _number(message, "dolly", default=1.0, limit=100.0)
    if not dolly > 0.0:
        raise LumosError(f"camera.dolly: expected a positive factor, got {dolly:g}")
    offset = np.subtract(position, look_at)
    radius = float(np.linalg.norm(offset))
    if radius == 0.0:
        raise LumosError("camera: position and look_at are the same point")
    along = float(np.dot(offset, up))
    across = offset - along * up
    if np.linalg.norm(across) < 1e-9 * radius:  # straight above or below: any horizontal direction will do
        across = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 0.0, 1.0])
    across /= np.linalg.norm(across)
    side = np.cross(up, across)
    across = math.cos(yaw) * across + math.sin(yaw) * side  # yaw: turn about the up axis
    theta = math.degrees(math.acos(max(-1.0, min(1.0, along / radius)))) - math.degrees(pitch)
    theta = math.radians(min(max(theta, PITCH_LIMITS[0]), PITCH_LIMITS[1]))
    radius = min(max(radius * dolly, DOLLY_LIMITS[0]), DOLLY_LIMITS[1])
    new = np.asarray(look_at) + radius * (math.cos(theta) * up + math.sin(theta) * across)
    camera = dict(camera)
    camera["position"] = [round(float(c), 5) for c in new]
    return camera


# -------------------------------------------------------------------------------------------------- lights


def _light(data: dict, base: dict, message: dict) -> None:
    lights = data.get("lights") or []
    index = message.get("index")
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(lights):
        raise LumosError(f"light: no light {index!r} (the scene has {len(lights)})")
    light = lights[index]
    key = message.get("key")
    kind = light.get("shape") if light.get("type") == "area" else light.get("type")
    if key == "strength":  # the largest channel of its colour; a light's own diffuse and specular follow
        value = _number(message, "value", RANGES["strength"], name=f"lights[{index}].strength")
        base_light = _item(base.get("lights"), index) or {}
        name, colour = _strength_key(light)
        was = _largest(base_light.get(name, colour))
        for colour_key in (name, "diffuse", "specular") if name == "intensity" else (name,):
            if colour_key == name or colour_key in light:
                hue = base_light.get(colour_key, light.get(colour_key, colour))
                light[colour_key] = _times(hue, value / was) if was > 0.0 else round(value, 6)
        return
    if key not in LIGHT_VECTORS.get(kind, ()):
        raise LumosError(f"lights[{index}]: a {kind} light has no {key!r} to move "
                         f"(it has {', '.join(LIGHT_VECTORS.get(kind, ())) or 'none'})")
    value = message.get("value")
    if not (isinstance(value, list) and len(value) == 3):
        raise LumosError(f"lights[{index}].{key}: expected [x, y, z], got {_show(value)}")
    vector = [_number({"v": v}, "v", (-MAX_COORDINATE, MAX_COORDINATE), name=f"lights[{index}].{key}") for v in value]
    if key == "direction" and not any(vector):
        raise LumosError(f"lights[{index}].direction: a direction cannot be [0, 0, 0]")
    light[key] = vector


def _strength_key(light: dict) -> tuple[str, Any]:
    """The key that holds a light's strength (`radiance` of an area light, else `intensity`) and its colour."""
    if light.get("type") == "area":
        return "radiance", light.get("radiance", 1.0)
    if "intensity" not in light and "diffuse" in light:
        return "diffuse", light["diffuse"]
    return "intensity", light.get("intensity", 1.0)


# ----------------------------------------------------------------------------------------------- materials


def _material(data: dict, base: dict, message: dict) -> None:
    name, key = message.get("name"), message.get("key")
    materials = data.get("materials")
    if not isinstance(materials, dict) or not isinstance(name, str) or not isinstance(materials.get(name), dict):
        have = ", ".join(map(str, materials)) if isinstance(materials, dict) and materials else "none"
        raise LumosError(f"material: no named material {name!r} (the scene has {have})")
    if key not in MATERIAL_KEYS:
        raise LumosError(f"materials.{name}: {key!r} is not an editable coefficient (choose from "
                         f"{', '.join(MATERIAL_KEYS)})")
    value = _number(message, "value", RANGES[key], name=f"materials.{name}.{key}")
    material = materials[name]
    if key in COLOUR_KEYS:
        hue = _item_dict(base.get("materials"), name).get(key, material.get(key, 0.0))
        material[key] = _scaled(hue, value)
    else:
        material[key] = value


# ------------------------------------------------------------------------------------------------- helpers


def _scaled(hue, value: float):
    """A colour of `hue` (a scalar or an RGB triple; black: grey) whose largest channel is `value`; a scalar
    stays a scalar."""
    if isinstance(hue, (list, tuple)) and len(hue) == 3 and _largest(hue) > 0.0:
        peak = _largest(hue)
        return [round(float(c) / peak * value, 6) for c in hue]
    return round(value, 6)


def _times(colour, factor: float):
    """A colour (a scalar or an RGB triple) times `factor`, in the same form."""
    if isinstance(colour, (list, tuple)):
        return [round(c * factor, 6) for c in _rgb(colour)]
    return round(_largest(colour) * factor, 6)


def number_in(value, limits, name: str) -> float:
    """`value` as a finite float within `limits`, or a one-line `LumosError` naming `name`."""
    return _number({name: value}, name, limits)


def _number(message: dict, key: str, limits=None, default=None, limit=None, name=None) -> float:
    """message[key] as a finite float within `limits` (or |x| <= `limit`); a bad one is a one-line error."""
    value = message.get(key, default)
    label = name or key
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LumosError(f"{label}: expected a number, got {_show(value)}")
    value = float(value)
    if not math.isfinite(value):
        raise LumosError(f"{label}: expected a finite number, got {value}")
    if limits is not None and not limits[0] <= value <= limits[1]:
        raise LumosError(f"{label}: {value:g} is out of range ({limits[0]:g} to {limits[1]:g})")
    if limit is not None and abs(value) > limit:
        raise LumosError(f"{label}: {value:g} is out of range (-{limit:g} to {limit:g})")
    return value


def _mapping(data: dict, key: str) -> dict:
    value = data.get(key)
    if not isinstance(value, dict):
        raise LumosError(f"{key}: the scene has no {key} block to edit")
    return value


def _item(items, index: int):
    return items[index] if isinstance(items, list) and 0 <= index < len(items) and isinstance(items[index], dict) \
        else None


def _item_dict(items, name: str) -> dict:
    value = items.get(name) if isinstance(items, dict) else None
    return value if isinstance(value, dict) else {}


def _vector(value):
    if isinstance(value, (list, tuple)) and len(value) == 3 and all(
            isinstance(c, (int, float)) and not isinstance(c, bool) for c in value):
        return [float(c) for c in value]
    return None


def _rgb(value) -> list:
    if isinstance(value, (list, tuple)) and len(value) == 3:
        return [float(c) if isinstance(c, (int, float)) else 0.0 for c in value]
    return [float(value)] * 3 if isinstance(value, (int, float)) else [0.0] * 3


def _largest(value) -> float:
    return max(_rgb(value))


def _number_or(value, default: float) -> float:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else default


def _distance(a, b) -> float:
    a, b = _vector(a), _vector(b)
    return float(np.linalg.norm(np.subtract(a, b))) if a is not None and b is not None else 1.0


def _css(value) -> str:
    """A colour (linear RGB) as a CSS `rgb(...)`, sRGB-encoded and normalised to its largest channel."""
    from ..tonemap import srgb_encode

    rgb = np.asarray(_rgb(value), np.float64)
    peak = rgb.max()
    shown = srgb_encode(np.clip(rgb / peak if peak > 1.0 else rgb, 0.0, 1.0))
    return "rgb({}, {}, {})".format(*(int(round(255 * c)) for c in shown))


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
