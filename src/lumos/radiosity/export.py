"""Exporting a radiosity solution's display mesh with its baked radiance, for Blender, MeshLab or a game engine.

    export_solution(solution, "baked.ply")                 # what Solution.export calls
    export_solution(solution, "baked.glb", exposure=0.5)

The display mesh (`vertices`, `faces`, `vertex_normal`, `vertex_radiance`; see `solution.py`) is written as is:
one-sided triangles wound counter-clockwise about their element's normal, the two sides of an open surface
as two coincident faces of opposite winding (so draw it with back faces culled). World units and y up, as in
the scene. Two kinds of colour go with each vertex:

- the **linear radiance** L, unclamped, as float32 (`radiance_r/g/b` in PLY, `_RADIANCE` in glTF): the data;
- a **display colour** after `exposure`: PLY `red green blue` uchar = `round(255 · srgb_encode(clamp(exposure · L,
  0, 1)))` (`lumos.tonemap.to_png8`, the PNG tone map; PLY readers take vertex colours as sRGB bytes); glTF
  `COLOR_0` float = `clamp(exposure · L, 0, 1)`, since glTF vertex colours are linear and viewers encode them.

PLY: binary little-endian, a `comment` naming what it is; `element vertex` with float `x y z nx ny nz radiance_r
radiance_g radiance_b` and uchar `red green blue`; `element face` with `list uchar int vertex_indices`.

GLB (glTF 2.0 binary; the container is `io.gltf_document.glb_container`, beside the reader that `io.gltf` uses):
one scene, node, mesh and indexed-triangle primitive with attributes `POSITION` (with min / max), `NORMAL`,
`COLOR_0` (float VEC3) and `_RADIANCE` (float VEC3, an application-specific attribute), uint32 indices, and an
unlit material (`KHR_materials_unlit`, white base colour) so that viewers
show the baked colours without lighting them again; `asset.generator` is "lumos", and `asset.extras` records
the exposure and what each attribute holds.

Writes are atomic (`io.atomic.write_atomically`); every problem is a `LumosError` with a one-line message.
"""

from __future__ import annotations

import json
import math
import numbers
import os

import numpy as np

from .. import tonemap
from ..errors import LumosError
from .solution import Solution
from ..io.atomic import check_output_path, write_atomically
from ..io.gltf_document import glb_container
from .store import DISPLAY_FIELDS, check_arrays

#: Extensions `export_solution` writes.
FORMATS = (".ply", ".glb")
PLY_COMMENT = "lumos radiosity solution: display mesh; units: linear radiance (radiance_r/g/b, unclamped)"

_FLOAT, _UINT32 = 5126, 5125  # glTF accessor componentType
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963  # bufferView target
_TRIANGLES = 4


def export_solution(solution: Solution, path: str | os.PathLike, exposure: float = 1.0) -> None:
    """Write the display mesh of `solution` with its radiance to `path` (`.ply` or `.glb`), atomically.

    exposure: a finite number > 0 that multiplies the radiance before the display colours are made (the linear
        radiance is stored unscaled).
    Raises LumosError for another extension, a bad path, a bad exposure, an empty or inconsistent display mesh.
    """
    action = "cannot export radiosity solution"
    out = check_output_path(path, FORMATS, action)
    fail = f"{action} '{path}'"
    if isinstance(exposure, bool) or not isinstance(exposure, numbers.Real) or not (
            math.isfinite(exposure) and exposure > 0):
        raise LumosError(f"{fail}: exposure must be a finite number > 0, got {exposure!r}")
    mesh = {name: np.asarray(getattr(solution, name)) for name in DISPLAY_FIELDS}
    check_arrays(mesh, fail)
    if len(mesh["faces"]) == 0:
        raise LumosError(f"{fail}: the display mesh has no faces")
    encode = _ply_bytes if out.suffix.lower() == ".ply" else _glb_bytes
    data = encode(mesh["vertices"], mesh["vertex_normal"], mesh["vertex_radiance"], mesh["faces"], float(exposure))

    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            f.write(data)

    write_atomically(out, write, fail, suffix=".tmp")


# ---------------------------------------------------------------------------------------------------- PLY


