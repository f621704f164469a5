"""From a hit record to the surface there: position, geometric and shading normals, UV, material, object.

Normals of analytic shapes come from their canonical form and are carried to world space by the transpose of
`object_from_world` (the inverse transpose of the placement). Meshes with vertex normals interpolate them. A csg
hit takes the normal of the solid it lies on, turned outward of the combined solid (`_csg_surface`).
"""

import math

import numpy as np

from .csg import csg_leaf
from .jit import njit, njit_inline
from .layout import (
    FLAG_NORMALS,
    FLAG_READS_UV,
    FLAG_UVS,
    INFO_FLAGS,
    INFO_KIND,
    INFO_LIGHT,
    INFO_MATERIAL,
    INFO_OBJECT,
    SHAPE_BOX,
    SHAPE_CONE,
    SHAPE_CSG,
    SHAPE_CYLINDER,
    SHAPE_DISK,
    SHAPE_MESH_SOLID,
    SHAPE_PLANE,
    SHAPE_RECT,
    SHAPE_SPHERE,
)
from .vec import cross, dot, madd, mul, normalize, sub, xform_normal, xform_point

_INV_2PI = 0.5 / math.pi


@njit_inline
def _canonical_normal_uv(kind, part, p, want_uv):
    """Object-space normal (not unit) and (u, v) on a canonical shape at point p; (u, v) = (0, 0) for the sphere
    and the sides of cylinders and cones unless `want_uv` (their uv costs an atan2, a tenth of a hit's time)."""
    if kind == SHAPE_SPHERE:
        if not want_uv:
            return p, 0.0, 0.0
        u = 0.5 + math.atan2(p[0], p[2]) * _INV_2PI
        v = 0.5 + math.asin(min(1.0, max(-1.0, p[1]))) / math.pi
        return p, u, v
    if kind == SHAPE_BOX:
        axis = part // 2
        sign = 1.0 if part % 2 == 1 else -1.0
        if axis == 0:
            return (sign, 0.0, 0.0), p[2], p[1]
        if axis == 1:
            return (0.0, sign, 0.0), p[0], p[2]
        return (0.0, 0.0, sign), p[0], p[1]
    if kind == SHAPE_CYLINDER or kind == SHAPE_CONE:
        if part == 1:
            return (0.0, 0.0, -1.0), 0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1]
        if part == 2:
            return (0.0, 0.0, 1.0), 0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1]
        u = 0.5 + math.atan2(p[1], p[0]) * _INV_2PI if want_uv else 0.0
        if kind == SHAPE_CYLINDER:
            return (p[0], p[1], 0.0), u, p[2]
        n = (p[0], p[1], 1.0 - p[2])
        if n[0] == 0.0 and n[1] == 0.0:
            n = (0.0, 0.0, 1.0)  # the apex
        return n, u, p[2]
    if kind == SHAPE_RECT or kind == SHAPE_PLANE:
        return (0.0, 0.0, 1.0), p[0], p[1]
    return (0.0, 0.0, 1.0), 0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1]  # disk


@njit_inline
def surface_at(surf, o, d, t, ref, b1, b2, part, time):
    """Returns (p, n_geometric, n_shading, u, v, material_id, object_id, light_id) for a hit (`surf` is a
    `layout.Surfaces`).

    Normals are unit length and not yet turned towards the viewer (see `face_forward`). (u, v) is (0, 0) on the
    curved shapes whose material reads no uv (`FLAG_READS_UV`).
    """
    return surface_at_of(surf, surf, o, d, t, ref, b1, b2, part, time)


