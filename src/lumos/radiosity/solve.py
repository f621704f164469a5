"""Solving the radiosity equation for a scene: mesh it into patches, light them, iterate to a solution.

    solution = solve(scene, settings)            # settings: a RenderSettings (its `radiosity` block)

    L_i = E_i + ρ_i · Σ_j F_ij · L_j             E_i = Le_i + (the light of point and directional lights)

Stages: (1) patches (`compile.patches`) and a BVH over them for visibility; (2) E: what each patch sends
before any interreflection: its own emission plus, for point and directional lights, the first bounce computed
analytically with shadow rays (DESIGN.md §3's units, so the result agrees with path and whitted); (3) one of
four solvers (`radiosity.solvers`); (4) the display mesh: radiance averaged to the patches' corners.
"""

from __future__ import annotations

import time
from typing import Callable, Optional

import numpy as np

from ..errors import LumosError
from ..kernels.threads import parallel_for
from ..kernels import layout as L
from ..compile.patches import Patches, refine
from .solution import Solution


def patch_arrays(p: Patches) -> L.PatchArrays:
    """The patches as the kernels read them: corners in each patch's own (counter-clockwise) order."""
    n = p.n
    idx = p.polys[p.patch_poly]  # (n, 4)
    k = np.where(idx[:, 3] >= 0, 4, 3).astype(np.int32)
    corners = np.zeros((n, 4, 3))
    tri = k == 3
    fwd = p.patch_side > 0
    order = np.where(fwd[:, None], np.arange(4), np.array([3, 2, 1, 0]))  # quads: reversed for the back side
    order[tri] = np.where(fwd[tri, None], np.array([0, 1, 2, 3]), np.array([2, 1, 0, 3]))
    picked = np.take_along_axis(idx, order, axis=1)
    corners[:] = p.vertices[np.maximum(picked, 0)]
    return L.PatchArrays(
        corners=corners, k=k, centre=np.ascontiguousarray(p.centre), normal=np.ascontiguousarray(p.normal),
        area=np.ascontiguousarray(p.area), rho=np.ascontiguousarray(p.reflectance, np.float64),
        emission=np.ascontiguousarray(p.emission, np.float64), poly=np.ascontiguousarray(p.patch_poly),
        side_patch=np.ascontiguousarray(p.side_patch), poly_normal=np.ascontiguousarray(p.poly_normal))


def _triangles(p: Patches) -> tuple[np.ndarray, np.ndarray]:
    """The patches' polygons as triangles (quads split in two): corners float64 (m, 3, 3) and the polygon of
    each, int32 (m,)."""
    polys = p.polys
    quad = polys[:, 3] >= 0
    a = np.concatenate([polys[:, [0, 1, 2]], polys[quad][:, [0, 2, 3]]])
    owner = np.concatenate([np.arange(len(polys)), np.nonzero(quad)[0]]).astype(np.int32)
    return p.vertices[a], owner


def patch_bvh(p: Patches):
    """A compiled scene of the patches' polygons as triangles (quads split in two), each carrying its polygon
    as object id: what visibility and shooting rays traverse. Returns (CompiledScene, tri_poly int32 (m,))."""
    from ..compile import triangle_arrays

    verts, owner = _triangles(p)
    compiled = triangle_arrays(verts.reshape(-1, 9), owner)
    tri_poly = np.ascontiguousarray(compiled.arrays.tri_info[:, L.INFO_OBJECT])
    return compiled, tri_poly


#: A triangle lies in a plane that bounds the scene when no vertex of the scene's convex hull is farther than
#: this share of the scene's size from its plane on the far side (the hull's vertices are float32).
BOUNDING_PLANE_TOLERANCE = 1e-6
#: The bounding-plane test costs (hull vertices × triangles); beyond this many products every triangle is kept.
BOUNDING_PLANE_WORK = 200_000_000


