"""A scene at a time: what the tracks of an `animation:` block animate, checked, evaluated and applied.

    scene = lumos.load_scene("turntable.yaml")
    frame_times(scene)                # [0.0, 1/24, 2/24, ...]: frame k at k / fps
    scene_at(scene, 0.5)              # a new Scene with every track evaluated at 0.5 s (the input is unchanged)

A track's `target` is a key path into the scene, written as error messages write them:

    camera.<key>                      position, look_at, up, fov, size, aperture, focus_distance
    objects[<name>].transform.<key>   translate, rotate, scale (objects are animated by their `name:`, unique)
    lights[<name or index>].<key>     intensity, diffuse, specular, position, direction, attenuation, angle,
                                      inner_angle, radiance, center, corner, edge_u, edge_v, normal, radius
    materials.<name>.<key>            ka, kd, ks, shininess, kr, kt, ior, emission

(`objects.ball.transform.rotate`, `lights.key.intensity` and `materials[red].kd` are the same paths written
otherwise.) Every key value is validated as the key itself is (a colour, a 3-vector, fov in (0, 180)...), when the
scene is loaded; a value between keys is validated when the scene at that time is made.

Motion blur: when the camera's shutter is open ([open, close] seconds, relative to the frame's time t), an
object with a `transform.translate` track gets translate = x(t + open) − open·v and motion (added to its own)
v = (x(t + close) − x(t + open)) / (close − open): it moves along the chord of its curve across the shutter,
linear within the shutter and at the curve at the shutter's opening and closing. Its rotation and scale, and the
camera, are those at time t. (Meshes and triangles cannot move while the shutter is open: they are drawn at t.)

Pure Python and NumPy (the keyframe model and curves are `lumos.scene.keyframes`).
"""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from pydantic import BaseModel, ValidationError

from ..errors import LumosError
from .keyframes import Animation, Curve, Key, Orbit, Track, rotate_about
from .messages import first_error, format_path, show
from .transform import Transform

__all__ = ["Animation", "AnimationError", "CAMERA_KEYS", "Key", "LIGHT_KEYS", "MATERIAL_KEYS", "Orbit",
           "TRANSFORM_KEYS", "Track", "animated_kinds", "check", "frame_count", "frame_time", "frame_times",
           "scene_at"]

CAMERA_KEYS = ("position", "look_at", "up", "fov", "size", "aperture", "focus_distance")
TRANSFORM_KEYS = ("translate", "rotate", "scale")
LIGHT_KEYS = ("intensity", "diffuse", "specular", "position", "direction", "attenuation", "angle", "inner_angle",
              "radiance", "center", "corner", "edge_u", "edge_v", "normal", "radius")
MATERIAL_KEYS = ("ka", "kd", "ks", "shininess", "kr", "kt", "ior", "emission")
ROOTS = ("camera", "objects", "lights", "materials")
#: object types whose `motion` the compile step takes (meshes and triangles cannot move during the shutter)
_MOVABLE = ("sphere", "plane", "box", "cylinder", "cone", "disk", "rect", "csg")


class AnimationError(ValueError):
    """A problem with a scene's `animation:` block, at key path `where` (such as ('animation', 'tracks', 2,
    'target'))."""

    def __init__(self, where: tuple, message: str):
        super().__init__(message)
        self.where = where


# ------------------------------------------------------------------------------------------------ frames


def frame_count(scene) -> int:
    """The number of frames of the scene's animation (1 for a scene without one)."""
    return 1 if scene.animation is None else scene.animation.frame_count()


def frame_time(scene, frame: int) -> float:
    """The time of frame `frame` in seconds: frame / fps (0 for a scene without an animation)."""
    return 0.0 if scene.animation is None else scene.animation.frame_time(frame)


def frame_times(scene) -> list[float]:
    """The time of every frame, frame k at k / fps ([0.0] for a scene without an animation)."""
    return [frame_time(scene, k) for k in range(frame_count(scene))]


# ----------------------------------------------------------------------------------------------- targets


