"""From patch radiance to what is drawn: radiance averaged to the patches' corners (Gouraud), or kept per
patch (flat), and the scan-line renderer drawing it.

Each corner of a patch takes the area-weighted mean, over the patches that meet at that point on the same
surface (object, material, side) and turned less than 35° from it, of their radiance carried to the corner
along their gradients (`extrapolated`: least squares over the neighbouring patches' centres): so a
tessellated sphere or a subdivided wall shades smoothly, the edge of a box or the line where two materials
meet stays sharp, as in the classic radiosity displays (Cohen & Wallace, *Radiosity and Realistic Image
Synthesis*, §8.3), and a surface's border takes the trend of the light there rather than repeating its edge
patches' centre values (nodal extrapolation, ibid.).
"""

from __future__ import annotations

import numpy as np

from ..kernels.radiosity import gradient_moments, smooth_corners
from ..compile.patches import SMOOTH_COS


def corner_buckets(patches, pa):
    """The patches' corners grouped by surface and point: (owner (m,) the patch of each corner, starts (b+1,)
    and order (m,): bucket b holds corners order[starts[b]:starts[b+1]])."""
    n = len(pa.area)
    mask = np.ones((n, 4), bool)
    mask[pa.k == 3, 3] = False
    vertices = pa.corners[mask]
    owner = np.repeat(np.arange(n), pa.k)
    extent = float(np.ptp(vertices, axis=0).max()) if len(vertices) else 1.0
    q = np.round(vertices / max(extent * 1e-7, 1e-300)).astype(np.int64)
    keys = np.column_stack([patches.smooth_group[owner].astype(np.int64), q])
    order = np.lexsort(keys.T[::-1])
    sk = keys[order]
    new = np.ones(len(sk), bool)
    new[1:] = np.any(sk[1:] != sk[:-1], axis=1)
    starts = np.concatenate([np.nonzero(new)[0], [len(sk)]]).astype(np.int64)
    return owner, starts, order.astype(np.int64)


#: Corners take each patch's radiance carried to them along its gradient (`extrapolated`), not its centre value.
EXTRAPOLATE = True


def extrapolated(pa, radiance, owner, starts, order, vertices):
    """Each patch's radiance at each of its corners, L_p + ∇L_p·(v − c_p), the gradient fitted by least squares
    to the neighbouring patches' centres on the same surface. Where patches meet all round a corner, the
    gradients of the patches around it cancel in the mean and the corner takes about the plain average; at a
    surface's edge (a box's crease, a wall's end), where the plain average can only repeat the edge patches'
    own centre values, the corner takes the trend instead: the darkening into a room's corners and the fall of
    light along a wall, which the patch centres alone put half a patch too far in. Kept within 0 and twice the
    brightest neighbour's radiance (a limiter: a shadow boundary's steep gradient does not overshoot)."""
    n = len(pa.area)
    a = np.zeros((n, 3, 3))
    b = np.zeros((n, 3, 3))
    normals = pa.normal[owner]
    gradient_moments(order, starts, owner.astype(np.int64), normals, pa.centre, radiance, SMOOTH_COS, a, b)
    # the gradient lies in the patch's plane: regularise the normal direction (and a lone patch) away
    scale = np.maximum(np.trace(a, axis1=1, axis2=2), 1e-30)
    a += scale[:, None, None] * pa.normal[:, :, None] * pa.normal[:, None, :]
    a += 1e-6 * scale[:, None, None] * np.eye(3)
    grad = np.linalg.solve(a, b)  # (n, 3 directions, 3 channels)
    offset = vertices - pa.centre[owner]
    value = radiance[owner] + np.einsum("md,mdc->mc", offset, grad[owner])
    # the limiter's bound: the brightest patch meeting each corner's bucket
    top = np.zeros((len(starts) - 1, 3))
    bucket = np.repeat(np.arange(len(starts) - 1), np.diff(starts))
    np.maximum.at(top, bucket, radiance[owner[order]])
    bound = np.empty_like(value)
    bound[order] = top[bucket]
    return np.clip(value, 0.0, 2.0 * bound)


def display_mesh(patches, pa, radiance):
    """The display mesh: one vertex per patch corner, with its smoothed radiance; triangles wound about their
    patch's normal. Returns (vertices (m, 3), normals (m, 3), radiance (m, 3) float64, faces (f, 3) int32,
    face_element (f,) int32)."""
    n = len(pa.area)
    k = pa.k
    mask = np.ones((n, 4), bool)
    mask[k == 3, 3] = False
    vertices = pa.corners[mask]
    owner, starts, order = corner_buckets(patches, pa)
    normals = pa.normal[owner]
    values = np.empty((len(vertices), 3))
    at_corner = extrapolated(pa, radiance, owner, starts, order, vertices) if EXTRAPOLATE else radiance[owner]
    smooth_corners(order, starts, normals, pa.area[owner], at_corner, SMOOTH_COS, values)
    # triangles: (0, 1, 2) of each patch and (0, 2, 3) of each quad
    first = np.concatenate([[0], np.cumsum(k)[:-1]])
    tris = [np.column_stack([first, first + 1, first + 2])]
    quads = np.nonzero(k == 4)[0]
    tris.append(np.column_stack([first[quads], first[quads] + 2, first[quads] + 3]))
    faces = np.concatenate(tris).astype(np.int32)
    face_element = np.concatenate([np.arange(n), quads]).astype(np.int32)
    return vertices, normals, values, faces, face_element