def occluder_bvh(p: Patches):
    """A compiled scene of the triangles that can block a form factor's visibility ray, each carrying its object
    as object id: the scene's surfaces uncut (`Patches.surfaces`: the same geometry as the patches' polygons, at
    every level of refinement, in far fewer pieces; the Cornell box's floor, light and blocks are 26 triangles,
    not the 1,126 of their patches or the 7,240 of their elements after refining), all but those lying in a plane
    that bounds the scene (a face of its convex hull: the walls, floor and ceiling of a room or a box). A segment
    between two points of the scene lies in their convex hull, so it meets such a triangle only at its own ends,
    which the visibility rays leave out; and a point on the outer side of a bounding plane faces nothing of the
    scene (cos θ <= 0), so no ray is asked there. Visibility is then the same, but the rays, which cross a room
    between its walls, no longer walk the BVH nodes of the walls they run along. Not for rays that may leave the
    scene (point lights outside it, the sky), which keep `patch_bvh`. Degenerate triangles, which block nothing,
    are left out too."""
    import manifold3d
    from ..compile import triangle_arrays

    verts, owner = p.surfaces, p.surface_object
    hull = manifold3d.Manifold.hull_points(np.ascontiguousarray(p.vertices, np.float64)).to_mesh()
    corners = np.asarray(hull.vert_properties, np.float64)[:, :3]
    keep = np.ones(len(verts), bool)
    if 0 < len(corners) * len(verts) <= BOUNDING_PLANE_WORK:
        size = float(np.linalg.norm(p.vertices.max(axis=0) - p.vertices.min(axis=0)))
        tol = BOUNDING_PLANE_TOLERANCE * max(size, 1e-300)
        normal = np.cross(verts[:, 1] - verts[:, 0], verts[:, 2] - verts[:, 0])
        length = np.linalg.norm(normal, axis=1)
        proper = length > 0.0
        normal[proper] /= length[proper, None]
        step = max(1, (1 << 22) // len(corners))
        for s in range(0, len(verts), step):
            n = normal[s:s + step]
            height = corners @ n.T - np.einsum("ij,ij->i", verts[s:s + step, 0], n)  # (hull corners, triangles)
            bounding = (height.max(axis=0) <= tol) | (height.min(axis=0) >= -tol)
            keep[s:s + step] = proper[s:s + step] & ~bounding
    return triangle_arrays(verts[keep].reshape(-1, 9), owner[keep])


def solve(scene, settings=None, progress: Optional[Callable[[float], None]] = None,
          say: Optional[Callable[[str], None]] = None) -> Solution:
    """The radiosity solution of `scene` (a Scene, a dict or a path) with the `radiosity` block of `settings`
    (a RenderSettings; default: the scene's own `render:` block)."""
    from ..compile import compile_scene, patches
    from ..scene.loader import load_scene

    scene = load_scene(scene)
    settings = scene.render if settings is None else settings
    settings = settings.model_copy(update={"method": "radiosity"})
    compiled = compile_scene(scene)
    patches.attach(compiled, scene, settings)
    return solve_compiled(compiled, settings, progress, say)


def solve_compiled(compiled, settings, progress=None, say=None) -> Solution:
    """`solve` on a scene compiled for method radiosity (`CompiledScene.patches`).

    With `subdivide`, the solution is refined up to `subdivide_levels` times: elements whose radiance differs
    from a neighbour's on the same surface by more than `subdivide_threshold` (relative) are cut in four and
    the system solved again, the patches still shooting as one (`solvers.Level`)."""
    from . import solvers

    rs = settings.radiosity
    t0 = time.perf_counter()
    patches = compiled.patches
    src = patch_arrays(patches)
    elements, recv_patch = patches, np.arange(patches.n, dtype=np.int64)
    direct_s = ff_s = 0.0
    rays = iterations = 0
    levels = rs.subdivide_levels if rs.subdivide else 0
    # only ray-cast form factors trace visibility rays (stochastic rays and hemicubes see every surface)
    traces_visibility = rs.form_factors == "raycast" and solvers.chosen(rs, patches.n) != "stochastic"
    # refining cuts polygons in four in their own planes: the surfaces, and what blocks a ray, stay the patches'
    occluders = occluder_bvh(patches) if traces_visibility else None
    inherited = columns = None
    # the elements' own tree: for the rays of point lights and the sky, and for every ray where no occluder tree
    # stands in (stochastic shooting, whose rays find the element they hit)
    lit = bool(np.any(compiled.arrays.light_kind <= L.LIGHT_DIRECTIONAL)) or compiled.environment is not None
    for level_index in range(levels + 1):
        recv = src if level_index == 0 else patch_arrays(elements)
        bvh, tri_poly = patch_bvh(elements) if lit or occluders is None else (None, None)
        level = solvers.Level(recv, src, recv_patch, bvh, tri_poly, patches, elements, occluders, inherited, columns)
        t1 = time.perf_counter()
        sent, r = _first_light(compiled, recv, bvh, rs, settings.seed)
        direct_s += time.perf_counter() - t1
        result = solvers.run(rs, level, sent, settings.seed, progress, say)
        columns = result.columns
        rays += r + result.rays
        ff_s += result.form_factor_s
        iterations += result.iterations
        if level_index == levels:
            break
        split = _to_refine(elements, recv, result.radiance, rs.subdivide_threshold)
        if not split.any():
            break
        if say is not None:
            say(f"refining {int(split.sum()):,} of {len(split):,} polygons where the radiance varies")
        cut = split[elements.patch_poly]  # per element of this level: its polygon is cut
        elements, parent = refine(elements, split)
        inherited = np.where(cut[parent], -1, parent).astype(np.int64)
        recv_patch = recv_patch[parent]
    t_solve = time.perf_counter()
    stats = {
        "patches": int(patches.n), "elements": int(elements.n), "polygons": int(len(elements.polys)),
        "direct_s": direct_s, "form_factor_s": ff_s, "solve_s": t_solve - t0 - direct_s - ff_s,
        "iterations": int(iterations), "residual": float(result.residual), "rays": int(rays),
        "solver": solvers.chosen(rs, patches.n), "form_factors": rs.form_factors,
    }
    return build_solution(elements, recv, result.radiance, recv_patch, rs.model_dump(), stats, compiled.digest)


def _first_light(compiled, recv, bvh, rs, seed):
    """E of every element: its emission and the first bounce of point, spot and directional lights and of the
    environment; (E, rays)."""
    from ..kernels.radiosity import direct_light, sky_light

    n = len(recv.area)
    first = np.zeros((n, 3))
    rays = np.zeros(-(-n // 256), np.int64)
    if np.any(compiled.arrays.light_kind <= L.LIGHT_DIRECTIONAL):
        parallel_for(lambda c0, c1: direct_light(bvh.arrays, compiled.arrays, recv, np.int64(rs.visibility_samples),
                                                 np.int64(seed), first, rays, np.int64(c0), np.int64(c1)),
                     0, len(rays))
    if compiled.environment is not None:
        sky = L.EnvironmentTable(*compiled.environment)
        sky_rays = np.zeros_like(rays)
        parallel_for(lambda c0, c1: sky_light(bvh.arrays, sky, recv, np.int64(rs.sky_samples), np.int64(seed), first,
                                              sky_rays, np.int64(c0), np.int64(c1)), 0, len(rays))
        rays += sky_rays
    sent = recv.emission + first
    if not np.any(sent > 0):
        raise LumosError("radiosity: nothing in the scene emits light (no area light, emissive object, point, spot "
                         "or directional light, or environment, reaches a surface)")
    return sent, int(rays.sum())


def _to_refine(elements: Patches, recv, radiance: np.ndarray, threshold: float) -> np.ndarray:
    """The polygons to cut: those of elements at a corner where the radiance of the surface's elements meeting
    there spans more than `threshold` of their mean (a shadow boundary, a steep gradient), ignoring the
    darkest (below 1/1000 of the brightest surface), where no one sees the difference."""
    from .display import corner_buckets

    owner, starts, order = corner_buckets(elements, recv)
    lum = radiance.mean(axis=1)
    floor = 1e-3 * float(lum[recv.emission.max(axis=1) <= 0].max(initial=lum.max()))
    flagged = np.zeros(elements.n, bool)
    vals = lum[owner[order]]
    for b in range(len(starts) - 1):
        lo, hi = starts[b], starts[b + 1]
        if hi - lo < 2:
            continue
        v = vals[lo:hi]
        top, bottom = v.max(), v.min()
        if top > floor and (top - bottom) > threshold * max(v.mean(), floor):
            flagged[owner[order[lo:hi]]] = True
    split = np.zeros(len(elements.polys), bool)
    split[elements.patch_poly[flagged]] = True
    return split


def _twins(p: Patches) -> np.ndarray:
    """The patch on the other side of each patch's polygon, -1 where that side is not a patch."""
    other = p.side_patch[p.patch_poly, np.where(p.patch_side > 0, 1, 0)]
    return np.ascontiguousarray(other, np.int32)


def build_solution(patches: Patches, pa: L.PatchArrays, radiance: np.ndarray, element_patch: np.ndarray,
                   settings: dict, stats: dict, digest: str) -> Solution:
    """The Solution: the patches with their radiance, and the display mesh (radiance averaged to corners)."""
    from .display import display_mesh

    vertices, normals, values, faces, face_element = display_mesh(patches, pa, radiance)
    n = patches.n
    element_vertices = pa.corners.reshape(-1, 3)
    element_polys = np.arange(4 * n, dtype=np.int32).reshape(n, 4)
    element_polys[pa.k == 3, 3] = -1
    return Solution(
        element_vertices=element_vertices, element_polys=element_polys, element_normal=pa.normal.copy(),
        element_area=pa.area.copy(), element_reflectance=pa.rho.copy(), element_emission=pa.emission.copy(),
        element_radiance=np.asarray(radiance, np.float64), element_object=patches.object_id.astype(np.int32),
        element_material=patches.material.astype(np.int32), element_patch=np.asarray(element_patch, np.int32),
        element_optics=np.ascontiguousarray(patches.optics, np.float64), element_twin=_twins(patches),
        vertices=vertices, vertex_normal=normals, vertex_radiance=values, faces=faces, face_element=face_element,
        settings=settings, stats=stats, scene_digest=digest)