@dataclass(frozen=True)
class Slot:
    """A resolved target: what kind of thing (camera, object, light, material), which one (an object's name, a
    light's index, a material's name; None for the camera) and its key."""

    kind: str
    which: Any
    key: str

    def owner(self, scene) -> BaseModel:
        """The model that holds the key: the camera, an object's transform, a light, a material."""
        if self.kind == "camera":
            return scene.camera
        if self.kind == "object":
            obj = _object_named(scene, self.which)
            return obj.transform if obj.transform is not None else Transform()
        if self.kind == "light":
            return scene.lights[self.which]
        return scene.materials[self.which]


#: one step of a target: `.name` (or the first name), `.3`, `[name]`, `[3]`, `['a name']`, `["a name"]`
_TOKEN = re.compile(r"(?P<dot>\.)?(?P<name>[A-Za-z_][\w-]*|\d+)"
                    r"""|\[\s*(?:'(?P<q1>[^']*)'|"(?P<q2>[^"]*)"|(?P<raw>[^\]'"]*?))\s*\]""")


def parse_target(text: str) -> list:
    """'lights[key].intensity' -> ['lights', 'key', 'intensity']; a bare number in brackets or after a dot is
    an index (int)."""
    parts, pos = [], 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos or (m["name"] is not None and (m["dot"] is None) != (pos == 0)):
            raise ValueError(f"cannot read target {text!r}: write a key path such as camera.position, "
                             "objects[ball].transform.translate, lights[key].intensity or materials.red.kd")
        if m["name"] is not None:
            part = m["name"]
        else:
            part = m["q1"] if m["q1"] is not None else m["q2"] if m["q2"] is not None else m["raw"]
            if m["q1"] is None and m["q2"] is None and part.isdigit():
                part = int(part)
        if isinstance(part, str) and part.isdigit() and m["name"] is not None:
            part = int(part)
        parts.append(part)
        pos = m.end()
    if not parts:
        raise ValueError("the target is empty: write a key path such as camera.position")
    return parts


def _choose(what: str, given: Any, known) -> str:
    known = list(known)
    match = difflib.get_close_matches(str(given), known, n=1, cutoff=0.6)
    hint = f"did you mean '{match[0]}'? " if match else ""
    return f"{what} {given!r} ({hint}animated keys: {', '.join(known)})" if known else f"{what} {given!r}"


def _object_named(scene, name: str):
    return next(obj for obj in scene.objects if obj.name == name)


