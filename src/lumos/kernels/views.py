"""Per-stage views of `SceneArrays` (see `layout`): the same arrays, regrouped so each call passes only its own."""

from .jit import njit, njit_alloc
from .layout import Geometry, Lighting, Surfaces, Textures


@njit
def geometry_of(sa):
    return Geometry(sa.node_box, sa.node_link, sa.prim_ref, sa.tri_verts, sa.shape_xform, sa.shape_info, sa.unbounded,
                    sa.csg_nodes, sa.wide_nodes, sa.wide_link, sa.leaf_tris, sa.leaf_link)


@njit
def surfaces_of(sa):
    return Surfaces(sa.tri_verts, sa.tri_normals, sa.tri_uvs, sa.tri_info, sa.shape_xform, sa.shape_info,
                    sa.shape_nscale)


@njit
def lighting_of(sa):
    return Lighting(sa.materials, sa.ambient, sa.light_kind, sa.light_samples, sa.light_vecs, sa.light_scalars,
                    sa.tex_info, sa.tex_pixels)


@njit
def sky_of(sa):
    """What rays that leave the scene see (`environment.sky_radiance`): the environment's image and info, and the
    background colour."""
    return sa.env_pixels, sa.env_info, sa.background


@njit
def textures_of(sa):
    return Textures(sa.tex_info, sa.tex_pixels, sa.tri_tangents)


@njit_alloc
def owned_views(sa):
    """(geometry, surfaces, lighting, textures) for a kernel compiled with Numba's runtime that is not a parallel
    loop (`whitted.explain_pixel`): built here, with the runtime, the views hold counted references. The
    device-function views above hold none (they are built inside each parallel loop's body), and a serial caller
    with the runtime would release references it never took."""
    return (Geometry(sa.node_box, sa.node_link, sa.prim_ref, sa.tri_verts, sa.shape_xform, sa.shape_info,
                     sa.unbounded, sa.csg_nodes, sa.wide_nodes, sa.wide_link, sa.leaf_tris, sa.leaf_link),
            Surfaces(sa.tri_verts, sa.tri_normals, sa.tri_uvs, sa.tri_info, sa.shape_xform, sa.shape_info,
                    sa.shape_nscale),
            Lighting(sa.materials, sa.ambient, sa.light_kind, sa.light_samples, sa.light_vecs, sa.light_scalars,
                    sa.tex_info, sa.tex_pixels),
            Textures(sa.tex_info, sa.tex_pixels, sa.tri_tangents))