@njit_inline
def surface_at_of(surf, shaped, o, d, t, ref, b1, b2, part, time):
    """`surface_at`, with `shaped` None where the scene is triangles only (raster's polygons): Numba then prunes
    the shapes' branch before typing it. Anything else where the hit may be an analytic shape's (`surface_at`
    passes `surf`, the shadow walk its geometry): only `shaped is None` is read."""
    p = madd(o, d, t)
    if ref >= 0 or shaped is None:
        v = surf.tri_verts
        # np.float64, not float(): Numba's float() keeps a float32 a float32, and the edges and normal would be
        # computed in single precision
        v0 = (np.float64(v[ref, 0]), np.float64(v[ref, 1]), np.float64(v[ref, 2]))
        e1 = (v[ref, 3] - v0[0], v[ref, 4] - v0[1], v[ref, 5] - v0[2])
        e2 = (v[ref, 6] - v0[0], v[ref, 7] - v0[1], v[ref, 8] - v0[2])
        n_geo = normalize(cross(e1, e2))
        b0 = 1.0 - b1 - b2
        info = surf.tri_info[ref]
        n_sh = n_geo
        if info[INFO_FLAGS] & FLAG_NORMALS:
            nn = surf.tri_normals
            n_sh = normalize((b0 * nn[ref, 0] + b1 * nn[ref, 3] + b2 * nn[ref, 6],
                              b0 * nn[ref, 1] + b1 * nn[ref, 4] + b2 * nn[ref, 7],
                              b0 * nn[ref, 2] + b1 * nn[ref, 5] + b2 * nn[ref, 8]))
            if n_sh[0] == 0.0 and n_sh[1] == 0.0 and n_sh[2] == 0.0:
                n_sh = n_geo
        u, w = b1, b2
        if info[INFO_FLAGS] & FLAG_UVS:
            uv = surf.tri_uvs
            u = b0 * uv[ref, 0] + b1 * uv[ref, 2] + b2 * uv[ref, 4]
            w = b0 * uv[ref, 1] + b1 * uv[ref, 3] + b2 * uv[ref, 5]
        return p, n_geo, n_sh, u, w, info[INFO_MATERIAL], info[INFO_OBJECT], info[INFO_LIGHT]
    s = ~ref
    info = surf.shape_info[s]
    if info[INFO_KIND] == SHAPE_CSG:
        return _csg_surface(surf, p, d, b1, b2, part, time, info[INFO_OBJECT])
    m = surf.shape_xform[s]
    q = p
    if m[3, 3] != 0.0:  # a moving shape, displaced by time·motion
        q = (p[0] - time * m[3, 0], p[1] - time * m[3, 1], p[2] - time * m[3, 2])
    kind = info[INFO_KIND]
    n_obj, u, w = _canonical_normal_uv(kind, part, xform_point(m, q), info[INFO_FLAGS] & FLAG_READS_UV)
    axis = _face_axis(kind, part)
    if axis >= 0:  # a canonical normal ±axis: its world length is known (`shape_nscale`), no square root
        n = mul(xform_normal(m, n_obj), surf.shape_nscale[s, axis])
    else:
        n = normalize(xform_normal(m, n_obj))
    return p, n, n, u, w, info[INFO_MATERIAL], info[INFO_OBJECT], info[INFO_LIGHT]


@njit_inline
def _face_axis(kind, part):
    """The axis a when the canonical normal of part `part` of a shape of this kind is ±axis a, else -1 (spheres,
    the sides of cylinders and cones)."""
    if kind == SHAPE_BOX:
        return part // 2
    if kind == SHAPE_RECT or kind == SHAPE_PLANE or kind == SHAPE_DISK:
        return 2
    if (kind == SHAPE_CYLINDER or kind == SHAPE_CONE) and part != 0:
        return 2
    return -1


@njit
def _csg_surface(surf, p, d, b1, b2, part, time, object_id):
    """The surface at a csg hit (record: see `kernels.csg`): the normal, uv and material of the solid hit, the
    normal turned outward of the combined solid: against d where the ray enters it (b1 > 0), along d where it
    leaves. So the cut face of a difference shows the subtracted solid's surface turned inward."""
    leaf, leaf_part = csg_leaf(part)
    info = surf.shape_info[leaf]
    m = surf.shape_xform[leaf]
    q = p
    if m[3, 3] != 0.0:  # the csg node moves: its solids are where they were at time 0 displaced by time·motion
        q = (p[0] - time * m[3, 0], p[1] - time * m[3, 1], p[2] - time * m[3, 2])
    if info[INFO_KIND] == SHAPE_MESH_SOLID:
        n, u, w = _triangle_at(surf, np.int64(b2), q)
    else:
        n_obj, u, w = _canonical_normal_uv(info[INFO_KIND], leaf_part, xform_point(m, q),
                                           info[INFO_FLAGS] & FLAG_READS_UV)
        n = normalize(xform_normal(m, n_obj))
    if (dot(n, d) > 0.0) == (b1 > 0.0):
        n = (-n[0], -n[1], -n[2])
    return p, n, n, u, w, info[INFO_MATERIAL], object_id, info[INFO_LIGHT]


