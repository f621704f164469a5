"""Models from the files users have (OBJ+MTL, glTF 2.0 / GLB, PLY, STL, OFF) as pieces of a lumos scene.

    model = import_model("knob.obj")       # an ImportedModel
    model.materials   # {"name": {...scene-format material...}}
    model.objects     # [{"type": "mesh", "name": ..., "material": "name", "vertices": (n,3), "faces": (m,3), ...}]
    model.cameras     # [{...scene-format camera...}]  (the file's own, in world space; glTF only)
    model.lights      # [{...scene-format light...}]   (the file's own; glTF KHR_lights_punctual)
    model.warnings    # ["knob.mtl:12: Ns 0: shininess set to 1", ...]  one line each

Every importer returns this one shape: plain scene-format dicts (the keys of docs/scene-format.md, with NumPy
arrays for mesh data and absolute paths for texture files), so the scene model validates an imported model
exactly as it validates a scene file, and a scene can include a model with its own transform and material
overrides. A file that cannot be read is a LumosError `<file>:<line>: <what is wrong>` (no line where the
format has none).
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import LumosError
from .imported import ImportedModel

__all__ = ["MODEL_FORMATS", "ImportedModel", "import_model"]

#: Extensions `import_model` reads (case-insensitive).
MODEL_FORMATS = (".obj", ".gltf", ".glb", ".ply", ".stl", ".off")


def import_model(path: str | os.PathLike) -> ImportedModel:
    """Read `path` (format from the extension) into an `ImportedModel`; LumosError on bad input."""
    src = Path(path)
    ext = src.suffix.lower()
    if ext not in MODEL_FORMATS:
        raise LumosError(f"{path}: unsupported model format '{src.suffix}' (supported: {', '.join(MODEL_FORMATS)})")
    if not src.is_file():
        raise LumosError(f"{path}: {'it is a directory' if src.is_dir() else 'file not found'}")
    if ext == ".obj":
        from .obj import import_obj

        return import_obj(src)
    if ext in (".gltf", ".glb"):
        from .gltf import import_gltf

        return import_gltf(src)
    return _import_plain_mesh(src)


def _import_plain_mesh(src: Path) -> ImportedModel:
    """PLY, STL, OFF: one mesh, no materials."""
    from .meshes import load_mesh

    data = load_mesh(src)
    obj = {"type": "mesh", "name": src.stem, "vertices": data.vertices, "faces": data.faces}
    if data.normals is not None:
        obj["normals"] = data.normals
    if data.uvs is not None:
        obj["uvs"] = data.uvs
    return ImportedModel(source=src.resolve(), objects=[obj])