def resolve_target(scene, text: str) -> Slot:
    """The Slot a target names in `scene`; ValueError with a one-line reason when there is none."""
    parts = parse_target(text)
    root = parts[0]
    if root not in ROOTS:
        match = difflib.get_close_matches(str(root), ROOTS, n=1, cutoff=0.6)
        hint = f"did you mean '{match[0]}'? " if match else ""
        raise ValueError(f"unknown target {text!r} ({hint}a target starts with camera, objects[<name>], "
                         f"lights[<name or index>] or materials.<name>)")
    if root == "camera":
        if len(parts) != 2 or parts[1] not in CAMERA_KEYS:
            key = parts[1] if len(parts) > 1 else ""
            raise ValueError(_choose("unknown animated camera key", ".".join(map(str, parts[1:])) or key,
                                     CAMERA_KEYS))
        return Slot("camera", None, parts[1])
    if len(parts) < 3:
        raise ValueError(f"target {text!r} names no key: write e.g. objects[ball].transform.translate, "
                         f"lights[key].intensity or materials.red.kd")
    which = parts[1]
    if root == "objects":
        if isinstance(which, int):
            raise ValueError(f"objects are animated by name: give objects[{which}] a name: and write "
                             f"objects[<name>]")
        named = [obj for obj in scene.objects if obj.name == which]
        if not named:
            names = sorted({obj.name for obj in scene.objects if obj.name})
            raise ValueError(f"no object is named {which!r} (named: {', '.join(names) or 'none'}; give the object "
                             f"a name: to animate it)")
        if len(named) > 1:
            raise ValueError(f"{len(named)} objects are named {which!r}; an animated object's name must be unique")
        if named[0].type == "model":
            raise ValueError(f"objects[{which}] is a model include: its meshes cannot be animated (animate an "
                             f"object of the scene's own)")
        if parts[2] != "transform" or len(parts) != 4 or parts[3] not in TRANSFORM_KEYS:
            key = ".".join(map(str, parts[2:]))
            raise ValueError(_choose("unknown animated object key", key, [f"transform.{k}" for k in TRANSFORM_KEYS]))
        return Slot("object", which, parts[3])
    if root == "lights":
        if isinstance(which, int):
            if not 0 <= which < len(scene.lights):
                raise ValueError(f"lights[{which}]: there is no such light (the scene has {len(scene.lights)})")
            index = which
        else:
            found = [i for i, light in enumerate(scene.lights) if getattr(light, "name", None) == which]
            if not found:
                names = sorted({light.name for light in scene.lights if getattr(light, "name", None)})
                raise ValueError(f"no light is named {which!r} (named: {', '.join(names) or 'none'}; give the "
                                 f"light a name: or write its index, lights[0])")
            if len(found) > 1:
                raise ValueError(f"{len(found)} lights are named {which!r}; an animated light's name must be unique")
            index = found[0]
        light = scene.lights[index]
        keys = [k for k in LIGHT_KEYS if k in type(light).model_fields]
        if len(parts) != 3 or parts[2] not in keys:
            kind = light.type if light.type != "area" else f"{light.shape} area"
            raise ValueError(_choose(f"unknown animated key of a {kind} light", ".".join(map(str, parts[2:])), keys))
        return Slot("light", index, parts[2])
    if which not in scene.materials:
        raise ValueError(f"unknown material {which!r} (defined: {', '.join(sorted(scene.materials)) or 'none'})")
    if len(parts) != 3 or parts[2] not in MATERIAL_KEYS:
        raise ValueError(_choose("unknown animated material key", ".".join(map(str, parts[2:])), MATERIAL_KEYS))
    return Slot("material", which, parts[2])


def _with(owner: BaseModel, updates: dict) -> BaseModel:
    """`owner` with `updates` (key -> value), validated as the owner's model validates them; raises
    ValidationError. Nested models and private attributes are kept (a shallow copy)."""
    data = owner.model_dump(include=set(owner.model_fields_set) | set(updates), warnings=False)
    data.update(updates)
    checked = type(owner).model_validate(data)
    return owner.model_copy(update={key: getattr(checked, key) for key in updates})


def _plain(value: np.ndarray, scalar: bool):
    return float(value[0]) if scalar else [float(x) for x in value]


# ------------------------------------------------------------------------------------------------- check


@dataclass
class _Resolved:
    index: int
    track: Track
    slot: Slot
    curve: Curve
    scalar: bool      # the key is a number (else a list)
    base: Optional[np.ndarray] = None  # orbit: the key's value as the scene gives it (angle 0)


def _where(i: int, *rest) -> tuple:
    return ("animation", "tracks", i) + rest


def _value_error(exc: ValidationError, key: str, where: tuple) -> AnimationError:
    path, message = first_error(exc)
    if path[:1] == (key,):
        return AnimationError(where + tuple(path[1:]), message)
    return AnimationError(where, message)


def _numbers(value: Any, where: tuple, n: Optional[int] = None) -> np.ndarray:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if isinstance(value, (list, tuple)):
        ok = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    if not ok:
        raise AnimationError(where, f"expected a number or a list of numbers, got {show(value)}")
    arr = np.atleast_1d(np.asarray(value, dtype=np.float64))
    if not np.all(np.isfinite(arr)):
        raise AnimationError(where, "is NaN or infinite")
    if n is not None and arr.size != n:
        raise AnimationError(where, f"must have {n} component{'s' if n != 1 else ''} (as the key's value), got "
                                    f"{arr.size}")
    return arr