@njit
def _triangle_at(surf, i, q):
    """Unit geometric normal and (u, v) of triangle i at the point q on it: its uvs interpolated when it has
    them, else the barycentrics (b1, b2) of q, found by least squares on the triangle's plane."""
    v = surf.tri_verts
    v0 = (np.float64(v[i, 0]), np.float64(v[i, 1]), np.float64(v[i, 2]))
    e1 = (v[i, 3] - v0[0], v[i, 4] - v0[1], v[i, 5] - v0[2])
    e2 = (v[i, 6] - v0[0], v[i, 7] - v0[1], v[i, 8] - v0[2])
    n = normalize(cross(e1, e2))
    r = sub(q, v0)
    d11, d12, d22 = dot(e1, e1), dot(e1, e2), dot(e2, e2)
    r1, r2 = dot(r, e1), dot(r, e2)
    det = d11 * d22 - d12 * d12
    b1 = (d22 * r1 - d12 * r2) / det if det != 0.0 else 0.0
    b2 = (d11 * r2 - d12 * r1) / det if det != 0.0 else 0.0
    if surf.tri_info[i, INFO_FLAGS] & FLAG_UVS:
        uv = surf.tri_uvs
        b0 = 1.0 - b1 - b2
        return n, b0 * uv[i, 0] + b1 * uv[i, 2] + b2 * uv[i, 4], b0 * uv[i, 1] + b1 * uv[i, 3] + b2 * uv[i, 5]
    return n, b1, b2


@njit
def face_forward(n, d):
    """n turned to face against the ray direction d (towards the viewer): planes and meshes are two-sided."""
    if n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0:
        return (-n[0], -n[1], -n[2])
    return n


@njit
def shading_side(n_sh, n_geo, V):
    """The shading normal on the viewer's side of a two-sided surface: turned to agree with the geometric
    normal, and turned over with it where the geometric normal faces away from V. Near a silhouette an
    interpolated normal may still face slightly away from V; it is kept so, since turning it towards the
    viewer on its own would light the dark side of the object."""
    s = 1.0
    if n_geo[0] * V[0] + n_geo[1] * V[1] + n_geo[2] * V[2] < 0.0:
        s = -s
    if n_sh[0] * n_geo[0] + n_sh[1] * n_geo[1] + n_sh[2] * n_geo[2] < 0.0:
        s = -s
    return (n_sh[0] * s, n_sh[1] * s, n_sh[2] * s)


@njit
def offset_origin(p, n, d_out, eps):
    """A ray origin off the surface at p, on the side d_out leaves towards (avoids self-intersection)."""
    scale = eps * max(1.0, abs(p[0]), abs(p[1]), abs(p[2]))
    if n[0] * d_out[0] + n[1] * d_out[1] + n[2] * d_out[2] < 0.0:
        scale = -scale
    return madd(p, n, scale)


@njit
def curvature_seen(surf, ref, d, n_geo):
    """The surface's curvature at a hit as the ray (unit direction d) meets it, n_geo the geometric normal that
    `surface_at` returns there (outward on a sphere), for ray cones' spread
    (`methods.whitted_trace`): positive where it bulges towards the ray (convex), negative where it is hollow.
    A sphere's 1/radius (its transform's mean scale); a triangle with vertex normals, the least-squares rate at
    which the normals turn along its edges, Σ Δn·Δp / Σ |Δp|²; 0 for the rest (taken as flat)."""
    if ref >= 0:
        if (surf.tri_info[ref, INFO_FLAGS] & FLAG_NORMALS) == 0:
            return 0.0
        v = surf.tri_verts
        nn = surf.tri_normals
        num = 0.0
        den = 0.0
        for i, j in ((0, 1), (1, 2), (2, 0)):
            for k in range(3):
                dp = np.float64(v[ref, 3 * j + k]) - np.float64(v[ref, 3 * i + k])
                num += (np.float64(nn[ref, 3 * j + k]) - np.float64(nn[ref, 3 * i + k])) * dp
                den += dp * dp
        if not den > 0.0:
            return 0.0
        facing = 0.0
        for k in range(3):
            facing += (nn[ref, k] + nn[ref, 3 + k] + nn[ref, 6 + k]) * d[k]
        return num / den if facing < 0.0 else -num / den
    s = ~ref
    if surf.shape_info[s, INFO_KIND] != SHAPE_SPHERE:
        return 0.0
    m = surf.shape_xform[s]
    scale = 0.0
    for r in range(3):
        scale += math.sqrt(m[r, 0] * m[r, 0] + m[r, 1] * m[r, 1] + m[r, 2] * m[r, 2])
    k = scale / 3.0  # the canonical sphere has radius 1
    return k if n_geo[0] * d[0] + n_geo[1] * d[1] + n_geo[2] * d[2] < 0.0 else -k
