"""Polygons to triangles: fans for convex polygons, ear clipping for concave ones.

    faces, face_polygon = triangulate(vertices, [[0, 1, 2, 3], [3, 2, 4, 5, 6]])
    local = triangulate_polygon(points)        # (k - 2, 3) indices into points

Interpolated shading of a polygon with more than three vertices depends on its orientation on the screen:
a scan line interpolates between its two edges, and which edges those are changes as the polygon turns.
Triangles have no such problem (linear interpolation over a triangle is the same from every view), so the
renderer splits every polygon into triangles once, at compile time.

A polygon is triangulated in its best-fit plane, whose normal is Newell's (Sutherland, Sproull & Schumacker
1974, "A characterization of ten hidden-surface algorithms"), so nearly planar polygons work too. Triangles
keep the polygon's winding. Convex polygons are fanned (all at once, vectorized); concave ones are clipped ear
by ear (Meisters 1975, "Polygons have ears").
"""

from __future__ import annotations

import numpy as np

#: Areas below this fraction of the squared polygon size count as zero (collinear corners, flat polygons).
_AREA_EPS = 1e-12


def triangulate_polygon(points) -> np.ndarray:
    """Triangulate one simple polygon, convex or concave, given by its corners in order.

    points: float (k, 3), k >= 3, planar or nearly planar; collinear corners are allowed.
    Returns int64 (k - 2, 3) local indices into `points`, each triangle with the polygon's winding (its normal
    along the polygon's Newell normal). A degenerate polygon (no area) is fanned from corner 0.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 3:
        raise ValueError(f"a polygon needs points of shape (k >= 3, 3), got {points.shape}")
    k = len(points)
    if k == 3:
        return np.array([[0, 1, 2]], dtype=np.int64)
    normal = _newell(points[None])[0]
    scale2 = float(np.ptp(points, axis=0).max()) ** 2
    if np.linalg.norm(normal) <= _AREA_EPS * scale2:
        return _fan(k, 0)
    xy = _project(points[None], normal[None])[0]
    return np.array(_ear_clip(xy.tolist(), _AREA_EPS * scale2), dtype=np.int64).reshape(k - 2, 3)


def triangulate(vertices, polygons) -> tuple[np.ndarray, np.ndarray]:
    """Split polygons into triangles.

    vertices: float (n, 3) positions.
    polygons: a sequence of int index arrays, each of length >= 3 (or an int (p, k) array).
    Returns (faces int64 (m, 3), face_polygon int64 (m,)): the triangles, in polygon order, and for each the
    index of the polygon it came from. Triangles pass through; convex polygons are fanned (from their only
    collinear corner, if they have exactly one, so that a vertex inserted into an edge is used); concave
    polygons and convex ones with several collinear corners are ear-clipped.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), got {vertices.shape}")
    polygons = [np.asarray(p, dtype=np.int64).ravel() for p in polygons]
    lengths = np.array([len(p) for p in polygons], dtype=np.int64)
    if len(polygons) == 0:
        return np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64)
    if lengths.min() < 3:
        bad = int(np.argmin(lengths))
        raise ValueError(f"polygon {bad} has {lengths[bad]} vertices (at least 3 are needed)")
    flat = np.concatenate(polygons)
    if flat.min() < 0 or flat.max() >= len(vertices):
        raise ValueError(f"polygons index vertices outside [0, {len(vertices)})")

    # Polygons of one length are triangulated together; the pieces are put back in polygon order after.
    pieces_faces, pieces_polygon = [], []
    for k in np.unique(lengths):
        ids = np.flatnonzero(lengths == k)
        rings = np.stack([polygons[i] for i in ids])                             # (p, k)
        local, local_polygon = _triangulate_rings(vertices[rings], int(k))
        pieces_faces.append(np.take_along_axis(rings[local_polygon], local, axis=1))
        pieces_polygon.append(ids[local_polygon])
    faces = np.concatenate(pieces_faces)
    face_polygon = np.concatenate(pieces_polygon)
    order = np.argsort(face_polygon, kind="stable")
    return faces[order], face_polygon[order]


