"""Analytic objects → canonical shapes: the matrix that places each canonical shape in the world, and its bounds.

`world_from_canonical = transform · canonical`, where `canonical` maps the shape's canonical form (see
`kernels.layout.SHAPE_*`) onto the object's own parameters (centre and radius, base/top, min/max…).
"""

from __future__ import annotations

import numpy as np

from ..kernels import layout as L


def frame(normal) -> np.ndarray:
    """Two unit tangents and the unit normal as columns of a 3×3 matrix (a right-handed frame)."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t = np.cross(helper, n)
    t /= np.linalg.norm(t)
    b = np.cross(n, t)
    return np.column_stack([t, b, n])


def _affine(columns3x3, origin) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = columns3x3
    m[:3, 3] = origin
    return m


def canonical(obj) -> tuple[int, np.ndarray]:
    """(shape kind, object_from_canonical 4×4) for an analytic scene object."""
    kind = obj.type
    if kind == "sphere":
        return L.SHAPE_SPHERE, _affine(np.eye(3) * obj.radius, obj.center)
    if kind == "box":
        return L.SHAPE_BOX, _affine(np.diag(np.subtract(obj.max, obj.min)), obj.min)
    if kind in ("cylinder", "cone"):
        axis = np.subtract(obj.top, obj.base)
        f = frame(axis)
        cols = np.column_stack([f[:, 0] * obj.radius, f[:, 1] * obj.radius, axis])
        return (L.SHAPE_CYLINDER if kind == "cylinder" else L.SHAPE_CONE), _affine(cols, obj.base)
    if kind == "disk":
        f = frame(obj.normal)
        cols = np.column_stack([f[:, 0] * obj.radius, f[:, 1] * obj.radius, f[:, 2]])
        return L.SHAPE_DISK, _affine(cols, obj.center)
    if kind == "plane":
        return L.SHAPE_PLANE, _affine(frame(obj.normal), obj.point)
    if kind == "rect":
        return L.SHAPE_RECT, rect_canonical(obj.corner, obj.edge_u, obj.edge_v)
    raise ValueError(f"not an analytic shape: {kind}")


def rect_canonical(corner, edge_u, edge_v) -> np.ndarray:
    n = np.cross(edge_u, edge_v)
    return _affine(np.column_stack([edge_u, edge_v, n / np.linalg.norm(n)]), corner)


_CORNERS = {
    L.SHAPE_BOX: ((0, 1), (0, 1), (0, 1)),
    L.SHAPE_CYLINDER: ((-1, 1), (-1, 1), (0, 1)),
    L.SHAPE_CONE: ((-1, 1), (-1, 1), (0, 1)),
    L.SHAPE_DISK: ((-1, 1), (-1, 1), (0, 0)),
    L.SHAPE_RECT: ((0, 1), (0, 1), (0, 0)),
}


def world_bounds(kind: int, world_from_canonical: np.ndarray) -> np.ndarray:
    """Axis-aligned bounds (min xyz, max xyz) of a canonical shape placed by the 4×4 matrix."""
    m = world_from_canonical
    if kind == L.SHAPE_SPHERE:
        # an ellipsoid's extent along axis i is the norm of row i of the linear part
        half = np.sqrt((m[:3, :3] ** 2).sum(axis=1))
        return np.concatenate([m[:3, 3] - half, m[:3, 3] + half])
    xs, ys, zs = _CORNERS[kind]
    corners = np.array([[x, y, z, 1.0] for x in xs for y in ys for z in zs]) @ m.T
    return np.concatenate([corners[:, :3].min(axis=0), corners[:, :3].max(axis=0)])
