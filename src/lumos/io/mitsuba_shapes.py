"""Mitsuba 3 shapes → lumos objects (and, where the shape is one lumos has, area-light geometry).

    obj, area = GEOMETRY["rectangle"](node, to_world, ctx, textured, emits)

`obj` is the lumos object (without its material); `area` the keys of a lumos area light of the same shape
(`shape: rect`, `disk` or `sphere`) when lumos can draw it as one exactly, else None (an emitting shape then
becomes an emissive object). Mitsuba's canonical shapes: `rectangle` is [-1, 1]² in z = 0 with normal +z,
`disk` the unit disk there, `cube` [-1, 1]³, `sphere` (center, radius), `cylinder` (p0, p1, radius, no caps);
each mapped by its `to_world`. A shape's emitting side is Mitsuba's normal, to_world's inverse transpose of the
canonical one (negated by `flip_normals`).

Texture coordinates: Mitsuba looks images up with v = 0 at the top row, lumos with v = 0 at the bottom. OBJ files
agree (Mitsuba flips their v, `flip_tex_coords`); for a textured PLY (or an OBJ with `flip_tex_coords` false)
the mesh is read inline with v flipped, and a textured rectangle is written with its v edge running down.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from ..errors import LumosError
from .meshes import MeshData, load_mesh
from .mitsuba_bsdfs import Context
from .mitsuba_serialized import read_serialized
from .mitsuba_xml import Node


def matrix_transform(m: np.ndarray) -> Optional[dict]:
    """A lumos transform for a 4×4 matrix, or None for the identity."""
    if np.allclose(m, np.eye(4), rtol=0, atol=1e-12):
        return None
    return {"matrix": [[float(c) for c in row] for row in m]}


def similarity(m3: np.ndarray, mirror: bool = False) -> Optional[float]:
    """The scale s when m3 = s·R with R a rotation (or, with `mirror`, any orthogonal matrix), else None."""
    gram = m3.T @ m3
    s2 = float(np.trace(gram)) / 3.0
    if s2 <= 0 or not np.allclose(gram, s2 * np.eye(3), rtol=0, atol=1e-9 * s2):
        return None
    if not mirror and np.linalg.det(m3) < 0:
        return None
    return math.sqrt(s2)


def _vec(v) -> list:
    return [float(c) for c in v]


def _with_transform(obj: dict, m: np.ndarray) -> dict:
    transform = matrix_transform(m)
    return obj if transform is None else {**obj, "transform": transform}


def _warn_flip(node: Node, ctx: Context, emits: bool) -> None:
    if emits and node.bool("flip_normals", False):
        ctx.warn(("flip_normals", node.type), node.where, f"{node.type}: flip_normals on an emitting {node.type} is "
                 f"not read (lumos's emits outward)")


def rectangle(node: Node, m: np.ndarray, ctx: Context, textured: bool, emits: bool):
    """lumos's rect: corner = to_world·(−1, −1, 0), edges to_world·(2, 0, 0) and to_world·(0, 2, 0); the v edge
    reversed where cross(edge_u, edge_v) would point against Mitsuba's normal (a mirroring to_world, or
    flip_normals), and on a textured rectangle (for the image's orientation: the rect is not a light then)."""
    m3 = m[:3, :3]
    reverse = (np.linalg.det(m3) < 0) != node.bool("flip_normals", False)

    def form(down: bool) -> dict:
        corner = m @ (-1.0, 1.0 if down else -1.0, 0.0, 1.0)
        return {"corner": _vec(corner[:3]), "edge_u": _vec(m3 @ (2.0, 0.0, 0.0)),
                "edge_v": _vec(m3 @ (0.0, -2.0 if down else 2.0, 0.0))}

    light = form(reverse)
    return {"type": "rect", **(form(True) if textured else light)}, {"shape": "rect", **light}


def disk(node: Node, m: np.ndarray, ctx: Context, textured: bool, emits: bool):
    """lumos's disk when to_world keeps the disk round (its x and y images orthogonal and as long), else the
    unit disk with to_world as its transform (an ellipse: drawn as an object, not as an area light)."""
    m3 = m[:3, :3]
    flip = -1.0 if node.bool("flip_normals", False) else 1.0
    normal = np.linalg.inv(m3).T @ (0.0, 0.0, 1.0)
    normal = flip * normal / np.linalg.norm(normal)
    ax, ay = m3[:, 0], m3[:, 1]
    ra, rb = np.linalg.norm(ax), np.linalg.norm(ay)
    if abs(ra - rb) <= 1e-9 * ra and abs(ax @ ay) <= 1e-9 * ra * rb:
        keys = {"center": _vec(m[:3, 3]), "normal": _vec(normal), "radius": float(ra)}
        return {"type": "disk", **keys}, {"shape": "disk", **keys}
    obj = {"type": "disk", "center": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, flip], "radius": 1.0}
    return _with_transform(obj, m), None


