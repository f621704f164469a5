"""Opacity cut-outs (glTF alphaMode MASK, MTL map_d): the surface a ray sees once the holes are skipped.

    hit = closest_visible_hit(geo, surf, lit, o, d, t_min, t_max, stack, stack_t, time)  # as traverse.closest_hit
    blocked = occluded(geo, surf, lit, o, d, t_max, stack, stack_t, time)             # as traverse.any_hit

A material whose textures include one applied to `opacity` has MAT_CUTOUT set (`compile.textures`); where its
coverage α (`texture.material_alpha`) is below `texture.ALPHA_CUTOFF` the surface is not there. After a closest
hit on such a surface, the α at the hit's (u, v) is looked up; at a hole the SAME ray is cast again from
t_min = t_hit (every intersection test keeps t_min < t strictly, so the surface just hit is not found again and
the ray's origin and direction, hence its numbers, stay those of the camera or bounce ray), at most
`config.MAX_HOLES` times; the surface met after that many holes counts as opaque.

The fast path: a scene without textures returns closest_hit's record after one test of tex_info's length, and a
textured scene pays one material column read per hit. Images of scenes without opacity maps are bit for bit
those of `closest_hit`.

Shadow rays of the classic model go through `illumination.shadow_transmittance`: `traverse.transmittance`
reports a cut-out primitive on the ray as unsettled, and the hit-by-hit walk looks its α up. `occluded` is the
path tracer's any-hit visibility with holes.

`lit` is the `layout.Lighting` view: its materials, and its tex_info and tex_pixels for the texture lookup.
"""

import numpy as np

from .. import config
from .jit import njit_inline
from .layout import INFO_KIND, INFO_MATERIAL, MAT_CUTOUT, SHAPE_CSG
from .surface import surface_at
from .texture import APPLY_OPACITY, TEX_APPLY, is_hole, lighting_textures
from .traverse import any_hit, closest_hit


@njit_inline
def closest_visible_hit(geo, surf, lit, o, d, t_min, t_max, stack, stack_t, time):
    """`traverse.closest_hit` (same arguments, same record: (t, ref, b1, b2, part), t = -1 on a miss) with the
    holes of opacity cut-outs skipped: the nearest hit with t_min < t < t_max where the surface is there."""
    t_lo = t_min
    holes = 0
    while True:
        hit = closest_hit(geo, o, d, t_lo, t_max, stack, stack_t, time)
        if hit[0] < 0.0 or _no_textures(lit.tex_info) or holes >= config.MAX_HOLES:
            return hit
        if not _may_cut(surf, lit, hit[1]):
            return hit
        p, n_geo, n_sh, u, v, mat_id, obj, light = surface_at(surf, o, d, hit[0], hit[1], hit[2], hit[3], hit[4],
                                                              time)
        mat = lit.materials[mat_id]
        if mat[MAT_CUTOUT] == 0.0 or not is_hole(lighting_textures(lit), mat, u, v, p):
            return hit
        t_lo = hit[0]
        holes += 1


@njit_inline
def _may_cut(surf, lit, ref):
    """Whether the primitive hit may have holes: its material's MAT_CUTOUT (a csg object: always asked, since its
    solids carry their own materials, which `surface_at` reports)."""
    if ref >= 0:
        return lit.materials[np.int64(surf.tri_info[ref, INFO_MATERIAL]), MAT_CUTOUT] != 0.0
    info = surf.shape_info[~ref]
    return info[INFO_KIND] == SHAPE_CSG or lit.materials[np.int64(info[INFO_MATERIAL]), MAT_CUTOUT] != 0.0


@njit_inline
def has_cutouts(lit):
    """Whether any texture of the scene applies to opacity (a scan of tex_info's rows, a handful; False, and
    nothing scanned, for the arrays of a scene without textures: `compile.features`)."""
    return _any_opacity(lit.tex_info)


@njit_inline
def _no_textures(info):
    """Whether the scene has no texture rows (None: arrays compiled without textures, `compile.features`)."""
    if info is None:
        return True
    return info.shape[0] == 0


@njit_inline
def _any_opacity(info):
    if info is None:
        return False
    for row in range(info.shape[0]):
        if np.int64(info[row, TEX_APPLY]) & APPLY_OPACITY:
            return True
    return False


@njit_inline
def occluded(geo, surf, lit, o, d, t_max, stack, stack_t, time):
    """True if a surface is on the ray with 0 < t < t_max where it is not cut away (`traverse.any_hit` with the
    holes of opacity cut-outs letting it through). The any-order walk answers first; only a blocked ray in a
    scene with cut-outs is walked again hit by hit."""
    if not any_hit(geo, o, d, 0.0, t_max, stack, time):
        return False
    if not has_cutouts(lit):
        return True
    return closest_visible_hit(geo, surf, lit, o, d, 0.0, t_max, stack, stack_t, time)[0] >= 0.0
