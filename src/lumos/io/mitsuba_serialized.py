"""Mitsuba's `.serialized` meshes (versions 3, 4 and 5), as Mitsuba 3's `serialized` shape reads them.

    mesh = read_serialized(Path("scene.serialized"), shape_index=2)   # a meshes.MeshData

The file (little-endian, documented in Mitsuba 3's src/shapes/serialized.cpp) is a sequence of meshes, each a
header (uint16 0x041C, uint16 version) and a zlib stream, and ends with a dictionary: the byte offset of every
mesh (uint64 each in versions 4 and 5, uint32 in version 3) and their count (uint32).

- Versions 3 and 4: uint32 flags (0x1 normals, 0x2 texture coordinates, 0x8 vertex colours, 0x2000 doubles),
  the name (version 4: a null-terminated string), uint64 vertex and triangle counts, then per-vertex arrays of
  positions, normals, uvs and colours, and 3 uint32 indices per triangle.
- Version 5: uint32 flags (low 3 bits the vertex layout: 0x1 normals, 0x2 tangents, 0x4 uvs), the name (uint32
  length + bytes), uint64 counts of vertices, triangles, surface points and normal groups, 8 float32 per vertex
  (position, normal or encoded frame, uv), 4 uint32 per triangle (3 indices and a BSDF index), then maps and
  attributes that lumos does not need.

Texture coordinates are stored as Mitsuba uses them (v = 0 at the image's top row); lumos's v runs up the image,
so they come back as (u, 1 − v). Raises ValueError with what is wrong.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from .meshes import MeshData

MAGIC = 0x041C
_HAS_NORMALS, _HAS_UVS, _HAS_COLORS, _DOUBLE = 0x0001, 0x0002, 0x0008, 0x2000


def read_serialized(path: Path, shape_index: int = 0) -> MeshData:
    data = path.read_bytes()
    if len(data) < 8:
        raise ValueError("too short to be a serialized mesh")
    magic, version = struct.unpack_from("<HH", data, 0)
    if magic != MAGIC or version not in (3, 4, 5):
        raise ValueError(f"not a Mitsuba serialized mesh (magic 0x{magic:04x}, version {version})")
    offset = _offset(data, version, shape_index)
    try:
        stream = zlib.decompressobj().decompress(data[offset + 4:])
    except zlib.error as exc:
        raise ValueError(f"mesh {shape_index}: corrupt zlib stream ({exc})") from None
    reader = _Reader(stream)
    mesh = _read_v5(reader) if version == 5 else _read_legacy(reader, version)
    if len(mesh.faces) and (mesh.faces.max() >= len(mesh.vertices)):
        raise ValueError(f"mesh {shape_index}: a face refers to a vertex that does not exist")
    if not np.all(np.isfinite(mesh.vertices)):
        raise ValueError(f"mesh {shape_index}: vertex positions that are not finite")
    return mesh


def _offset(data: bytes, version: int, shape_index: int) -> int:
    """The byte offset of mesh `shape_index`, from the dictionary at the end of the file."""
    if shape_index == 0:
        return 0
    (count,) = struct.unpack_from("<I", data, len(data) - 4)
    if not 0 <= shape_index < count:
        raise ValueError(f"shape_index {shape_index} is out of range (the file holds {count} meshes)")
    if version >= 4:
        (offset,) = struct.unpack_from("<Q", data, len(data) - 4 - 8 * (count - shape_index))
    else:
        (offset,) = struct.unpack_from("<I", data, len(data) - 4 * (count - shape_index + 1))
    if offset + 4 > len(data):
        raise ValueError(f"shape_index {shape_index}: its offset lies outside the file")
    return offset


class _Reader:
    """Reads little-endian values and arrays off the decompressed stream, refusing to run past its end."""

    def __init__(self, data: bytes):
        self.data, self.at = data, 0

    def take(self, n: int) -> bytes:
        if self.at + n > len(self.data):
            raise ValueError("the mesh data ends early (truncated file?)")
        chunk = self.data[self.at:self.at + n]
        self.at += n
        return chunk

    def scalar(self, fmt: str):
        return struct.unpack("<" + fmt, self.take(struct.calcsize(fmt)))[0]

    def array(self, dtype, count: int, columns: int) -> np.ndarray:
        dtype = np.dtype(dtype).newbyteorder("<")
        return np.frombuffer(self.take(dtype.itemsize * count * columns), dtype).reshape(count, columns)


def _read_legacy(reader: _Reader, version: int) -> MeshData:
    flags = reader.scalar("I")
    if version == 4:
        while reader.take(1) != b"\0":  # the name
            pass
    vertices, triangles = reader.scalar("Q"), reader.scalar("Q")
    real = np.float64 if flags & _DOUBLE else np.float32
    positions = reader.array(real, vertices, 3).astype(np.float64)
    normals = reader.array(real, vertices, 3).astype(np.float64) if flags & _HAS_NORMALS else None
    uvs = reader.array(real, vertices, 2).astype(np.float64) if flags & _HAS_UVS else None
    if flags & _HAS_COLORS:
        reader.array(real, vertices, 3)
    faces = reader.array(np.uint32, triangles, 3).astype(np.int64)
    return MeshData(positions, faces, normals, _flip_v(uvs))


def _read_v5(reader: _Reader) -> MeshData:
    flags = reader.scalar("I")
    reader.take(reader.scalar("I"))  # the name
    vertices, triangles = reader.scalar("Q"), reader.scalar("Q")
    reader.scalar("Q"), reader.scalar("Q")  # surface points, normal groups: maps lumos does not need
    records = reader.array(np.float32, vertices, 8).astype(np.float64)
    faces = reader.array(np.uint32, triangles, 4)[:, :3].astype(np.int64)
    layout = flags & 0x7
    normals = records[:, 3:6] if layout & 0x1 and not layout & 0x2 else None
    uvs = records[:, 6:8] if layout & 0x4 else None
    return MeshData(records[:, :3].copy(), faces, normals, _flip_v(uvs))


def _flip_v(uvs):
    if uvs is None:
        return None
    out = uvs.copy()
    out[:, 1] = 1.0 - out[:, 1]
    return out
