"""Radiosity solutions on disk (`radiosity.store`): save → load bit-identical, the scene check, damaged files.

The solution they save is the `solution` fixture (conftest.py); the PLY / GLB exports: radiosity/test_export.py."""

from __future__ import annotations

import json
import os
from dataclasses import fields

import numpy as np
import pytest
from helpers import RADIANCE, one_line_error

from lumos.errors import LumosError
from lumos.radiosity import store
from lumos.radiosity.solution import Solution


def assert_same(a: Solution, b: Solution) -> None:
    """Every field equal; arrays with the same dtype, shape and bytes."""
    for f in fields(Solution):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert (y.dtype, y.shape) == (x.dtype, x.shape), f.name
            assert y.tobytes() == x.tobytes(), f.name
        else:
            assert y == x, f.name


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
