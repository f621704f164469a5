"""A whole scene from a model file alone, and the pieces a scene's `{type: model}` include expands into.

    scene_dict, about = scene_from_model(import_model("teapot.obj"))   # what `lumos render teapot.obj` renders

Pure Python (NumPy for the vertex bounds; never Numba). The scene built for a bare model file:

- **camera**: the file's first camera if it has one; otherwise a front view from +z looking towards −z with y up
  (the OBJ and glTF convention), vertical fov 40°, at the distance where the model's bounding sphere (centred
  on its bounding box) fills the frame's height with a 10% margin (`MARGIN`). Wider-than-tall images show all of
  it; a portrait image crops the sides. An open model whose faces mostly face one way (`view_direction`: a
  floor, a wall, a backdrop or a Cornell box open on one side) is looked at from the side its faces show: from
  −z when they face −z, and from the front raised or swung by 40° (`TILT`) when they face up, down or sideways,
  so that a floor is not seen edge-on and a backdrop not from behind.
- **lights**: the file's own lights if it has them; otherwise, unless the model's own emissive materials are
  meant to light it, a three-point set-up around the bounding sphere (`three_point_lights`): a key light
  up-left-front, a weaker fill from the right, a rim light from behind and above, point lights without fall-off,
  so a white Lambertian surface facing the key reads about 0.65 and none goes over 1 (DESIGN.md §3 units).
- **method**: `whitted` (shadows, mirrors and glass: MTL illum 3–7) at 4 spp; `path` at 64 spp when the model
  has no lights of its own and some of its materials emit (MTL `Ke`, glTF `emissiveFactor`): the McGuire
  Cornell boxes are lit by their ceiling light only, which only the path tracer samples as a light.
- **no ground**, a dark grey background (black when the model lights itself), ambient 0.05.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .model import Transform

#: Vertical field of view of the framing camera, degrees.
FOV = 40.0
#: The bounding sphere's diameter is 1/MARGIN of the frame's height.
MARGIN = 1.1
AMBIENT = 0.05
BACKGROUND = 0.05


# ----------------------------------------------------------------------------------------------- geometry


def object_matrix(obj: dict) -> Optional[np.ndarray]:
    """world_from_object (4, 4) float64 of an object dict's `transform`, or None when it has none."""
    t = obj.get("transform")
    if t is None:
        return None
    return (t if isinstance(t, Transform) else Transform.model_validate(t)).to_matrix()


def _world_points(objects: list[dict]) -> list[np.ndarray]:
    """(k, 3) float64 world points per object: mesh vertices, the corners of spheres' and boxes' boxes."""
    out = []
    for obj in objects:
        if obj.get("type") == "mesh" and obj.get("vertices") is not None:
            p = np.asarray(obj["vertices"], dtype=np.float64).reshape(-1, 3)
        elif obj.get("type") in ("sphere", "box"):
            if obj["type"] == "sphere":
                c, r = np.asarray(obj.get("center", (0, 0, 0)), float), float(obj.get("radius", 1.0))
                lo, hi = c - r, c + r
            else:
                lo, hi = np.asarray(obj.get("min", (-1, -1, -1)), float), np.asarray(obj.get("max", (1, 1, 1)), float)
            p = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        else:
            continue
        m = object_matrix(obj)
        if m is not None:
            p = p @ m[:3, :3].T + m[:3, 3]
        p = p[np.all(np.isfinite(p), axis=1)]
        if len(p):
            out.append(p)
    return out


def model_bounds(objects: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi), each (3,) float64: the world box of the meshes' vertices (with their transforms), and of the
    boxes around spheres and boxes; the cube [-1, 1]³ when there is nothing to measure."""
    points = _world_points(objects)
    if not points:
        return np.full(3, -1.0), np.full(3, 1.0)
    return np.min([p.min(axis=0) for p in points], axis=0), np.max([p.max(axis=0) for p in points], axis=0)


def bounding_sphere(objects: list[dict]) -> tuple[np.ndarray, float]:
    """(centre (3,), radius): the sphere centred on the bounds' box that holds every point of `objects` (tighter
    than the box's own sphere); a flat or empty model gets a radius > 0."""
    lo, hi = model_bounds(objects)
    center = (lo + hi) / 2
    points = _world_points(objects)
    radius = max((float(np.sqrt(((p - center) ** 2).sum(axis=1).max())) for p in points), default=0.0)
    if not points:
        radius = float(np.linalg.norm(hi - lo)) / 2
    if not radius > 0:
        radius = max(float(np.abs(center).max()) * 1e-3, 1e-3)
    return center, radius


