"""Radiosity exports (`radiosity.export`): the PLY / GLB exports of the display mesh (read back by independent
parsers here and by trimesh), and their errors. The solution exported is the `solution` fixture (conftest.py)."""

from __future__ import annotations

import json
import os
import struct

import numpy as np
import pytest
from helpers import RADIANCE, one_line_error

from lumos import tonemap
from lumos.errors import LumosError
from lumos.io.gltf_document import glb_container
from lumos.radiosity import export as export_module

#: sRGB bytes of rows 0–1, round(255·srgb(clamp(e·L))): 0 → 0, 0.125 → 99, 0.25 → 137, 0.5 → 188, ≥1 → 255.
RGB8 = {1.0: [[0, 188, 255], [255, 137, 0]], 0.5: [[0, 137, 188], [255, 99, 0]]}


# ------------------------------------------------------------------------------------------ PLY export


def read_ply(path) -> tuple[list[str], np.ndarray, np.ndarray]:
    """A small independent reader of binary little-endian PLY: (header lines, vertex records, faces (nf, 3))."""
    raw = path.read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    header = raw[:end].decode("ascii").splitlines()
    assert header[0] == "ply" and header[1] == "format binary_little_endian 1.0"
    types = {"float": "<f4", "uchar": "u1", "int": "<i4"}
    elements, current = {}, None
    for line in header:
        words = line.split()
        if words[0] == "element":
            current = elements.setdefault(words[1], {"count": int(words[2]), "props": []})
        elif words[0] == "property" and words[1] != "list":
            current["props"].append((words[2], types[words[1]]))
    vertex = np.frombuffer(raw, np.dtype(elements["vertex"]["props"]), elements["vertex"]["count"], end)
    at = end + vertex.nbytes
    faces = []
    for _ in range(elements["face"]["count"]):
        count = raw[at]
        faces.append(struct.unpack_from(f"<{count}i", raw, at + 1))
        at += 1 + 4 * count
    assert at == len(raw)
    return header, vertex, np.array(faces)


@pytest.mark.parametrize("exposure", [1.0, 0.5])
def test_ply_export_round_trip(tmp_path, solution, exposure):
    path = tmp_path / "baked.ply"
    solution.export(path, exposure=exposure)
    header, vertex, faces = read_ply(path)
    assert header[2].startswith("comment lumos radiosity solution") and "linear radiance" in header[2]
    assert [line for line in header if line.startswith(("element", "property"))] == [
        "element vertex 8", *(f"property float {n}" for n in
                              ("x", "y", "z", "nx", "ny", "nz", "radiance_r", "radiance_g", "radiance_b")),
        "property uchar red", "property uchar green", "property uchar blue",
        "element face 4", "property list uchar int vertex_indices"]
    xyz = np.stack([vertex[n] for n in ("x", "y", "z")], axis=1)
    radiance = np.stack([vertex[f"radiance_{c}"] for c in "rgb"], axis=1)
    rgb8 = np.stack([vertex[n] for n in ("red", "green", "blue")], axis=1)
    assert np.array_equal(xyz, solution.vertices.astype(np.float32))
    normals = np.stack([vertex[n] for n in ("nx", "ny", "nz")], axis=1)
    assert np.array_equal(normals, solution.vertex_normal.astype(np.float32))
    assert radiance.tobytes() == RADIANCE.astype(np.float32).tobytes()  # linear, unclamped, exact as float32
    assert np.array_equal(faces, solution.faces)
    assert rgb8[:2].tolist() == RGB8[exposure]
    expected = np.rint(255 * tonemap.srgb_encode(np.clip(exposure * RADIANCE, 0, 1))).astype(np.uint8)
    assert np.array_equal(rgb8, expected)
    assert os.listdir(tmp_path) == ["baked.ply"]


