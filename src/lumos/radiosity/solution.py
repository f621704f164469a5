"""A radiosity solution: the patches a scene was meshed into, what each sends out, and how it was solved.

    solution = solve(scene)                    # lumos.radiosity.solve
    solution.save("box.npz"); Solution.load("box.npz")
    solution.export("baked.ply")              # or .glb: the display mesh with per-vertex radiance

Everything is in world space, linear RGB radiance (Lambertian surfaces: radiosity B = π·L). Two levels:

- **elements** — the polygons the solvers compute radiance for (`element_*` arrays). Each is one side of a
  planar triangle or quad, facing `element_normal`: a closed solid has its outside only; an open surface (a
  wall, a disk, a mesh) one element per side, since light may reach either side.
- **display mesh** — what is drawn and exported: one-sided polygons (each element's, wound to face its
  normal) over vertices split where the surface creases or the material changes, each vertex carrying the
  area-weighted mean radiance of the elements around it (`vertex_radiance`), so that Gouraud interpolation
  shows a continuous surface; `face_element` ties each display face to its element.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np


@dataclass
class Solution:
    # elements (what the solvers solve for)
    element_vertices: np.ndarray  # float64 (nv_e, 3): corner positions shared by the elements
    element_polys: np.ndarray  # int32 (n, 4): corner indices in counter-clockwise order about the normal;
    # column 3 is -1 for triangles
    element_normal: np.ndarray  # float64 (n, 3): unit normal of the side the element faces
    element_area: np.ndarray  # float64 (n,)
    element_reflectance: np.ndarray  # float64 (n, 3): ρ (the material's kd, read physically)
    element_emission: np.ndarray  # float64 (n, 3): Le, radiance the element emits on its own
    element_radiance: np.ndarray  # float64 (n, 3): the solution: L = Le + ρ·(irradiance)/π
    element_object: np.ndarray  # int32 (n,): object index (scene lights: n_objects + light index)
    element_material: np.ndarray  # int32 (n,): material row
    element_patch: np.ndarray  # int32 (n,): the patch each element refines (its own index when unrefined)
    element_optics: np.ndarray  # float64 (n, 9): kr (3), kt (3), ior, fresnel (1/0), and 1 for a solid's outside,
    # -1 for its inside, 0 for an open surface (what the two-pass display traces mirrors and glass with)
    element_twin: np.ndarray  # int32 (n,): the element on the other side of the same polygon, -1 where none
    # display mesh
    vertices: np.ndarray  # float64 (nv, 3)
    vertex_normal: np.ndarray  # float64 (nv, 3): unit
    vertex_radiance: np.ndarray  # float64 (nv, 3)
    faces: np.ndarray  # int32 (nf, 3): triangles, wound counter-clockwise about their element's normal
    face_element: np.ndarray  # int32 (nf,)
    # provenance
    settings: dict = field(default_factory=dict)  # the radiosity settings it was solved with
    stats: dict = field(default_factory=dict)  # patches, elements, form-factor and solve seconds, iterations...
    scene_digest: str = ""  # of the geometry and materials it was solved for (reloading checks it)

    @property
    def n_elements(self) -> int:
        return int(len(self.element_polys))

    def element_corners(self, i: int) -> np.ndarray:
        """float64 (3 or 4, 3): the corners of element i."""
        idx = self.element_polys[i]
        return self.element_vertices[idx[idx >= 0]]

    def save(self, path) -> None:
        from .store import save_solution

        save_solution(self, path)

    @classmethod
    def load(cls, path, scene_digest: Optional[str] = None) -> "Solution":
        from .store import load_solution

        return load_solution(path, scene_digest)

    def export(self, path, exposure: float = 1.0) -> None:
        from .export import export_solution

        export_solution(self, path, exposure=exposure)