def _triangulate_rings(points: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of p polygons with k corners each, points (p, k, 3): local indices (t, 3) and polygon (t,)."""
    p = len(points)
    if k == 3:
        return np.tile(np.arange(3, dtype=np.int64), (p, 1)), np.arange(p, dtype=np.int64)
    normals = _newell(points)
    scale2 = np.ptp(points, axis=1).max(axis=1) ** 2
    eps = _AREA_EPS * scale2                                                      # (p,)
    flat_polygon = np.linalg.norm(normals, axis=1) <= eps

    # Turn at each corner, as twice the signed area of (previous, corner, next) along the Newell normal.
    before = points - np.roll(points, 1, axis=1)
    after = np.roll(points, -1, axis=1) - points
    turn = np.einsum("pkc,pc->pk", np.cross(before, after), normals / np.maximum(
        np.linalg.norm(normals, axis=1), 1e-300)[:, None])
    collinear = np.abs(turn) <= eps[:, None]
    convex = (turn >= -eps[:, None]).all(axis=1)
    n_collinear = collinear.sum(axis=1)

    fan_ok = flat_polygon | (convex & (n_collinear <= 1))
    apex = np.where(n_collinear == 1, np.argmax(collinear, axis=1), 0) * ~flat_polygon
    local_parts, polygon_parts = [], []
    if fan_ok.any():
        ids = np.flatnonzero(fan_ok)
        fan = _fan(k, 0)                                                          # (k - 2, 3)
        local = (fan[None, :, :] + apex[ids, None, None]) % k                    # rotate the fan to the apex
        local_parts.append(local.reshape(-1, 3))
        polygon_parts.append(np.repeat(ids, k - 2))
    for i in np.flatnonzero(~fan_ok):
        local_parts.append(triangulate_polygon(points[i]))
        polygon_parts.append(np.full(k - 2, i, dtype=np.int64))
    return np.concatenate(local_parts), np.concatenate(polygon_parts)


def _newell(points: np.ndarray) -> np.ndarray:
    """Newell normals (p, 3) of polygons (p, k, 3): twice the vector area, about the centroid for accuracy."""
    centred = points - points.mean(axis=1, keepdims=True)
    return np.cross(centred, np.roll(centred, -1, axis=1)).sum(axis=1)


def _project(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Coordinates (p, k, 2) in each polygon's plane, in a basis (u, v) with u x v along the normal.

    The polygon then runs counter-clockwise in (u, v).
    """
    w = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    # Any vector not parallel to w: the axis along w's smallest component.
    helper = np.eye(3)[np.argmin(np.abs(w), axis=1)]
    u = np.cross(helper, w)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(w, u)
    return np.stack([np.einsum("pkc,pc->pk", points, u), np.einsum("pkc,pc->pk", points, v)], axis=2)


def _fan(k: int, apex: int) -> np.ndarray:
    """Fan (k - 2, 3) of a k-gon from corner `apex`."""
    i = np.arange(1, k - 1)
    return (np.stack([np.zeros_like(i), i, i + 1], axis=1) + apex) % k


def _ear_clip(xy: list, eps: float) -> list:
    """Ear clipping of a counter-clockwise simple polygon given as [[x, y], ...]; returns corner triples.

    An ear is a strictly convex corner whose triangle holds no other remaining corner, not even on its
    border (a corner on the new diagonal would leave a sliver). Where no ear exists (round-off on nearly
    degenerate input), the most convex corner is clipped anyway, so there are always k - 2 triangles.
    """
    remaining = list(range(len(xy)))
    triangles = []

    def area2(a, b, c):
        (ax, ay), (bx, by), (cx, cy) = xy[a], xy[b], xy[c]
        return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)

    def is_ear(j):
        m = len(remaining)
        a, b, c = remaining[j - 1], remaining[j], remaining[(j + 1) % m]
        if area2(a, b, c) <= eps:
            return False
        for q in remaining:
            if q in (a, b, c) or xy[q] in (xy[a], xy[b], xy[c]):
                continue
            if area2(a, b, q) >= -eps and area2(b, c, q) >= -eps and area2(c, a, q) >= -eps:
                return False
        return True

    start = 0
    while len(remaining) > 3:
        m = len(remaining)
        # Look for the next ear where the last one was cut: ears cluster, which keeps this near O(k^2).
        j = next((j % m for j in range(start, start + m) if is_ear(j % m)), None)
        if j is None:   # no clean ear: take the most convex corner
            j = max(range(m), key=lambda j: area2(remaining[j - 1], remaining[j], remaining[(j + 1) % m]))
        start = max(j - 1, 0)
        triangles.append((remaining[j - 1], remaining[j], remaining[(j + 1) % m]))
        del remaining[j]
    triangles.append(tuple(remaining))
    return triangles
