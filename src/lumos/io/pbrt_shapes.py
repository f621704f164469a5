"""pbrt-v4 shapes as lumos objects and area lights.

    items = shape_items(record, world, material, variants, ctx)
    # [("object", {...}) or ("light", {...})], in world space (`world`: the 4×4 world_from_object matrix);
    # variants.emissive(material, rgb) and variants.cut_out(material, texture) name derived materials

- `sphere`, `disk`, `cylinder` (whole): lumos's `sphere`, `disk`, `cylinder` (`capped: false`: pbrt's has no caps);
  partial ones (`zmin`/`zmax`, `phimax`, `innerradius`) a tessellated `mesh`.
- `trianglemesh`: a `mesh` with `vertices` (in world space), `faces`, `normals` (`N`), `uvs` (`uv`); `smooth: false`
  without `N` (pbrt shades such meshes flat). `bilinearmesh`: each patch two triangles, (p00, p10, p11) and
  (p00, p11, p01) (exact for flat patches). `loopsubdiv`: a `mesh` with `subdivide: levels` (at most 6).
- `plymesh`: a `mesh` with `file` (relative to the main file's folder, as pbrt resolves it) and a `transform`
  (`.ply.gz` decompressed to a cache folder). `curve` and others: left out, with a warning.

Emitters (a shape under an `AreaLightSource "diffuse"`): a whole sphere, a whole disk, and a mesh that is one
flat parallelogram (two triangles) become lumos area lights (`sphere`, `disk`, `rect`) whose `material` is the
shape's, so they reflect as pbrt's do and light every method; every other emitter is an object whose material
emits (`emission`), `two_sided` as the light's `twosided`. The emitting side is pbrt's: the shape's outside (a
sphere, a cylinder), its +z side (a disk), its counter-clockwise side (triangles; the side of `N` when the mesh
has normals), reversed by ReverseOrientation, and kept through transforms that mirror (pbrt flips the normal
of a shape whose transform swaps handedness). Meshes are written in world space with their faces wound so that
their counter-clockwise side is that front.

`power` (pbrt's watts) sets the radiance L = power/(k·A·π), k = 2 for a two-sided light: A is the shape's area as
pbrt measures it (spheres, disks, cylinders in their own units, before the transform; triangles in world units,
and per triangle: pbrt scales each triangle of a mesh by its own area, so here by the mean triangle's).
"""

from __future__ import annotations

import gzip
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from .pbrt_textures import Context, texture_ref, tidy
from .pbrt_tokens import Params, Where

#: segments around a full circle, and rings over a full sphere, when a partial quadric is tessellated
_SEGMENTS, _RINGS = 64, 32


@dataclass
class Emission:
    """An AreaLightSource in force: its radiance (L × scale), sides and `power` (≤ 0: none)."""

    rgb: tuple
    two_sided: bool
    power: float
    where: Where


@dataclass
class ShapeRecord:
    """A Shape statement with the graphics state it was given in."""

    kind: str
    params: Params
    ctm: np.ndarray
    reverse: bool
    material: object
    emission: Optional[Emission]
    where: Where


def shape_items(rec: ShapeRecord, world: np.ndarray, material: str, variants, ctx: Context) -> list[tuple[str, dict]]:
    """The lumos objects and lights of one shape. `variants.emissive(material, rgb)` names the emitting variant of a
    material, `variants.cut_out(material, texture)` its variant with an opacity texture (pbrt's `alpha`)."""
    ps, kind = rec.params, rec.kind
    if abs(np.linalg.det(world[:3, :3])) < 1e-300 or not np.all(np.isfinite(world)):
        ctx.warn.once(("singular",), rec.where, f"Shape '{kind}' under a transform that flattens it: left out")
        ps.ignore(*ps.params)
        return []
    alpha = ps.get("alpha")
    if alpha is not None:
        material = _alpha(alpha, material, variants, ctx, rec.where)
        if material is None:
            ps.ignore(*ps.params)
            return []
    emissive = variants.emissive
    ps.ignore("emissionfilename")
    emit = rec.emission if rec.emission is not None and any(rec.emission.rgb) else None
    if kind in ("sphere", "disk", "cylinder"):
        items = _quadric(rec, world, material, emit, emissive, ctx)
    elif kind in ("trianglemesh", "bilinearmesh", "loopsubdiv"):
        items = _inline_mesh(rec, world, material, emit, emissive, ctx)
    elif kind == "plymesh":
        items = _plymesh(rec, world, material, emit, emissive, ctx)
    else:
        status = "not supported" if kind == "curve" else "unknown"
        ctx.warn.once(("shape", kind), rec.where, f"Shape '{kind}' is {status}: left out")
        ps.ignore(*ps.params)
        items = []
    for p in ps.unused():
        ctx.warn.once(("param", "Shape", kind, p.name), p.where, f"Shape '{kind}': parameter \"{p.type} {p.name}\" "
                      f"is not used")
    return items


