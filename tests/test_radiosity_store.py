"""Radiosity solutions on disk: save → load bit-identical, the scene check, damaged files, and the PLY / GLB
exports of the display mesh (read back by independent parsers here and by trimesh)."""

from __future__ import annotations

import json
import os
import struct
from dataclasses import fields

import numpy as np
import pytest

from lumos import tonemap
from lumos.errors import LumosError
from lumos.radiosity import export as export_module
from lumos.radiosity import store
from lumos.io.gltf_document import glb_container
from lumos.radiosity.solution import Solution

#: Display radiance of the 8 vertices: rows 0–1 hold the hand-checked values 0, 0.25, 0.5, 1, 2.
RADIANCE = np.array([[0.0, 0.5, 1.0], [2.0, 0.25, 0.0], [0.3, 1.7, 0.01], [0.002, 0.8, 5.0],
                     [1.0, 1.0, 1.0], [0.5, 0.5, 0.5], [0.9, 0.1, 0.6], [3.0, 0.04, 0.7]])
#: sRGB bytes of rows 0–1, round(255·srgb(clamp(e·L))): 0 → 0, 0.125 → 99, 0.25 → 137, 0.5 → 188, ≥1 → 255.
RGB8 = {1.0: [[0, 188, 255], [255, 137, 0]], 0.5: [[0, 137, 188], [255, 99, 0]]}


@pytest.fixture
def solution() -> Solution:
    """Two unit quads (a floor facing +y and a wall facing −x, apart), each split into two display triangles."""
    corners = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0],  # floor, CCW about +y
                        [2, 0, 0], [2, 1, 0], [2, 1, 1], [2, 0, 1]], dtype=np.float64)  # wall, CCW about −x
    normals = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    return Solution(
        element_vertices=corners,
        element_polys=np.array([[0, 1, 2, 3], [4, 5, 6, 7]], np.int32),
        element_normal=normals,
        element_area=np.array([1.0, 1.0]),
        element_reflectance=np.array([[0.7, 0.6, 0.5], [0.2, 0.8, 0.3]]),
        element_emission=np.array([[0.0, 0.0, 0.0], [1.5, 1.5, 1.5]]),
        element_radiance=np.array([[0.25, 1.0 / 3.0, 2.5], [1.5, 1.9, 1.6]]),
        element_object=np.array([0, 3], np.int32),
        element_material=np.array([1, 0], np.int32),
        element_patch=np.array([0, 1], np.int32),
        element_optics=np.array([[0.0] * 9, [0.5, 0.5, 0.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]]),
        element_twin=np.array([-1, -1], np.int32),
        vertices=corners + 0.0,
        vertex_normal=np.repeat(normals, 4, axis=0),
        vertex_radiance=RADIANCE.copy(),
        faces=np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]], np.int32),
        face_element=np.array([0, 0, 1, 1], np.int32),
        settings={"solver": "progressive", "max_area": 0.25, "tolerance": 1e-3, "hemicube": [64, 64],
                  "nested": {"on": True, "none": None, "name": "Ünïcode"}},
        stats={"patches": 2, "elements": 2, "solve_s": 0.0123456789, "iterations": np.int64(7),
               "residual": np.float64(1e-17)},
        scene_digest="3f786850e387550fdab836ed7e6dc881de23001b",
    )


def assert_same(a: Solution, b: Solution) -> None:
    """Every field equal; arrays with the same dtype, shape and bytes."""
    for f in fields(Solution):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert (y.dtype, y.shape) == (x.dtype, x.shape), f.name
            assert y.tobytes() == x.tobytes(), f.name
        else:
            assert y == x, f.name


def one_line_error(excinfo, path) -> str:
    message = str(excinfo.value)
    assert "\n" not in message and str(path) in message, message
    return message


def rewrite(path, **changes) -> None:
    """Rewrite the npz at `path` with some members replaced (or removed, for None), bypassing the checks."""
    with np.load(path, allow_pickle=False) as npz:
        contents = {name: npz[name] for name in npz.files}
    for name, value in changes.items():
        if value is None:
            del contents[name]
        else:
            contents[name] = value
    with open(path, "wb") as f:
        np.savez(f, **contents)


# ------------------------------------------------------------------------------------------ save and load


def test_save_load_bit_identical(tmp_path, solution):
    solution.save(tmp_path / "box.npz")
    back = Solution.load(tmp_path / "box.npz")
    assert_same(solution, back)
    assert all(getattr(back, name).flags.c_contiguous for name in store.SCHEMA)
    assert os.listdir(tmp_path) == ["box.npz"]  # no temporary file left behind
    assert_same(solution, Solution.load(str(tmp_path / "box.npz"), solution.scene_digest))


def test_save_keeps_values_of_strided_arrays_and_overwrites(tmp_path, solution):
    (tmp_path / "box.npz").write_bytes(b"old")
    wide = np.zeros((8, 6))
    wide[:, ::2] = RADIANCE
    solution.vertex_radiance = wide[:, ::2]  # a non-contiguous view: saved by value
    solution.save(tmp_path / "box.npz")
    assert Solution.load(tmp_path / "box.npz").vertex_radiance.tobytes() == RADIANCE.tobytes()


