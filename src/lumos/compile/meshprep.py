"""A mesh or triangle object → world-space polygons with the fix-ups its scene keys ask for.

The one place that reads the mesh keys, for every method: T-junction repair, triangulation (ear clipping),
Loop or midpoint subdivision, and vertex normals for meshes that have none (`smooth`, averaged from the faces
sharing each vertex with `normal_weighting`, not across edges sharper than `crease_angle`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Union

import numpy as np

from .. import mesh as meshops
from ..kernels.raster import MAX_VERTS


@dataclass
class PreparedMesh:
    vertices: np.ndarray  # (n, 3) float64, world space
    normals: Optional[np.ndarray]  # (n, 3) float64 unit vertex normals, or None: faceted (each face its own normal)
    uvs: Optional[np.ndarray]  # (n, 2) float64 or None
    polygons: Union[np.ndarray, list]  # (m, 3) int64 triangles, or (keep_polygons) a list of index arrays
    groups: Optional[np.ndarray]  # triangles: the polygon each came from (flat shading shades a polygon once)
    tangents: Optional[np.ndarray] = None  # (n, 4) float64 world-space tangent xyz + handedness w, or None


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)


def prepare_mesh(obj, world_from_object: Optional[np.ndarray], keep_polygons: bool = False) -> PreparedMesh:
    """World-space geometry of a `mesh` or `triangle` object. With `keep_polygons` (the scan-line renderer), a
    mesh with `triangulate: false` keeps its polygons (those with fewer than MAX_VERTS vertices)."""
    if obj.type == "triangle":
        verts = np.array(obj.vertices, dtype=np.float64)
        polys, normals, uvs = np.array([[0, 1, 2]], np.int64), None, None
        fix = None
        tangents = None
    else:
        fix = obj
        verts, normals, uvs = obj.vertices, obj.normals, obj.uvs
        tangents = getattr(obj, "tangents", None)
        as_polygons = obj.repair_t_junctions or (keep_polygons and not obj.triangulate)
        polys = obj.polygons if as_polygons else obj.faces
    if world_from_object is not None:
        verts = verts @ world_from_object[:3, :3].T + world_from_object[:3, 3]
        if normals is not None:
            normals = normals @ np.linalg.inv(world_from_object[:3, :3])  # inverse transpose, row vectors
        if tangents is not None:  # tangents are carried like edges; a mirror turns the handedness over
            linear = world_from_object[:3, :3]
            tangents = np.column_stack([tangents[:, :3] @ linear.T,
                                        tangents[:, 3] * np.sign(np.linalg.det(linear))])
    if fix is not None and fix.repair_t_junctions:
        # the inserted vertices are existing ones, so per-vertex normals and uvs stay valid
        polys = meshops.repair_t_junctions(verts, [np.asarray(p) for p in polys])
    groups = None if isinstance(polys, list) or fix is None else fix.face_polygon
    if isinstance(polys, list):
        keep = keep_polygons and not fix.triangulate and not fix.subdivide and all(len(p) < MAX_VERTS for p in polys)
        if not keep:
            polys, groups = meshops.triangulate(verts, polys)
    if fix is not None and fix.subdivide:
        verts, polys, uvs = meshops.subdivide(verts, polys, scheme=fix.subdivision, levels=fix.subdivide, uvs=uvs)
        normals, groups = None, None  # new vertices need new normals; each small triangle is its own polygon
        tangents = None  # and new tangents: the normal maps take their frame from the uvs
    if normals is None and fix is not None and fix.smooth:
        if isinstance(polys, list):  # polygons drawn as polygons
            verts, polys, normals, source = _polygon_normals(verts, polys, fix.normal_weighting, fix.crease_angle)
            if uvs is not None:
                uvs = uvs[source]
            if tangents is not None:
                tangents = tangents[source]
        else:
            verts, polys, normals, source = meshops.vertex_normals(
                verts, polys, weighting=fix.normal_weighting, crease_angle=fix.crease_angle)
            if uvs is not None:
                uvs = uvs[source]  # faces keep their order, so groups stay valid
            if tangents is not None:
                tangents = tangents[source]
    if normals is not None:
        normals = _unit(np.asarray(normals, dtype=np.float64))
    if groups is None and not isinstance(polys, list):
        groups = np.arange(len(polys))
    return PreparedMesh(verts, normals, uvs, polys, groups, tangents)


def _polygon_normals(verts, polys, weighting, crease_angle):
    """Vertex normals for polygons kept whole: computed on their triangles (crease splitting included), then
    each polygon corner takes the (possibly split) vertex its triangles gave that corner."""
    tris, owner = meshops.triangulate(verts, polys)
    verts2, tris2, normals, source = meshops.vertex_normals(verts, tris, weighting=weighting,
                                                            crease_angle=crease_angle)
    if len(verts2) == len(verts):
        return verts2, polys, normals, source
    corner = {}
    for (p, v_old, v_new) in zip(np.repeat(owner, 3), source[tris2.ravel()], tris2.ravel()):
        corner[(int(p), int(v_old))] = int(v_new)
    new_polys = [np.array([corner[(i, int(v))] for v in poly], np.int64) for i, poly in enumerate(polys)]
    return verts2, new_polys, normals, source


def facet(m: PreparedMesh) -> PreparedMesh:
    """Each polygon with vertices of its own whose normal is the polygon's (Newell) normal: flat facets for
    methods that need a normal at every vertex."""
    polys = list(m.polygons) if not isinstance(m.polygons, list) else m.polygons
    counts = np.array([len(p) for p in polys], np.int64)
    index = np.concatenate([np.asarray(p, np.int64) for p in polys])
    verts = m.vertices[index]
    uvs = None if m.uvs is None else m.uvs[index]
    p = verts
    q_index = np.arange(len(index)) + 1
    ends = np.cumsum(counts)
    q_index[ends - 1] = ends - counts  # each polygon's last vertex wraps to its first
    q = verts[q_index]
    cross = np.stack([(p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2]),
                      (p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0]),
                      (p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1])], axis=1)
    owner = np.repeat(np.arange(len(polys)), counts)
    newell = _unit(np.stack([np.bincount(owner, cross[:, k], len(polys)) for k in range(3)], axis=1))
    normals = newell[owner]
    starts = ends - counts
    if isinstance(m.polygons, list):
        new_polys = [np.arange(a, b) for a, b in zip(starts, ends)]
    else:
        new_polys = np.arange(len(index)).reshape(-1, 3)
    return PreparedMesh(verts, normals, uvs, new_polys, m.groups)


def mesh_triangles(obj, world_from_object):
    """World-space triangle vertices (m, 9), normals (m, 9) or None (facets) and uvs (m, 6) or None of a
    triangle or mesh object, after the fix-ups its keys ask for."""
    m = prepare_mesh(obj, world_from_object)
    faces = m.polygons
    tri_v = m.vertices[faces].reshape(-1, 9)
    tri_n = None if m.normals is None else m.normals[faces].reshape(-1, 9)
    tri_uv = None if m.uvs is None else m.uvs[faces].reshape(-1, 6)
    tri_t = None if m.tangents is None else m.tangents[faces].reshape(-1, 12)
    return tri_v, tri_n, tri_uv, tri_t