def _alpha(p, material: str, variants, ctx: Context, where: Where) -> Optional[str]:
    """The material of a shape with pbrt's `alpha`: an image texture cuts it out (lumos's opacity, a hole where
    α < 0.5; pbrt's alpha is stochastic in between), a constant 0 removes it (None), other values keep it whole."""
    if p.type == "texture":
        tex = texture_ref(p, "float", ctx)
        if tex.pattern is not None and tex.pattern["type"] == "image":
            return variants.cut_out(material, tex.pattern)
        value = tex.scalar
    else:
        value = float(p.values[0]) if p.values else 1.0
    if value <= 0:
        return None
    if value < 1:
        ctx.warn.once(("alpha",), where, f"\"alpha\" {value:g}: lumos has no partial coverage; the whole shape "
                      f"stands")
    return material


# ---------------------------------------------------------------------------------------------- quadrics


def _similarity(m: np.ndarray) -> Optional[float]:
    """The scale s when m's linear part is s times an orthogonal matrix (a rotation or a mirror), else None."""
    lin = m[:3, :3]
    gram = lin.T @ lin
    s2 = float(np.trace(gram) / 3.0)
    if s2 <= 0 or np.abs(gram - s2 * np.eye(3)).max() > 1e-9 * max(s2, 1.0):
        return None
    return math.sqrt(s2)


def _point(m: np.ndarray, p) -> list:
    return [float(v) for v in m[:3, :3] @ np.asarray(p, dtype=np.float64) + m[:3, 3]]


def _normal(m: np.ndarray, n) -> list:
    v = np.linalg.inv(m[:3, :3]).T @ np.asarray(n, dtype=np.float64)
    return [float(c) for c in v / np.linalg.norm(v)]


def _matrix(m: np.ndarray) -> dict:
    return {"matrix": [[float(v) for v in row] for row in m]}


def _quadric(rec: ShapeRecord, world, material, emit, emissive, ctx) -> list:
    """A sphere, disk or cylinder: lumos's own shape (or area light) when whole, else a tessellated mesh."""
    r = rec.params.float("radius", 1.0)
    phimax = min(max(rec.params.float("phimax", 360.0), 0.0), 360.0)
    if r <= 0 or phimax <= 0:
        return []
    build = {"sphere": _sphere, "disk": _disk, "cylinder": _cylinder}[rec.kind]
    items, mesh, area = build(rec, r, phimax, world, material, emit)
    if items is not None:
        return items
    v, f = mesh[0], mesh[1]
    keep = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1) > 1e-12 * r * r
    if not keep.any() or not np.all(np.isfinite(v)):
        return []  # nothing left of it (zmin = zmax, an inner radius as large as the radius)
    obj = bake(v, f[keep], mesh[2], mesh[3], world, rec.reverse)  # without the poles' empty triangles
    return _emitting_or_not(obj, material, emit, emissive, area)


def _sphere(rec: ShapeRecord, r: float, phimax: float, world, material, emit) -> tuple:
    """(items, None, area) for a lumos sphere, or (None, mesh, area) for a tessellated one."""
    ps, s = rec.params, _similarity(world)
    zmin, zmax = sorted((min(max(ps.float("zmin", -r), -r), r), min(max(ps.float("zmax", r), -r), r)))
    whole = zmin <= -r and zmax >= r and phimax >= 360.0
    area = math.radians(phimax) * r * (zmax - zmin)
    if whole and emit is not None and s is not None and not rec.reverse:
        return [("light", {"type": "area", "shape": "sphere", "center": _point(world, (0, 0, 0)), "radius": r * s,
                           "radiance": _radiance(emit, area), "material": material})], None, area
    if whole and emit is None:
        if s is not None:
            return [("object", {"type": "sphere", "center": _point(world, (0, 0, 0)), "radius": r * s,
                                "material": material})], None, area
        return [("object", {"type": "sphere", "radius": r, "material": material,
                            "transform": _matrix(world)})], None, area
    return None, _sphere_mesh(r, zmin, zmax, math.radians(phimax)), area