def test_file_layout(tmp_path, solution):
    store.save_solution(solution, tmp_path / "box.NPZ")  # the extension is case-insensitive
    with np.load(tmp_path / "box.NPZ", allow_pickle=False) as npz:
        assert set(npz.files) == {"format_version", "metadata", *store.SCHEMA}
        assert npz["format_version"].shape == () and int(npz["format_version"]) == store.FORMAT_VERSION == 2
        meta = json.loads(str(npz["metadata"]))
        assert npz["faces"].dtype == np.int32 and npz["vertex_radiance"].dtype == np.float64
    assert meta["format"] == "lumos radiosity solution"
    assert meta["scene_digest"] == solution.scene_digest and meta["stats"]["iterations"] == 7


def test_scene_digest_check(tmp_path, solution):
    path = tmp_path / "box.npz"
    solution.save(path)
    Solution.load(path, solution.scene_digest)
    Solution.load(path, None)
    with pytest.raises(LumosError) as excinfo:
        Solution.load(path, "another digest")
    message = one_line_error(excinfo, path)
    assert "different scene" in message and "geometry or materials" in message and "solve" in message


@pytest.mark.parametrize("name, expect", [
    ("missing/box.npz", "does not exist"),
    ("folder", "is a directory"),
    ("box.npy", "unsupported extension '.npy'"),
    ("box", "no extension"),
    ("afile/box.npz", "is not a folder"),
])
def test_save_bad_paths(tmp_path, solution, name, expect):
    (tmp_path / "folder").mkdir()
    (tmp_path / "afile").write_text("x")
    before = sorted(os.listdir(tmp_path))
    with pytest.raises(LumosError) as excinfo:
        solution.save(tmp_path / name)
    assert expect in one_line_error(excinfo, tmp_path / name)
    assert sorted(os.listdir(tmp_path)) == before and os.listdir(tmp_path / "folder") == []


def test_save_unwritable_folder(tmp_path, solution, monkeypatch):
    # the check itself (running as root, chmod would not stop the write)
    monkeypatch.setattr(store.os, "access", lambda path, mode: False)
    with pytest.raises(LumosError) as excinfo:
        solution.save(tmp_path / "box.npz")
    assert "not writable" in one_line_error(excinfo, tmp_path / "box.npz")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("field, value, expect", [
    ("faces", np.zeros((4, 3), np.int64), "faces has dtype int64, expected int32"),
    ("vertex_radiance", RADIANCE[:7], "vertex_radiance has shape (7, 3), expected (8, 3)"),
    ("element_radiance", np.array([[np.nan, 0, 0], [0, 0, 0]]), "element_radiance holds NaN"),
    ("settings", {"bad": object()}, "JSON"),
    ("scene_digest", None, "scene_digest must be a string"),
])
def test_save_invalid_solution_writes_nothing(tmp_path, solution, field, value, expect):
    setattr(solution, field, value)
    with pytest.raises(LumosError) as excinfo:
        solution.save(tmp_path / "box.npz")
    assert expect in one_line_error(excinfo, tmp_path / "box.npz")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("failure", [OSError("disk full"), KeyboardInterrupt()])
def test_failed_write_leaves_old_file_and_no_temporary(tmp_path, solution, monkeypatch, failure):
    path = tmp_path / "box.npz"
    path.write_bytes(b"previous")

    def partial_savez(f, **arrays):
        f.write(b"PK\x03\x04 half an archive")
        raise failure

    monkeypatch.setattr(store.np, "savez", partial_savez)
    with pytest.raises(LumosError if isinstance(failure, OSError) else KeyboardInterrupt) as excinfo:
        solution.save(path)
    if isinstance(failure, OSError):
        assert "disk full" in one_line_error(excinfo, path)
    assert os.listdir(tmp_path) == ["box.npz"] and path.read_bytes() == b"previous"


# ------------------------------------------------------------------------------------------ damaged files


def test_load_missing_directory_and_foreign_files(tmp_path, solution):
    cases = {"nothing.npz": "file not found", "folder": "it is a directory", "text.npz": "not an .npz file",
             "array.npz": "not an .npz file", "other.npz": "not a lumos radiosity solution"}
    (tmp_path / "folder").mkdir()
    (tmp_path / "text.npz").write_text("solution\n")
    np.save(tmp_path / "array.npy", np.zeros(3))
    os.replace(tmp_path / "array.npy", tmp_path / "array.npz")  # an .npy under the npz name
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    for name, expect in cases.items():
        with pytest.raises(LumosError) as excinfo:
            Solution.load(tmp_path / name)
        assert expect in one_line_error(excinfo, tmp_path / name), name


