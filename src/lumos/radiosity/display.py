"""From patch radiance to what is drawn: radiance averaged to the patches' corners (Gouraud), or kept per
patch (flat), and the scan-line renderer drawing it.

Each corner of a patch takes the area-weighted mean radiance of the patches that meet at that point, on the
same surface (object, material, side) and turned less than 35° from it: so a tessellated sphere or a
subdivided wall shades smoothly, while the edge of a box or the line where two materials meet stays sharp,
as in the classic radiosity displays (Cohen & Wallace, *Radiosity and Realistic Image Synthesis*, §8.3).
"""

from __future__ import annotations

import numpy as np

from ..kernels.radiosity import smooth_corners
from .patches import SMOOTH_COS


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
    smooth_corners(order, starts, normals, pa.area[owner], radiance[owner], SMOOTH_COS, values)
    # triangles: (0, 1, 2) of each patch and (0, 2, 3) of each quad
    first = np.concatenate([[0], np.cumsum(k)[:-1]])
    tris = [np.column_stack([first, first + 1, first + 2])]
    quads = np.nonzero(k == 4)[0]
    tris.append(np.column_stack([first[quads], first[quads] + 2, first[quads] + 3]))
    faces = np.concatenate(tris).astype(np.int32)
    face_element = np.concatenate([np.arange(n), quads]).astype(np.int32)
    return vertices, normals, values, faces, face_element
