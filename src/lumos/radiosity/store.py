"""Saving and reloading a radiosity `Solution`: one `.npz` file, bit-identical on reload.

    save_solution(solution, "box.npz")                  # what Solution.save calls
    solution = load_solution("box.npz", scene_digest)   # what Solution.load calls; checks the scene

The file is a NumPy `.npz` archive (uncompressed: a solution is mostly float64 that zlib barely shrinks, and
loading stays a copy) holding

- `format_version`: int64 0-d, `FORMAT_VERSION`; a file of another version is refused, not guessed at;
- `metadata`: a 0-d unicode array, the JSON object `{"format": FORMAT_NAME, "settings": {...}, "stats": {...},
  "scene_digest": "..."}` (no pickles: it loads with `allow_pickle=False`);
- one array per array field of `Solution`, under the field's name, with the dtype and shape given in `SCHEMA`.

Both directions check every array against `SCHEMA` and against each other (n elements, nv_e element
corners, nv display vertices, nf faces), that indices stay in range and that every float is finite, so a
file that loads is one the renderer can draw. Writes are atomic: the archive goes to a temporary file in the
target folder and `os.replace` moves it over the target once complete, so a failed write leaves neither a
partial nor a temporary file. Every problem is a `LumosError` with a one-line message naming the file.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path
from typing import Optional

import numpy as np

from ..errors import LumosError
from ..io.atomic import check_output_path, one_line, write_atomically
from .solution import Solution

#: Bumped whenever the arrays or their meaning change; `load_solution` refuses other versions.
FORMAT_VERSION = 2
FORMAT_NAME = "lumos radiosity solution"

#: field → (dtype, shape); a shape is a tuple of sizes, where a string names a size shared between arrays.
SCHEMA: dict[str, tuple[np.dtype, tuple]] = {
    "element_vertices": (np.dtype(np.float64), ("nv_e", 3)),
    "element_polys": (np.dtype(np.int32), ("n", 4)),
    "element_normal": (np.dtype(np.float64), ("n", 3)),
    "element_area": (np.dtype(np.float64), ("n",)),
    "element_reflectance": (np.dtype(np.float64), ("n", 3)),
    "element_emission": (np.dtype(np.float64), ("n", 3)),
    "element_radiance": (np.dtype(np.float64), ("n", 3)),
    "element_object": (np.dtype(np.int32), ("n",)),
    "element_material": (np.dtype(np.int32), ("n",)),
    "element_patch": (np.dtype(np.int32), ("n",)),
    "element_optics": (np.dtype(np.float64), ("n", 9)),
    "element_twin": (np.dtype(np.int32), ("n",)),
    "vertices": (np.dtype(np.float64), ("nv", 3)),
    "vertex_normal": (np.dtype(np.float64), ("nv", 3)),
    "vertex_radiance": (np.dtype(np.float64), ("nv", 3)),
    "faces": (np.dtype(np.int32), ("nf", 3)),
    "face_element": (np.dtype(np.int32), ("nf",)),
}
#: The fields that make the display mesh (all `export_solution` needs).
DISPLAY_FIELDS = ("vertices", "vertex_normal", "vertex_radiance", "faces", "face_element")
#: Index arrays → (the size their values index, whether -1 is allowed: element_polys' 4th corner of a triangle).
_INDEX_RANGES = {"element_polys": ("nv_e", True), "faces": ("nv", False), "face_element": ("n", False),
                 "element_twin": ("n", True)}
_META_KEYS = ("settings", "stats", "scene_digest")


# ---------------------------------------------------------------------------------------------------- saving


def save_solution(solution: Solution, path: str | os.PathLike) -> None:
    """Write `solution` to `path` (a `.npz` file), atomically.

    Raises LumosError, before anything is written, for a bad path (wrong extension, a directory, a missing
    or unwritable folder), an array whose dtype or shape does not match `SCHEMA` (no silent conversion: what
    is saved reloads bit-identically), an index out of range, a NaN or infinite value, or settings / stats
    that are not JSON (str keys; str, int, float, bool, None, lists and dicts; tuples are stored as lists).
    """
    out = check_output_path(path, (".npz",), "cannot save radiosity solution")
    fail = f"cannot save radiosity solution '{path}'"
    arrays = {name: np.asarray(getattr(solution, name)) for name in SCHEMA}
    check_arrays(arrays, fail)
    meta = {"format": FORMAT_NAME, **{key: getattr(solution, key) for key in _META_KEYS}}
    if not isinstance(meta["scene_digest"], str):
        raise LumosError(f"{fail}: scene_digest must be a string, got {type(meta['scene_digest']).__name__}")
    try:
        text = json.dumps(meta, default=_json_scalar, allow_nan=True)
    except (TypeError, ValueError) as exc:
        raise LumosError(f"{fail}: settings and stats must be JSON values ({one_line(exc)})") from None
    contents = {"format_version": np.array(FORMAT_VERSION, np.int64), "metadata": np.array(text), **arrays}

    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            np.savez(f, **contents)

    write_atomically(out, write, fail, suffix=".tmp")


def _json_scalar(value):
    """json.dumps fallback: NumPy scalars become the Python number they equal; anything else is an error."""
    if isinstance(value, (np.integer, np.floating, np.bool_)):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


# ---------------------------------------------------------------------------------------------------- loading


def load_solution(path: str | os.PathLike, scene_digest: Optional[str] = None) -> Solution:
    """Read a solution written by `save_solution`: every array with the dtype, shape and bytes it was saved
    with (C-contiguous), `settings` and `stats` equal to the saved dicts.

    scene_digest: the digest of the scene about to be drawn; when given (non-empty) and the file's is not
        empty, they must match, else the solution belongs to another scene and LumosError says to solve again.
    Raises LumosError (one line, naming the file) for a missing file, a file that is not an npz archive, a
    truncated or corrupted one (zip CRCs are checked), another format version, and missing, mis-typed or
    mis-shaped arrays, out-of-range indices or NaN / infinite values.
    """
    src = Path(path)
    fail = f"cannot load radiosity solution '{path}'"
    contents = _read_npz(src, fail)
    version = contents.get("format_version")
    if version is None or "metadata" not in contents:
        raise LumosError(f"{fail}: not a lumos radiosity solution (no format_version / metadata)")
    if version.shape != () or not np.issubdtype(version.dtype, np.integer):
        raise LumosError(f"{fail}: bad format_version (dtype {version.dtype}, shape {version.shape})")
    if int(version) != FORMAT_VERSION:
        raise LumosError(f"{fail}: format version {int(version)}, this lumos reads version {FORMAT_VERSION}; "
                         f"solve the scene again")
    meta = _parse_metadata(contents["metadata"], fail)
    missing = [name for name in SCHEMA if name not in contents]
    if missing:
        raise LumosError(f"{fail}: missing array(s) {', '.join(missing)}")
    arrays = {name: np.ascontiguousarray(contents[name]) for name in SCHEMA}
    check_arrays(arrays, fail)
    stored = meta["scene_digest"]
    if scene_digest and stored and scene_digest != stored:
        raise LumosError(f"radiosity solution '{path}' was solved for a different scene (its geometry or materials "
                         f"changed, or its lights, or the camera moved into or out of a solid, whose inside "
                         f"is meshed only then); solve the scene again")
    return Solution(**arrays, settings=meta["settings"], stats=meta["stats"], scene_digest=stored)


def _read_npz(src: Path, fail: str) -> dict[str, np.ndarray]:
    """Every member of the archive, read in full (so each zip CRC is checked)."""
    if not src.is_file():
        raise LumosError(f"{fail}: {'it is a directory' if src.is_dir() else 'file not found'}")
    try:
        with open(src, "rb") as f:
            magic = f.read(4)
    except OSError as exc:
        raise LumosError(f"{fail}: {one_line(exc)}") from None
    if magic != b"PK\x03\x04":
        raise LumosError(f"{fail}: not an .npz file")
    try:
        with np.load(src, allow_pickle=False) as npz:
            return {name: npz[name] for name in npz.files}
    except OSError as exc:
        raise LumosError(f"{fail}: {one_line(exc)}") from None
    except (zipfile.BadZipFile, EOFError) as exc:
        raise LumosError(f"{fail}: damaged or truncated .npz file ({one_line(exc)})") from None
    except Exception as exc:  # numpy's own ValueError / zlib errors for a damaged member
        raise LumosError(f"{fail}: damaged .npz file ({one_line(exc)})") from None


def _parse_metadata(meta_array: np.ndarray, fail: str) -> dict:
    """The `metadata` member → dict with settings (dict), stats (dict) and scene_digest (str)."""
    if meta_array.shape != () or meta_array.dtype.kind != "U":
        raise LumosError(f"{fail}: bad metadata (dtype {meta_array.dtype}, shape {meta_array.shape})")
    try:
        meta = json.loads(str(meta_array))
    except ValueError as exc:
        raise LumosError(f"{fail}: bad metadata JSON ({one_line(exc)})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT_NAME:
        raise LumosError(f"{fail}: not a lumos radiosity solution (metadata format is not '{FORMAT_NAME}')")
    for key, kind in (("settings", dict), ("stats", dict), ("scene_digest", str)):
        if not isinstance(meta.get(key), kind):
            raise LumosError(f"{fail}: bad metadata: '{key}' is missing or not a {kind.__name__}")
    return meta


# ---------------------------------------------------------------------------------------------------- checks


def check_arrays(arrays: dict[str, np.ndarray], fail: str) -> dict[str, int]:
    """Check arrays (a subset of `SCHEMA`'s fields) against `SCHEMA` and each other; return the sizes found.

    Dtypes must match exactly (native byte order), shapes agree on every shared size (the first array that
    names a size fixes it), index arrays stay in range and float arrays are finite. Raises LumosError
    `'{fail}: <what is wrong>'`.
    """
    sizes: dict[str, int] = {}
    for name, array in arrays.items():
        dtype, shape = SCHEMA[name]
        if array.dtype != dtype:
            raise LumosError(f"{fail}: {name} has dtype {array.dtype}, expected {dtype}")
        if array.ndim != len(shape):
            raise LumosError(f"{fail}: {name} has shape {array.shape}, expected {_shown(shape)}")
        for axis, (size, want) in enumerate(zip(array.shape, shape)):
            expected = sizes.setdefault(want, size) if isinstance(want, str) else want
            if size != expected:
                raise LumosError(f"{fail}: {name} has shape {array.shape}, expected {_shown(shape, sizes)}")
        if dtype.kind == "f" and not np.isfinite(array).all():
            raise LumosError(f"{fail}: {name} holds NaN or infinite values")
    for name, (size_name, minus_one) in _INDEX_RANGES.items():
        if name in arrays and arrays[name].size and size_name in sizes:
            _check_range(name, arrays[name], sizes[size_name], minus_one, fail)
    return sizes


def _check_range(name: str, index: np.ndarray, size: int, minus_one: bool, fail: str) -> None:
    low = -1 if minus_one else 0
    if index.min() < low or index.max() >= size:
        raise LumosError(f"{fail}: {name} has indices outside [{low}, {size}) "
                         f"(min {int(index.min())}, max {int(index.max())})")
    if minus_one and index.ndim == 2 and (index[:, :3] < 0).any():
        raise LumosError(f"{fail}: {name} has -1 among its first three corners")


def _shown(shape: tuple, sizes: Optional[dict] = None) -> str:
    """('n', 3) → '(n, 3)', or '(12, 3)' once n is known."""
    parts = [str((sizes or {}).get(s, s)) for s in shape]
    return f"({parts[0]},)" if len(parts) == 1 else f"({', '.join(parts)})"


# ---------------------------------------------------------------------------------------------------- files