def test_ply_opens_in_trimesh_with_colours(tmp_path, solution):
    import trimesh

    solution.export(tmp_path / "baked.ply")
    mesh = trimesh.load(tmp_path / "baked.ply")
    assert isinstance(mesh, trimesh.Trimesh) and len(mesh.vertices) == 8 and len(mesh.faces) == 4
    assert mesh.visual.kind == "vertex"
    assert mesh.visual.vertex_colors[:2, :3].tolist() == RGB8[1.0]
    raw = trimesh.load(tmp_path / "baked.ply", process=False)
    assert np.array_equal(raw.faces, solution.faces)
    assert np.array_equal(raw.metadata["_ply_raw"]["vertex"]["data"]["radiance_g"], RADIANCE[:, 1].astype(np.float32))


# ------------------------------------------------------------------------------------------ GLB export


def read_glb(path) -> tuple[dict, bytes]:
    """The GLB container by hand (glTF 2.0 §4.4): check the header, chunks and padding; return (JSON, BIN)."""
    raw = path.read_bytes()
    magic, version, length = struct.unpack_from("<III", raw, 0)
    assert (magic, version, length) == (0x46546C67, 2, len(raw))
    json_length, json_type = struct.unpack_from("<II", raw, 12)
    assert json_type == 0x4E4F534A and json_length % 4 == 0
    text = raw[20:20 + json_length]
    bin_at = 20 + json_length
    bin_length, bin_type = struct.unpack_from("<II", raw, bin_at)
    assert bin_type == 0x004E4942 and bin_length % 4 == 0 and bin_at + 8 + bin_length == len(raw)
    gltf = json.loads(text.decode("utf-8"))
    assert text == text.rstrip(b" ") + b" " * (len(text) - len(text.rstrip(b" ")))  # padded with spaces only
    return gltf, raw[bin_at + 8:]


def read_accessor(gltf: dict, binary: bytes, index: int) -> np.ndarray:
    accessor = gltf["accessors"][index]
    view = gltf["bufferViews"][accessor["bufferView"]]
    dtype = {5126: "<f4", 5125: "<u4"}[accessor["componentType"]]
    width = {"VEC3": 3, "SCALAR": 1}[accessor["type"]]
    start = view["byteOffset"] + accessor.get("byteOffset", 0)
    assert start % 4 == 0 and view["byteLength"] == accessor["count"] * width * 4
    assert view["byteOffset"] + view["byteLength"] <= gltf["buffers"][0]["byteLength"] <= len(binary)
    data = np.frombuffer(binary, dtype, accessor["count"] * width, start)
    return data.reshape(-1, 3) if width == 3 else data


@pytest.mark.parametrize("exposure", [1.0, 0.5])
def test_glb_export_structure_and_round_trip(tmp_path, solution, exposure):
    path = tmp_path / "baked.glb"
    solution.export(path, exposure=exposure)
    gltf, binary = read_glb(path)
    assert gltf["asset"]["version"] == "2.0" and gltf["asset"]["generator"] == "lumos"
    assert gltf["extensionsUsed"] == ["KHR_materials_unlit"]
    assert gltf["scenes"][gltf["scene"]]["nodes"] == [0] and gltf["nodes"][0]["mesh"] == 0
    (primitive,) = gltf["meshes"][0]["primitives"]
    assert primitive["mode"] == 4 and set(primitive["attributes"]) == {"POSITION", "NORMAL", "COLOR_0", "_RADIANCE"}
    material = gltf["materials"][primitive["material"]]
    assert "KHR_materials_unlit" in material["extensions"]
    assert material["pbrMetallicRoughness"]["baseColorFactor"] == [1.0, 1.0, 1.0, 1.0]
    attr = {name: read_accessor(gltf, binary, i) for name, i in primitive["attributes"].items()}
    for name in attr:
        accessor = gltf["accessors"][primitive["attributes"][name]]
        assert (accessor["componentType"], accessor["type"], accessor["count"]) == (5126, "VEC3", 8)
    position = gltf["accessors"][primitive["attributes"]["POSITION"]]
    assert position["min"] == [0.0, 0.0, 0.0] and position["max"] == [2.0, 1.0, 1.0]
    assert np.array_equal(attr["POSITION"], solution.vertices.astype(np.float32))
    assert np.array_equal(attr["NORMAL"], solution.vertex_normal.astype(np.float32))
    assert attr["_RADIANCE"].tobytes() == RADIANCE.astype(np.float32).tobytes()
    assert np.array_equal(attr["COLOR_0"], np.clip(exposure * RADIANCE, 0, 1).astype(np.float32))
    assert attr["COLOR_0"][:2].tolist() == [[0.0, 0.5 * exposure, exposure], [1.0, 0.25 * exposure, 0.0]]
    indices = gltf["accessors"][primitive["indices"]]
    assert (indices["componentType"], indices["type"], indices["count"]) == (5125, "SCALAR", 12)
    assert np.array_equal(read_accessor(gltf, binary, primitive["indices"]).reshape(-1, 3), solution.faces)
    assert gltf["asset"]["extras"]["exposure"] == exposure
    assert os.listdir(tmp_path) == ["baked.glb"]