def _disk(rec: ShapeRecord, r: float, phimax: float, world, material, emit) -> tuple:
    ps, s = rec.params, _similarity(world)
    h, ri = ps.float("height", 0.0), min(max(ps.float("innerradius", 0.0), 0.0), r)
    whole = ri <= 0 and phimax >= 360.0
    area = math.radians(phimax) * 0.5 * (r * r - ri * ri)
    front = (0.0, 0.0, -1.0 if rec.reverse else 1.0)
    if whole and s is not None:
        disk = {"center": _point(world, (0, 0, h)), "normal": _normal(world, front), "radius": r * s}
        if emit is not None:
            return [("light", {"type": "area", "shape": "disk", **disk, "radiance": _radiance(emit, area),
                               "two_sided": emit.two_sided, "material": material})], None, area
        return [("object", {"type": "disk", **disk, "material": material})], None, area
    if whole and emit is None:
        return [("object", {"type": "disk", "center": [0.0, 0.0, h], "normal": list(front), "radius": r,
                            "material": material, "transform": _matrix(world)})], None, area
    return None, _disk_mesh(r, ri, h, math.radians(phimax)), area


def _cylinder(rec: ShapeRecord, r: float, phimax: float, world, material, emit) -> tuple:
    ps, s = rec.params, _similarity(world)
    zmin, zmax = sorted((ps.float("zmin", -1.0), ps.float("zmax", 1.0)))
    if zmax - zmin <= 0:
        return [], None, 0.0
    area = math.radians(phimax) * r * (zmax - zmin)
    if phimax >= 360.0 and emit is None:
        if s is not None:
            return [("object", {"type": "cylinder", "base": _point(world, (0, 0, zmin)),
                                "top": _point(world, (0, 0, zmax)), "radius": r * s, "capped": False,
                                "material": material})], None, area
        return [("object", {"type": "cylinder", "base": [0.0, 0.0, zmin], "top": [0.0, 0.0, zmax], "radius": r,
                            "capped": False, "material": material, "transform": _matrix(world)})], None, area
    return None, _cylinder_mesh(r, zmin, zmax, math.radians(phimax)), area


def _grid_faces(rows: int, cols: int) -> np.ndarray:
    """Two triangles per cell of a (rows+1) × (cols+1) vertex grid, counter-clockwise in (column, row)."""
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = (i * (cols + 1) + j).ravel()
    b, c, d = a + 1, a + cols + 2, a + cols + 1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def _sphere_mesh(r, zmin, zmax, phimax):
    t0, t1 = math.acos(max(min(zmax / r, 1.0), -1.0)), math.acos(max(min(zmin / r, 1.0), -1.0))
    t1 = max(t1, t0 + 1e-12)
    rows, cols = max(int(_RINGS * (t1 - t0) / math.pi), 2), max(int(_SEGMENTS * phimax / (2 * math.pi)), 3)
    theta, phi = np.meshgrid(np.linspace(t0, t1, rows + 1), np.linspace(0, phimax, cols + 1), indexing="ij")
    n = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1).reshape(-1, 3)
    uv = np.stack([phi / phimax, 1 - (theta - t0) / (t1 - t0)], -1).reshape(-1, 2)
    return r * n, _grid_faces(rows, cols), n, uv


def _disk_mesh(r, ri, h, phimax):
    rows, cols = 2, max(int(_SEGMENTS * phimax / (2 * math.pi)), 3)
    rho, phi = np.meshgrid(np.linspace(max(ri, 1e-9 * r), r, rows + 1), np.linspace(0, phimax, cols + 1),
                           indexing="ij")
    v = np.stack([rho * np.cos(phi), rho * np.sin(phi), np.full_like(rho, h)], -1).reshape(-1, 3)
    n = np.tile([0.0, 0.0, 1.0], (len(v), 1))
    uv = np.stack([phi / phimax, (r - rho) / max(r - ri, 1e-300)], -1).reshape(-1, 2)
    return v, _grid_faces(rows, cols), n, uv


def _cylinder_mesh(r, zmin, zmax, phimax):
    rows, cols = 1, max(int(_SEGMENTS * phimax / (2 * math.pi)), 3)
    z, phi = np.meshgrid(np.linspace(zmin, zmax, rows + 1), np.linspace(0, phimax, cols + 1), indexing="ij")
    n = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], -1).reshape(-1, 3)
    v = n * r + np.stack([np.zeros_like(z), np.zeros_like(z), z], -1).reshape(-1, 3)
    uv = np.stack([phi / phimax, (z - zmin) / (zmax - zmin)], -1).reshape(-1, 2)
    return v, _grid_faces(rows, cols), n, uv


# ---------------------------------------------------------------------------------------------- meshes