def framing_camera(center: np.ndarray, radius: float, fov: float = FOV, margin: float = MARGIN,
                   direction=(0.0, 0.0, 1.0)) -> dict:
    """A perspective camera on the `direction` side of `center` (default +z: looking along −z), y up, at the
    distance where a sphere of `radius` spans 1/`margin` of the vertical field of view `fov` (degrees)."""
    distance = margin * radius / math.sin(math.radians(fov) / 2)
    position = center + distance * np.asarray(direction, dtype=np.float64)
    return {"type": "perspective", "position": _vec(position), "look_at": _vec(center), "up": [0.0, 1.0, 0.0],
            "fov": fov}


#: How far (degrees) the front view is raised or swung towards a model whose faces mostly face up, down or
#: sideways; and how one-sided (|mean unit normal|, 0 for a closed surface) a model must be to be turned to.
TILT = 40.0
ONE_SIDED = 0.3


def view_direction(objects: list[dict]) -> np.ndarray:
    """Unit (3,) direction from the model's centre to the framing camera: +z, unless the area-weighted mean of
    the meshes' face normals (their winding, counter-clockwise as the file gives it) is at least ONE_SIDED long
    (a closed surface's is 0): then from the side the faces show, −z when they face mostly −z, else the front
    view raised (faces up), lowered (faces down) or swung left or right by TILT degrees."""
    total, area = np.zeros(3), 0.0
    for obj in objects:
        if obj.get("type") != "mesh" or obj.get("vertices") is None or obj.get("faces") is None:
            continue
        v = np.asarray(obj["vertices"], dtype=np.float64).reshape(-1, 3)
        m = object_matrix(obj)
        if m is not None:
            v = v @ m[:3, :3].T + m[:3, 3]
        try:
            f = np.asarray(obj["faces"], dtype=np.int64).reshape(-1, 3)
        except ValueError:  # polygons: the scene model triangulates them; count only the framing's triangles
            continue
        if not len(f) or f.min() < 0 or f.max() >= len(v):
            continue
        n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])  # 2 × area × unit normal
        n = n[np.all(np.isfinite(n), axis=1)]
        total += n.sum(axis=0)
        area += float(np.linalg.norm(n, axis=1).sum())
    if not area > 0 or np.linalg.norm(total) < ONE_SIDED * area:
        return np.array([0.0, 0.0, 1.0])
    mean = total / area
    axis = int(np.argmax(np.abs(mean)))
    side = 1.0 if mean[axis] > 0 else -1.0
    if axis == 2:
        return np.array([0.0, 0.0, side])
    tilt = math.radians(TILT)
    out = np.array([0.0, 0.0, math.cos(tilt)])
    out[axis] = side * math.sin(tilt)
    return out


#: (direction from the centre, intensity) of the key, fill and rim lights of `three_point_lights`.
THREE_POINT = (
    ((-1.0, 1.0, 1.0), 0.65),   # key: up-left-front
    ((1.2, 0.3, 1.0), 0.25),    # fill: from the other side, lower, weaker
    ((0.3, 0.8, -1.0), 0.45),   # rim: from behind and above, lights the silhouette
)


def three_point_lights(center: np.ndarray, radius: float) -> list[dict]:
    """Key, fill and rim point lights (no fall-off) at 4 bounding radii from `center`."""
    lights = []
    for direction, intensity in THREE_POINT:
        d = np.asarray(direction) / np.linalg.norm(direction)
        lights.append({"type": "point", "position": _vec(center + 4.0 * radius * d), "intensity": intensity})
    return lights


def _vec(v) -> list[float]:
    return [float(x) for x in v]


# ------------------------------------------------------------------------------------------------ a model