def test_glb_opens_in_trimesh_with_colours(tmp_path, solution):
    import trimesh

    solution.export(tmp_path / "baked.glb")
    (mesh,) = trimesh.load(tmp_path / "baked.glb").geometry.values()
    assert len(mesh.vertices) == 8 and np.array_equal(mesh.faces, solution.faces)
    assert np.array_equal(mesh.visual.vertex_attributes["color"], np.clip(RADIANCE, 0, 1).astype(np.float32))
    assert np.array_equal(mesh.vertex_attributes["_RADIANCE"], RADIANCE.astype(np.float32))
    (plain,) = trimesh.load(tmp_path / "baked.glb", skip_materials=True).geometry.values()
    assert plain.visual.kind == "vertex" and plain.visual.vertex_colors[0, :3].tolist() == [0, 128, 255]


def test_glb_container_padding():
    data = glb_container(b'{"a":1}', b"abcde")
    assert len(data) == 12 + 8 + 8 + 8 + 8 and len(data) % 4 == 0
    assert data[20:28] == b'{"a":1} ' and data[36:44] == b"abcde\0\0\0"


# ------------------------------------------------------------------------------------------ export errors


@pytest.mark.parametrize("name, exposure, expect", [
    ("baked.obj", 1.0, "unsupported extension '.obj' (supported: .ply, .glb)"),
    ("baked", 1.0, "no extension"),
    ("missing/baked.ply", 1.0, "does not exist"),
    ("baked.glb", 0.0, "exposure must be a finite number > 0"),
    ("baked.ply", float("nan"), "exposure must be a finite number > 0"),
    ("baked.ply", "2", "exposure must be a finite number > 0"),
])
def test_export_bad_input(tmp_path, solution, name, exposure, expect):
    with pytest.raises(LumosError) as excinfo:
        solution.export(tmp_path / name, exposure=exposure)
    assert expect in one_line_error(excinfo, tmp_path / name)
    assert os.listdir(tmp_path) == []


def test_export_bad_display_mesh(tmp_path, solution):
    solution.faces = solution.faces[:0]
    solution.face_element = solution.face_element[:0]
    with pytest.raises(LumosError, match="no faces"):
        solution.export(tmp_path / "baked.glb")
    solution.faces = np.zeros((4, 3), np.int64)
    with pytest.raises(LumosError, match="faces has dtype int64"):
        solution.export(tmp_path / "baked.ply")
    assert os.listdir(tmp_path) == []


def test_failed_export_leaves_no_file(tmp_path, solution, monkeypatch):
    def fail(*args):
        raise OSError("no space left on device")

    monkeypatch.setattr(export_module.os, "replace", fail)
    with pytest.raises(LumosError, match="no space left"):
        solution.export(tmp_path / "baked.glb")
    assert os.listdir(tmp_path) == []
