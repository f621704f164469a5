"""Canonical analytic shapes → triangle meshes with exact per-vertex normals, for the scan-line renderer.

    t = tessellate_shape(SHAPE_SPHERE, world_from_canonical, segments=32)
    t.vertices (n, 3)  t.normals (n, 3)  t.uvs (n, 2)  t.faces (m, 3)  t.groups (m,)

Each shape is built in its canonical form (`kernels.layout.SHAPE_*`) and then placed by the 4×4 affine
`world_from_canonical`: points by the matrix, normals by the inverse transpose of its 3×3 part (then normalised).
Normals are the exact analytic surface normals at the vertices, not averages of face normals, so Gouraud and
Phong shading of the mesh converge to the ray-traced image. UVs follow `kernels.surface._canonical_normal_uv`, so
textures agree between ray tracing and raster:

    sphere            u = 0.5 + atan2(x, z) / 2π,  v = 0.5 + asin(y) / π      (poles on the y axis)
    cylinder, cone    u = 0.5 + atan2(y, x) / 2π,  v = z;   caps and disk: (0.5 + x/2, 0.5 + y/2)
    box face on axis  x: (z, y)   y: (x, z)   z: (x, y);     rect and plane: (x, y)

Along a u seam (u = 0 and u = 1) and at poles and the cone apex, vertices are duplicated so that every vertex
carries its own exact uv and normal; merging vertices by position gives a watertight mesh for the closed shapes.

Faces are counter-clockwise seen from the side the normal points to (outward), also under a mirroring matrix
(negative determinant: the winding is flipped). Triangles cut from one planar polygon of the tessellation (a
quad of a strip, a box face, a cap or disk fan) share a group id, numbered 0.. per tessellation: flat shading
uses one intensity per group.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels.layout import (
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CYLINDER,
    SHAPE_DISK,
    SHAPE_PLANE,
    SHAPE_RECT,
    SHAPE_SPHERE,
)

_AXIAL_ROWS = 1  # rows of quads along a cylinder's axis (normals are constant along it); cones add apex triangles


@dataclass
class Tessellation:
    vertices: np.ndarray  # (n, 3) float64, world space
    normals: np.ndarray  # (n, 3) float64, world space, unit, the exact outward surface normal at the vertex
    uvs: np.ndarray  # (n, 2) float64
    faces: np.ndarray  # (m, 3) int64, counter-clockwise seen from the side the normal points to
    groups: np.ndarray  # (m,) int64, one id per planar polygon of the tessellation, numbered 0..


@dataclass
class _Part:
    """A piece of a canonical mesh; faces and groups index its own vertices and groups from 0."""

    points: np.ndarray  # (n, 3) canonical positions
    normals: np.ndarray  # (n, 3) canonical normals (any length, outward)
    uvs: np.ndarray  # (n, 2)
    faces: np.ndarray  # (m, 3)
    groups: np.ndarray  # (m,)


# ---------------------------------------------------------------------------------------------- public API


def tessellate_object(kind: int, world_from_canonical: np.ndarray, segments: int, capped: bool, where: str,
                      noun: str = "object") -> Tessellation:
    """`tessellate_shape` for a scene's object (or light) at key path `where`: a shape whose placement cannot be
    tessellated (a radius or scale so small that its transform is singular in float64, or not finite) is a
    one-line `LumosError` naming it, not a ValueError."""
    from ..errors import LumosError

    try:
        return tessellate_shape(kind, world_from_canonical, segments, capped)
    except ValueError as exc:
        raise LumosError(f"{where}: this {noun} cannot be turned into polygons ({exc}; is a radius, size or scale "
                         "zero or far below 1e-100?)") from None


def tessellate_shape(kind: int, world_from_canonical: np.ndarray, segments: int, capped: bool = True) -> Tessellation:
    """Triangle mesh of the canonical shape `kind` placed by `world_from_canonical` (4×4, affine).

    `segments` is the number of segments around a full circle (>= 3); a sphere has `max(2, segments // 2)` rings
    from pole to pole. `capped` adds the caps of a cylinder (z = 0 and z = 1) or cone (z = 0).
    Planes are unbounded: use `tessellate_plane`.
    """
    segments = _check_segments(segments, 3)
    builders = {
        SHAPE_SPHERE: lambda: [_sphere(segments)],
        SHAPE_BOX: lambda: [_box()],
        SHAPE_CYLINDER: lambda: _cylinder(segments, capped),
        SHAPE_CONE: lambda: _cone(segments, capped),
        SHAPE_DISK: lambda: [_fan(segments, 0.0, +1.0)],
        SHAPE_RECT: lambda: [_rect()],
    }
    if kind == SHAPE_PLANE:
        raise ValueError("a plane is unbounded: tessellate it with tessellate_plane(world_from_canonical, center, ...)")
    if kind not in builders:
        raise ValueError(f"unknown shape kind: {kind!r}")
    return _place(_merge(builders[kind]()), _matrix(world_from_canonical))


def tessellate_plane(world_from_canonical: np.ndarray, center, half_size: float, segments: int) -> Tessellation:
    """A square patch of the plane z = 0 placed by `world_from_canonical`.

    The patch is centred at the projection of the world point `center` onto the world plane, has half-size
    `half_size` in world units (its sides run along the world image of the canonical x axis and the in-plane
    direction perpendicular to it) and is split into `segments` × `segments` quads of two triangles, one group
    per quad. Every normal is the plane's normal; uvs are the canonical (x, y) of each vertex, as the ray
    tracer's plane uv.
    """
    segments = _check_segments(segments, 1)
    m = _matrix(world_from_canonical)
    half_size = float(half_size)
    if not (math.isfinite(half_size) and half_size > 0.0):
        raise ValueError(f"half_size must be a positive number, got {half_size!r}")
    linear, origin = m[:3, :3], m[:3, 3]
    normal = _unit(np.linalg.inv(linear).T @ np.array([0.0, 0.0, 1.0]))
    # (t1, t2, normal) is right-handed, so a grid laid out along t1 then t2 is counter-clockwise from the normal
    t1 = _unit(linear[:, 0])
    t2 = np.cross(normal, t1)
    c = np.asarray(center, dtype=np.float64).reshape(3)
    c = c - np.dot(c - origin, normal) * normal
    s = np.linspace(-half_size, half_size, segments + 1)
    a, b = np.meshgrid(s, s)  # b runs along rows, a along columns: vertex (row j, column i)
    vertices = c + a.reshape(-1, 1) * t1 + b.reshape(-1, 1) * t2
    canonical = (vertices - origin) @ np.linalg.inv(linear).T
    faces, groups = _quad_grid(segments, segments)
    return Tessellation(
        vertices=vertices,
        normals=np.tile(normal, (len(vertices), 1)),
        uvs=np.ascontiguousarray(canonical[:, :2]),
        faces=faces,
        groups=groups,
    )


# ------------------------------------------------------------------------------------------- canonical parts


def _sphere(segments: int) -> _Part:
    """Latitude-longitude sphere about the y axis: quads between interior rings, triangle fans at the poles.

    With φ = 2π(u − ½) and θ = π(v − ½): p = (sin φ cos θ, sin θ, cos φ cos θ), so (u, v) increase
    counter-clockwise seen from outside (∂p/∂u × ∂p/∂v points outward).
    """
    rings = max(2, segments // 2)
    u = np.arange(segments + 1) / segments
    v = np.arange(1, rings) / rings  # interior rings only; the poles are added per segment below
    uu, vv = np.meshgrid(u, v)
    ring_points = _sphere_point(uu.ravel(), vv.ravel())
    n_ring = len(ring_points)
    row = segments + 1

    faces, groups = _quad_grid(segments, rings - 2)
    # one pole vertex per segment, at the segment's middle u (the exact normal there is ±y whatever u is)
    u_mid = (np.arange(segments) + 0.5) / segments
    i = np.arange(segments)
    south = n_ring + i
    north = n_ring + segments + i
    last = (rings - 2) * row  # first vertex of the ring nearest the north pole
    south_faces = np.column_stack([south, i + 1, i])
    north_faces = np.column_stack([last + i, last + i + 1, north])
    pole_groups = len(groups) // 2 + np.arange(2 * segments)  # two triangles per quad group

    points = np.concatenate([
        ring_points,
        np.tile([0.0, -1.0, 0.0], (segments, 1)),
        np.tile([0.0, 1.0, 0.0], (segments, 1)),
    ])
    uvs = np.concatenate([
        np.column_stack([uu.ravel(), vv.ravel()]),
        np.column_stack([u_mid, np.zeros(segments)]),
        np.column_stack([u_mid, np.ones(segments)]),
    ])
    return _Part(
        points=points,
        normals=points.copy(),  # the gradient of |p|² − 1 is 2p
        uvs=uvs,
        faces=np.concatenate([faces, south_faces, north_faces]),
        groups=np.concatenate([groups, pole_groups]),
    )


def _sphere_point(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    phi = 2.0 * math.pi * (u - 0.5)
    theta = math.pi * (v - 0.5)
    return np.column_stack([np.sin(phi) * np.cos(theta), np.sin(theta), np.cos(phi) * np.cos(theta)])


def _circle(segments: int, seam: bool):
    """u and the unit circle (cos φ, sin φ) at φ = 2π(u − ½), u = k / segments; `seam` repeats u = 1."""
    u = np.arange(segments + (1 if seam else 0)) / segments
    phi = 2.0 * math.pi * (u - 0.5)
    return u, np.cos(phi), np.sin(phi)


def _cylinder(segments: int, capped: bool) -> list[_Part]:
    """Side x² + y² = 1, 0 <= z <= 1 as a quad strip ((u, z) counter-clockwise from outside), plus caps."""
    u, c, s = _circle(segments, seam=True)
    z = np.arange(_AXIAL_ROWS + 1) / _AXIAL_ROWS
    uu, zz = np.meshgrid(u, z)
    cc, ss = np.meshgrid(c, z)[0], np.meshgrid(s, z)[0]
    points = np.column_stack([cc.ravel(), ss.ravel(), zz.ravel()])
    faces, groups = _quad_grid(segments, _AXIAL_ROWS)
    side = _Part(
        points=points,
        normals=np.column_stack([cc.ravel(), ss.ravel(), np.zeros(cc.size)]),  # ∇(x² + y²) = (2x, 2y, 0)
        uvs=np.column_stack([uu.ravel(), zz.ravel()]),
        faces=faces,
        groups=groups,
    )
    return [side, _fan(segments, 0.0, -1.0), _fan(segments, 1.0, +1.0)] if capped else [side]


def _cone(segments: int, capped: bool) -> list[_Part]:
    """Side x² + y² = (1 − z)², apex at z = 1: quad rows, then one triangle per segment up to the apex.

    Each segment has its own apex vertex whose normal is the exact slant normal (cos φ, sin φ, 1) at the
    segment's middle angle; the apex itself has no normal.
    """
    u, c, s = _circle(segments, seam=True)
    z = np.arange(_AXIAL_ROWS) / _AXIAL_ROWS  # ring rows below the apex
    uu, zz = np.meshgrid(u, z)
    r = 1.0 - zz
    cc, ss = np.meshgrid(c, z)[0], np.meshgrid(s, z)[0]
    ring_points = np.column_stack([(r * cc).ravel(), (r * ss).ravel(), zz.ravel()])
    # ∇(x² + y² − (1 − z)²) ∝ (x, y, 1 − z) = r (cos φ, sin φ, 1)
    ring_normals = np.column_stack([cc.ravel(), ss.ravel(), np.ones(cc.size)])
    faces, groups = _quad_grid(segments, _AXIAL_ROWS - 1)

    u_mid = (np.arange(segments) + 0.5) / segments
    phi_mid = 2.0 * math.pi * (u_mid - 0.5)
    n_ring = len(ring_points)
    last = (_AXIAL_ROWS - 1) * (segments + 1)
    i = np.arange(segments)
    apex_faces = np.column_stack([last + i, last + i + 1, n_ring + i])
    side = _Part(
        points=np.concatenate([ring_points, np.tile([0.0, 0.0, 1.0], (segments, 1))]),
        normals=np.concatenate([ring_normals, np.column_stack([np.cos(phi_mid), np.sin(phi_mid), np.ones(segments)])]),
        uvs=np.concatenate([np.column_stack([uu.ravel(), zz.ravel()]), np.column_stack([u_mid, np.ones(segments)])]),
        faces=np.concatenate([faces, apex_faces]),
        groups=np.concatenate([groups, len(groups) // 2 + i]),  # two triangles per quad group
    )
    return [side, _fan(segments, 0.0, -1.0)] if capped else [side]


def _fan(segments: int, z: float, facing: float) -> _Part:
    """The unit disk in the plane `z` facing ±z (`facing`) as a fan around its centre: one planar polygon, one
    group. uv = (0.5 + x/2, 0.5 + y/2) is continuous around the rim, so the rim needs no seam vertex."""
    _, c, s = _circle(segments, seam=False)
    points = np.column_stack([np.append(c, 0.0), np.append(s, 0.0), np.full(segments + 1, z)])
    centre = segments
    i = np.arange(segments)
    j = (i + 1) % segments
    faces = np.column_stack([np.full(segments, centre), i, j] if facing > 0 else [np.full(segments, centre), j, i])
    return _Part(
        points=points,
        normals=np.tile([0.0, 0.0, facing], (segments + 1, 1)),
        uvs=0.5 + 0.5 * points[:, :2],
        faces=faces,
        groups=np.zeros(segments, np.int64),
    )


def _box() -> _Part:
    """The cube [0, 1]³: per face (part = 2·axis + (1 if on the + side)) four corners with that face's normal
    and uv axes (x: (z, y), y: (x, z), z: (x, y)), ordered counter-clockwise seen from outside."""
    uv_axes = {0: (2, 1), 1: (0, 2), 2: (0, 1)}
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    parts = []
    for part in range(6):
        axis, side = divmod(part, 2)
        a, b = uv_axes[axis]
        points = np.zeros((4, 3))
        points[:, a], points[:, b], points[:, axis] = square[:, 0], square[:, 1], float(side)
        normal = np.zeros(3)
        normal[axis] = 1.0 if side else -1.0
        order = [0, 1, 2, 3]
        if np.dot(np.cross(np.eye(3)[a], np.eye(3)[b]), normal) < 0.0:
            order = [0, 3, 2, 1]  # the uv axes run clockwise seen from outside on this face
        parts.append(_Part(points[order], np.tile(normal, (4, 1)), square[order].copy(),
                           np.array([[0, 1, 2], [0, 2, 3]]), np.zeros(2, np.int64)))
    return _merge(parts)


def _rect() -> _Part:
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return _Part(np.column_stack([square, np.zeros(4)]), np.tile([0.0, 0.0, 1.0], (4, 1)), square.copy(),
                 np.array([[0, 1, 2], [0, 2, 3]]), np.zeros(2, np.int64))


# ------------------------------------------------------------------------------------------------- helpers


def _quad_grid(columns: int, rows: int):
    """Faces and groups of a grid of `rows` × `columns` quads over vertices indexed row · (columns + 1) + column.

    Quad (i, j) → triangles (a, b, c), (a, c, d) with a = (i, j), b = (i+1, j), c = (i+1, j+1), d = (i, j+1):
    counter-clockwise when the column index and the row index run counter-clockwise, one group per quad.
    """
    if rows <= 0:
        return np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    stride = columns + 1
    i, j = np.meshgrid(np.arange(columns), np.arange(rows))
    a = (j * stride + i).ravel()
    b, c, d = a + 1, a + stride + 1, a + stride
    quads = len(a)
    faces = np.empty((2 * quads, 3), np.int64)
    faces[0::2] = np.column_stack([a, b, c])
    faces[1::2] = np.column_stack([a, c, d])
    return faces, np.repeat(np.arange(quads, dtype=np.int64), 2)


def _merge(parts: list[_Part]) -> _Part:
    """One part from several: faces and groups offset by the vertices and groups before them."""
    faces, groups = [], []
    n_vertices = n_groups = 0
    for p in parts:
        faces.append(np.asarray(p.faces, np.int64) + n_vertices)
        groups.append(np.asarray(p.groups, np.int64) + n_groups)
        n_vertices += len(p.points)
        n_groups += int(p.groups.max()) + 1 if len(p.groups) else 0
    return _Part(
        points=np.concatenate([p.points for p in parts]),
        normals=np.concatenate([p.normals for p in parts]),
        uvs=np.concatenate([p.uvs for p in parts]),
        faces=np.concatenate(faces),
        groups=np.concatenate(groups),
    )


def _place(part: _Part, m: np.ndarray) -> Tessellation:
    """Canonical part → world: points by m, normals by the inverse transpose of its 3×3 part; a mirroring m
    (negative determinant) reverses the geometric normal cross(b − a, c − a), so the winding is flipped."""
    linear = m[:3, :3]
    normals = part.normals @ np.linalg.inv(linear)  # row-vector form of inv(linear).T @ n
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    faces = np.ascontiguousarray(part.faces, dtype=np.int64)
    if np.linalg.det(linear) < 0.0:
        faces = np.ascontiguousarray(faces[:, [0, 2, 1]])
    return Tessellation(
        vertices=part.points @ linear.T + m[:3, 3],
        normals=normals,
        uvs=np.ascontiguousarray(part.uvs, dtype=np.float64),
        faces=faces,
        groups=np.ascontiguousarray(part.groups, dtype=np.int64),
    )


def _matrix(world_from_canonical) -> np.ndarray:
    m = np.asarray(world_from_canonical, dtype=np.float64)
    if m.shape != (4, 4):
        raise ValueError(f"world_from_canonical must be 4×4, got shape {m.shape}")
    if not np.all(np.isfinite(m)) or abs(np.linalg.det(m[:3, :3])) < 1e-300:
        raise ValueError("world_from_canonical must be finite and invertible")
    return m


def _check_segments(segments, minimum: int) -> int:
    if isinstance(segments, bool) or int(segments) != segments or segments < minimum:
        raise ValueError(f"segments must be an integer >= {minimum}, got {segments!r}")
    return int(segments)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)