def _ply_bytes(vertices, normals, radiance, faces, exposure: float) -> bytes:
    """vertices, normals, radiance: float64 (nv, 3); faces: int32 (nf, 3) → a binary little-endian PLY file."""
    names = ["x", "y", "z", "nx", "ny", "nz", "radiance_r", "radiance_g", "radiance_b"]
    vertex = np.empty(len(vertices), dtype=[(n, "<f4") for n in names] + [(n, "u1") for n in ("red", "green", "blue")])
    for columns, source in ((names[0:3], vertices), (names[3:6], normals), (names[6:9], radiance)):
        for i, name in enumerate(columns):
            vertex[name] = source[:, i]
    rgb8 = tonemap.to_png8(radiance, exposure)
    for i, name in enumerate(("red", "green", "blue")):
        vertex[name] = rgb8[:, i]
    face = np.empty(len(faces), dtype=[("count", "u1"), ("vertex_indices", "<i4", (3,))])
    face["count"] = 3
    face["vertex_indices"] = faces
    header = [
        "ply",
        "format binary_little_endian 1.0",
        f"comment {PLY_COMMENT}",
        f"comment red/green/blue: sRGB 8-bit of clamp(exposure * radiance), exposure {exposure!r}",
        f"element vertex {len(vertex)}",
        *(f"property float {n}" for n in names),
        *(f"property uchar {n}" for n in ("red", "green", "blue")),
        f"element face {len(face)}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    return ("\n".join(header) + "\n").encode("ascii") + vertex.tobytes() + face.tobytes()


# ---------------------------------------------------------------------------------------------------- glTF


def _glb_bytes(vertices, normals, radiance, faces, exposure: float) -> bytes:
    """vertices, normals, radiance: float64 (nv, 3); faces: int32 (nf, 3) → a glTF 2.0 binary (GLB) file."""
    positions = np.ascontiguousarray(vertices, dtype="<f4")
    columns = [  # (attribute, data, target): every block is float32 or uint32, so offsets stay 4-aligned
        ("POSITION", positions, _ARRAY_BUFFER),
        ("NORMAL", np.ascontiguousarray(normals, dtype="<f4"), _ARRAY_BUFFER),
        ("COLOR_0", np.clip(exposure * radiance, 0.0, 1.0).astype("<f4"), _ARRAY_BUFFER),
        ("_RADIANCE", np.ascontiguousarray(radiance, dtype="<f4"), _ARRAY_BUFFER),
        (None, np.ascontiguousarray(faces, dtype="<u4").reshape(-1), _ELEMENT_ARRAY_BUFFER),
    ]
    views, accessors, blobs, offset = [], [], [], 0
    for i, (_, data, target) in enumerate(columns):
        raw = data.tobytes()
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(raw), "target": target})
        accessor = {"bufferView": i, "componentType": _FLOAT if data.dtype.kind == "f" else _UINT32,
                    "count": len(data), "type": "VEC3" if data.ndim == 2 else "SCALAR"}
        accessors.append(accessor)
        blobs.append(raw)
        offset += len(raw)
    accessors[0]["min"] = [float(v) for v in positions.min(axis=0)]  # float32 values, exactly as stored
    accessors[0]["max"] = [float(v) for v in positions.max(axis=0)]
    attributes = {name: i for i, (name, _, _) in enumerate(columns) if name is not None}
    gltf = {
        "asset": {"version": "2.0", "generator": "lumos",
                  "extras": {"content": "lumos radiosity solution (display mesh)", "exposure": exposure,
                             "COLOR_0": "clamp(exposure * radiance, 0, 1), linear",
                             "_RADIANCE": "linear radiance, unclamped"}},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "radiosity"}],
        "meshes": [{"name": "radiosity", "primitives": [
            {"attributes": attributes, "indices": len(columns) - 1, "material": 0, "mode": _TRIANGLES}]}],
        "materials": [{"name": "baked radiance (unlit)",
                       "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
                                                "roughnessFactor": 1.0},
                       "extensions": {"KHR_materials_unlit": {}}}],
        "buffers": [{"byteLength": offset}],
        "bufferViews": views,
        "accessors": accessors,
    }
    return glb_container(json.dumps(gltf, separators=(",", ":")).encode("utf-8"), b"".join(blobs))

