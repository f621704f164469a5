"""Hemicube form factors for the solvers (`kernels.hemicube`): the full matrix, and progressive shots.

Each row of the matrix is one hemicube at a receiving element's centre, rendered over the patches' polygons
(the shooters), turned about its normal by a random angle; a progressive shot is one hemicube at the shooting
patch's centre over the elements' polygons, and reciprocity (A_i·F_ij = A_j·F_ji) turns what it sees into
what each element receives. The hemicube's resolution is `hemicube_resolution` (the top face's side in pixels).
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels.hemicube import delta_form_factors, form_factor_matrix, hemicube_scratch
from ..kernels.rng import rand01

#: The hemicube's near plane and the lift of its centre off the surface, relative to the scene's size.
_NEAR = 1e-7
_LIFT = 1e-6


def _extent(patches) -> float:
    v = patches.vertices
    return float(np.ptp(v, axis=0).max()) if len(v) else 1.0


def _res(rs) -> int:
    return max(8, 2 * (rs.hemicube_resolution // 2))


def hemicube_matrix(rs, level, seed, F) -> None:
    """F (n_elements, n_patches) float32 in place: a hemicube at every element's centre over the patches."""
    geom = level.src_patches
    recv = level.recv
    scale = _extent(geom)
    points = recv.centre + recv.normal * (_LIFT * scale)
    phis = np.array([2 * math.pi * rand01(seed, i, 0, 7) for i in range(len(recv.area))])
    skip = level.src.poly[level.recv_patch].astype(np.int32)
    form_factor_matrix(np.ascontiguousarray(points), np.ascontiguousarray(recv.normal), phis, skip,
                       geom.vertices, geom.polys, geom.poly_normal, geom.side_patch, delta_form_factors(_res(rs)),
                       _NEAR * scale, F)


class HemicubeShooter:
    """Progressive shots through a hemicube at each shooting patch, over the receiving elements' polygons; the
    form factors of up to `keep` shooters are kept (float32) for their next shots."""

    def __init__(self, rs, level, seed, keep: int = 0):
        self.level = level
        self.seed = int(seed)
        self.dF = delta_form_factors(_res(rs))
        self.scratch = hemicube_scratch(self.dF.shape[1])
        self.ff = np.zeros(len(level.recv.area))
        self.scale = _extent(level.recv_patches)
        self.keep = keep
        self.kept: dict[int, np.ndarray] = {}  # shooter → F_j→i for every receiver i

    def shoot(self, j: int, d: np.ndarray, shot: int, radiance: np.ndarray, unshot: np.ndarray) -> None:
        from ..kernels.radiosity import hemicube_shot

        src, recv, geom = self.level.src, self.level.recv, self.level.recv_patches
        if j in self.kept:  # a shooter shot before: the same hemicube, applied as the kernel does
            got = recv.rho * (self.kept[j] * (float(src.area[j]) / recv.area))[:, None] * d
            radiance += got
            unshot += got
            return
        x = tuple(src.centre[j] + src.normal[j] * (_LIFT * self.scale))
        phi = 2 * math.pi * rand01(self.seed, j, shot, 7)
        hemicube_shot(x, tuple(src.normal[j]), phi, geom.vertices, geom.polys, geom.poly_normal, geom.side_patch,
                      self.dF, _NEAR * self.scale, self.scratch, self.ff, float(src.area[j]), float(d[0]),
                      float(d[1]), float(d[2]), recv.area, recv.rho, radiance, unshot)
        if len(self.kept) < self.keep:
            self.kept[j] = self.ff.astype(np.float32)
