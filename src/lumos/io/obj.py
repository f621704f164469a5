"""Wavefront OBJ files (with their MTL libraries) as lumos scene pieces.

    model = import_obj("knob.obj")     # an ImportedModel (lumos.io.models): materials, objects, warnings

One pass over the lines sorts the statements by kind; the numbers of each kind are then converted together
with NumPy (so a file of a million lines takes seconds), indices resolved (negative ones count back from the
element defined last), polygons triangulated (`lumos.mesh.triangulate`: fans, ear clipping where concave) and
the faces split into one mesh per (object or group, material) pair, in order of first appearance.

Normals follow the file: a corner with `vn` keeps it; otherwise its smoothing group decides (`s 1`, `s 7`...:
the faces of one group share an angle-weighted normal at each position they share, repeated vertices welded,
`lumos.mesh.vertex_normals`;
`s off` / `s 0`: the face's own normal). A file with neither `vn` nor `s` says nothing about shading and
gets no normals (the mesh keys `smooth`, `crease_angle` then decide). Vertices are split only where a
position carries several uvs or normals. See docs/formats.md ("OBJ + MTL") for everything that is read.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import LumosError
from ..mesh import triangulate, vertex_normals, weld_ids
from .imported import ImportedModel
from .mtl import UNDEFINED_MATERIAL, find_file, read_mtl
from .text import logical_lines

#: Statements read silently even though they change nothing lumos draws.
_QUIET = {"mg", "lod", "bevel", "c_interp", "d_interp", "shadow_obj", "trace_obj", "maplib", "usemap"}
#: Largest smoothing-group number (keys of (group, vertex) pairs stay within int64).
_MAX_GROUP = (1 << 31) - 1


class _Parsed:
    """Statements of one OBJ file, sorted by kind (lists in file order)."""

    def __init__(self):
        self.v, self.v_line, self.vt, self.vt_line, self.vn, self.vn_line = [], [], [], [], [], []
        self.corners: list[str] = []                            # every face corner token, faces one after another
        self.face_len, self.face_line, self.face_piece, self.face_group = [], [], [], []
        self.face_counts: list[tuple[int, int, int]] = []      # (v, vt, vn) defined before each face
        self.pieces: dict[tuple[str, str | None], int] = {}     # (name, material) -> piece id
        self.usemtl_line: dict[str, int] = {}
        self.mtllibs: list[tuple[int, str]] = []
        self.any_group = False


def import_obj(path: str | os.PathLike) -> ImportedModel:
    """Read the OBJ file `path` and the MTL libraries it names into an `ImportedModel`.

    Objects: {"type": "mesh", "name", "material" (an MTL name or None), "vertices" float64 (n, 3),
    "faces" int64 (m, 3), "normals"? float64 (n, 3) unit, "uvs"? float64 (n, 2), "two_sided"? False where its
    material emits (Ke): emission leaves the counter-clockwise side only}. Raises LumosError
    `<file>:<line>: <what>` for an index out of range, a number that is not one (or NaN, infinite), a face
    with fewer than 3 corners, and a file without faces; sloppy but readable input is a warning.
    """
    src, label = Path(path), str(path)
    try:
        data = src.read_bytes()
    except OSError as exc:
        raise LumosError(f"{label}: cannot read the file ({exc.strerror or type(exc).__name__})") from None
    warnings: list[str] = []
    lines, crlf = logical_lines(data)
    if crlf:
        warnings.append(f"{label}:1: CRLF (Windows) line ends; read as plain line ends")
    parsed = _parse(lines, label, src.stem, warnings)
    if not parsed.face_len:
        raise LumosError(f"{label}: no faces (the file holds {len(parsed.v)} vertices and no 'f' statements)")

    positions = _rows(parsed.v, parsed.v_line, 3, 3, "v", label)
    uvs = _rows(parsed.vt, parsed.vt_line, 1, 2, "vt", label)
    normals = _rows(parsed.vn, parsed.vn_line, 3, 3, "vn", label)
    corner_v, corner_vt, corner_vn, corner_face = _corner_indices(parsed, len(positions), len(uvs), len(normals),
                                                                  label, warnings)
    triangles, triangle_face = _triangles(positions[corner_v], np.asarray(parsed.face_len, dtype=np.int64))

    has_normals = parsed.any_group or (corner_vn >= 0).any()
    if has_normals:
        corner_normal, normal_table = _corner_normals(parsed, positions, normals, corner_v, corner_vn, corner_face,
                                                      triangles)
    else:
        corner_normal, normal_table = np.zeros(len(corner_v), dtype=np.int64), None

    materials = _materials(parsed, src.parent, label, warnings)
    objects = []
    triangle_piece = np.asarray(parsed.face_piece, dtype=np.int64)[triangle_face]
    for (name, material), piece in parsed.pieces.items():
        tris = triangles[triangle_piece == piece]
        if len(tris):
            objects.append(_mesh(name, material, tris, corner_v, corner_vt, corner_normal, positions, uvs,
                                 normal_table, label, warnings))
    for obj in objects:  # an emissive part (Ke) emits on the side its faces wind to, as Mitsuba and pbrt read lights
        if np.any(np.asarray(materials.get(obj["material"], {}).get("emission", 0.0)) > 0):
            obj["two_sided"] = False
    return ImportedModel(source=src.resolve(), materials=materials, objects=objects, warnings=warnings)


# ------------------------------------------------------------------------------------------------ statements


def _parse(lines, label: str, stem: str, warnings: list[str]) -> _Parsed:
    """Sort the statements by kind; the numbers stay text until `_rows` converts each kind at once."""
    p = _Parsed()
    obj_name = group_name = material = None
    piece, group = -1, 0
    unsupported: set[str] = set()
    for number, line in lines:
        parts = line.split()
        key = parts[0]
        if key == "v":
            p.v.append(parts)
            p.v_line.append(number)
        elif key == "vt":
            p.vt.append(parts)
            p.vt_line.append(number)
        elif key == "vn":
            p.vn.append(parts)
            p.vn_line.append(number)
        elif key == "f" or key == "fo":
            if len(parts) < 4:
                raise LumosError(f"{label}:{number}: a face needs at least 3 vertices, got {len(parts) - 1}")
            if piece < 0:
                piece_key = (group_name or obj_name or stem, material)
                piece = p.pieces.setdefault(piece_key, len(p.pieces))
            p.corners.extend(parts[1:])
            p.face_len.append(len(parts) - 1)
            p.face_line.append(number)
            p.face_piece.append(piece)
            p.face_group.append(group)
            p.face_counts.append((len(p.v), len(p.vt), len(p.vn)))
        elif key in ("o", "g", "usemtl"):
            name = " ".join(parts[1:]) or None
            if key == "o":
                obj_name, group_name = name, None
            elif key == "g":
                group_name = name
            else:
                material = name
                if name is None:
                    warnings.append(f"{label}:{number}: usemtl without a name; the default material is used")
                else:
                    p.usemtl_line.setdefault(name, number)
            piece = -1
        elif key == "s":
            group = _smoothing_group(parts, number, label)
            p.any_group = True
        elif key == "mtllib":
            rest = line.split(None, 1)[1].strip() if len(parts) > 1 else ""
            if rest:
                p.mtllibs.append((number, rest))
        elif key not in _QUIET and key not in unsupported:
            unsupported.add(key)
            warnings.append(f"{label}:{number}: '{key[:40]}' statements are not supported; ignored")
    return p


def _smoothing_group(parts: list[str], number: int, label: str) -> int:
    if len(parts) < 2:
        raise LumosError(f"{label}:{number}: s needs a smoothing group (off or a number)")
    word = parts[1].lower()
    if word == "off":
        return 0
    try:
        value = int(word)
    except ValueError:
        raise LumosError(f"{label}:{number}: s: '{parts[1][:40]}' is not off or a group number") from None
    if not 0 <= value <= _MAX_GROUP:
        raise LumosError(f"{label}:{number}: s: smoothing group {value} is outside 0..{_MAX_GROUP}")
    return value


def _rows(rows: list[list[str]], line_of: list[int], need: int, take: int, kind: str, label: str) -> np.ndarray:
    """The numbers of every `kind` statement as float64 (len(rows), take): the first `take` numbers of each
    (missing ones after `need` are 0: vt's v; extra ones are ignored: v's w and vertex colours)."""
    out = np.zeros((len(rows), take), dtype=np.float64)
    if not rows:
        return out
    lengths = np.fromiter(map(len, rows), dtype=np.int64, count=len(rows)) - 1
    problems = []                                            # (row, message): the first in the file is reported
    short = np.flatnonzero(lengths < need)
    if len(short):
        i = int(short[0])
        problems.append((i, f"{kind} needs {need} number{'s' if need > 1 else ''}, got {lengths[i]}"))
    width_of = np.clip(lengths, need, take)
    for width in np.unique(width_of):
        ids = np.flatnonzero((width_of == width) & (lengths >= need))
        if not len(ids):
            continue
        text = np.array([rows[i][1:1 + width] for i in ids])
        try:
            out[ids, :width] = text.astype(np.float64)
        except (ValueError, OverflowError):
            problems.append(_bad_number(rows, ids, width, kind))
    bad = ~np.isfinite(out).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        problems.append((i, f"{kind}: {' '.join(rows[i][1:1 + take])[:60]} is not finite (NaN or infinity)"))
    if problems:
        i, message = min(problems)
        raise LumosError(f"{label}:{line_of[i]}: {message}")
    return out


def _bad_number(rows, ids, width, kind) -> tuple[int, str]:
    """The first row among `ids` with a token that float() refuses, and what is wrong with it."""
    for i in ids:
        for token in rows[i][1:1 + width]:
            try:
                float(token)
            except ValueError:
                return int(i), f"{kind}: '{token[:40]}' is not a number"
    return int(ids[0]), f"{kind}: unreadable numbers"


def _corner_indices(p: _Parsed, nv: int, nvt: int, nvn: int, label: str, warnings: list[str]):
    """Zero-based (v, vt, vn) of every face corner (-1 where a corner gives no vt or vn) and its face (c,)."""
    face_len = np.asarray(p.face_len, dtype=np.int64)
    corner_face = np.repeat(np.arange(len(face_len)), face_len)
    split = np.array([(c + "//").split("/")[:3] for c in p.corners])           # (c, 3) str
    counts = np.asarray(p.face_counts, dtype=np.int64)[corner_face]            # (c, 3) defined before the face
    resolved = []
    for column, (kind, total) in enumerate((("vertex", nv), ("texture coordinate", nvt), ("normal", nvn))):
        text = split[:, column]
        given = text != ""
        if column > 0 and total == 0 and given.any():   # references to a kind the file never defines
            c = int(np.argmax(given))
            warnings.append(f"{label}:{p.face_line[corner_face[c]]}: faces refer to {kind}s but the file defines "
                            "none; those references are ignored")
            given[:] = False
        if column == 0 and not given.all():
            c = int(np.argmin(given))
            raise LumosError(f"{label}:{p.face_line[corner_face[c]]}: f: corner '{p.corners[c][:40]}' has no "
                             "vertex index")
        try:
            index = np.where(given, text, "0").astype(np.int64)
        except (ValueError, OverflowError):
            c = next((i for i, t in enumerate(text) if t and not _is_int(t)), 0)
            raise LumosError(f"{label}:{p.face_line[corner_face[c]]}: f: '{p.corners[c][:40]}' is not a "
                             f"vertex reference (v, v/vt, v//vn or v/vt/vn)") from None
        # 1-based, or negative: counted back from the last one defined before the face (-1 is that one)
        zero = np.where(index > 0, index - 1, counts[:, column] + index)
        bad = given & ((index == 0) | (zero < 0) | (zero >= total))
        if bad.any():
            c = int(np.argmax(bad))
            raise LumosError(f"{label}:{p.face_line[corner_face[c]]}: f: {kind} index {index[c]} is out of range "
                             f"(the file has {total} {kind}{'s' if total != 1 else ''}"
                             + (f", {counts[c, column]} before this face)" if index[c] < 0 else ")"))
        resolved.append(np.where(given, zero, -1))
    return resolved[0], resolved[1], resolved[2], corner_face


def _is_int(text: str) -> bool:
    """Whether `text` is an index NumPy reads as int64."""
    try:
        return abs(int(text)) < 1 << 62
    except ValueError:
        return False


def _triangles(corner_positions: np.ndarray, face_len: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangles (t, 3) of corner ids, in face order, and the face each came from (t,)."""
    starts = np.r_[0, np.cumsum(face_len)[:-1]]
    tri_ids = np.flatnonzero(face_len == 3)
    parts = [starts[tri_ids, None] + np.arange(3)]
    part_face = [tri_ids]
    poly_ids = np.flatnonzero(face_len > 3)
    if len(poly_ids):
        # Triangulated in a frame scaled to unit size (the ear test squares lengths: huge files stay finite).
        scale = max(float(np.abs(corner_positions).max()), 1e-300)
        polygons = [np.arange(starts[f], starts[f] + face_len[f]) for f in poly_ids]
        with np.errstate(all="ignore"):
            faces, face_polygon = triangulate(corner_positions / scale, polygons)
        parts.append(faces)
        part_face.append(poly_ids[face_polygon])
    triangles, triangle_face = np.concatenate(parts), np.concatenate(part_face)
    order = np.argsort(triangle_face, kind="stable")
    return triangles[order], triangle_face[order]


