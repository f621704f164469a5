"""Per-stage views of `SceneArrays` (see `layout`): the same arrays, regrouped so each call passes only its own."""

from numba.core import types
from numba.extending import overload

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
    """The `Textures` view, or None for the lean arrays of a plain scene (`compile.features`), whose kernels then
    compile no texture lookup: every reader of the view returns the untextured value for None."""
    return textures_view(sa.tex_info, sa.tex_pixels, sa.tri_tangents)


def textures_view(info, pixels, tangents):
    """The `Textures` view of these arrays, or None where `info` is None (see `textures_of`). Chosen as Numba types
    the call (an `@overload`), so that the kernel holds the view or None, never an optional of both: an `if info
    is None` in a kernel is settled before typing only where `info` is None, and with arrays both returns would
    be typed."""
    return None if info is None else Textures(info, pixels, tangents)


def opacity_view(info, pixels):
    """`textures_view` without tangents (shape (0, 12)), for the opacity cut-outs' readers
    (`texture.lighting_textures`)."""
    return None if info is None else Textures(info, pixels, pixels[:0])


@overload(textures_view)
def _textures_view(info, pixels, tangents):
    if isinstance(info, types.NoneType):
        return lambda info, pixels, tangents: None
    return lambda info, pixels, tangents: Textures(info, pixels, tangents)


@overload(opacity_view)
def _opacity_view(info, pixels):
    if isinstance(info, types.NoneType):
        return lambda info, pixels: None
    return lambda info, pixels: Textures(info, pixels, pixels[:0])


@njit_alloc
def owned_views(sa):
    """(geometry, surfaces, lighting, textures) for a kernel compiled with Numba's runtime that is not a parallel
    loop (`whitted.explain_pixel`, which takes the general arrays): built here, with the runtime, the views hold
    counted references. The device-function views above hold none (they are built inside each parallel loop's
    body), and a serial caller with the runtime would release references it never took."""
    return (Geometry(sa.node_box, sa.node_link, sa.prim_ref, sa.tri_verts, sa.shape_xform, sa.shape_info,
                     sa.unbounded, sa.csg_nodes, sa.wide_nodes, sa.wide_link, sa.leaf_tris, sa.leaf_link),
            Surfaces(sa.tri_verts, sa.tri_normals, sa.tri_uvs, sa.tri_info, sa.shape_xform, sa.shape_info,
                    sa.shape_nscale),
            Lighting(sa.materials, sa.ambient, sa.light_kind, sa.light_samples, sa.light_vecs, sa.light_scalars,
                    sa.tex_info, sa.tex_pixels),
            Textures(sa.tex_info, sa.tex_pixels, sa.tri_tangents))
