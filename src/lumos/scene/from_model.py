"""A whole scene from a model file alone, and the pieces a scene's `{type: model}` include expands into.

    scene_dict, about = scene_from_model(import_model("teapot.obj"))   # what `lumos render teapot.obj` renders

Pure Python (NumPy for the vertex bounds; never Numba). The scene built for a bare model file:

- **camera**: the file's first camera if it has one (unless `--view` or `--up` is given); otherwise a camera
  framing the model, vertical fov 40°, at the distance where its bounding sphere (centred on its bounding box)
  fills the frame's height with a 10% margin (`MARGIN`):
  - **up**: +y for glTF (its specification); for OBJ, PLY, STL and OFF, which carry no up axis, +z when the
    bounds are at least 1.4× taller along z than along y (`Z_UP_RATIO`: a bottle or a figure modelled z-up)
    and not flat along y (a floor), else +y (`up_axis`);
  - **front**: of the four horizontal sides, the one the most faces face (`front_direction`; counting faces,
    not area: a scan's face and hands are finely meshed), +z (−y for z-up) unless another side has 10% more;
  - **view**: from the front, swung 30° to the model's left and raised 25° (`three-quarter`, a product shot),
    or the `--view` asked for (front, back, left, right, top). An open model whose faces mostly face one way
    (`view_direction`: a floor, a wall, a backdrop) is looked at from the side its faces show instead: from
    behind when they face back, and from the front raised or swung by 40° (`TILT`) when they face up, down or
    sideways, so that a floor is not seen edge-on and a backdrop not from behind.
- **lights**: the file's own lights if it has them; otherwise a three-point set-up around the bounding sphere,
  placed about the camera's view (`three_point_lights`): a key light up-left-front, a weaker fill from the right, a rim light from behind and
  above, point lights without fall-off, so a white Lambertian surface facing the key reads about 0.65 and none
  goes over 1 (DESIGN.md §3 units). A model's emissive materials add to them (they used to replace them, and
  the DamagedHelmet showed only its glowing parts), except in a model seen from inside (a Cornell box with
  its lamp), which its own light lights. A model seen from inside gets its lights close to the view's axis
  (`INSIDE_LIGHTS`), so that they shine in through the opening the camera looks through.
- **method**: `whitted` (shadows, mirrors and glass: MTL illum 3–7) at 4 spp; `path` at 64 spp (`PATH_SPP`) when
  some of its materials emit (MTL `Ke`, glTF `emissiveFactor`), since only the path tracer samples them as
  lights. `--method path` on a model file also gets 64 spp unless `--spp` says otherwise (`api.resolve_settings`).
- **no ground**, a dark grey background, ambient 0.05.
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
#: Samples per pixel of `path` for a model file (its method when the model emits light, or `--method path`):
#: enough that a teapot or a bunny under the three-point lights is not speckled.
PATH_SPP = 64


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
                   direction=(0.0, 0.0, 1.0), up=(0.0, 1.0, 0.0)) -> dict:
    """A perspective camera on the `direction` side of `center` (default +z: looking along −z), `up` up, at the
    distance where a sphere of `radius` spans 1/`margin` of the vertical field of view `fov` (degrees)."""
    distance = margin * radius / math.sin(math.radians(fov) / 2)
    position = center + distance * np.asarray(direction, dtype=np.float64)
    return {"type": "perspective", "position": _vec(position), "look_at": _vec(center), "up": _vec(up), "fov": fov}


#: How far (degrees) the front view is raised or swung towards a model whose faces mostly face up, down or
#: sideways; and how one-sided (|mean unit normal|, 0 for a closed surface) a model must be to be turned to.
TILT = 40.0
ONE_SIDED = 0.3
#: The views `--view` names; `three-quarter` is the default for a model that is not one-sided.
VIEWS = ("three-quarter", "front", "back", "left", "right", "top")
#: The three-quarter view: swung this far (degrees) round the up axis from the front, towards the model's
#: left (the viewer's right), and raised this far above the horizon: a product shot.
SWING = 30.0
RAISE = 25.0
#: OBJ, PLY, STL and OFF carry no up axis: a model is taken as z-up when its bounds are at least this much taller
#: along z than along y (a bottle or a figure modelled z-up); otherwise y-up, the OBJ and glTF convention.
Z_UP_RATIO = 1.4
#: A side of the model is its front when more faces face it than face any other side by this share; on a tie
#: (a box, a sphere) the front is the first of +z, −z, +x, −x (y-up; −y, +y, +x, −x for z-up).
FRONT_MARGIN = 0.1


def up_axis(objects: list[dict], source=None) -> str:
    """"y" or "z": glTF is +y by its specification; any other format, "z" when the model's bounds are at least
    Z_UP_RATIO times taller along z than along y, and not flat along y (a floor in the xz plane)."""
    if source is not None and str(source).lower().endswith((".gltf", ".glb")):
        return "y"
    lo, hi = model_bounds(objects)
    extent = hi - lo
    flat = extent[1] <= 0.05 * extent.max()  # a floor in the xz plane: y-up's ground, not a z-up wall
    return "z" if extent[2] > Z_UP_RATIO * extent[1] and not flat else "y"


def _frame(up: str) -> np.ndarray:
    """(3, 3) rotation from world to the viewing frame, where up is +y and the first front candidate +z."""
    if up == "z":
        return np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # z → y, −y → +z
    return np.eye(3)


def _triangles(objects: list[dict]) -> np.ndarray:
    """(m, 3, 3) float64: the corners of every triangle of the meshes, in world space, as the file winds them
    (counter-clockwise about the front); polygon faces (which the scene model triangulates later) are skipped."""
    out = []
    for obj in objects:
        if obj.get("type") != "mesh" or obj.get("vertices") is None or obj.get("faces") is None:
            continue
        v = np.asarray(obj["vertices"], dtype=np.float64).reshape(-1, 3)
        m = object_matrix(obj)
        if m is not None:
            v = v @ m[:3, :3].T + m[:3, 3]
        try:
            f = np.asarray(obj["faces"], dtype=np.int64).reshape(-1, 3)
        except ValueError:
            continue
        if not len(f) or f.min() < 0 or f.max() >= len(v):
            continue
        t = v[f]
        out.append(t[np.all(np.isfinite(t), axis=(1, 2))])
    return np.concatenate(out) if out else np.zeros((0, 3, 3))


def _face_normals(objects: list[dict]) -> np.ndarray:
    """(m, 3) float64: 2 × area × unit normal of every triangle of the meshes, in world space."""
    t = _triangles(objects)
    return np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])


def view_direction(objects: list[dict], up: str = "y") -> np.ndarray | None:
    """A one-sided model's view, unit (3,) from its centre to the camera, or None for a model that is not one-sided.
    One-sided: the area-weighted mean of the face normals is at least ONE_SIDED long (a closed surface's is 0);
    then the view is from the side the faces show: from behind (−z for y-up) when they face mostly back, else
    the front view raised (faces up), lowered (faces down) or swung left or right by TILT degrees."""
    n = _face_normals(objects) @ _frame(up).T
    area = float(np.linalg.norm(n, axis=1).sum())
    total = n.sum(axis=0)
    if not area > 0 or np.linalg.norm(total) < ONE_SIDED * area:
        return None
    mean = total / area
    axis = int(np.argmax(np.abs(mean)))
    side = 1.0 if mean[axis] > 0 else -1.0
    if axis == 2:
        out = np.array([0.0, 0.0, side])
    else:
        tilt = math.radians(TILT)
        out = np.array([0.0, 0.0, math.cos(tilt)])
        out[axis] = side * math.sin(tilt)
    return _frame(up).T @ out


def front_direction(objects: list[dict], up: str = "y") -> np.ndarray:
    """Unit (3,) world direction of the model's front: of the four horizontal sides, the one the most faces face
    (unit normal within 60° of it), counting faces, not area (a scan's face, hands and feet are finely meshed);
    a side must beat the first candidate by FRONT_MARGIN to take its place."""
    n = _face_normals(objects) @ _frame(up).T
    length = np.linalg.norm(n, axis=1)
    unit = n[length > 0] / length[length > 0, None]
    candidates = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    counts = (unit @ candidates.T > 0.5).sum(axis=0)
    best = 0
    for i in range(1, 4):
        if counts[i] > counts[best] and counts[i] > (1.0 + FRONT_MARGIN) * counts[0]:
            best = i
    return _frame(up).T @ candidates[best]


def faces_inward(objects: list[dict]) -> bool:
    """Whether the model is mostly seen from inside (a room, a Cornell box open on one side): its faces, weighted
    by area, point towards its centre rather than away from it. Such a model is looked into straight from its
    front, where a three-quarter view would show the outside of a wall."""
    t = _triangles(objects)
    if not len(t):
        return False
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    lo, hi = model_bounds(objects)
    outward = np.einsum("ij,ij->i", n, t.mean(axis=1) - (lo + hi) / 2)
    return float(outward.sum()) < 0.0


def camera_direction(objects: list[dict], view: str | None = None, up: str = "y") -> tuple[np.ndarray, np.ndarray]:
    """(direction from the model's centre to the camera, the camera's up), both unit (3,) world vectors, for
    `view` (one of VIEWS; None: a one-sided model's own view, else three-quarter)."""
    u = _frame(up).T @ np.array([0.0, 1.0, 0.0])
    if view is None:
        own = view_direction(objects, up)
        if own is not None:
            return own, u
        view = "front" if faces_inward(objects) else "three-quarter"
    f = front_direction(objects, up)
    right = np.cross(u, f)  # the viewer's right, looking at the front
    if view == "front":
        return f, u
    if view == "back":
        return -f, u
    if view == "left":  # the model's left: the viewer's right
        return right, u
    if view == "right":
        return -right, u
    if view == "top":
        return u, -f  # looking down, the front at the bottom of the image
    swing, rise = math.radians(SWING), math.radians(RAISE)
    d = math.cos(rise) * (math.cos(swing) * f + math.sin(swing) * right) + math.sin(rise) * u
    return d / np.linalg.norm(d), u


#: (direction from the centre, intensity) of the key, fill and rim lights of `three_point_lights`.
THREE_POINT = (
    ((-1.0, 1.0, 1.0), 0.65),   # key: up-left-front
    ((1.2, 0.3, 1.0), 0.25),    # fill: from the other side, lower, weaker
    ((0.3, 0.8, -1.0), 0.45),   # rim: from behind and above, lights the silhouette
)


#: The same lights for a model seen from inside (`faces_inward`: a room, a box open on one side): close to the
#: view's axis, so that their light comes in through the opening the camera looks through (the wide key light
#: of THREE_POINT lit the outside of a Cornell box's wall), and no rim light (it would be behind the back wall).
INSIDE_LIGHTS = (
    ((-0.25, 0.3, 1.0), 0.65),
    ((0.3, 0.05, 1.0), 0.25),
)


def three_point_lights(center: np.ndarray, radius: float, camera: dict | None = None,
                       inside: bool = False) -> list[dict]:
    """Key, fill and rim point lights (no fall-off) at 4 bounding radii from `center`, placed about the view of
    `camera` (a camera dict: THREE_POINT's x is the image's right, y its up, z towards the camera; without one,
    the +z front view's: world x, y, z)."""
    frame = np.eye(3)
    if camera is not None and camera.get("position") is not None and camera.get("look_at") is not None:
        back = np.subtract(camera["position"], camera["look_at"]).astype(np.float64)
        right = np.cross(np.asarray(camera.get("up", (0.0, 1.0, 0.0)), np.float64), back)
        if np.linalg.norm(back) > 0 and np.linalg.norm(right) > 0:
            back /= np.linalg.norm(back)
            right /= np.linalg.norm(right)
            frame = np.stack([right, np.cross(back, right), back])
    lights = []
    for direction, intensity in INSIDE_LIGHTS if inside else THREE_POINT:
        d = np.asarray(direction) / np.linalg.norm(direction) @ frame
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


def scene_from_model(model, view: str | None = None, up: str | None = None) -> tuple[dict, str]:
    """(scene dict, a line saying what was made up) for an `ImportedModel` rendered on its own; `view` (one of
    VIEWS) and `up` ("y" or "z") override the file's camera and the up-axis heuristic."""
    materials, objects = dict(model.materials), [dict(o) for o in model.objects]
    center, radius = bounding_sphere(objects)
    about = []
    own_camera = bool(model.cameras) and view is None and up is None
    if own_camera:
        camera = dict(model.cameras[0])
        about.append("the file's camera")
    else:
        up = up or up_axis(objects, model.source)
        direction, camera_up = camera_direction(objects, view, up)
        camera = framing_camera(center, radius, direction=direction, up=camera_up)
        about.append(f"a {view or 'model-chosen'} view framing the bounds, {up} up")
    self_lit = emits(materials, objects)
    inside = not own_camera and view in (None, "front") and faces_inward(objects)
    if model.lights:
        lights = [dict(light) for light in model.lights]
        about.append(f"the file's {len(lights)} light{'s' if len(lights) > 1 else ''}")
    elif self_lit and inside:
        lights = []
        about.append("no lights (its emissive materials light its inside)")
    else:
        lights = three_point_lights(center, radius, camera, inside)
        about.append("three-point lights" + (" (its emissive materials add to them)" if self_lit else ""))
    render = {"method": "path", "spp": PATH_SPP} if self_lit else {"method": "whitted", "spp": 4}
    about.append(f"method {render['method']}")
    scene = {
        "camera": camera,
        "render": render,
        "ambient": AMBIENT,
        "background": BACKGROUND,
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