# --------------------------------------------------------------------------------------------------- normals


def _corner_normals(p: _Parsed, positions, normals, corner_v, corner_vn, corner_face, triangles):
    """Which normal each corner takes (c,) and the table of normals (k, 3) those ids index.

    A corner's own `vn` (when not zero) wins; otherwise the corner shares the angle-weighted normal of its
    smoothing group at its vertex (group > 0), or takes its face's normal (group 0).
    """
    group = np.asarray(p.face_group, dtype=np.int64)[corner_face]
    nv = len(positions)
    # One key per (group, position) for smooth corners, per (face, vertex) for flat ones: a position the file
    # repeats (a seam between patches) is one vertex of its smoothing group (`weld_ids`)
    welded = weld_ids(positions)[corner_v]
    key = np.where(group > 0, group * nv + welded, -(corner_face * nv + corner_v) - 1)
    unique_keys, key_id = np.unique(key, return_inverse=True)
    key_vertex = np.empty(len(unique_keys), dtype=np.int64)
    key_vertex[key_id] = corner_v
    scale = max(float(np.abs(positions).max()), 1e-300)
    with np.errstate(all="ignore"):
        _, _, computed, _ = vertex_normals(positions[key_vertex] / scale, key_id[triangles], weighting="angle",
                                           weld=False)  # the keys already weld, and keep the groups apart

    length = np.linalg.norm(normals, axis=1)
    usable = np.zeros(len(corner_vn), dtype=bool)
    given = corner_vn >= 0
    usable[given] = length[corner_vn[given]] > 0
    table = np.concatenate([normals / np.where(length > 0, length, 1.0)[:, None], computed])
    return np.where(usable, corner_vn, len(normals) + key_id), table


