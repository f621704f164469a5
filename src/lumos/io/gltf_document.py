"""A glTF 2.0 document (`Document`): the JSON, its buffers (embedded, beside the file, or a GLB's binary chunk),
and typed reads of its accessors, images and node transforms, each checked, with one-line errors
`<file>: <key path>: <what is wrong>`. `io.gltf` turns a document into scene-format pieces.
"""

from __future__ import annotations

import base64
import binascii
import json
import math
import struct
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from ..errors import LumosError


#: componentType → little-endian dtype
COMPONENT_TYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}

#: accessor type → number of components
ACCESSOR_TYPES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}

#: extensions this reader understands (others in extensionsRequired are an error, in extensionsUsed a warning)
SUPPORTED_EXTENSIONS = ("KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission",
                        "KHR_materials_ior", "KHR_materials_specular", "KHR_materials_clearcoat",
                        "KHR_texture_transform")

#: The GLB container (glTF 2.0 §4.4): its magic (b"glTF") and chunk types (b"JSON", b"BIN\0"), read by `_glb_chunks`
#: and written by `glb_container`.
_GLB_MAGIC, _CHUNK_JSON, _CHUNK_BIN = 0x46546C67, 0x4E4F534A, 0x004E4942

#: elements of an accessor without a bufferView (all zeros, maybe sparse): more is taken as a corrupt count
_MAX_ZEROS = 1 << 27


