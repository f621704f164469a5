"""Scene → the polygon list the scan-line renderer draws (`RasterMesh`).

Every object becomes polygons in world space with a shading normal at each vertex: meshes as given (after the
fix-ups they ask for: T-junction repair, triangulation, subdivision, vertex normals averaged from the faces
that share a vertex), analytic shapes tessellated at `render.tessellation` segments with their exact normals,
csg objects as their solids' tessellations combined by mesh booleans (`compile.csg_mesh`), planes as a large
patch around the camera, and area lights as emitting polygons the camera can see. Objects are drawn where they
are at time 0: `motion` is not read (no motion blur).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import mesh as meshops
from ..kernels import layout as L
from .csg_mesh import csg_pieces
from .meshprep import facet, prepare_mesh
from .shapes import canonical
from .tessellate import tessellate_object, tessellate_plane


@dataclass
class RasterMesh:
    positions: np.ndarray  # float64 (nv, 3) world space
    normals: np.ndarray  # float64 (nv, 3) unit shading normals
    uvs: np.ndarray  # float64 (nv, 2)
    prim_start: np.ndarray  # int64 (np + 1,): polygon p has vertices prim_index[prim_start[p]:prim_start[p + 1]]
    prim_index: np.ndarray  # int32
    prim_info: np.ndarray  # int32 (np, 3): material, object, area light (or -1)
    prim_point: np.ndarray  # float64 (np, 3): where flat shading evaluates the model (the polygon's centroid)
    prim_normal: np.ndarray  # float64 (np, 3): the polygon's unit face normal (its winding's side)
    prim_uv: np.ndarray = None  # float64 (np, 2): the surface coordinates at prim_point (flat shading's texture)

    @property
    def n_prims(self) -> int:
        return len(self.prim_start) - 1

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """Every polygon as triangles: (faces (m, 3) int64, prim of each triangle (m,) int64)."""
        counts = np.diff(self.prim_start)
        if np.all(counts == 3):
            return self.prim_index.reshape(-1, 3).astype(np.int64), np.arange(self.n_prims)
        polys = [self.prim_index[a:b] for a, b in zip(self.prim_start[:-1], self.prim_start[1:])]
        return meshops.triangulate(self.positions, polys)

    def uv_frames(self) -> np.ndarray:
        """float64 (np, 12) per polygon: ∂p/∂u, ∂p/∂v (world space, for bump maps) and the gradients of u and of
        v with respect to the world position within the polygon's plane (∇u·∂p/∂u = 1, ∇u·∂p/∂v = 0, and so on:
        a pixel's texture footprint is ∇u·dp/dx, ...), from its largest triangle's uvs. A polygon whose uvs are
        degenerate gets zero rows: no bump, and its textures are looked up unfiltered."""
        faces, prim = self.triangles()
        out = np.zeros((self.n_prims, 12))
        if not len(faces):
            return out
        p0, p1, p2 = (self.positions[faces[:, k]] for k in range(3))
        t0, t1, t2 = (self.uvs[faces[:, k]] for k in range(3))
        e1, e2 = p1 - p0, p2 - p0
        du1, dv1 = t1[:, 0] - t0[:, 0], t1[:, 1] - t0[:, 1]
        du2, dv2 = t2[:, 0] - t0[:, 0], t2[:, 1] - t0[:, 1]
        det = du1 * dv2 - dv1 * du2
        area = np.linalg.norm(np.cross(e1, e2), axis=1)
        ok = (det != 0.0) & (area > 0.0)
        inv = np.divide(1.0, det, out=np.zeros_like(det), where=ok)[:, None]
        dpdu = (dv2[:, None] * e1 - dv1[:, None] * e2) * inv
        dpdv = (du1[:, None] * e2 - du2[:, None] * e1) * inv
        n = np.cross(dpdu, dpdv)
        a = np.cross(dpdv, n)  # ⊥ ∂p/∂v, in the plane
        b = np.cross(n, dpdu)  # ⊥ ∂p/∂u, in the plane
        ga = np.einsum("ij,ij->i", a, dpdu)
        gb = np.einsum("ij,ij->i", b, dpdv)
        ok &= (ga != 0.0) & (gb != 0.0) & np.isfinite(ga) & np.isfinite(gb)
        grad_u = np.divide(a, ga[:, None], out=np.zeros_like(a), where=ok[:, None])
        grad_v = np.divide(b, gb[:, None], out=np.zeros_like(b), where=ok[:, None])
        frames = np.where(ok[:, None], np.concatenate([dpdu, dpdv, grad_u, grad_v], axis=1), 0.0)
        # each polygon takes its largest triangle's frame
        best = np.lexsort((np.where(ok, area, -1.0), prim))
        last = np.r_[prim[best][1:] != prim[best][:-1], True]
        out[prim[best][last]] = frames[best][last]
        return out


class _Part:
    __slots__ = ("verts", "normals", "uvs", "polys", "groups", "material", "object", "light")

    def __init__(self, verts, normals, uvs, polys, groups, material, object_id, light=-1):
        self.verts, self.normals, self.uvs = verts, normals, uvs
        self.polys = polys  # (m, 3) int64 triangles, or a list of index arrays (polygons)
        self.groups = groups  # triangles only: flat-shading group of each triangle
        self.material, self.object, self.light = material, object_id, light


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)


def _mesh_part(obj, world_from_object, material, object_id) -> _Part:
    m = prepare_mesh(obj, world_from_object, keep_polygons=True)
    if m.normals is None:
        m = facet(m)
    uvs = m.uvs if m.uvs is not None else np.zeros((len(m.vertices), 2))
    return _Part(m.vertices, m.normals, uvs, m.polygons, m.groups, material, object_id)


def _tess_part(t, material, object_id, light=-1) -> _Part:
    return _Part(t.vertices, t.normals, t.uvs, t.faces, t.groups, material, object_id, light)


def _plane_part(world_from_canonical, center, extent, segments, material, object_id) -> _Part:
    """A plane as a square patch around `center` reaching 50 extents out on each side, its grid lines spaced
    quadratically so that cells are small near the camera and large towards the horizon."""
    t = tessellate_plane(world_from_canonical, center, 1.0, segments)
    m = world_from_canonical
    e1 = m[:3, 0] / np.linalg.norm(m[:3, 0])
    e2 = m[:3, 1] / np.linalg.norm(m[:3, 1])
    origin = t.vertices.mean(axis=0)
    d = t.vertices - origin
    a, b = d @ e1, d @ e2
    far = 50.0 * extent
    a, b = np.sign(a) * a * a * far, np.sign(b) * b * b * far
    verts = origin + a[:, None] * e1 + b[:, None] * e2
    inv = np.linalg.inv(m)
    local = verts @ inv[:3, :3].T + inv[:3, 3]
    return _Part(verts, t.normals, local[:, :2].copy(), t.faces, t.groups, material, object_id)


def build_raster_mesh(scene, segments: int, object_materials: list, emitters: list, *, material_row) -> RasterMesh:
    """The polygons of `scene`. `object_materials[i]` is object i's material row; `emitters` lists the area
    lights' (shape kind, world_from_canonical, material row, light index); `material_row(material, one_sided)`
    gives the row of a scene Material (for the solids of csg objects that have their own)."""
    cam = np.asarray(scene.camera.position, dtype=np.float64)
    parts = []
    analytic_points = [cam]
    for obj in scene.objects:
        if obj.type in ("triangle", "mesh", "csg"):
            continue
        if obj.type != "plane":
            kind, m = canonical(obj)
            w = obj.transform.to_matrix() @ m if obj.transform is not None else m
            analytic_points.append(w[:3, 3])
    for object_id, obj in enumerate(scene.objects):
        mat = object_materials[object_id]
        world_from_object = None if obj.transform is None else obj.transform.to_matrix()
        if obj.type in ("triangle", "mesh", "csg"):
            if obj.type == "csg":
                new = [_Part(p.vertices, p.normals, p.uvs, p.faces, p.groups, material_row(p.material, not obj.two_sided),
                              object_id)
                       for p in csg_pieces(scene, obj, world_from_object, segments, f"objects[{object_id}]")]
            else:
                new = [_mesh_part(obj, world_from_object, mat, object_id)]
            for part in new:
                parts.append(part)
                analytic_points.append(part.verts.min(axis=0))
                analytic_points.append(part.verts.max(axis=0))
            continue
        kind, m = canonical(obj)
        w = m if world_from_object is None else world_from_object @ m
        if kind == L.SHAPE_PLANE:
            continue  # after the extent of everything else is known
        t = tessellate_object(kind, w, segments, getattr(obj, "capped", True), f"objects[{object_id}]")
        parts.append(_tess_part(t, mat, object_id))
    pts = np.array(analytic_points)
    extent = max(float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))), 1.0)
    for object_id, obj in enumerate(scene.objects):
        if obj.type == "plane":
            kind, m = canonical(obj)
            w = m if obj.transform is None else obj.transform.to_matrix() @ m
            parts.append(_plane_part(w, cam, extent, segments, object_materials[object_id], object_id))
    n_objects = len(scene.objects)
    for kind, w, mat, light in emitters:
        t = tessellate_object(kind, w, segments, True, f"lights[{light}]", "light")
        parts.append(_tess_part(t, mat, n_objects + light, light))
    return _assemble(parts)


def _assemble(parts) -> RasterMesh:
    positions, normals, uvs, starts, indices, infos, points, fnormals, cuvs = [], [], [], [], [], [], [], [], []
    v_off = 0
    i_off = 0
    for p in parts:
        verts = np.asarray(p.verts, dtype=np.float64)
        if isinstance(p.polys, list):
            counts = np.array([len(q) for q in p.polys], np.int64)
            idx = np.concatenate([np.asarray(q, np.int64) for q in p.polys]) if p.polys else np.zeros(0, np.int64)
            # flat shading per polygon: the centroid and the Newell normal
            pt = np.array([verts[q].mean(axis=0) for q in p.polys]).reshape(-1, 3)
            nn = np.array([_newell(verts[q]) for q in p.polys]).reshape(-1, 3)
            cuv = np.array([np.asarray(p.uvs, np.float64)[q].mean(axis=0) for q in p.polys]).reshape(-1, 2)
        else:
            faces = np.asarray(p.polys, np.int64).reshape(-1, 3)
            counts = np.full(len(faces), 3, np.int64)
            idx = faces.ravel()
            pt, nn, cuv = _group_flat(verts, np.asarray(p.uvs, np.float64), faces, np.asarray(p.groups, np.int64))
        positions.append(verts)
        normals.append(np.asarray(p.normals, np.float64))
        uvs.append(np.asarray(p.uvs, np.float64))
        starts.append(i_off + np.concatenate([[0], np.cumsum(counts)[:-1]]) if len(counts) else np.zeros(0, np.int64))
        indices.append(idx + v_off)
        info = np.empty((len(counts), 3), np.int32)
        info[:] = (p.material, p.object, p.light)
        infos.append(info)
        points.append(pt)
        cuvs.append(cuv)
        fnormals.append(_unit(nn))
        v_off += len(verts)
        i_off += len(idx)
    if not parts:
        return RasterMesh(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 2)), np.zeros(1, np.int64),
                          np.zeros(0, np.int32), np.zeros((0, 3), np.int32), np.zeros((0, 3)), np.zeros((0, 3)),
                          np.zeros((0, 2)))
    prim_start = np.concatenate(starts + [np.array([i_off], np.int64)]).astype(np.int64)
    return RasterMesh(
        np.ascontiguousarray(np.concatenate(positions)),
        np.ascontiguousarray(np.concatenate(normals)),
        np.ascontiguousarray(np.concatenate(uvs)),
        prim_start,
        np.concatenate(indices).astype(np.int32),
        np.ascontiguousarray(np.concatenate(infos)),
        np.ascontiguousarray(np.concatenate(points)),
        np.ascontiguousarray(np.concatenate(fnormals)),
        np.ascontiguousarray(np.concatenate(cuvs)),
    )


def _newell(p: np.ndarray) -> np.ndarray:
    q = np.roll(p, -1, axis=0)
    return np.array([
        np.sum((p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2])),
        np.sum((p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0])),
        np.sum((p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1])),
    ])


def _group_flat(verts, uvs, faces, groups):
    """Per triangle: its group's area-weighted centroid, its group's normal (sum of the cross products) and the
    surface coordinates at that centroid (the area-weighted mean of the triangles' centroid uvs)."""
    v0, v1, v2 = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    cr = np.cross(v1 - v0, v2 - v0)
    area = np.linalg.norm(cr, axis=1)
    cen = (v0 + v1 + v2) / 3.0
    cuv = (uvs[faces[:, 0]] + uvs[faces[:, 1]] + uvs[faces[:, 2]]) / 3.0
    if len(groups) and np.array_equal(groups, np.arange(len(faces))):
        return cen, cr, cuv
    ng = int(groups.max()) + 1 if len(groups) else 0
    gn = np.stack([np.bincount(groups, cr[:, k], ng) for k in range(3)], axis=1)
    ga = np.bincount(groups, area, ng)
    gc = np.stack([np.bincount(groups, cen[:, k] * area, ng) for k in range(3)], axis=1)
    gc = np.divide(gc, ga[:, None], out=np.zeros_like(gc), where=ga[:, None] > 0)
    gu = np.stack([np.bincount(groups, cuv[:, k] * area, ng) for k in range(2)], axis=1)
    gu = np.divide(gu, ga[:, None], out=np.zeros_like(gu), where=ga[:, None] > 0)
    # a group of zero area keeps its own triangle's centroid
    has_area = ga[groups][:, None] > 0
    return np.where(has_area, gc[groups], cen), gn[groups], np.where(has_area, gu[groups], cuv)