# ------------------------------------------------------------------------------------------- pieces, materials


def _mesh(name, material, tris, corner_v, corner_vt, corner_normal, positions, uvs, normal_table, label,
          warnings) -> dict:
    """One mesh object: its triangles' corners made into vertices, split only where uv or normal differ."""
    corners = tris.ravel()
    keys = np.stack([corner_v[corners], corner_vt[corners], corner_normal[corners]], axis=1)
    unique, inverse = np.unique(keys, axis=0, return_inverse=True)
    obj = {"type": "mesh", "name": name, "material": material, "vertices": positions[unique[:, 0]],
           "faces": inverse.reshape(-1, 3).astype(np.int64)}
    if normal_table is not None:
        obj["normals"] = normal_table[unique[:, 2]]
    has_uv = unique[:, 1] >= 0
    if has_uv.any():
        if not has_uv.all():
            warnings.append(f"{label}: object '{name}': some face corners have texture coordinates and some do "
                            "not; those without get (0, 0)")
        obj["uvs"] = np.where(has_uv[:, None], uvs[np.maximum(unique[:, 1], 0)], 0.0)
    return obj


def _materials(p: _Parsed, folder: Path, label: str, warnings: list[str]) -> dict[str, dict]:
    """The materials of every `mtllib`, plus a default for each `usemtl` name none of them defines."""
    materials: dict[str, dict] = {}
    for number, rest in p.mtllibs:
        whole = find_file(folder, rest)
        names = [rest] if whole is not None or len(rest.split()) == 1 else rest.split()
        for name in names:
            mtl = whole if len(names) == 1 and whole is not None else find_file(folder, name)
            if mtl is None:
                warnings.append(f"{label}:{number}: material library '{name}' not found; its materials get "
                                "the default")
                continue
            try:
                found, notes = read_mtl(mtl, os.path.join(os.path.dirname(label), name))
            except OSError as exc:
                warnings.append(f"{label}:{number}: cannot read material library '{name}' "
                                f"({exc.strerror or type(exc).__name__}); its materials get the default")
                continue
            materials.update(found)
            warnings.extend(notes)
    used = {material for _, material in p.pieces if material is not None}
    for name in sorted(used - set(materials), key=lambda n: p.usemtl_line.get(n, 0)):
        warnings.append(f"{label}:{p.usemtl_line.get(name, 0)}: usemtl '{name}': no material library defines "
                        "it; the default matte grey is used")
        materials[name] = dict(UNDEFINED_MATERIAL)
    return materials