class Document:
    """The parsed JSON, its buffers (read when first used) and typed getters that raise one-line errors."""

    def __init__(self, src: Path, data, glb_bin: bytes | None):
        self.src, self.name, self.folder = src, str(src), src.parent
        if not isinstance(data, dict):
            raise self.error("", "the top level must be a JSON object")
        self.json, self.glb_bin = data, glb_bin
        self.warnings: list[str] = []
        self._buffers: dict[int, bytes] = {}
        self._accessors: dict[int, np.ndarray] = {}  # read once each; callers do not write to them
        self._check_asset_and_extensions()

    # ---- reading the file

    @classmethod
    def read(cls, src: Path) -> "Document":
        try:
            raw = src.read_bytes()
        except FileNotFoundError:
            raise LumosError(f"{src}: file not found") from None
        except OSError as exc:
            raise LumosError(f"{src}: cannot read: {exc.strerror or exc}") from None
        if raw[:4] == b"glTF" or src.suffix.lower() == ".glb":
            text, glb_bin = _glb_chunks(src, raw)
        else:
            text, glb_bin = raw, None
        try:
            data = json.loads(text.decode("utf-8-sig"))
        except UnicodeDecodeError as exc:
            raise LumosError(f"{src}: the JSON is not UTF-8 text (byte offset {exc.start})") from None
        except json.JSONDecodeError as exc:
            raise LumosError(f"{src}:{exc.lineno}: invalid JSON: {exc.msg} (column {exc.colno})") from None
        except RecursionError:
            raise LumosError(f"{src}: invalid JSON: nested too deeply") from None
        return cls(src, data, glb_bin)

    def _check_asset_and_extensions(self) -> None:
        asset = self.obj(self.json, "asset", "")
        version = asset.get("version")
        if not isinstance(version, str) or not version.startswith("2."):
            raise self.error("asset.version", f"this reader reads glTF 2.x, the file says {show_value(version)}")
        required = self.strings(self.json, "extensionsRequired")
        unknown = [e for e in required if e not in SUPPORTED_EXTENSIONS]
        if unknown:
            raise self.error("extensionsRequired", f"unsupported extension{'s' * (len(unknown) > 1)} "
                             f"{', '.join(unknown)} (supported: {', '.join(SUPPORTED_EXTENSIONS)})")
        used = [e for e in self.strings(self.json, "extensionsUsed") if e not in SUPPORTED_EXTENSIONS]
        if used:
            self.warn(f"extensionsUsed: ignoring unsupported extension{'s' * (len(used) > 1)} {', '.join(used)}")

    # ---- messages

    def error(self, at: str, what: str) -> LumosError:
        return LumosError(f"{self.name}: {at}: {what}" if at else f"{self.name}: {what}")

    def warn(self, what: str) -> None:
        line = f"{self.name}: {what}"
        if line not in self.warnings:
            self.warnings.append(line)

    # ---- typed getters: `at` is the key path of `d`

    def obj(self, d: dict, key: str, at: str) -> dict:
        """d[key] as a JSON object ({} when absent)."""
        v = d.get(key, {})
        if not isinstance(v, dict):
            raise self.error(key_path(at, key), f"must be a JSON object, got {show_value(v)}")
        return v

    def list(self, d: dict, key: str, at: str) -> list:
        v = d.get(key, [])
        if not isinstance(v, list):
            raise self.error(key_path(at, key), f"must be a JSON array, got {show_value(v)}")
        return v

    def strings(self, d: dict, key: str) -> list:
        v = self.list(d, key, "")
        if not all(isinstance(s, str) for s in v):
            raise self.error(key, "must be an array of strings")
        return v

    def int(self, d: dict, key: str, at: str, default=None, lo: int = 0) -> int:
        v = d.get(key, default)
        if v is None:
            raise self.error(key_path(at, key), "is required")
        if isinstance(v, float) and v.is_integer():
            v = int(v)
        if not isinstance(v, int) or isinstance(v, bool) or v < lo:
            raise self.error(key_path(at, key), f"must be an integer >= {lo}, got {show_value(v)}")
        return v

    def number(self, d: dict, key: str, at: str, default: float, lo=-math.inf, hi=math.inf) -> float:
        v = d.get(key, default)
        if not is_number(v) or not lo <= v <= hi:
            raise self.error(key_path(at, key), f"must be a number in [{lo}, {hi}], got {show_value(v)}")
        return float(v)

    def numbers(self, d: dict, key: str, at: str, default, n: int) -> np.ndarray:
        v = d.get(key, default)
        if not isinstance(v, list) or len(v) != n or not all(is_number(x) for x in v):
            raise self.error(key_path(at, key), f"must be an array of {n} finite numbers, got {show_value(v)}")
        return np.array(v, dtype=np.float64)

    def item(self, kind: str, index: int, at: str) -> dict:
        """The object doc[kind][index] (`at` names the key that held the index)."""
        items = self.list(self.json, kind, "")
        if not 0 <= index < len(items):
            raise self.error(at, f"{kind}[{index}] does not exist (there are {len(items)})")
        if not isinstance(items[index], dict):
            raise self.error(f"{kind}[{index}]", f"must be a JSON object, got {show_value(items[index])}")
        return items[index]

    def index(self, d: dict, key: str, at: str, kind: str) -> int:
        """d[key], an index into doc[kind] that must exist."""
        i = self.int(d, key, at)
        self.item(kind, i, key_path(at, key))
        return i

    # ---- scene graph

    def scene_nodes(self):
        """(node index, float64 (4, 4) world_from_node) for every node of the default scene, parents first."""
        scenes = self.list(self.json, "scenes", "")
        if scenes:
            s = self.int(self.json, "scene", "", default=0)
            scene = self.item("scenes", s, "scene")
            roots = [self.index({"n": r}, "n", f"scenes[{s}].nodes[{k}]", "nodes")
                     for k, r in enumerate(self.list(scene, "nodes", f"scenes[{s}]"))]
        else:  # no scenes: every node that is nobody's child
            nodes = self.list(self.json, "nodes", "")
            children = {c for k, node in enumerate(nodes) if isinstance(node, dict)
                        for c in self.list(node, "children", f"nodes[{k}]") if isinstance(c, int)}
            roots = [i for i in range(len(self.list(self.json, "nodes", ""))) if i not in children]
        seen: set[int] = set()
        stack = [(r, np.eye(4)) for r in reversed(roots)]
        while stack:
            node, parent = stack.pop()
            at = f"nodes[{node}]"
            if node in seen:
                raise self.error(at, "is reached twice in the scene (a node has one parent, and no cycles)")
            seen.add(node)
            item = self.item("nodes", node, at)
            world = parent @ self.local_matrix(item, at)
            yield node, world
            children = self.list(item, "children", at)
            for k in reversed(range(len(children))):
                stack.append((self.index({"c": children[k]}, "c", f"{at}.children[{k}]", "nodes"), world))

    def local_matrix(self, node: dict, at: str) -> np.ndarray:
        """A node's local transform, float64 (4, 4): its `matrix` (column-major) or T·R·S."""
        if "matrix" in node:
            return self.numbers(node, "matrix", at, None, 16).reshape(4, 4).T
        t = self.numbers(node, "translation", at, [0, 0, 0], 3)
        q = self.numbers(node, "rotation", at, [0, 0, 0, 1], 4)
        s = self.numbers(node, "scale", at, [1, 1, 1], 3)
        m = np.eye(4)
        m[:3, :3] = quaternion_matrix(q) @ np.diag(s)
        m[:3, 3] = t
        return m

    # ---- buffers and accessors

    def buffer(self, index: int, at: str) -> bytes:
        if index in self._buffers:
            return self._buffers[index]
        item = self.item("buffers", index, at)
        at = f"buffers[{index}]"
        length = self.int(item, "byteLength", at, lo=1)
        if "uri" in item:
            data = self.uri_bytes(item, at)
        elif index == 0 and self.glb_bin is not None:
            data = self.glb_bin
        else:
            raise self.error(at, "has no uri (only buffer 0 of a .glb file may use the BIN chunk)")
        if len(data) < length:
            raise self.error(at, f"byteLength is {length} but the data holds only {len(data)} bytes")
        self._buffers[index] = data
        return data

    def uri_bytes(self, item: dict, at: str) -> bytes:
        """The bytes behind item['uri']: a base64 data URI, or a file relative to the glTF file's folder."""
        uri = item["uri"]
        if not isinstance(uri, str):
            raise self.error(f"{at}.uri", f"must be a string, got {show_value(uri)}")
        if uri.startswith("data:"):
            head, sep, payload = uri.partition(",")
            if not sep or not head.endswith(";base64"):
                raise self.error(f"{at}.uri", "a data URI must be base64 (data:...;base64,...)")
            try:
                return base64.b64decode(payload, validate=True)
            except (binascii.Error, ValueError):
                raise self.error(f"{at}.uri", "the data URI is not valid base64") from None
        path = self.uri_path(uri)
        try:
            return path.read_bytes()
        except OSError as exc:
            what = "no such file" if isinstance(exc, FileNotFoundError) else f"cannot read ({exc.strerror or exc})"
            raise self.error(f"{at}.uri", f"{what} {str(path)!r}") from None

    def uri_path(self, uri: str) -> Path:
        """The absolute path of a relative URI (percent-encoded, '/'-separated) beside the glTF file."""
        if "://" in uri:
            raise self.error("", f"cannot fetch {uri!r}: only relative file URIs and data URIs are read")
        return (self.folder / unquote(uri)).resolve()

    def buffer_view(self, index: int, at: str) -> tuple[bytes, int, int, int]:
        """(buffer bytes, byteOffset, byteLength, byteStride or 0) of bufferViews[index], checked against the buffer."""
        view = self.item("bufferViews", index, at)
        at = f"bufferViews[{index}]"
        data = self.buffer(self.index(view, "buffer", at, "buffers"), f"{at}.buffer")
        offset = self.int(view, "byteOffset", at, default=0)
        length = self.int(view, "byteLength", at, lo=1)
        stride = self.int(view, "byteStride", at, default=0)
        if offset + length > len(data):
            raise self.error(at, f"bytes {offset}..{offset + length} lie outside its buffer ({len(data)} bytes)")
        return data, offset, length, stride

    def accessor(self, index: int, at: str) -> np.ndarray:
        """The elements of accessors[index]: (count, components) float64 (normalized integers turned to
        [0, 1] or [-1, 1]) or int64 (other integers); sparse substitutions applied."""
        if index in self._accessors:
            return self._accessors[index]
        self._accessors[index] = values = self._read_accessor(index, at)
        return values

    def _read_accessor(self, index: int, at: str) -> np.ndarray:
        acc = self.item("accessors", index, at)
        at = f"accessors[{index}]"
        ctype = self.int(acc, "componentType", at)
        if ctype not in COMPONENT_TYPES:
            raise self.error(f"{at}.componentType", f"must be one of {', '.join(map(str, COMPONENT_TYPES))}, "
                             f"got {ctype}")
        kind = acc.get("type")
        if not isinstance(kind, str) or kind not in ACCESSOR_TYPES:
            raise self.error(f"{at}.type", f"must be one of {', '.join(ACCESSOR_TYPES)}, got {show_value(kind)}")
        count, ncomp, dtype = self.int(acc, "count", at, lo=1), ACCESSOR_TYPES[kind], np.dtype(COMPONENT_TYPES[ctype])
        if "bufferView" in acc:
            values = self._strided(self.index(acc, "bufferView", at, "bufferViews"),
                                   self.int(acc, "byteOffset", at, default=0), count, ncomp, dtype, at)
        elif count * ncomp <= _MAX_ZEROS:
            values = np.zeros((count, ncomp), dtype)
        else:
            raise self.error(f"{at}.count", f"{count} elements without a bufferView is more than this reader allocates")
        if "sparse" in acc:
            values = self._sparse(acc, values, ncomp, dtype, at)
        if dtype.kind == "f":
            return values.astype(np.float64)
        if acc.get("normalized", False) is True:
            info = np.iinfo(dtype)
            return np.maximum(values.astype(np.float64) / info.max, -1.0)
        return values.astype(np.int64)

    def _strided(self, view: int, offset: int, count: int, ncomp: int, dtype: np.dtype, at: str) -> np.ndarray:
        data, start, length, stride = self.buffer_view(view, f"{at}.bufferView")
        size = ncomp * dtype.itemsize
        stride = stride or size
        if stride < size:
            raise self.error(f"bufferViews[{view}].byteStride", f"{stride} is less than one element ({size} bytes)")
        end = offset + stride * (count - 1) + size
        if end > length:
            raise self.error(at, f"{count} elements from byteOffset {offset} need {end} bytes but "
                             f"bufferViews[{view}] holds {length}")
        arr = np.ndarray((count, ncomp), dtype, buffer=data, offset=start + offset, strides=(stride, dtype.itemsize))
        return arr.copy()

    def _sparse(self, acc: dict, values: np.ndarray, ncomp: int, dtype: np.dtype, at: str) -> np.ndarray:
        sparse = self.obj(acc, "sparse", at)
        at = f"{at}.sparse"
        n = self.int(sparse, "count", at, lo=1)
        ind, val = self.obj(sparse, "indices", at), self.obj(sparse, "values", at)
        itype = self.int(ind, "componentType", f"{at}.indices")
        if itype not in (5121, 5123, 5125):
            raise self.error(f"{at}.indices.componentType", f"must be 5121, 5123 or 5125, got {itype}")
        idx = self._strided(self.index(ind, "bufferView", f"{at}.indices", "bufferViews"),
                            self.int(ind, "byteOffset", f"{at}.indices", default=0), n, 1,
                            np.dtype(COMPONENT_TYPES[itype]), f"{at}.indices")[:, 0].astype(np.int64)
        if idx.max() >= len(values):
            raise self.error(f"{at}.indices", f"index {int(idx.max())} is out of range (count {len(values)})")
        subs = self._strided(self.index(val, "bufferView", f"{at}.values", "bufferViews"),
                             self.int(val, "byteOffset", f"{at}.values", default=0), n, ncomp, dtype,
                             f"{at}.values")
        values = values.copy()
        values[idx] = subs
        return values