def bake(v, faces, normals, uvs, world: np.ndarray, reverse: bool) -> dict:
    """A lumos mesh in world space whose counter-clockwise side is pbrt's front (see the module's doc)."""
    lin = world[:3, :3]
    vw = np.asarray(v, dtype=np.float64) @ lin.T + world[:3, 3]
    faces = np.array(faces, dtype=np.int64).reshape(-1, 3)
    ccw = np.cross(vw[faces[:, 1]] - vw[faces[:, 0]], vw[faces[:, 2]] - vw[faces[:, 0]])
    out = {"type": "mesh", "vertices": vw}
    if normals is not None:
        nw = np.asarray(normals, dtype=np.float64) @ np.linalg.inv(lin)
        length = np.linalg.norm(nw, axis=1, keepdims=True)
        nw = np.where(length > 0, nw / np.where(length > 0, length, 1.0), 0.0) * (-1.0 if reverse else 1.0)
        front = nw[faces].sum(axis=1)
        flip = np.einsum("ij,ij->i", ccw, front) < 0
        out["normals"] = nw
    else:
        flip = np.full(len(faces), (np.linalg.det(lin) < 0) != reverse)
    faces[flip] = faces[flip][:, ::-1]
    out["faces"] = faces
    if uvs is not None:
        out["uvs"] = np.asarray(uvs, dtype=np.float64)
    else:
        out["smooth"] = False
    return out


def _inline_mesh(rec: ShapeRecord, world, material, emit, emissive, ctx) -> list:
    ps, where = rec.params, rec.where
    p = _array(ps, "P", 3, ("point3",), where)
    if p is None or len(p) == 0:
        raise where.error(f"Shape '{rec.kind}' needs \"point3 P\"")
    per = 4 if rec.kind == "bilinearmesh" else 3
    idx = ps.floats("indices", "integer")
    if idx is None:
        if len(p) != per:
            raise where.error(f"Shape '{rec.kind}' needs \"integer indices\" (it has {len(p)} points)")
        idx = list(range(per))
    idx = np.asarray(idx, dtype=np.int64)
    if len(idx) % per:
        raise where.error(f"Shape '{rec.kind}': {len(idx)} indices is not a multiple of {per}")
    if len(idx) and (idx.min() < 0 or idx.max() >= len(p)):
        raise where.error(f"Shape '{rec.kind}': index {int(idx.max() if idx.max() >= len(p) else idx.min())} is out"
                          f" of range (there are {len(p)} points)")
    normals = _array(ps, "N", 3, ("normal",), where, len(p), ctx, rec.kind)
    uvs = _array(ps, "uv", 2, ("point2", "float"), where, len(p), ctx, rec.kind)
    if uvs is None:
        uvs = _array(ps, "st", 2, ("point2", "float"), where, len(p), ctx, rec.kind)
    ps.ignore("S", "faceIndices", "edgelength")
    if rec.kind == "bilinearmesh":
        q = idx.reshape(-1, 4)
        faces = np.concatenate([q[:, [0, 1, 3]], q[:, [0, 3, 2]]])
    else:
        faces = idx.reshape(-1, 3)
    obj = bake(p, faces, normals, uvs, world, rec.reverse)
    if rec.kind == "loopsubdiv":
        obj.update(subdivide=min(max(ps.int("levels", 3), 0), 6), subdivision="loop")
        obj.pop("smooth", None)
        return _emitting_or_not(obj, material, emit, emissive, _mean_area(obj) / 4 ** obj["subdivide"])
    return _emitting_mesh(obj, material, emit, emissive, 2 if rec.kind == "bilinearmesh" else 1)


def _array(ps: Params, name: str, size: int, types: tuple, where: Where, count: Optional[int] = None,
           ctx: Optional[Context] = None, kind: str = "") -> Optional[np.ndarray]:
    values = ps.floats(name, *types)
    if values is None:
        return None
    if len(values) % size:
        raise where.error(f"Shape: \"{name}\" needs a multiple of {size} numbers, got {len(values)}")
    arr = np.asarray(values, dtype=np.float64).reshape(-1, size)
    if count is not None and len(arr) != count:
        ctx.warn.once(("count", kind, name), where, f"Shape '{kind}': {len(arr)} \"{name}\" for {count} points: "
                      f"left out (as pbrt does)")
        return None
    return arr