def sphere(node: Node, m: np.ndarray, ctx: Context, textured: bool, emits: bool):
    """Mitsuba's sphere is to_world·T(center)·S(radius) of the unit sphere: a lumos sphere (and sphere light)
    when that is a similarity, else the sphere with to_world as its transform (an ellipsoid)."""
    center, radius = node.vector("center", (0.0, 0.0, 0.0)), node.float("radius", 1.0)
    full = m.copy()
    full[:3, 3] = m[:3, :3] @ center + m[:3, 3]
    full[:3, :3] = m[:3, :3] * radius
    _warn_flip(node, ctx, emits)
    scale = similarity(full[:3, :3], mirror=True)
    if scale is not None:
        keys = {"center": _vec(full[:3, 3]), "radius": scale}
        return {"type": "sphere", **keys}, (None if node.bool("flip_normals", False) else {"shape": "sphere", **keys})
    return _with_transform({"type": "sphere", "center": _vec(center), "radius": radius}, m), None


def cube(node: Node, m: np.ndarray, ctx: Context, textured: bool, emits: bool):
    """lumos's box [-1, 1]³ with to_world (baked into min and max for a positive axis-aligned scale)."""
    _warn_flip(node, ctx, emits)
    m3 = m[:3, :3]
    if np.allclose(m3, np.diag(np.diag(m3)), rtol=0, atol=0) and np.all(np.diag(m3) > 0):
        half = np.diag(m3)
        return {"type": "box", "min": _vec(m[:3, 3] - half), "max": _vec(m[:3, 3] + half)}, None
    return _with_transform({"type": "box", "min": [-1.0] * 3, "max": [1.0] * 3}, m), None


def cylinder(node: Node, m: np.ndarray, ctx: Context, textured: bool, emits: bool):
    """lumos's cylinder from p0 to p1 without caps (Mitsuba's has none)."""
    _warn_flip(node, ctx, emits)
    p0, p1 = node.vector("p0", (0.0, 0.0, 0.0)), node.vector("p1", (0.0, 0.0, 1.0))
    radius = node.float("radius", 1.0)
    scale = similarity(m[:3, :3], mirror=True)
    if scale is not None:
        return {"type": "cylinder", "base": _vec(m[:3, :3] @ p0 + m[:3, 3]), "top": _vec(m[:3, :3] @ p1 + m[:3, 3]),
                "radius": radius * scale, "capped": False}, None
    obj = {"type": "cylinder", "base": _vec(p0), "top": _vec(p1), "radius": radius, "capped": False}
    return _with_transform(obj, m), None


def mesh_file(node: Node, m: np.ndarray, ctx: Context, textured: bool, emits: bool):
    """An OBJ or PLY file: lumos's `type: mesh` with `file` (relative to the scene's folder), or the mesh read
    inline where lumos must change it: its faces turned over (flip_normals on an emitter: the emitting side is
    the counter-clockwise one) or its v flipped (see the module's docstring)."""
    rel, path = ctx.file(node)
    flip_faces = emits and node.bool("flip_normals", False)
    flip_v = textured and not node.bool("flip_tex_coords", node.type == "obj")
    if flip_faces or flip_v:
        try:
            mesh = load_mesh(path)
        except LumosError as exc:
            raise node.where_of("filename").error(str(exc)) from None
        obj = _inline(mesh, flip_faces, flip_v)
    else:
        obj = {"type": "mesh", "file": rel}
    if node.bool("face_normals", False):
        obj["smooth"] = False
    return _with_transform(obj, m), None


def serialized(node: Node, m: np.ndarray, ctx: Context, textured: bool, emits: bool):
    """A mesh of a Mitsuba `.serialized` file (`shape_index`), read inline."""
    _, path = ctx.file(node)
    try:
        mesh = read_serialized(path, node.int("shape_index", 0))
    except (ValueError, OSError) as exc:
        raise node.where_of("filename").error(f"serialized '{path.name}': {exc}") from None
    obj = _inline(mesh, emits and node.bool("flip_normals", False), False)
    if node.bool("face_normals", False):
        obj.pop("normals", None)
        obj["smooth"] = False
    return _with_transform(obj, m), None


def _inline(mesh: MeshData, flip_faces: bool, flip_v: bool) -> dict:
    faces = mesh.faces[:, ::-1].copy() if flip_faces else mesh.faces
    obj = {"type": "mesh", "vertices": mesh.vertices, "faces": faces}
    if mesh.normals is not None:
        obj["normals"] = -mesh.normals if flip_faces else mesh.normals
    if mesh.uvs is not None:
        uvs = mesh.uvs.copy()
        if flip_v:
            uvs[:, 1] = 1.0 - uvs[:, 1]
        obj["uvs"] = uvs
    return obj


#: Mitsuba shape plugin → (lumos object, area-light keys or None)
GEOMETRY = {"rectangle": rectangle, "disk": disk, "sphere": sphere, "cube": cube, "cylinder": cylinder,
            "obj": mesh_file, "ply": mesh_file, "serialized": serialized}