def _glb_chunks(src: Path, raw: bytes) -> tuple[bytes, bytes | None]:
    """The JSON and BIN chunks of a .glb (12-byte header: magic, version 2, length; then chunks)."""
    if len(raw) < 20:
        raise LumosError(f"{src}: not a GLB file (only {len(raw)} bytes)")
    magic, version, length = struct.unpack_from("<III", raw, 0)
    if magic != _GLB_MAGIC:
        raise LumosError(f"{src}: not a GLB file (the magic is {raw[:4]!r}, not b'glTF')")
    if version != 2:
        raise LumosError(f"{src}: GLB version {version}; this reader reads version 2")
    if length > len(raw):
        raise LumosError(f"{src}: the GLB header says {length} bytes but the file has {len(raw)} (truncated?)")
    chunks, pos = [], 12
    while pos + 8 <= length:
        size, kind = struct.unpack_from("<II", raw, pos)
        if pos + 8 + size > length:
            raise LumosError(f"{src}: GLB chunk {len(chunks)} at byte {pos} runs past the end of the file")
        chunks.append((kind, raw[pos + 8 : pos + 8 + size]))
        pos += 8 + size + (-size % 4)  # chunks are padded to 4 bytes
    if not chunks or chunks[0][0] != _CHUNK_JSON:
        raise LumosError(f"{src}: the first GLB chunk must be JSON")
    glb_bin = chunks[1][1] if len(chunks) > 1 and chunks[1][0] == _CHUNK_BIN else None
    return chunks[0][1], glb_bin


def quaternion_matrix(q) -> np.ndarray:
    """float64 (3, 3) rotation of the quaternion [x, y, z, w] (normalised first; glTF's order)."""
    x, y, z, w = np.asarray(q, np.float64) / (np.linalg.norm(q) or 1.0)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def key_path(at: str, key: str) -> str:
    return f"{at}.{key}" if at else key


def show_value(v) -> str:
    text = json.dumps(v) if not isinstance(v, float) or math.isfinite(v) else repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def glb_container(json_bytes: bytes, binary: bytes) -> bytes:
    """The GLB layout (glTF 2.0 §4.4): a 12-byte header, then the JSON chunk padded with spaces and the BIN chunk
    padded with zeros, each to a multiple of 4 bytes."""
    json_chunk = json_bytes + b" " * (-len(json_bytes) % 4)
    bin_chunk = binary + b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(json_chunk) + 8 + len(bin_chunk)
    return b"".join([struct.pack("<III", _GLB_MAGIC, 2, total),
                     struct.pack("<II", len(json_chunk), _CHUNK_JSON), json_chunk,
                     struct.pack("<II", len(bin_chunk), _CHUNK_BIN), bin_chunk])
