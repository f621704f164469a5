"""Triangle meshes from files: OBJ, PLY (ASCII and binary), STL (ASCII and binary), OFF, glTF / GLB.

    mesh = load_mesh("bunny.ply")
    mesh.vertices   # float64 (n, 3)
    mesh.faces      # int64 (m, 3), indices into vertices; quads and polygons come back as triangles
    mesh.normals    # float64 (n, 3) unit vertex normals if the file has them (OBJ vn, PLY nx/ny/nz,
                    # glTF NORMAL), else None: the compile step decides how to shade a mesh without them
    mesh.uvs        # float64 (n, 2) texture coordinates if the file has them (OBJ vt, PLY s/t or u/v,
                    # glTF TEXCOORD_0), else None

Parsing is trimesh's (`process=False`: no vertex merging, no reordering, so file indices stay valid; OBJ
vertices are split only where one position carries several vt/vn, and vertices that no face uses are
dropped, keeping the order of the rest). A file with several meshes (glTF
nodes, OBJ groups with different materials) is flattened into one with each node's transform applied.
Materials are ignored for now. Every failure is a LumosError `cannot read mesh '<path>': <reason>`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import LumosError

#: Extensions `load_mesh` reads (case-insensitive).
MESH_FORMATS = (".obj", ".ply", ".stl", ".off", ".gltf", ".glb")


class MeshData(NamedTuple):
    """A triangle mesh as arrays.

    vertices: float64 (n, 3) positions.
    faces:    int64 (m, 3) vertex indices of each triangle, counter-clockwise as in the file.
    normals:  float64 (n, 3) unit vertex normals from the file, or None.
    uvs:      float64 (n, 2) texture coordinates from the file, or None.
    """

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None
    uvs: np.ndarray | None


def load_mesh(path: str | os.PathLike) -> MeshData:
    """Read the mesh file `path` (format from the extension) into a `MeshData`.

    Raises LumosError for a missing file, an unsupported extension, an empty or corrupt file, a file with
    no triangles and non-finite vertex positions.
    """
    src = Path(path)
    fail = f"cannot read mesh '{path}'"
    ext = src.suffix.lower()
    if ext not in MESH_FORMATS:
        raise LumosError(f"{fail}: unsupported extension '{src.suffix}' (supported: {', '.join(MESH_FORMATS)})")
    if not src.is_file():
        raise LumosError(f"{fail}: {'it is a directory' if src.is_dir() else 'file not found'}")
    if src.stat().st_size == 0:
        raise LumosError(f"{fail}: the file is empty")

    import trimesh  # ~0.5 s to import; only when a mesh is actually read

    try:
        # (trimesh's OBJ `maintain_order` is not used: it drops vn/vt where a position carries several.)
        kwargs = {"skip_materials": True} if ext == ".obj" else {}
        loaded = trimesh.load(str(src), process=False, **kwargs)
        parts = _parts(loaded, trimesh)
    except LumosError as exc:
        raise LumosError(f"{fail}: {exc}") from None
    except Exception as exc:  # trimesh raises many types on damaged files
        reason = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise LumosError(f"{fail}: not a valid {ext[1:].upper()} file ({reason})") from None
    try:
        return _checked(_merge(parts))
    except LumosError as exc:
        raise LumosError(f"{fail}: {exc}") from None


def _parts(loaded, trimesh) -> list[MeshData]:
    """The triangle meshes of a trimesh.Trimesh or trimesh.Scene, each in world space."""
    if isinstance(loaded, trimesh.Trimesh):
        return [_from_trimesh(loaded)]
    if not isinstance(loaded, trimesh.Scene):
        raise LumosError(f"no triangles (the file holds a {type(loaded).__name__})")
    parts = []
    for node in loaded.graph.nodes_geometry:
        world_from_object, name = loaded.graph[node]
        geometry = loaded.geometry.get(name)
        if isinstance(geometry, trimesh.Trimesh) and len(geometry.faces):
            parts.append(_transformed(_from_trimesh(geometry), np.asarray(world_from_object, dtype=np.float64)))
    return parts


def _from_trimesh(mesh) -> MeshData:
    """Arrays of one trimesh.Trimesh, with normals and uvs only where the file supplied them.

    trimesh computes `vertex_normals` on demand, so reading that property cannot tell file normals from
    computed ones. The loaders hand file normals to the constructor, which stores them in the mesh's cache
    under 'vertex_normals'; computed ones appear there only after the property is first read, which nothing
    has done yet on a freshly loaded mesh. So the cache entry, checked before anything else, says whether the
    file had normals (tests/io/test_meshes.py checks this for every format, with and without normals).
    """
    normals = mesh._cache.cache.get("vertex_normals")
    uvs = getattr(mesh.visual, "uv", None) if getattr(mesh.visual, "kind", None) == "texture" else None
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if normals is not None:
        normals = np.asarray(normals, dtype=np.float64)
        normals = normals if normals.shape == vertices.shape else None
    if uvs is not None:
        uvs = np.asarray(uvs, dtype=np.float64)[:, :2]
        uvs = uvs if len(uvs) == len(vertices) else None
    return MeshData(vertices, np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3), normals, uvs)


def _transformed(part: MeshData, world_from_object: np.ndarray) -> MeshData:
    """Apply a 4×4 transform: points by the matrix, normals by its inverse transpose (then renormalised).

    A mirroring transform (negative determinant) also reverses each face's winding, so the geometric normal
    keeps facing the same way as the shading normals.
    """
    if np.allclose(world_from_object, np.eye(4)):
        return part
    linear, shift = world_from_object[:3, :3], world_from_object[:3, 3]
    vertices = part.vertices @ linear.T + shift
    faces = part.faces[:, [0, 2, 1]] if np.linalg.det(linear) < 0 else part.faces
    normals = part.normals
    if normals is not None:
        normals = normals @ np.linalg.inv(linear)  # (M⁻ᵀ n) for row vectors is n @ M⁻¹
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = normals / np.where(length > 0, length, 1.0)
    return MeshData(vertices, faces, normals, part.uvs)


def _merge(parts: list[MeshData]) -> MeshData:
    """Concatenate meshes, offsetting face indices; normals / uvs survive only if every part has them."""
    if not parts:
        raise LumosError("no triangles in the file")
    if len(parts) == 1:
        return parts[0]
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    faces = np.concatenate([p.faces + off for p, off in zip(parts, offsets)])
    vertices = np.concatenate([p.vertices for p in parts])
    normals = None if any(p.normals is None for p in parts) else np.concatenate([p.normals for p in parts])
    uvs = None if any(p.uvs is None for p in parts) else np.concatenate([p.uvs for p in parts])
    return MeshData(vertices, faces, normals, uvs)


def _checked(mesh: MeshData) -> MeshData:
    """Contiguous arrays of the documented dtypes; errors for no triangles, bad indices, non-finite values."""
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    if len(faces) == 0:
        raise LumosError("no triangles in the file")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise LumosError(f"face indices outside 0..{len(vertices) - 1}")
    if not np.isfinite(vertices).all():
        raise LumosError("vertex positions contain NaN or Inf")
    normals, uvs = mesh.normals, mesh.uvs
    if normals is not None:
        normals = np.ascontiguousarray(normals, dtype=np.float64)
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = normals / np.where(length > 0, length, 1.0)  # unit length; zero normals stay zero
        normals = normals if np.isfinite(normals).all() else None  # unusable normals: shade as if absent
    if uvs is not None:
        uvs = np.ascontiguousarray(uvs, dtype=np.float64)
        uvs = uvs if np.isfinite(uvs).all() else None
    return MeshData(vertices, faces, normals, uvs)
