"""A csg object → triangle meshes by mesh booleans, for the methods that draw polygons (raster).

    pieces = csg_pieces(scene, obj, world_from_object, segments, where="objects[3]")
    piece.vertices (n, 3)  piece.normals (n, 3)  piece.uvs (n, 2)  piece.faces (m, 3)  piece.groups (m,)
    piece.material (the scene Material of the solid the faces came from)

Each solid (leaf) is meshed in world space: spheres, boxes, cylinders and cones by `tessellate.tessellate_object`
at `segments` (with their exact normals and uvs), closed meshes by `meshprep.prepare_mesh` (faceted when they
have no normals). The leaves are combined along the csg tree by manifold3d (the Python binding of Emmett
Lalish's Manifold library, github.com/elalish/manifold, whose booleans return closed 2-manifolds), each
node's transform composed with its parents' as `compile.csg` does for the ray methods, so both see the same
solid.

What each face shows is carried through the booleans, not found again afterwards: a leaf's vertices hold
(x, y, z, nx, ny, nz, u, v) as manifold property channels, which the booleans interpolate at every new vertex
(where two surfaces cut each other), so a sphere's smooth normals stay smooth and a box's flat faces stay flat;
each leaf is its own original mesh (`Manifold.reserve_ids`), so every run of output triangles names the leaf it
came from, and so its material (a solid without one takes the nearest csg node's, as in `compile.csg`). A run
that manifold turned inside out (the part of a difference's right operand that bounds the result) has its
normals negated here: the cut face of a difference shows the subtracted solid's surface turned inward, as the
ray methods draw it. The tessellation's planar polygons travel as manifold face ids, so flat shading still
shades each (cut) polygon once.

The result is closed and consistently wound (outward) because every operand must be: a mesh leaf that is not a
closed 2-manifold is a `LumosError` naming it.
"""

from __future__ import annotations

from dataclasses import dataclass

import manifold3d
import numpy as np

from ..errors import LumosError
from .csg import operands
from .meshprep import facet, prepare_mesh
from .shapes import canonical
from .tessellate import tessellate_object

#: Property channels of a leaf's vertices: position, normal, uv.
_POS, _NRM, _UV = slice(0, 3), slice(3, 6), slice(6, 8)
_N_PROPS = 8


@dataclass
class CsgPiece:
    """The faces of a csg object's surface that one solid contributes (those of one orientation)."""

    vertices: np.ndarray  # (n, 3) float64, world space
    normals: np.ndarray  # (n, 3) float64 unit shading normals, pointing out of the combined solid
    uvs: np.ndarray  # (n, 2) float64, the solid's own uvs
    faces: np.ndarray  # (m, 3) int64, counter-clockwise seen from outside the combined solid
    groups: np.ndarray  # (m,) int64: faces cut from one planar polygon of the solid share a group, numbered 0..
    material: object  # the scene Material these faces show
    solid: str  # where the solid is in the scene, e.g. "objects[2].right.left"


@dataclass
class _Leaf:
    material: object
    where: str


def csg_pieces(scene, obj, world_from_object, segments: int, where: str) -> list[CsgPiece]:
    """The surface of the csg object `obj` (placed by `world_from_object`, 4×4 or None) as triangle pieces, one
    per solid that shows (and per orientation); empty when the combined solid is empty."""
    leaves: list[_Leaf] = []
    first_id = manifold3d.Manifold.reserve_ids(_count_leaves(obj))
    solid = _node(scene, obj, world_from_object, scene.material_of(obj), segments, where, leaves, first_id)
    out = solid.to_mesh64()
    props = np.asarray(out.vert_properties, dtype=np.float64).reshape(-1, _N_PROPS)
    tris = np.asarray(out.tri_verts, dtype=np.int64).reshape(-1, 3)
    run_index = np.asarray(out.run_index, dtype=np.int64) // 3
    run_id = np.asarray(out.run_original_id, dtype=np.int64)
    face_id = np.asarray(out.face_id, dtype=np.int64)
    # leaves are built in world space and never moved by manifold, so every run's transform is the identity
    runs: dict[tuple[int, bool], list[np.ndarray]] = {}
    for r in range(len(run_id)):
        key = (int(run_id[r] - first_id), bool(out.backside(r)))
        runs.setdefault(key, []).append(np.arange(run_index[r], run_index[r + 1]))
    pieces = []
    for (leaf, backside), ranges in sorted(runs.items()):
        sel = np.concatenate(ranges)
        if len(sel):
            pieces.append(_piece(props, tris[sel], face_id[sel], backside, leaves[leaf]))
    return pieces


