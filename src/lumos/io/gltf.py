"""glTF 2.0 (`.gltf` JSON with embedded or external buffers, `.glb` binary) → an `ImportedModel`.

    model = import_gltf("BoxTextured.gltf")
    model.objects[0]["vertices"]    # float64 (n, 3), in world space (the node transforms are applied)

A reader of our own: glTF is JSON plus typed views of binary buffers, which NumPy reads directly
(`np.ndarray(buffer=..., strides=...)`), so a library would add a dependency and little else.

What is read (docs/formats.md#gltf-20 has the tables):
* the default scene (`scene`, else scene 0, else every root node) and its node hierarchy: each node's local
  transform is its `matrix` (column-major) or T·R·S (rotation a unit quaternion [x, y, z, w]); world = parent·local.
* meshes and primitives: mode 4 triangles, 5 strips and 6 fans (turned into triangles); points and lines are
  skipped with a warning. Indexed or not; POSITION, NORMAL, TEXCOORD_0 and TANGENT. **The world transform is
  baked into the vertices** (normals by its inverse transpose, tangents by its linear part; the winding is
  reversed under a mirroring transform), one lumos mesh per primitive instance: glTF allows degenerate node
  matrices (scale 0 hides a node) that a lumos `transform` refuses, and baked vertices give the model's
  bounds directly. glTF's v runs down the image (origin top-left); lumos's image v runs up (rows stored
  bottom row first), so `uvs` are (u, 1 − v).
* cameras (perspective, orthographic) and KHR_lights_punctual lights in world space; materials
  (`gltf_materials`).

Errors are one-line `LumosError`s `<file>: <what>`, with the JSON line for a JSON syntax error and the key path
(`meshes[0].primitives[1].indices`) for a bad value. Warnings go to `ImportedModel.warnings`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .gltf_document import Document, show_value
from .imported import ImportedModel

#: glTF's primitive modes
_TRIANGLES, _STRIP, _FAN = 4, 5, 6
_MODE_NAMES = {0: "points", 1: "lines", 2: "line loop", 3: "line strip"}


def import_gltf(path: str | os.PathLike) -> ImportedModel:
    """Read a `.gltf` or `.glb` file into an `ImportedModel` (see the module docstring); LumosError on bad input."""
    from .gltf_materials import Materials

    src = Path(path)
    doc = Document.read(src)
    model = ImportedModel(source=src.resolve(), warnings=doc.warnings)
    materials = Materials(doc)
    for node, world in doc.scene_nodes():
        at = f"nodes[{node}]"
        item = doc.item("nodes", node, "nodes")
        if "mesh" in item:
            mesh = doc.index(item, "mesh", at, "meshes")
            model.objects.extend(_mesh_objects(doc, mesh, world, item.get("name"), materials))
        if "camera" in item:
            camera = _camera(doc, doc.index(item, "camera", at, "cameras"), world, at)
            if camera is not None:
                model.cameras.append(camera)
        ext = doc.obj(doc.obj(item, "extensions", at), "KHR_lights_punctual", at + ".extensions")
        if "light" in ext:
            lights = doc.obj(doc.obj(doc.json, "extensions", ""), "KHR_lights_punctual", "extensions")
            index = doc.int(ext, "light", f"{at}.extensions.KHR_lights_punctual")
            model.lights.append(_light(doc, lights, index, world))
    model.materials = materials.used
    return model


# ------------------------------------------------------------------------------------------------ document


# ---------------------------------------------------------------------------------------------------- meshes


def _mesh_objects(doc: Document, mesh: int, world: np.ndarray, node_name, materials) -> list[dict]:
    """One lumos mesh dict per triangle primitive of meshes[mesh], its vertices in world space."""
    item = doc.item("meshes", mesh, "mesh")
    at = f"meshes[{mesh}]"
    name = item.get("name") if isinstance(item.get("name"), str) else node_name
    name = name if isinstance(name, str) and name else f"mesh{mesh}"
    prims = doc.list(item, "primitives", at)
    objects = []
    for p, prim in enumerate(prims):
        at_p = f"{at}.primitives[{p}]"
        if not isinstance(prim, dict):
            raise doc.error(at_p, f"must be a JSON object, got {show_value(prim)}")
        obj = _primitive(doc, prim, at_p, world)
        if obj is None:
            continue
        obj["name"] = name if len(prims) == 1 else f"{name}.{p}"
        obj["material"] = materials.key(doc.index(prim, "material", at_p, "materials")) if "material" in prim else None
        if obj["material"] is None:
            del obj["material"]  # the scene's default matte grey (glTF's default material is a rough white metal)
        elif obj["material"] in materials.one_sided_emitters:
            obj["two_sided"] = False  # glTF: a material that is not doubleSided has a front only, emission included
        objects.append(obj)
    return objects


def _primitive(doc: Document, prim: dict, at: str, world: np.ndarray) -> dict | None:
    mode = doc.int(prim, "mode", at, default=_TRIANGLES)
    if mode not in (_TRIANGLES, _STRIP, _FAN):
        doc.warn(f"{at}: skipping a primitive of {_MODE_NAMES.get(mode, f'mode {mode}')} (lumos renders triangles)")
        return None
    attrs = doc.obj(prim, "attributes", at)
    if "POSITION" not in attrs:
        raise doc.error(f"{at}.attributes", "has no POSITION")

    def attribute(key: str, ncomp: int):
        if key not in attrs:
            return None
        arr = doc.accessor(doc.int(attrs, key, f"{at}.attributes"), f"{at}.attributes.{key}")
        if arr.shape[1] != ncomp:
            raise doc.error(f"{at}.attributes.{key}", f"must be a VEC{ncomp} accessor, got {arr.shape[1]} components")
        if len(arr) != n:
            raise doc.error(f"{at}.attributes.{key}", f"has {len(arr)} elements but POSITION has {n}")
        if not np.isfinite(arr).all():
            raise doc.error(f"{at}.attributes.{key}", "holds NaN or infinite values")
        return arr.astype(np.float64)

    n = len(doc.accessor(doc.int(attrs, "POSITION", f"{at}.attributes"), f"{at}.attributes.POSITION"))
    positions = attribute("POSITION", 3)
    if "indices" in prim:
        indices = doc.accessor(doc.int(prim, "indices", at), f"{at}.indices")
        if indices.shape[1] != 1 or indices.dtype.kind != "i":
            raise doc.error(f"{at}.indices", "must be a SCALAR accessor of unsigned integers")
        indices = indices[:, 0]
        if indices.size and (indices.min() < 0 or indices.max() >= n):
            bad = int(indices[(indices < 0) | (indices >= n)][0])
            raise doc.error(f"{at}.indices", f"index {bad} is out of range (there are {n} vertices)")
    else:
        indices = np.arange(n, dtype=np.int64)
    faces = triangles(indices, mode)
    if len(faces) == 0:
        doc.warn(f"{at}: skipping a primitive with no triangles")
        return None
    # world space: points by the matrix, normals by its inverse transpose, tangents by its linear part
    linear = world[:3, :3]
    vertices = positions @ linear.T + world[:3, 3]
    if not np.isfinite(vertices).all():
        raise doc.error(f"{at}.attributes.POSITION", "the node transform takes vertices to infinity")
    mirrored = np.linalg.det(linear) < 0
    obj = {"type": "mesh", "vertices": vertices, "faces": faces[:, ::-1].copy() if mirrored else faces}
    normals = attribute("NORMAL", 3)
    if normals is not None:
        obj["normals"] = _unit_rows(normals @ _inverse_transpose(linear).T)
    else:
        obj["smooth"] = False  # glTF: a primitive without normals is drawn with flat normals
    uvs = attribute("TEXCOORD_0", 2)
    if uvs is not None:
        obj["uvs"] = np.column_stack([uvs[:, 0], 1.0 - uvs[:, 1]])  # glTF v runs down the image, lumos's up
    tangents = attribute("TANGENT", 4)
    if tangents is not None:
        # glTF's bitangent B = w·(N × T) points up the image (its normal maps' green is "up"), which is lumos's +v
        # after the v flip, so w passes through; a mirroring transform turns N × T over, and w with it
        w = np.where(tangents[:, 3] < 0, -1.0, 1.0) * (-1.0 if mirrored else 1.0)
        obj["tangents"] = np.column_stack([_unit_rows(tangents[:, :3] @ linear.T), w])
    return obj


def triangles(indices: np.ndarray, mode: int) -> np.ndarray:
    """int64 (m, 3) triangles of an index list in glTF mode 4 (list), 5 (strip) or 6 (fan), in the order
    (and winding) the glTF specification gives; degenerate strip and fan triangles are dropped."""
    if mode == _TRIANGLES:
        m = len(indices) // 3
        faces = indices[: 3 * m].reshape(m, 3)
    else:
        k = np.arange(max(len(indices) - 2, 0))
        if mode == _STRIP:  # triangle i: (i, i+1, i+2), every other one reversed to keep the winding
            odd = k % 2 == 1
            faces = np.column_stack([indices[k + odd], indices[k + 1 - odd], indices[k + 2]])
        else:  # fan: (0, i+1, i+2)
            faces = np.column_stack([np.full(len(k), indices[0] if len(indices) else 0), indices[k + 1], indices[k + 2]])
        faces = faces.reshape(-1, 3)
        keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
        faces = faces[keep]
    return np.ascontiguousarray(faces, dtype=np.int64)


# ------------------------------------------------------------------------------------------ cameras, lights


def _camera(doc: Document, index: int, world: np.ndarray, at_node: str) -> dict | None:
    """A glTF camera (looking down its local −z, +y up) placed by its node, as a lumos camera dict."""
    cam = doc.item("cameras", index, f"{at_node}.camera")
    at = f"cameras[{index}]"
    position = world[:3, 3]
    forward, up = world[:3, :3] @ [0.0, 0.0, -1.0], world[:3, :3] @ [0.0, 1.0, 0.0]
    if np.linalg.norm(forward) < 1e-12 or np.linalg.norm(np.cross(forward, up)) < 1e-9 * np.linalg.norm(forward) * np.linalg.norm(up):
        doc.warn(f"{at_node}: skipping camera {index}: its node transform is degenerate")
        return None
    forward = forward / np.linalg.norm(forward)
    out = {"position": position.tolist(), "look_at": (position + forward).tolist(), "up": (up / np.linalg.norm(up)).tolist()}
    kind = cam.get("type")
    if kind == "perspective":
        p = doc.obj(cam, "perspective", at)
        yfov = doc.number(p, "yfov", f"{at}.perspective", None, 1e-9, math.pi - 1e-9)
        return {"type": "perspective", "fov": math.degrees(yfov), **out}
    if kind == "orthographic":
        o = doc.obj(cam, "orthographic", at)
        ymag = doc.number(o, "ymag", f"{at}.orthographic", None)
        if ymag == 0:
            raise doc.error(f"{at}.orthographic.ymag", "must not be zero")
        return {"type": "orthographic", "size": 2.0 * abs(ymag), **out}
    raise doc.error(f"{at}.type", f"must be perspective or orthographic, got {show_value(kind)}")


def _light(doc: Document, lights: dict, index: int, world: np.ndarray) -> dict:
    """A KHR_lights_punctual light (shining down its local −z) placed by its node, as a lumos light dict.

    glTF point and spot intensities are in candela (irradiance I·cosθ/d²), directional ones in lux (I·cosθ);
    a lumos light of intensity I' delivers π·I'·cosθ/att(d), so I' = colour·I/π with att = [0, 0, 1]."""
    items = doc.list(lights, "lights", "extensions.KHR_lights_punctual")
    at = f"extensions.KHR_lights_punctual.lights[{index}]"
    if not 0 <= index < len(items) or not isinstance(items[index], dict):
        raise doc.error(at, f"does not exist (there are {len(items)} lights)")
    light = items[index]
    color = doc.numbers(light, "color", at, [1.0, 1.0, 1.0], 3)
    intensity = doc.number(light, "intensity", at, 1.0, lo=0.0)
    if (color < 0).any():
        raise doc.error(f"{at}.color", "must not be negative")
    rgb = (color * intensity / math.pi).tolist()
    direction = world[:3, :3] @ [0.0, 0.0, -1.0]
    kind = light.get("type")
    if kind in ("spot", "directional") and np.linalg.norm(direction) < 1e-12:
        raise doc.error(at, "its node transform is degenerate (no direction)")
    if "range" in light and kind != "directional":
        doc.warn(f"{at}: range is ignored (lumos lights fall off as 1/d² without a cut-off)")
    if kind == "directional":
        return {"type": "directional", "direction": direction.tolist(), "intensity": rgb}
    point = {"position": world[:3, 3].tolist(), "intensity": rgb, "attenuation": [0.0, 0.0, 1.0]}
    if kind == "point":
        return {"type": "point", **point}
    if kind == "spot":
        spot = doc.obj(light, "spot", at)
        outer = doc.number(spot, "outerConeAngle", f"{at}.spot", math.pi / 4, 1e-9, math.pi / 2)
        inner = doc.number(spot, "innerConeAngle", f"{at}.spot", 0.0, 0.0, outer)
        return {"type": "spot", **point, "direction": direction.tolist(),
                "angle": math.degrees(outer), "inner_angle": math.degrees(inner)}
    raise doc.error(f"{at}.type", f"must be point, spot or directional, got {show_value(kind)}")


# ------------------------------------------------------------------------------------------------- helpers


def _inverse_transpose(linear: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.inv(linear).T
    except np.linalg.LinAlgError:  # a flattened node: its normals are any unit vectors
        return np.eye(3)


def _unit_rows(a: np.ndarray) -> np.ndarray:
    """Rows of `a` scaled to unit length; zero (or non-finite) rows become +z."""
    n = np.linalg.norm(a, axis=1, keepdims=True)
    ok = np.isfinite(n) & (n > 1e-300)
    out = np.where(ok, a / np.where(ok, n, 1.0), [0.0, 0.0, 1.0])
    return out


