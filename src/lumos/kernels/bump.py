"""Bump and normal maps: the shading normal tilted by a height field's gradient or given by a tangent-space
normal map, at a point or filtered over a footprint (the textures' table and lookups: `kernels.texture`).

    dpdu, dpdv = bump_frame(surf, tex, mat, ref, part, b1, b2, p, n, time)  # the surface's tangents, or a mesh's
    n_bumped = bump_normal(tex, mat, u, v, p, n, dpdu, dpdv)        # unit; n itself when there is no bump map
    n_bumped = bump_normal_filtered(tex, mat, u, v, p, n, dpdu, dpdv, dudx, dvdx, dudy, dvdy)
    ka, kd, ks, kr, ke, shininess, n_bumped = material_in_cone(surf, tex, mat, ref, part, b1, b2, p, n_geo, n, u,
                                                               v, d, width, time)  # a ray's hit: both, over its cone

## Bump mapping (Blinn 1978, "Simulation of wrinkled surfaces", eq. 4 without the small terms)

The surface is displaced to p' = p + k·h(u, v)·n (k = strength; n unit). To first order its normal is

    N' = σ·(p'_u × p'_v) = A·n + σ·k·(h_u·(n × p_v) − h_v·(n × p_u))

with A = |p_u × p_v| and σ = sign(n·(p_u × p_v)), so that N' stays on n's side whichever way the uv
parameterisation turns (bumps rise along n). `bump_normal` returns N'/|N'|. The height derivatives h_u, h_v
are central differences over one texel (images) or 1e-3 of a pattern period (noise).

## Filtered bumps

`bump_normal_filtered` takes the same footprint as the colour lookups (raster's, or a ray cone's): a height image's
height comes from the mip-map level of detail λ the footprint picks (as `texture_rgb_filtered`), and its central
differences span one texel of that level, 2^λ level-0 texels; a noise height field's differences span the
footprint (the slope averaged over it); a normal map's texel is filtered as a colour image's (mip-mapped raw RGB,
renormalised after the tangent frame is applied). Far away the bumps average out instead of turning into
noise. A zero footprint is `bump_normal` exactly.
"""

import math

import numpy as np

from .jit import njit, njit_inline
from .layout import FLAG_TANGENTS, INFO_FLAGS, MAT_BUMP, MAT_TEXTURE
from .tangents import surface_tangents
from .texture import (
    BUMP_NORMAL,
    CLAMP_MAX,
    NOISE_STEP,
    TEX_BUMP_TYPE,
    TEX_HEIGHT,
    TEX_KIND,
    TEX_LEVELS,
    TEX_SCALE_U,
    TEX_SCALE_V,
    TEX_SHIFT_U,
    TEX_SHIFT_V,
    TEX_STRENGTH,
    TEX_WIDTH,
    TEX_WRAP,
    TEXTURE_IMAGE,
    WRAP_CLAMP,
    cone_footprint,
    material_coeffs_filtered,
    texture_rgb,
    texture_rgb_filtered,
    trilinear,
)
from .vec import cross, dot, length, normalize


@njit_inline
def bump_normal(tex, mat, u, v, p, n, dpdu, dpdv):
    """The unit shading normal tilted by the material's bump map at (u, v) (Blinn 1978, see the module doc), or
    given by its normal map (`normal_mapped`); n unchanged when the material has none, its strength is 0 (height
    maps) or the tangents are degenerate."""
    return bump_normal_filtered(tex, mat, u, v, p, n, dpdu, dpdv, 0.0, 0.0, 0.0, 0.0)