def test_load_truncated(tmp_path, solution):
    solution.save(tmp_path / "box.npz")
    raw = (tmp_path / "box.npz").read_bytes()
    for cut in (0, 3, 10, 200, len(raw) // 2, len(raw) - 22, len(raw) - 1):
        (tmp_path / "cut.npz").write_bytes(raw[:cut])
        with pytest.raises(LumosError) as excinfo:
            Solution.load(tmp_path / "cut.npz")
        one_line_error(excinfo, tmp_path / "cut.npz")


def test_load_corrupted_radiance_bytes_fail_the_crc(tmp_path, solution):
    solution.save(tmp_path / "box.npz")
    raw = bytearray((tmp_path / "box.npz").read_bytes())
    at = raw.find(RADIANCE.tobytes())
    assert at > 0
    raw[at + 13] ^= 0x01  # one bit of one radiance value
    (tmp_path / "bad.npz").write_bytes(raw)
    with pytest.raises(LumosError) as excinfo:
        Solution.load(tmp_path / "bad.npz")
    assert "CRC" in one_line_error(excinfo, tmp_path / "bad.npz")


def test_every_byte_flip_is_caught_or_harmless(tmp_path, solution):
    """Flip each byte of a saved file (every ninth, for time): loading either fails with LumosError or gives the
    same solution (the byte was zip bookkeeping that does not change the data, e.g. a timestamp)."""
    solution.save(tmp_path / "box.npz")
    raw = (tmp_path / "box.npz").read_bytes()
    caught, offsets = 0, range(0, len(raw), 9)
    for at in offsets:
        bad = bytearray(raw)
        bad[at] ^= 0xFF
        (tmp_path / "bad.npz").write_bytes(bad)
        try:
            back = Solution.load(tmp_path / "bad.npz")
        except LumosError as exc:
            assert "\n" not in str(exc)
            caught += 1
        else:
            assert_same(solution, back)
    assert caught > len(offsets) // 2  # most bytes are data or headers that matter


@pytest.mark.parametrize("changes, expect", [
    ({"format_version": np.array(1, np.int64)}, "format version 1, this lumos reads version 2"),
    ({"format_version": None}, "not a lumos radiosity solution"),
    ({"format_version": np.array([1, 1])}, "bad format_version"),
    ({"metadata": np.array("{not json")}, "bad metadata JSON"),
    ({"metadata": np.array(json.dumps({"format": "other"}))}, "not a lumos radiosity solution"),
    ({"metadata": np.array(json.dumps({"format": "lumos radiosity solution", "settings": {}, "stats": {}}))},
     "'scene_digest' is missing"),
    ({"element_patch": None}, "missing array(s) element_patch"),
    ({"element_normal": np.zeros((2, 2))}, "element_normal has shape (2, 2), expected (2, 3)"),
    ({"element_area": np.ones(3)}, "element_area has shape (3,), expected (2,)"),
    ({"element_object": np.zeros(2, np.int64)}, "element_object has dtype int64, expected int32"),
    ({"element_vertices": np.zeros((8, 3), np.float32)}, "element_vertices has dtype float32"),
    ({"vertex_normal": np.zeros((9, 3))}, "vertex_normal has shape (9, 3), expected (8, 3)"),
    ({"vertex_radiance": np.zeros((8, 3, 1))}, "vertex_radiance has shape (8, 3, 1)"),
    ({"face_element": np.zeros(5, np.int32)}, "face_element has shape (5,), expected (4,)"),
    ({"faces": np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 8]], np.int32)}, "faces has indices outside [0, 8)"),
    ({"face_element": np.array([0, 0, 1, 2], np.int32)}, "face_element has indices outside [0, 2)"),
    ({"element_polys": np.array([[0, 1, 2, 8], [4, 5, 6, 7]], np.int32)}, "element_polys has indices outside"),
    ({"element_polys": np.array([[0, -1, 2, 3], [4, 5, 6, 7]], np.int32)}, "-1 among its first three corners"),
    ({"vertex_radiance": np.where(np.eye(8, 3) > 0, np.nan, RADIANCE)}, "vertex_radiance holds NaN or infinite"),
    ({"element_radiance": np.array([[np.inf, 0, 0], [0, 0, 0]])}, "element_radiance holds NaN or infinite"),
])
def test_load_bad_contents(tmp_path, solution, changes, expect):
    path = tmp_path / "box.npz"
    solution.save(path)
    rewrite(path, **changes)
    with pytest.raises(LumosError) as excinfo:
        Solution.load(path)
    assert expect in one_line_error(excinfo, path)


def test_load_triangle_elements_and_empty_mesh(tmp_path, solution):
    solution.element_polys[1, 3] = -1  # a triangle: its fourth corner is −1
    solution.save(tmp_path / "tri.npz")
    assert_same(solution, Solution.load(tmp_path / "tri.npz"))
    empty = Solution(*(np.zeros((0,) + tuple(s for s in shape[1:]), dtype) for dtype, shape in store.SCHEMA.values()))
    empty.save(tmp_path / "empty.npz")
    assert_same(empty, Solution.load(tmp_path / "empty.npz"))


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