def _piece(props, tris, face_id, backside, leaf: _Leaf) -> CsgPiece:
    """One piece with vertices of its own (so negating normals touches no other piece)."""
    used, faces = np.unique(tris, return_inverse=True)
    p = props[used]
    normals = _unit(p[:, _NRM])  # interpolated at new vertices, so no longer unit there
    if backside:
        normals = -normals
    _, groups = np.unique(face_id, return_inverse=True)
    return CsgPiece(np.ascontiguousarray(p[:, _POS]), normals, np.ascontiguousarray(p[:, _UV]),
                    faces.reshape(-1, 3).astype(np.int64), groups.astype(np.int64), leaf.material, leaf.where)


def _count_leaves(obj) -> int:
    return _count_leaves(obj.left) + _count_leaves(obj.right) if obj.type == "csg" else 1


def _node(scene, obj, world_from_node, material, segments, where, leaves, first_id) -> manifold3d.Manifold:
    """The manifold of csg node `obj` placed by world_from_node; its leaves are appended to `leaves`."""
    sides = []
    for child, world, at in operands(obj, world_from_node, where):
        mat = material if child.material is None else scene.material_of(child)
        if child.type == "csg":
            sides.append(_node(scene, child, world, mat, segments, at, leaves, first_id))
        else:
            sides.append(_leaf(child, world, segments, at, first_id + len(leaves)))
            leaves.append(_Leaf(mat, at))
    a, b = sides
    if obj.op == "union":
        return a + b
    if obj.op == "intersection":
        return a ^ b
    return a - b


def _leaf(obj, world_from_object, segments, where, original_id) -> manifold3d.Manifold:
    """A solid as a manifold whose vertices carry (position, normal, uv) and whose triangles carry the planar
    polygon they belong to as their face id."""
    if obj.type == "mesh":
        verts, normals, uvs, faces, groups = _mesh_leaf(obj, world_from_object, where)
    else:
        kind, object_from_canonical = canonical(obj)
        m = object_from_canonical if world_from_object is None else world_from_object @ object_from_canonical
        t = tessellate_object(kind, m, segments, True, where, "solid")  # csg solids are capped (the model checks)
        verts, normals, uvs, faces, groups = t.vertices, t.normals, t.uvs, t.faces, t.groups
    solid = _manifold(verts, normals, uvs, faces, groups, original_id)
    status = solid.status()
    if status != manifold3d.Error.NoError:
        raise LumosError(f"{where}: raster cannot combine this {obj.type} by mesh booleans: it is not a closed "
                         f"surface whose every edge borders exactly two triangles (manifold3d: {status.name})")
    if solid.volume() < 0.0:  # a closed mesh wound inward: turn it out (parity, not winding, is its inside)
        solid = _manifold(verts, -normals, uvs, faces[:, ::-1], groups, original_id)
    return solid


def _manifold(verts, normals, uvs, faces, groups, original_id) -> manifold3d.Manifold:
    mesh = manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(np.hstack([verts, normals, uvs]), dtype=np.float64),
        tri_verts=np.ascontiguousarray(faces, dtype=np.uint64),
        run_index=np.array([0, 3 * len(faces)], dtype=np.uint64),
        run_original_id=np.array([original_id], dtype=np.uint32),
        face_id=np.ascontiguousarray(groups, dtype=np.uint64),
    )
    # seams, poles and edges repeat a position with other normals or uvs: merge those by position only
    mesh.merge()
    return manifold3d.Manifold(mesh)


def _mesh_leaf(obj, world_from_object, where):
    m = prepare_mesh(obj, world_from_object)
    if len(m.polygons) == 0:
        raise LumosError(f"{where}: a mesh inside a csg object must be closed, but it has no triangles")
    if m.normals is None:
        m = facet(m)  # each triangle its own vertices with its face normal
    faces = np.asarray(m.polygons, np.int64).reshape(-1, 3)
    uvs = m.uvs if m.uvs is not None else np.zeros((len(m.vertices), 2))
    return m.vertices, m.normals, uvs, faces, np.asarray(m.groups, np.int64)


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)
