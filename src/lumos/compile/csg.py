"""A csg object → one `SHAPE_CSG` shape in the BVH, its solids as shapes outside it, and its rows of `csg_nodes`.

The layout is `kernels.csg`'s: the operator nodes in post-order with their parents, then one row per solid
(leaf). Each leaf is an ordinary canonical shape placed by the composed transforms of the csg nodes above it
and its own, or a `SHAPE_MESH_SOLID` whose world-space triangles go to `shapes.solid_triangles` (placed after
the BVH's triangles by `_assemble`, outside the BVH). The csg node's `motion` is stored in every leaf. A solid
without a material takes the nearest csg node's (`Scene.material_of` semantics).

Bounds: union → the union of the children's boxes; intersection → their intersection; difference → the left's.
"""

from __future__ import annotations

import numpy as np

from ..errors import LumosError
from ..kernels import layout as L
from ..kernels.csg import CSG_DIFFERENCE, CSG_INTERSECTION, CSG_LEAF, CSG_UNION
from .meshprep import mesh_triangles
from .shapes import canonical, world_bounds

_OPS = {"union": CSG_UNION, "intersection": CSG_INTERSECTION, "difference": CSG_DIFFERENCE}


def operands(obj, world_from_node, where: str):
    """(child, world_from_child, key path) for the left and right operands of csg node `obj` placed by
    world_from_node (None: the identity): each child's own transform composed after its node's, as every
    method places csg solids (the ray methods' rows here, the scan-line renderer's booleans in `csg_mesh`)."""
    for side in ("left", "right"):
        child = getattr(obj, side)
        world = world_from_node
        if child.transform is not None:
            m = child.transform.to_matrix()
            world = m if world is None else world @ m
        yield child, world, f"{where}.{side}"


def add_csg(obj, object_id, world_from_object, scene, materials, shapes, tri_parts) -> int:
    """Add csg object `obj` (objects[object_id]) to `shapes`; returns the csg shape's index. `tri_parts` (the
    BVH's triangles) is left alone: a mesh solid's triangles must not be hit on their own."""
    if not hasattr(shapes, "csg_nodes"):
        shapes.csg_nodes = []
        shapes.solid_triangles = []  # (verts, normals, uvs, material, object), as tri_parts
    builder = _Builder(scene, materials, shapes, object_id, obj.motion, len(shapes.csg_nodes), not obj.two_sided)
    root_material = materials.add(scene.material_of(obj), one_sided=not obj.two_sided)
    root, box = builder.node(obj, world_from_object, root_material, f"objects[{object_id}]")
    shapes.csg_nodes.extend(builder.nodes)
    shapes.csg_nodes.extend(builder.leaves)
    return shapes.add(L.SHAPE_CSG, np.eye(4), root_material, object_id, motion=obj.motion, ref=root,
                      count=len(builder.leaves), bounds=box)


class _Builder:
    def __init__(self, scene, materials, shapes, object_id, motion, first_row, one_sided=False):
        self.scene, self.materials, self.shapes, self.one_sided = scene, materials, shapes, one_sided
        self.object_id, self.motion, self.first_row = object_id, motion, first_row
        self.nodes = []  # [op, left, right, parent], post-order
        self.leaves = []  # [CSG_LEAF, ~shape, parent, 0]
        self.leaf_row = {}  # ~shape → index in self.leaves

    def node(self, obj, world_from_node, material, where):
        """(child reference, world bounds (6,)) of the csg node `obj` placed by world_from_node."""
        refs, boxes = [], []
        for child, world, at in operands(obj, world_from_node, where):
            mat = material if child.material is None else self.materials.add(self.scene.material_of(child),
                                                                              one_sided=self.one_sided)
            ref, box = self.node(child, world, mat, at) if child.type == "csg" else self.leaf(child, world, mat, at)
            refs.append(ref)
            boxes.append(box)
        row = self.first_row + len(self.nodes)
        self.nodes.append([_OPS[obj.op], refs[0], refs[1], -1])
        for ref in refs:  # the children's parent is this row
            if ref >= 0:
                self.nodes[ref - self.first_row][3] = row
            else:
                self.leaves[self.leaf_row[ref]][2] = row
        return row, _combine(obj.op, boxes[0], boxes[1])

    def leaf(self, obj, world_from_object, material, where):
        """(~shape, world bounds) of a solid."""
        if obj.type == "mesh":
            verts, _, uvs, _ = mesh_triangles(obj, world_from_object)
            _check_closed(verts, where)
            solid = self.shapes.solid_triangles
            first = sum(len(part[0]) for part in solid)  # relative to the solid triangles; _assemble adds the rest
            solid.append((verts, None, uvs, material, self.object_id))
            s = self.shapes.add(L.SHAPE_MESH_SOLID, np.eye(4), material, self.object_id, motion=self.motion,
                                ref=first, count=len(verts), bounded=False)
            v = verts.reshape(-1, 3)
            box = np.concatenate([v.min(axis=0), v.max(axis=0)])
        else:
            kind, object_from_canonical = canonical(obj)
            m = object_from_canonical if world_from_object is None else world_from_object @ object_from_canonical
            flags = L.FLAG_CAPPED if getattr(obj, "capped", False) else 0
            s = self.shapes.add(kind, m, material, self.object_id, flags, motion=self.motion, bounded=False)
            box = world_bounds(kind, m)
        self.leaf_row[~s] = len(self.leaves)
        self.leaves.append([CSG_LEAF, ~s, -1, 0])
        return ~s, box


def _combine(op, a, b):
    if op == "union":
        return np.concatenate([np.minimum(a[:3], b[:3]), np.maximum(a[3:], b[3:])])
    if op == "intersection":
        lo, hi = np.maximum(a[:3], b[:3]), np.minimum(a[3:], b[3:])
        return np.concatenate([lo, np.maximum(lo, hi)])  # disjoint boxes: an empty solid, any valid box will do
    return a


def _check_closed(verts, where):
    """A mesh solid must be closed: with vertices merged by position, every edge is shared by an even number of
    triangles (parity decides what is inside)."""
    points = verts.reshape(-1, 3)
    _, index = np.unique(points, axis=0, return_inverse=True)
    tri = index.reshape(-1, 3)
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    edges = edges[edges[:, 0] != edges[:, 1]]  # degenerate triangles add nothing
    _, counts = np.unique(edges, axis=0, return_counts=True)
    open_edges = int((counts % 2 == 1).sum())
    if open_edges:
        raise LumosError(f"{where}: a mesh inside a csg object must be closed, but {open_edges} of its edges "
                         "border only one triangle")