def emits(materials: dict[str, dict], objects: list[dict]) -> bool:
    """Whether an object of the model uses a material with a non-zero `emission`."""
    for obj in objects:
        mat = obj.get("material")
        mat = materials.get(mat) if isinstance(mat, str) else mat
        if isinstance(mat, dict):
            e = mat.get("emission", 0.0)
            if np.any(np.asarray(e, dtype=float) > 0):
                return True
    return False


def scene_from_model(model) -> tuple[dict, str]:
    """(scene dict, a line saying what was made up) for an `ImportedModel` rendered on its own."""
    materials, objects = dict(model.materials), [dict(o) for o in model.objects]
    center, radius = bounding_sphere(objects)
    about = []
    if model.cameras:
        camera = dict(model.cameras[0])
        about.append("the file's camera")
    else:
        camera = framing_camera(center, radius, direction=view_direction(objects))
        about.append("a front camera framing the bounds")
    self_lit = not model.lights and emits(materials, objects)
    if model.lights:
        lights = [dict(light) for light in model.lights]
        about.append(f"the file's {len(lights)} light{'s' if len(lights) > 1 else ''}")
    elif self_lit:
        lights = []
        about.append("no lights (its emissive materials light it)")
    else:
        lights = three_point_lights(center, radius)
        about.append("three-point lights")
    render = {"method": "path", "spp": 64} if self_lit else {"method": "whitted", "spp": 4}
    about.append(f"method {render['method']}")
    scene = {
        "camera": camera,
        "render": render,
        "ambient": AMBIENT,
        "background": 0.0 if self_lit else BACKGROUND,
        "lights": lights,
        "materials": materials,
        "objects": objects,
    }
    return scene, ", ".join(about)


# ------------------------------------------------------------------------------------------------ includes


def merge_material(base: Optional[dict], override: dict) -> dict:
    """The file's material dict with the keys of `override` replacing its own (a missing base is the empty
    material: every coefficient 0)."""
    return {**(base or {}), **override}


def include_pieces(model, prefix: str, matrix: Optional[np.ndarray] = None,
                   overrides: Optional[dict[str, dict]] = None, keep_materials: bool = True) -> tuple[dict, list]:
    """(materials, objects) of an included model: materials named `<prefix>:<name>` with `overrides`
    (name in the file -> material keys) merged over them; objects named `<prefix>/<name>`, pointing at those
    names, with `matrix` (4, 4) composed before their own transforms (world = matrix · own). With
    `keep_materials` false the objects get no material (the include's own replaces them all)."""
    overrides = overrides or {}
    materials = {}
    if keep_materials:
        for name, mat in model.materials.items():
            materials[f"{prefix}:{name}"] = merge_material(mat, overrides.get(name, {}))
    objects = []
    for i, obj in enumerate(model.objects):
        obj = dict(obj)
        own_name = obj.get("name") or f"{obj.get('type', 'object')}#{i}"
        obj["name"] = f"{prefix}/{own_name}"
        mat = obj.get("material")
        if not keep_materials:
            obj["material"] = None
        elif isinstance(mat, str):
            obj["material"] = f"{prefix}:{mat}"
        if matrix is not None:
            own = object_matrix(obj)
            obj["transform"] = {"matrix": (matrix if own is None else matrix @ own).tolist()}
        objects.append(obj)
    return materials, objects


def transform_light(light: dict, matrix: np.ndarray) -> dict:
    """A light dict moved by world_from_object `matrix` (4, 4): points and directions carried, normals by the
    inverse transpose, radii by the cube root of the volume scale."""
    m3 = matrix[:3, :3]
    out = dict(light)
    for key in ("position", "center", "corner"):
        if key in out:
            out[key] = _vec(m3 @ np.asarray(out[key], float) + matrix[:3, 3])
    for key in ("direction", "edge_u", "edge_v"):
        if key in out:
            out[key] = _vec(m3 @ np.asarray(out[key], float))
    if "normal" in out:
        out["normal"] = _vec(np.linalg.inv(m3).T @ np.asarray(out["normal"], float))
    if "radius" in out:
        out["radius"] = float(out["radius"]) * abs(np.linalg.det(m3)) ** (1 / 3)
    return out