def _resolve(scene) -> list[_Resolved]:
    """Every track of the scene's animation checked and made ready to evaluate; AnimationError at the key path
    of the first problem."""
    animation: Animation = scene.animation
    resolved, seen = [], {}
    for i, track in enumerate(animation.tracks):
        try:
            slot = resolve_target(scene, track.target)
        except ValueError as exc:
            raise AnimationError(_where(i, "target"), str(exc)) from None
        if slot in seen:
            raise AnimationError(_where(i, "target"), f"{track.target!r} is animated twice (also by "
                                 f"animation.tracks[{seen[slot]}])")
        seen[slot] = i
        owner = slot.owner(scene)
        times = [animation.key_time(key) for key in track.keys]
        for j in range(1, len(times)):
            if not times[j] > times[j - 1]:
                field = "time" if track.keys[j].time is not None else "frame"
                raise AnimationError(_where(i, "keys", j, field), f"keyframes out of order: {times[j]:g} s is not "
                                     f"after the previous key's {times[j - 1]:g} s (keys must be in increasing time)")
        values, base = [], None
        if track.orbit is not None:
            current = getattr(owner, slot.key)
            if not (isinstance(current, tuple) and len(current) == 3):
                raise AnimationError(_where(i, "orbit"), f"orbit turns a 3-vector (a position); {track.target} is "
                                     f"not one")
            base = np.asarray(current, dtype=np.float64)
            for j, key in enumerate(track.keys):
                values.append(_numbers(key.value, _where(i, "keys", j, "value"), 1))
            scalar = True
        else:
            scalar = True
            for j, key in enumerate(track.keys):
                where = _where(i, "keys", j, "value")
                if key.value is None:
                    raise AnimationError(where, "expected a number or a list of numbers, got nothing (null)")
                try:
                    checked = getattr(_with(owner, {slot.key: key.value}), slot.key)
                except ValidationError as exc:
                    raise _value_error(exc, slot.key, where) from None
                scalar = scalar and not isinstance(checked, tuple)
                values.append(np.atleast_1d(np.asarray(checked, dtype=np.float64)))
            sizes = {v.size for v in values}
            if sizes == {1, 3}:  # a scale given as one number in some keys and as three in others
                values = [np.repeat(v, 3) if v.size == 1 else v for v in values]
            elif len(sizes) > 1:
                j = next(j for j, v in enumerate(values) if v.size != values[0].size)
                raise AnimationError(_where(i, "keys", j, "value"), f"has {values[j].size} components, the first "
                                     f"key {values[0].size}")
        n = values[0].size
        slopes_in, slopes_out = [None] * len(values), [None] * len(values)
        for j, key in enumerate(track.keys):
            for name in ("tangent", "tangent_in", "tangent_out"):
                given = getattr(key, name)
                if given is None:
                    continue
                if track.interpolation != "bezier":
                    raise AnimationError(_where(i, "keys", j, name), f"{name} shapes a bezier curve; this track's "
                                         f"interpolation is {track.interpolation}")
                slope = _numbers(given, _where(i, "keys", j, name), None if n == 3 and np.size(given) == 1 else n)
                slope = np.repeat(slope, n) if slope.size == 1 else slope
                if name in ("tangent", "tangent_in"):
                    slopes_in[j] = slope
                if name in ("tangent", "tangent_out"):
                    slopes_out[j] = slope
        curve = Curve(times, np.stack(values), track.interpolation, [key.ease for key in track.keys],
                      slopes_in, slopes_out)
        resolved.append(_Resolved(i, track, slot, curve, scalar, base))
    return resolved


def check(scene) -> None:
    """Check the scene's animation against the scene: keys in increasing time, targets that exist (objects by
    a unique name), key values valid for their key. Raises AnimationError (key path `where`, one-line message)."""
    if scene.animation is not None:
        _resolve(scene)


def animated_kinds(scene) -> set[str]:
    """What the animation moves or changes: a subset of {'camera', 'object', 'light', 'material'} (empty for a
    scene without an animation or without tracks)."""
    if scene.animation is None:
        return set()
    return {item.slot.kind for item in _resolve_or_raise(scene)}


