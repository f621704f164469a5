"""Radiosity: the diffuse light of a scene solved once for its surfaces, then drawn from any camera by the
scan-line renderer with Gouraud interpolation (the chapter's two halves joined).

    L_i = E_i + ρ_i · Σ_j F_ij · L_j           (the radiosity equation over the patches; B = π·L)

The solution (`lumos.radiosity`: meshing into patches, form factors, four solvers) depends only on the
geometry, materials and lights, not on the camera: `lumos radiosity solve` saves it, and `render(...,
solution=...)` draws a new view of it without solving again. Patch radiance is averaged to the patches'
corners and interpolated across them (`display: gouraud`), or each patch is shown in its own colour
(`display: flat`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import LumosError
from ..kernels.threads import parallel_for
from .capabilities import check_settings
from .common import Film, background_image
from .raster import draw_colours


#: The two-pass display's mirror and glass bounces when max_depth is -1 (unbounded): each costs one ray and
#: takes kr or kt of what remains, so past this many the rest is below any display's precision.
UNBOUNDED_DEPTH = 32


def render_radiosity(compiled, camera, settings, progress=None, solution=None) -> Film:
    """Solve (or take `solution`: a `radiosity.Solution` or the path of a saved one) and draw it from `camera`."""
    from ..radiosity.solution import Solution
    from ..radiosity.solve import solve_compiled
    from .common import set_threads

    check_settings(settings)
    set_threads(settings.threads)  # the solve, too, runs on the threads asked for
    solve_rays = 0
    if solution is None:
        # the bar covers the solve (its first 90%: shots, sweeps or iterations against the tolerance) and then
        # the display
        solution = solve_compiled(compiled, settings, None if progress is None else (lambda f: progress(0.9 * f)))
        solve_rays = int(solution.stats.get("rays", 0))
        progress = None if progress is None else _after(progress, 0.9)
    elif isinstance(solution, (str, Path)):
        solution = Solution.load(solution, compiled.digest)
    elif solution.scene_digest and compiled.digest and solution.scene_digest != compiled.digest:
        raise LumosError("radiosity: the solution was solved for a different scene (its geometry, materials or lights "
                         "differ); solve this one again")
    if np.any(solution.element_optics[:, :6] > 0.0):
        if settings.aov:
            import warnings

            from ..errors import LumosWarning

            warnings.warn("radiosity: the two-pass display (mirrors and glass) gives no AOVs; "
                          f"{', '.join(settings.aov)} not written", LumosWarning, stacklevel=2)
        film = _two_pass(solution, camera, settings, compiled.arrays.background, progress)
    else:
        face = solution.face_element
        film = draw_colours(solution.vertices, solution.vertex_normal, solution.faces, solution.vertex_radiance,
                            solution.element_radiance[face], solution.element_reflectance[face],
                            solution.element_object[face], camera, settings,
                            background_image(compiled.environment, compiled.arrays.background, camera,
                                             settings.width, settings.height), progress)
    film.extra = {"radiosity": dict(solution.stats)}
    film.rays += solve_rays  # the solve's shadow and visibility rays count as this render's rays
    return film


def _after(progress, start: float):
    """`progress` for the rest of a task, from `start` to 1."""
    return lambda f: progress(start + (1.0 - start) * f)


def _two_pass(solution, camera, settings, background, progress) -> Film:
    """Mirrors and glass: camera rays traced through them into the solution (`kernels.radiosity.trace_two_pass`).
    What it captures: the view-dependent reflections and refractions of the diffuse solution, seen from the eye.
    What it does not: light that mirrors and glass send onto diffuse surfaces (caustics; the solution treats
    them by their kd alone), and glossy (ks) highlights."""
    from ..compile import triangle_arrays
    from ..compile.camera import camera_arrays
    from ..kernels.radiosity import trace_two_pass
    from .common import check_memory, set_threads

    width, height = settings.width, settings.height
    check_memory(width, height)
    threads = set_threads(settings.threads)
    faces = solution.faces
    bvh = triangle_arrays(solution.vertices[faces].reshape(-1, 9), np.arange(len(faces), dtype=np.int32))
    from ..kernels.layout import INFO_OBJECT

    tri_face = np.ascontiguousarray(bvh.arrays.tri_info[:, INFO_OBJECT])
    n = solution.n_elements
    face0 = np.full(n, -1, np.int32)
    face1 = np.full(n, -1, np.int32)
    order = np.argsort(solution.face_element, kind="stable")
    fe = solution.face_element[order]
    first = np.searchsorted(fe, np.arange(n), side="left")
    count = np.searchsorted(fe, np.arange(n), side="right") - first
    face0[count > 0] = order[first[count > 0]]
    two = count > 1
    face1[two] = order[first[two] + 1]
    cam_vecs, cam_params = camera_arrays(camera)
    spp = 1 if settings.antialias == "none" else settings.spp
    depth = settings.resolved_max_depth()
    out = np.zeros((height, width, 3))
    rays = np.zeros(height, np.int64)
    faces, background = np.ascontiguousarray(faces), np.asarray(background, np.float64)
    max_depth = np.int64(UNBOUNDED_DEPTH if depth is None else depth)
    parallel_for(lambda y0, y1: trace_two_pass(bvh.arrays, tri_face, faces, solution.face_element, face0, face1,
                                               solution.vertices, solution.vertex_radiance, solution.element_normal,
                                               solution.element_optics, solution.element_twin, cam_vecs, cam_params,
                                               np.int64(width), np.int64(height), np.int64(spp),
                                               np.int64(settings.seed), max_depth, background, out, rays,
                                               np.int64(y0), np.int64(y1)), 0, height)
    if progress is not None:
        progress(1.0)
    return Film(out.astype(np.float32), {}, int(rays.sum()), threads, primary_rays=width * height * spp)