@njit
def bump_normal_filtered(tex, mat, u, v, p, n, dpdu, dpdv, dudx, dvdx, dudy, dvdy):
    """`bump_normal` filtered over the footprint (du/dx, dv/dx, du/dy, dv/dy) (module doc: filtered bumps); a zero
    footprint is the point lookup. n where `tex` is None (a scene without textures)."""
    if tex is None:
        return n
    row = np.int64(mat[MAT_BUMP])
    if row < 0:
        return n
    info = tex.tex_info[row]
    if info[TEX_BUMP_TYPE] == BUMP_NORMAL:
        return normal_mapped(tex, row, u, v, p, n, dpdu, dpdv, dudx, dvdx, dudy, dvdy)
    strength = info[TEX_STRENGTH]
    if strength == 0.0:
        return n
    lod = 0.0
    if info[TEX_KIND] == TEXTURE_IMAGE:  # one texel (of the level the footprint picks)
        texels = _footprint_texels(info, dudx, dvdx, dudy, dvdy)
        if texels > 1.0:
            lod = math.log2(texels)
        du = min(max(texels, 1.0), info[TEX_WIDTH]) / (info[TEX_SCALE_U] * info[TEX_WIDTH])
        dv = min(max(texels, 1.0), info[TEX_HEIGHT]) / (info[TEX_SCALE_V] * info[TEX_HEIGHT])
    else:  # noise: the height's slope averaged over the footprint
        du = max(NOISE_STEP / info[TEX_SCALE_U], 0.5 * max(abs(dudx), abs(dudy)))
        dv = max(NOISE_STEP / info[TEX_SCALE_V], 0.5 * max(abs(dvdx), abs(dvdy)))
    h_u = (_height(tex, row, u + du, v, p, lod) - _height(tex, row, u - du, v, p, lod)) / (2.0 * du)
    h_v = (_height(tex, row, u, v + dv, p, lod) - _height(tex, row, u, v - dv, p, lod)) / (2.0 * dv)
    c = cross(dpdu, dpdv)
    area = length(c)
    if area == 0.0:
        return n
    k = strength / area
    if dot(n, c) < 0.0:
        k = -k
    a = cross(n, dpdv)
    b = cross(n, dpdu)
    bumped = normalize((n[0] + k * (h_u * a[0] - h_v * b[0]),
                        n[1] + k * (h_u * a[1] - h_v * b[1]),
                        n[2] + k * (h_u * a[2] - h_v * b[2])))
    if bumped[0] == 0.0 and bumped[1] == 0.0 and bumped[2] == 0.0:
        return n
    return bumped


@njit_inline
def _footprint_texels(info, dudx, dvdx, dudy, dvdy):
    """The longer axis of the footprint in level-0 texels of image row `info` (0 for no footprint; huge, not
    inf, for a footprint that is)."""
    w = info[TEX_WIDTH] * info[TEX_SCALE_U]
    h = info[TEX_HEIGHT] * info[TEX_SCALE_V]
    longest = max((dudx * w) ** 2 + (dvdx * h) ** 2, (dudy * w) ** 2 + (dvdy * h) ** 2)
    if not longest < 1e300:
        return 0.0 if longest != longest else 1e150  # NaN: no footprint
    return math.sqrt(longest)


@njit_inline
def _height(tex, row, u, v, p, lod):
    """Channel 0 of texture `row` at (u, v), from mip-map level of detail `lod` (0: level 0, bilinear)."""
    info = tex.tex_info[row]
    if not (lod > 0.0) or info[TEX_LEVELS] <= 1.0:
        return texture_rgb(tex, row, u, v, p)[0]
    if info[TEX_WRAP] == WRAP_CLAMP:
        u = min(max(u, 0.0), CLAMP_MAX)
        v = min(max(v, 0.0), CLAMP_MAX)
    su = info[TEX_SCALE_U]
    sv = info[TEX_SCALE_V]
    return trilinear(tex.tex_pixels, info, su * u + info[TEX_SHIFT_U], sv * v + info[TEX_SHIFT_V], su, sv, lod)[0]


