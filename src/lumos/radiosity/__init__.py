"""Radiosity: the diffuse light of a scene solved over patches of its surfaces, view-independent.

    from lumos.radiosity import solve, Solution
    solution = solve("scene.yaml")                    # the scene's render.radiosity settings
    solution.save("scene.npz"); solution.export("scene.ply")
    lumos.render("scene.yaml", method="radiosity", solution="scene.npz")   # another view, no solving

Modules: `patches` (meshing into patches), `solvers` (Gauss–Seidel, Jacobi, progressive, stochastic),
`solve` (the pipeline), `display` (radiance to the display mesh), `solution`, `store` (.npz) and `export`
(.ply, .glb). The kernels are in `lumos.kernels.formfactor`, `lumos.kernels.radiosity` and
`lumos.kernels.hemicube`.
"""

from .solution import Solution
from .solve import solve

__all__ = ["Solution", "solve"]