def _rect(v: np.ndarray, faces: np.ndarray) -> Optional[tuple]:
    """(corner, edge_u, edge_v) when two triangles make one flat parallelogram facing one way, else None."""
    if len(faces) != 2:
        return None
    a, b = [list(f) for f in faces]
    shared = set(a) & set(b)
    if len(shared) != 2 or len(set(a) | set(b)) != 4:
        return None
    p, q = sorted(shared, key=a.index)
    r, s = (set(a) - shared).pop(), (set(b) - shared).pop()
    size = float(np.abs(v[[p, q, r, s]]).max()) + 1.0
    if np.abs(v[p] + v[q] - v[r] - v[s]).max() > 1e-9 * size:
        return None
    na = np.cross(v[a[1]] - v[a[0]], v[a[2]] - v[a[0]])
    nb = np.cross(v[b[1]] - v[b[0]], v[b[2]] - v[b[0]])
    if np.dot(na, nb) <= 0:
        return None
    eu, ev = v[p] - v[r], v[q] - v[r]
    if np.dot(np.cross(eu, ev), na) < 0:
        eu, ev = ev, eu
    return [float(c) for c in v[r]], [float(c) for c in eu], [float(c) for c in ev]


def _plymesh(rec: ShapeRecord, world, material, emit, emissive, ctx) -> list:
    ps, where = rec.params, rec.where
    filename = ps.string("filename", None)
    if not filename:
        raise where.error("Shape 'plymesh' needs \"string filename\"")
    if ps.get("displacement") is not None:
        ctx.warn.once(("displacement",), where, "\"displacement\" is not supported: the surface is drawn undisplaced")
    ps.ignore("edgelength")
    path = ctx.folder / filename
    if not path.is_file():
        raise where.error(f"Shape 'plymesh': no such file '{filename}'")
    if filename.lower().endswith(".gz"):
        filename = str(_gunzipped(path, where))
    if emit is None:
        return [("object", {"type": "mesh", "file": filename, "smooth": False, "transform": _matrix(world),
                            "material": material})]
    from .meshes import load_mesh

    mesh = load_mesh(ctx.folder / filename)
    return _emitting_mesh(bake(mesh.vertices, mesh.faces, mesh.normals, mesh.uvs, world, rec.reverse), material,
                          emit, emissive)


def _emitting_mesh(obj: dict, material: str, emit, emissive, per_light: int = 1) -> list:
    """A baked mesh, emitting or not: one flat parallelogram that emits is a rect area light. pbrt makes a light of
    each of its shapes, `per_light` triangles here (2 for a bilinear patch), whose area `power` is spread over."""
    v, tri = obj["vertices"], obj["faces"]
    mean_area = _mean_area(obj) * per_light
    rect = _rect(v, tri) if emit is not None else None
    if rect is not None:
        corner, eu, ev = rect
        return [("light", {"type": "area", "shape": "rect", "corner": corner, "edge_u": eu, "edge_v": ev,
                           "radiance": _radiance(emit, mean_area), "two_sided": emit.two_sided, "material": material})]
    return _emitting_or_not(obj, material, emit, emissive, mean_area)


def _mean_area(obj: dict) -> float:
    """The mean area of a baked mesh's triangles (pbrt scales `power` per triangle)."""
    v, tri = obj["vertices"], obj["faces"]
    areas = np.linalg.norm(np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]]), axis=1) / 2
    return float(areas.mean()) if len(areas) else 0.0


def _gunzipped(path: Path, where: Where) -> Path:
    """A .ply.gz decompressed once into the process's cache folder (lumos reads mesh files by name)."""
    from .gltf_materials import cache_folder

    try:
        data = gzip.decompress(path.read_bytes())
    except (OSError, EOFError) as exc:
        raise where.error(f"Shape 'plymesh': '{path.name}' is not a readable gzip file ({exc})") from None
    out = cache_folder() / f"{hashlib.sha256(data).hexdigest()[:16]}.ply"
    if not out.is_file():
        out.write_bytes(data)
    return out


# ---------------------------------------------------------------------------------------------- emission


def _radiance(emit: Emission, area: float) -> list:
    """L × scale, or with `power` the radiance that emits that many watts from a shape of this area."""
    rgb = emit.rgb
    if emit.power > 0:
        k = (2.0 if emit.two_sided else 1.0) * area * math.pi
        rgb = tuple(c * emit.power / k for c in rgb) if k > 0 else rgb
    return [tidy(c) for c in rgb]


def _emitting_or_not(obj: dict, material: str, emit, emissive, area: float) -> list:
    if emit is None:
        obj["material"] = material
        return [("object", obj)]
    obj["material"] = emissive(material, tuple(_radiance(emit, area)))
    obj["two_sided"] = emit.two_sided
    return [("object", obj)]