@njit
def normal_mapped(tex, row, u, v, p, n, dpdu, dpdv, dudx, dvdx, dudy, dvdy):
    """The unit normal of tangent-space normal map `row` at (u, v): texel c (raw RGB in [0, 1]) → m = 2c − 1,
    m_x and m_y times the strength, N' = normalize(m_x·T + m_y·B + m_z·n) with T = dpdu made orthogonal to n
    (Gram–Schmidt) and B = ±(n × T), on dpdv's side (glTF's frame: B = w·(n × T) with the tangent's
    handedness w). n unchanged where T vanishes or N' is zero. The texel is filtered over the footprint
    (du/dx, dv/dx, du/dy, dv/dy) as colour images are (`texture_rgb_filtered`): averaged normals, renormalised."""
    c = texture_rgb_filtered(tex, row, u, v, p, dudx, dvdx, dudy, dvdy)
    k = tex.tex_info[row, TEX_STRENGTH]
    mx = k * (2.0 * c[0] - 1.0)
    my = k * (2.0 * c[1] - 1.0)
    mz = 2.0 * c[2] - 1.0
    d = dot(n, dpdu)
    t = (dpdu[0] - d * n[0], dpdu[1] - d * n[1], dpdu[2] - d * n[2])
    lt = length(t)
    if not lt > 0.0:
        return n
    t = (t[0] / lt, t[1] / lt, t[2] / lt)
    b = cross(n, t)
    if dot(b, dpdv) < 0.0:
        b = (-b[0], -b[1], -b[2])
    out = (mx * t[0] + my * b[0] + mz * n[0], mx * t[1] + my * b[1] + mz * n[1], mx * t[2] + my * b[2] + mz * n[2])
    if length(out) == 0.0:
        return n
    return normalize(out)


@njit
def bump_frame(surf, tex, mat, ref, part, b1, b2, p, n, time):
    """(∂p/∂u, ∂p/∂v) for the material's bump map at a hit: `surface_tangents`, except that a normal map on a
    triangle with per-vertex tangents (FLAG_TANGENTS) takes T, the tangents interpolated by the barycentrics
    (b1, b2), and B = w·(n × T) with the handedness w of the first vertex."""
    if tex is None:  # (a scene without textures)
        return surface_tangents(surf, ref, part, p, n, time)
    row = np.int64(mat[MAT_BUMP])
    if (ref >= 0 and row >= 0 and tex.tex_info[row, TEX_BUMP_TYPE] == BUMP_NORMAL
            and (surf.tri_info[ref, INFO_FLAGS] & FLAG_TANGENTS) != 0):
        g = tex.tri_tangents
        b0 = 1.0 - b1 - b2
        t = (b0 * g[ref, 0] + b1 * g[ref, 4] + b2 * g[ref, 8], b0 * g[ref, 1] + b1 * g[ref, 5] + b2 * g[ref, 9],
             b0 * g[ref, 2] + b1 * g[ref, 6] + b2 * g[ref, 10])
        w = np.float64(g[ref, 3])
        c = cross(n, t)
        return t, (w * c[0], w * c[1], w * c[2])
    return surface_tangents(surf, ref, part, p, n, time)


@njit_inline
def material_in_cone(surf, tex, mat, ref, part, b1, b2, p, n_geo, n_sh, u, v, d, width, time):
    """What a ray method needs of the material row `mat` at a hit: (ka, kd, ks, kr, ke, shininess) with its
    textures applied and the shading normal with its bump or normal map, both filtered over the footprint of a ray
    cone `width` wide there (`texture.cone_footprint`; width 0: point lookups), for a ray of unit direction d
    meeting the surface (`ref`, `part`, barycentrics b1, b2) at p, geometric normal n_geo. `tex` None (a scene
    without textures, `compile.features`): the row's own values and n_sh, nothing else compiled."""
    if tex is None:
        ka, kd, ks, kr, ke, shininess = material_coeffs_filtered(tex, mat, u, v, p, 0.0, 0.0, 0.0, 0.0)
        return ka, kd, ks, kr, ke, shininess, n_sh
    fp = (0.0, 0.0, 0.0, 0.0)
    if mat[MAT_TEXTURE] >= 0.0 or mat[MAT_BUMP] >= 0.0:
        fp = cone_footprint(surf, ref, part, p, n_geo, d, width, time)
    ka, kd, ks, kr, ke, shininess = material_coeffs_filtered(tex, mat, u, v, p, fp[0], fp[1], fp[2], fp[3])
    if mat[MAT_BUMP] >= 0.0:
        dpdu, dpdv = bump_frame(surf, tex, mat, ref, part, b1, b2, p, n_sh, time)
        n_sh = bump_normal_filtered(tex, mat, u, v, p, n_sh, dpdu, dpdv, fp[0], fp[1], fp[2], fp[3])
    return ka, kd, ks, kr, ke, shininess, n_sh
