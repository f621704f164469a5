"""Interference of two solids (`RayCaster.interference`): do they share volume, where, and how much.

    found = measure_interference(segments, box_a, box_b, ia, ib, tolerance, resolution, seed)

Parallel rays on a jittered grid along each axis over the overlap of the two solids' boxes; the pieces of each
ray inside a and inside b (from `segments`, the ray caster's inside-pieces query) are intersected: their total
length times the cell area is the shared volume, four interleaved sub-grids per axis give twelve independent
estimates and so its standard error; the pieces' ends are surface points, whose least distance estimates the
clearance of solids that do not touch. NumPy only: the rays are cast by the caller's kernel.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from ..errors import LumosError


@dataclass
class Interference:
    """What `RayCaster.interference` found (docs/queries.md: accuracy)."""

    intersects: bool  # the solids share volume (or, with a tolerance, come closer than it along x, y or z)
    volume: float  # estimated volume of their intersection
    volume_error: float  # standard error of `volume`
    points: np.ndarray  # float64 (k, 3): sample points inside both (empty when they do not intersect)
    spacing: float  # the ray grid's spacing: overlaps thinner than about this may be missed
    min_distance: Optional[float]  # not intersecting: the least distance between sampled surface points
    # (an upper bound of the true distance, within about `spacing` of it); 0 when they intersect; None when
    # the solids' boxes are too far apart for any ray to cross both or scipy is missing


def measure_interference(segments: Callable, ba: np.ndarray, bb: np.ndarray, ia: int, ib: int, tol: float,
                         res: int, seed: int) -> Interference:
    """Whether solids ia and ib intersect, where and by how much: `segments(origins, directions)` gives the
    pieces of each ray inside either solid (`queries.Segments`, whole rays), `ba` and `bb` their world boxes
    (2, 3). A jittered grid of res × res parallel rays along each of x, y and z over the overlap of the boxes;
    the pieces inside a and inside b intersected per ray (docs/queries.md)."""
    if not (np.isfinite(ba).all() and np.isfinite(bb).all()):
        raise LumosError("interference: both objects must be bounded")
    # the overlap of the two boxes; on an axis where they are apart, the gap between them (rays along that axis
    # then cross both solids' facing surfaces: the clearance estimate)
    lo, hi = np.maximum(ba[0], bb[0]), np.minimum(ba[1], bb[1])
    lo, hi = np.minimum(lo, hi) - tol, np.maximum(lo, hi) + tol
    rng = np.random.default_rng(seed)
    estimates, points, surf_a, surf_b = [], [], [], []
    spacing, touch = 0.0, False
    for axis in range(3):
        u, v = [k for k in range(3) if k != axis]
        size_u, size_v = hi[u] - lo[u], hi[v] - lo[v]
        spacing = max(spacing, size_u / res, size_v / res)
        gi, gj = (g.ravel() for g in np.meshgrid(np.arange(res), np.arange(res), indexing="ij"))
        o = np.zeros((res * res, 3))
        o[:, u] = lo[u] + (gi + rng.random(gi.size)) * size_u / res  # one jittered ray per cell: unbiased
        o[:, v] = lo[v] + (gj + rng.random(gj.size)) * size_v / res
        o[:, axis] = lo[axis]
        d = np.zeros_like(o)
        d[:, axis] = 1.0
        seg = segments(o, d)
        overlap, (rays, mids), _ = _overlaps(seg, ia, ib, len(o), 0.0)
        # four interleaved sub-grids (every other cell) give four independent estimates from this axis
        group = (gi % 2) * 2 + (gj % 2)
        cell = size_u * size_v / (res * res)
        estimates += [4.0 * cell * overlap[group == g].sum() for g in range(4)]
        points.append(o[rays] + mids[:, None] * d[rays])
        if tol > 0.0:
            touch = touch or _overlaps(seg, ia, ib, len(o), tol)[2]
        for obj, out in ((ia, surf_a), (ib, surf_b)):
            m = seg.object_id == obj
            ends = np.concatenate([seg.t_in[m], seg.t_out[m]])
            r = np.concatenate([seg.ray[m], seg.ray[m]])
            out.append(o[r] + ends[:, None] * d[r])
    estimates = np.array(estimates)
    volume = float(estimates.mean())
    error = float(estimates.std(ddof=1) / np.sqrt(len(estimates)))
    pts = np.concatenate(points)
    min_distance = 0.0 if len(pts) else _min_distance(np.concatenate(surf_a), np.concatenate(surf_b))
    return Interference(bool(len(pts)) or touch, volume, error, pts, float(spacing), min_distance)


def _overlaps(seg, ia, ib, n, tol):
    """Per ray, the total length inside both a and b ((n,) float64); the (ray, t) of each overlap's middle; and
    with tol > 0 whether any pieces of a and b, each grown by tol/2 at both ends, overlap."""
    ma, mb = seg.object_id == ia, seg.object_id == ib
    ra, a0, a1 = seg.ray[ma], seg.t_in[ma] - tol / 2, seg.t_out[ma] + tol / 2
    rb, b0, b1 = seg.ray[mb], seg.t_in[mb] - tol / 2, seg.t_out[mb] + tol / 2
    # every pair of an a piece and a b piece on the same ray (few per ray)
    order = np.argsort(rb, kind="stable")
    rb, b0, b1 = rb[order], b0[order], b1[order]
    start = np.searchsorted(rb, ra, "left")
    stop = np.searchsorted(rb, ra, "right")
    reps = stop - start
    ia_idx = np.repeat(np.arange(len(ra)), reps)
    ib_idx = (np.arange(reps.sum()) - np.repeat(np.cumsum(reps) - reps, reps)) + np.repeat(start, reps)
    lo = np.maximum(a0[ia_idx], b0[ib_idx])
    hi = np.minimum(a1[ia_idx], b1[ib_idx])
    live = hi > lo
    rays = ra[ia_idx][live]
    length = np.bincount(rays, weights=(hi - lo)[live], minlength=n)
    return length, (rays, 0.5 * (lo + hi)[live]), bool(live.any())


def _min_distance(a: np.ndarray, b: np.ndarray) -> Optional[float]:
    if not len(a) or not len(b):
        return None
    try:
        from scipy.spatial import cKDTree
    except ImportError:
        return None
    dist, _ = cKDTree(b).query(a, k=1)
    return float(dist.min())