def _source(scene) -> str:
    return str(scene.source) if scene.source is not None else "scene"


def _resolve_or_raise(scene) -> list[_Resolved]:
    try:
        return _resolve(scene)
    except AnimationError as exc:
        raise LumosError(f"{_source(scene)}: {format_path(exc.where)}: {exc}") from None


# --------------------------------------------------------------------------------------------- scene_at


def _value(item: _Resolved, t: float) -> np.ndarray:
    v = item.curve(t)
    if item.base is not None:
        return rotate_about(item.base, item.track.orbit.center, item.track.orbit.axis, float(v[0]))
    return v


def scene_at(scene, time: float):
    """A new, validated Scene: `scene` with every track of its animation evaluated at `time` (seconds) and no
    animation of its own. The input is not changed (unanimated parts are shared with it). A scene without an
    animation is returned as it is. Raises LumosError (one line: the file, the track, the time, what is wrong)
    when a value between keys is not valid for its key (a curve overshooting below 0, say)."""
    if scene.animation is None:
        return scene
    time = float(time)
    if not math.isfinite(time):
        raise LumosError(f"{_source(scene)}: animation: the time must be a finite number of seconds, got {time}")
    resolved = _resolve_or_raise(scene)
    shutter = tuple(scene.camera.shutter)
    updates: dict[tuple, dict] = {}   # (kind, which) -> {key: plain value}
    motions: dict[str, np.ndarray] = {}
    for item in resolved:
        slot = item.slot
        value = _value(item, time)
        if (slot.kind == "object" and slot.key == "translate" and shutter[1] > shutter[0]
                and _object_named(scene, slot.which).type in _MOVABLE):
            x_open, x_close = _value(item, time + shutter[0]), _value(item, time + shutter[1])
            velocity = (x_close - x_open) / (shutter[1] - shutter[0])
            value = x_open - shutter[0] * velocity
            motions[slot.which] = velocity
        scalar = item.scalar and item.base is None
        updates.setdefault((slot.kind, slot.which), {})[slot.key] = _plain(value, scalar)
    changed: dict[str, Any] = {"animation": None}
    objects = lights = materials = None
    for (kind, which), values in updates.items():
        slot = Slot(kind, which, next(iter(values)))
        try:
            new = _with(slot.owner(scene), values)
        except ValidationError as exc:
            path, message = first_error(exc)
            mine = [r for r in resolved if (r.slot.kind, r.slot.which) == (kind, which)]
            item = next((r for r in mine if path[:1] == (r.slot.key,)), mine[0])
            raise LumosError(f"{_source(scene)}: animation.tracks[{item.index}] ({item.track.target}) at "
                             f"{time:g} s: {message}") from None
        if kind == "camera":
            changed["camera"] = new
        elif kind == "object":
            objects = list(scene.objects) if objects is None else objects
            k = next(n for n, obj in enumerate(objects) if obj.name == which)
            extra = {}
            if which in motions:
                extra["motion"] = tuple(float(a + b) for a, b in zip(objects[k].motion, motions[which]))
            objects[k] = objects[k].model_copy(update={"transform": new, **extra})
        elif kind == "light":
            lights = list(scene.lights) if lights is None else lights
            lights[which] = new
        else:
            materials = dict(scene.materials) if materials is None else materials
            materials[which] = new
    if objects is not None:
        changed["objects"] = objects
    if lights is not None:
        changed["lights"] = lights
    if materials is not None:
        changed["materials"] = materials
    out = scene.model_copy(update=changed)
    if materials is not None:  # an area light's material must not come to emit (Scene's own check)
        for i, light in enumerate(out.lights):
            mat = out.material_of(light) if light.type == "area" else None
            if mat is not None and any(c > 0 for c in mat.emission):
                raise LumosError(f"{_source(scene)}: animation at {time:g} s: lights[{i}].material: an area light's "
                                 f"material must not emit (the light's emission is its radiance)")
    return out
