"""Textures, UV derivatives and bump mapping at a hit: what the ray methods call between `surface_at` and the
illumination model.

    ka, kd, ks, kr, ke, n = material_coeffs(tex, mat, u, v, p)      # the textures applied in list order
    dpdu, dpdv = surface_tangents(surf, ref, part, p, n, time)     # world-space ∂p/∂u, ∂p/∂v
    dpdu, dpdv = bump_frame(surf, tex, mat, ref, part, b1, b2, p, n, time)  # the same, or a mesh's tangents
    (bump maps: `kernels.bump`)
    hole = is_hole(tex, mat, u, v, p)                               # an opacity texture's α < ALPHA_CUTOFF
    fp = cone_footprint(surf, ref, part, p, n_geo, d, width, time)  # a ray cone's (du/dx, dv/dx, du/dy, dv/dy)
    ka, kd, ks, kr, ke, n = material_coeffs_filtered(tex, mat, u, v, p, *fp)    # filtered over it
    n_bumped = bump_normal_filtered(tex, mat, u, v, p, n, dpdu, dpdv, *fp)

* `tex` is a `layout.Textures` view (`views.textures_of`), `surf` a `layout.Surfaces` view.
* `mat` is the material's ROW, `materials[material_id]` (float64 (MAT_SIZE,)); its textures are the
  `MAT_TEXTURE_COUNT` rows of `tex_info` from `MAT_TEXTURE` (-1: none), its bump map row `MAT_BUMP` (or -1).
* `tex.tri_tangents`: float32 (nt, 12), per triangle the three vertices' tangents (xyz, w) where tri_info's
  FLAG_TANGENTS is set ((0, 12) when no triangle has them).
* `u, v` are the hit's surface coordinates from `surface_at`; `p` the world-space hit point (unused by the
  current 2-D texture kinds; kept for solid textures).
* `ref, part` are the hit record of `traverse.closest_hit` (triangle index or ~shape, the face hit); `time` the
  ray's shutter time (moving shapes are displaced by time·motion).
* `n` is the unit shading normal as `surface_at` returns it (outward on closed shapes), BEFORE `face_forward` /
  `shading_side`: bumps raise the surface along n. Turn the bumped normal towards the viewer afterwards.

Everything is a tuple of float64; nothing allocates.

## tex_info columns (float64 (n, TEX_SIZE)), one row per texture or bump map

    TEX_KIND       TEXTURE_IMAGE | TEXTURE_CHECKER | TEXTURE_STRIPES | TEXTURE_NOISE
    TEX_SCALE_U/V  repeats across the uv square: the pattern is looked up at (s, t) = (scale_u·u + shift_u, scale_v·v + shift_v)
    TEX_WRAP       WRAP_REPEAT: (s, t) unbounded, the pattern tiles; WRAP_CLAMP: (u, v) clamped to the uv square
                   first, so the pattern covers it once (scale times) and its edge extends beyond
    TEX_COLOR0..+2, TEX_COLOR1..+2   the two colours of checker, stripes and noise (linear RGB); a bump map's
                   are black and white, so that channel 0 of its `texture_rgb` is its height
    TEX_OFFSET, TEX_WIDTH, TEX_HEIGHT   image: its first texel in tex_pixels, and its size in texels
    TEX_APPLY      bit mask of the coefficients the colour applies to: APPLY_KA | APPLY_KD | APPLY_KS | APPLY_KR |
                   APPLY_EMISSION | APPLY_BASE (a principled material's base colour), or APPLY_OPACITY alone (a
                   coverage row: channel 0 is α), or APPLY_METAL_ROUGH alone (raw texels: blue multiplies a
                   principled material's metallic, green its roughness); 0 for bump maps
    TEX_MODE       MODE_REPLACE (the coefficient becomes the colour) or MODE_MULTIPLY (is multiplied by it)
    TEX_SHIFT_U/V  the offset added to the scaled coordinates: (s, t) = (scale_u·u + shift_u, scale_v·v + shift_v)
    TEX_BUMP_TYPE  bump maps: BUMP_HEIGHT (Blinn bumps of a height field) or BUMP_NORMAL (a tangent-space normal
                   map; its texels are raw RGB, `normal_mapped`)
    TEX_STRENGTH   bump maps: the height scale (world units of displacement per unit of height)
    TEX_LEVELS     colour, height and normal images: how many mip-map levels follow one another from OFFSET (1: the
                   image alone; opacity images have no others)

tex_pixels: float32 (m, 3). An image of W×H texels occupies rows OFFSET .. OFFSET + W·H − 1, bottom image row
first: texel (i, j) is `tex_pixels[OFFSET + j·W + i]`, centred at uv ((i + 0.5)/W, (j + 0.5)/H), so v = 0 is the
bottom of the picture and images appear upright on a sphere's latitude–longitude map and on planar maps.
Colour textures hold linear RGB (decoded from sRGB at compile time); bump maps hold the Rec. 709 luminance of
the file's raw (not decoded) values in all three channels, a height in [0, 1]. A colour, height or normal
image's mip-map levels follow it: level k + 1 is level k box-filtered to max(1, w_k // 2) × max(1, h_k // 2)
texels (colours in linear RGB), stored the same way right after level k.

## Filtering by the footprint (raster's screen-space derivatives, or a ray cone's)

`texture_rgb_filtered` / `material_coeffs_filtered` take the screen-space derivatives of (u, v), a footprint
(du/dx, dv/dx, du/dy, dv/dy) per pixel, and filter each pattern over it; a zero footprint gives exactly the
point lookup of `texture_rgb` (what the ray methods use under `mipmap: false`, and `path` always).

    image    trilinear mip-mapping (Williams 1983): the level of detail λ = log2 of the longer of the two
             footprint axes measured in level-0 texels, bilinear in levels ⌊λ⌋ and ⌊λ⌋ + 1, blended by λ's
             fraction; λ <= 0 is the bilinear lookup itself (magnification), λ beyond the last level its texel
    checker, stripes   box-filtered in closed form (as pbrt's checkerboard does): over a box of half-widths
             (ds, dt) = half the larger footprint component along each axis (a box one pixel wide, the pixel's
             own extent; pbrt's box of half-width one footprint blurs twice as far, and measured against a
             supersampled floor to the horizon left 0.6 of the point lookup's error where this box leaves 0.2),
             the fraction of "odd" cells along s is
             (C(s + ds) − C(s − ds)) / 2ds with C(x) = ⌊x/2⌋ + 2·max(x/2 − ⌊x/2⌋ − ½, 0) the integral of the
             odd-cell indicator; the checker's odd fraction is f_s(1 − f_t) + f_t(1 − f_s), and the colour the
             blend of COLOR0 and COLOR1 by it. Far away both fade to their mean instead of aliasing.
    noise    point-sampled (its features are larger than a cell of the lattice and it has no hard edges)

## Patterns (at the scaled coordinates (s, t))

    image    bilinear between the four nearest texel centres (neighbours wrap under repeat, clamp at the edge)
    checker  COLOR0 where floor(s) + floor(t) is even, else COLOR1
    stripes  COLOR0 where floor(s) is even, else COLOR1
    noise    lerp(COLOR0, COLOR1, x), x = 0.5 + perlin(s, t)/√2 in [0, 1]: 2-D gradient noise (Perlin 2002, with
             the quintic fade) over unit gradients at multiples of 45° picked by an integer hash of the lattice
             point, whose magnitude stays below √2/2. The lattice repeats every round(scale) cells, so integer
             scales tile seamlessly across u = 0 / 1 (the sphere's seam).

## Ray cones (the ray methods' footprint)

`cone_footprint` turns a ray cone (Akenine-Möller et al. 2019, "Texture Level of Detail Strategies for Real-Time
Ray Tracing", Ray Tracing Gems ch. 20) into the footprint (du/dx, dv/dx, du/dy, dv/dy): at the hit the cone is
`width` wide (one pixel's spacing: `kernels.camera.camera_cone` at the eye, growing by its spread times the
distance); two axes of that length at right angles to the ray, one in the plane of the ray and the normal (it
lengthens by 1/|cos θ| on the surface) and one across it, are carried along the ray onto the tangent plane and
into (u, v) by the least-squares inverse of (∂p/∂u, ∂p/∂v) (`surface_tangents`). Whitted's reflected and
transmitted rays carry the cone on, as wide as it was at the hit and spread further by the surface's curvature
(`methods.whitted_trace`).
"""

import math

import numpy as np

from .jit import njit, njit_inline
from .layout import (
    MAT_BASE,
    MAT_EMISSION,
    MAT_KA,
    MAT_KD,
    MAT_KR,
    MAT_KS,
    MAT_METALLIC,
    MAT_MODEL,
    MAT_ROUGHNESS,
    MAT_SHININESS,
    MAT_TEXTURE,
    MAT_TEXTURE_COUNT,
    MODEL_PRINCIPLED,
)
from .principled_classic import principled_classic
from .tangents import surface_tangents
from .vec import cross, dot, length, orthonormal_basis
from .views import opacity_view

# tex_info columns
TEX_KIND = 0
TEX_SCALE_U = 1
TEX_SCALE_V = 2
TEX_WRAP = 3
TEX_COLOR0 = 4
TEX_COLOR1 = 7
TEX_OFFSET = 10
TEX_WIDTH = 11
TEX_HEIGHT = 12
TEX_APPLY = 13
TEX_STRENGTH = 14
TEX_LEVELS = 15
TEX_SHIFT_U = 16
TEX_SHIFT_V = 17
TEX_MODE = 18
TEX_BUMP_TYPE = 19
TEX_SIZE = 20

# TEX_KIND values
TEXTURE_IMAGE = 0
TEXTURE_CHECKER = 1
TEXTURE_STRIPES = 2
TEXTURE_NOISE = 3

# TEX_WRAP values
WRAP_REPEAT = 0
WRAP_CLAMP = 1

# TEX_APPLY bits
APPLY_KA = 1
APPLY_KD = 2
APPLY_KS = 4
APPLY_KR = 8
APPLY_EMISSION = 16
APPLY_OPACITY = 32
APPLY_BASE = 64  # a principled material's base colour (`kernels.principled`)
APPLY_METAL_ROUGH = 128  # its metallic (blue) and roughness (green), raw texels
#: the bits `material_coeffs` reads
APPLY_COEFFS = APPLY_KA | APPLY_KD | APPLY_KS | APPLY_KR | APPLY_EMISSION

# TEX_MODE values (colour textures)
MODE_REPLACE = 0
MODE_MULTIPLY = 1

# TEX_BUMP_TYPE values (bump maps)
BUMP_HEIGHT = 0
BUMP_NORMAL = 1

#: Coverage below this is a cut-out hole (glTF alphaMode MASK's default alphaCutoff, MTL map_d read the same way).
ALPHA_CUTOFF = 0.5

#: Under clamp, u and v stay below this so that the far edge of the uv square keeps the last cell's colour.
CLAMP_MAX = 1.0 - 1e-9
#: Finite-difference step of a noise height field, as a fraction of one pattern period.
NOISE_STEP = 1e-3
_SQRT_HALF = math.sqrt(0.5)

# ------------------------------------------------------------------------------------------------ lookups


@njit
def texture_rgb(tex, row, u, v, p):
    """Linear (r, g, b) of texture `row` of `tex.tex_info` at surface coordinates (u, v) (see the module doc)."""
    info = tex.tex_info[row]
    if info[TEX_WRAP] == WRAP_CLAMP:
        u = min(max(u, 0.0), CLAMP_MAX)
        v = min(max(v, 0.0), CLAMP_MAX)
    su = info[TEX_SCALE_U]
    sv = info[TEX_SCALE_V]
    s = su * u + info[TEX_SHIFT_U]
    t = sv * v + info[TEX_SHIFT_V]
    kind = info[TEX_KIND]
    if kind == TEXTURE_IMAGE:
        return _bilinear(tex.tex_pixels, info, s, t, su, sv)
    if kind == TEXTURE_NOISE:
        x = noise01(s, t, _period(su), _period(sv))
        y = 1.0 - x
        c0, c1 = TEX_COLOR0, TEX_COLOR1
        return (y * info[c0] + x * info[c1], y * info[c0 + 1] + x * info[c1 + 1], y * info[c0 + 2] + x * info[c1 + 2])
    if kind == TEXTURE_CHECKER:
        odd = (np.int64(math.floor(s)) + np.int64(math.floor(t))) & 1
    else:  # stripes
        odd = np.int64(math.floor(s)) & 1
    c = TEX_COLOR1 if odd else TEX_COLOR0
    return info[c], info[c + 1], info[c + 2]


@njit
def texture_rgb_filtered(tex, row, u, v, p, dudx, dvdx, dudy, dvdy):
    """`texture_rgb` filtered over the pixel footprint (du/dx, dv/dx, du/dy, dv/dy) (see the module doc)."""
    info = tex.tex_info[row]
    kind = info[TEX_KIND]
    if kind == TEXTURE_NOISE or (dudx == 0.0 and dvdx == 0.0 and dudy == 0.0 and dvdy == 0.0):
        return texture_rgb(tex, row, u, v, p)
    if info[TEX_WRAP] == WRAP_CLAMP:
        u = min(max(u, 0.0), CLAMP_MAX)
        v = min(max(v, 0.0), CLAMP_MAX)
    su = info[TEX_SCALE_U]
    sv = info[TEX_SCALE_V]
    if kind == TEXTURE_IMAGE:
        w = info[TEX_WIDTH] * su
        h = info[TEX_HEIGHT] * sv
        ax = (dudx * w) ** 2 + (dvdx * h) ** 2
        ay = (dudy * w) ** 2 + (dvdy * h) ** 2
        longest = max(ax, ay)  # squared, in level-0 texels
        if not (longest > 1.0) or info[TEX_LEVELS] <= 1.0:  # magnified (or NaN): bilinear
            return _bilinear(tex.tex_pixels, info, su * u + info[TEX_SHIFT_U], sv * v + info[TEX_SHIFT_V], su, sv)
        lod = 0.5 * math.log2(longest) if longest < 1e300 else 1e9
        return trilinear(tex.tex_pixels, info, su * u + info[TEX_SHIFT_U], sv * v + info[TEX_SHIFT_V], su, sv, lod)
    # half a footprint each side: the box is one pixel wide
    fs = _odd_fraction(su * u + info[TEX_SHIFT_U], 0.5 * su * max(abs(dudx), abs(dudy)))
    if kind == TEXTURE_CHECKER:
        ft = _odd_fraction(sv * v + info[TEX_SHIFT_V], 0.5 * sv * max(abs(dvdx), abs(dvdy)))
        x = fs * (1.0 - ft) + ft * (1.0 - fs)
    else:  # stripes
        x = fs
    y = 1.0 - x
    c0, c1 = TEX_COLOR0, TEX_COLOR1
    return (y * info[c0] + x * info[c1], y * info[c0 + 1] + x * info[c1 + 1], y * info[c0 + 2] + x * info[c1 + 2])


@njit
def _bilinear(pixels, info, s, t, su, sv):
    """Bilinear filtering between texel centres at scaled coordinates (s, t) (one image per unit square)."""
    return _bilinear_level(pixels, np.int64(info[TEX_OFFSET]), np.int64(info[TEX_WIDTH]), np.int64(info[TEX_HEIGHT]),
                           info[TEX_WRAP] == WRAP_CLAMP, s, t, su, sv, info[TEX_SHIFT_U], info[TEX_SHIFT_V])


@njit_inline
def _bilinear_level(pixels, offset, w, h, clamp, s, t, su, sv, ou, ov):
    """`_bilinear` on the w × h texels from row `offset` of `pixels` (one mip-map level); (ou, ov) is the
    texture's offset, where the clamped strip [ou, ou + su] × [ov, ov + sv] of scaled coordinates starts."""
    x = s * w - 0.5
    y = t * h - 0.5
    if clamp:  # stop at the centres of the first and last texels of the strip
        x = min(max(x, ou * w), max((su + ou) * w - 1.0, ou * w))
        y = min(max(y, ov * h), max((sv + ov) * h - 1.0, ov * h))
    xf = math.floor(x)
    yf = math.floor(y)
    fx = x - xf
    fy = y - yf
    i0 = np.int64(xf) % w
    j0 = np.int64(yf) % h
    i1 = (i0 + 1) % w
    j1 = (j0 + 1) % h
    a = offset + j0 * w
    b = offset + j1 * w
    w00 = (1.0 - fx) * (1.0 - fy)
    w10 = fx * (1.0 - fy)
    w01 = (1.0 - fx) * fy
    w11 = fx * fy
    r = (w00 * np.float64(pixels[a + i0, 0]) + w10 * np.float64(pixels[a + i1, 0])
         + w01 * np.float64(pixels[b + i0, 0]) + w11 * np.float64(pixels[b + i1, 0]))
    g = (w00 * np.float64(pixels[a + i0, 1]) + w10 * np.float64(pixels[a + i1, 1])
         + w01 * np.float64(pixels[b + i0, 1]) + w11 * np.float64(pixels[b + i1, 1]))
    bl = (w00 * np.float64(pixels[a + i0, 2]) + w10 * np.float64(pixels[a + i1, 2])
          + w01 * np.float64(pixels[b + i0, 2]) + w11 * np.float64(pixels[b + i1, 2]))
    return r, g, bl


@njit
def trilinear(pixels, info, s, t, su, sv, lod):
    """Trilinear mip-map lookup at level of detail `lod` (> 0; see the module doc)."""
    offset = np.int64(info[TEX_OFFSET])
    w = np.int64(info[TEX_WIDTH])
    h = np.int64(info[TEX_HEIGHT])
    clamp = info[TEX_WRAP] == WRAP_CLAMP
    last = np.int64(info[TEX_LEVELS]) - 1
    if lod >= last:
        lo = last
        frac = 0.0
    else:
        lo = np.int64(math.floor(lod))
        frac = lod - lo
    for _ in range(lo):  # walk to level lo
        offset += w * h
        w = max(np.int64(1), w // 2)
        h = max(np.int64(1), h // 2)
    ou = info[TEX_SHIFT_U]
    ov = info[TEX_SHIFT_V]
    c0 = _bilinear_level(pixels, offset, w, h, clamp, s, t, su, sv, ou, ov)
    if frac == 0.0:
        return c0
    offset += w * h
    c1 = _bilinear_level(pixels, offset, max(np.int64(1), w // 2), max(np.int64(1), h // 2), clamp, s, t, su, sv,
                         ou, ov)
    a = 1.0 - frac
    return a * c0[0] + frac * c1[0], a * c0[1] + frac * c1[1], a * c0[2] + frac * c1[2]


@njit_inline
def _odd_integral(x):
    """∫₀ˣ [⌊y⌋ is odd] dy."""
    h = math.floor(0.5 * x)
    return h + 2.0 * max(0.5 * x - h - 0.5, 0.0)


@njit_inline
def _odd_fraction(s, ds):
    """The fraction of [s − ds, s + ds] where ⌊·⌋ is odd (the point value when ds is 0)."""
    if ds <= 0.0:
        return 1.0 if (np.int64(math.floor(s)) & 1) else 0.0
    if ds >= 1.0e6:
        return 0.5
    return (_odd_integral(s + ds) - _odd_integral(s - ds)) / (2.0 * ds)


@njit
def _period(scale):
    """Lattice period of the noise along one axis: the scale rounded to a whole number of cells (at least 1)."""
    return max(np.int64(1), np.int64(math.floor(scale + 0.5)))


@njit
def _lattice_dot(ix, iy, dx, dy):
    """Dot product of the hashed unit gradient at lattice point (ix, iy) (both >= 0) with the offset (dx, dy).

    The hash is integer-only and stays below 2**63, so it gives the same bits compiled and interpreted."""
    h = (ix * 374761393 + iy * 668265263) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    h = (h ^ (h >> 16)) & 7
    if h == 0:
        return dx
    if h == 1:
        return _SQRT_HALF * (dx + dy)
    if h == 2:
        return dy
    if h == 3:
        return _SQRT_HALF * (dy - dx)
    if h == 4:
        return -dx
    if h == 5:
        return -_SQRT_HALF * (dx + dy)
    if h == 6:
        return -dy
    return _SQRT_HALF * (dx - dy)


@njit
def _fade(x):
    return x * x * x * (x * (x * 6.0 - 15.0) + 10.0)


@njit
def noise01(s, t, period_s, period_t):
    """Gradient noise at (s, t), mapped to [0, 1]; the lattice repeats every period_s × period_t cells."""
    xf = math.floor(s)
    yf = math.floor(t)
    dx = s - xf
    dy = t - yf
    ix0 = np.int64(xf) % period_s
    iy0 = np.int64(yf) % period_t
    ix1 = (ix0 + 1) % period_s
    iy1 = (iy0 + 1) % period_t
    n00 = _lattice_dot(ix0, iy0, dx, dy)
    n10 = _lattice_dot(ix1, iy0, dx - 1.0, dy)
    n01 = _lattice_dot(ix0, iy1, dx, dy - 1.0)
    n11 = _lattice_dot(ix1, iy1, dx - 1.0, dy - 1.0)
    fx = _fade(dx)
    fy = _fade(dy)
    a = n00 + fx * (n10 - n00)
    b = n01 + fx * (n11 - n01)
    value = 0.5 + _SQRT_HALF * (a + fy * (b - a))
    return min(max(value, 0.0), 1.0)


# ------------------------------------------------------------------------------------------------ material


@njit_inline
def _row_coeffs(mat):
    """(ka, kd, ks, kr, emission, shininess) of the material row itself, no texture applied."""
    return ((mat[MAT_KA], mat[MAT_KA + 1], mat[MAT_KA + 2]), (mat[MAT_KD], mat[MAT_KD + 1], mat[MAT_KD + 2]),
            (mat[MAT_KS], mat[MAT_KS + 1], mat[MAT_KS + 2]), (mat[MAT_KR], mat[MAT_KR + 1], mat[MAT_KR + 2]),
            (mat[MAT_EMISSION], mat[MAT_EMISSION + 1], mat[MAT_EMISSION + 2]), mat[MAT_SHININESS])


@njit_inline
def material_coeffs(tex, mat, u, v, p):
    """(ka, kd, ks, kr, emission, shininess), the first five RGB tuples: the material row's coefficients with its
    textures applied at (u, v) in list order, each replacing or multiplying the coefficients of its apply_to mask,
    and its Phong exponent. No textures: the row's own values. For the path tracer, which reads a principled
    material through `principled.principled_at` (its emission from here): no classic reading of it per point
    (`material_coeffs_filtered`)."""
    return _classic_coeffs(tex, mat, u, v, p, 0.0, 0.0, 0.0, 0.0)


@njit_inline
def _apply(mode, old, color):
    if mode == MODE_MULTIPLY:
        return old[0] * color[0], old[1] * color[1], old[2] * color[2]
    return color


@njit_inline
def material_coeffs_filtered(tex, mat, u, v, p, dudx, dvdx, dudy, dvdy):
    """`material_coeffs` with the textures filtered over the footprint (du/dx, dv/dx, du/dy, dv/dy); a zero
    footprint is the point lookup. A textured principled material's coefficients and exponent follow its base
    colour, metallic and roughness at the point (`principled_coeffs_filtered`). `tex` None (a scene without
    textures, `compile.features`): the row's own values, and no texture lookup is compiled."""
    if tex is None:
        return _row_coeffs(mat)
    if mat[MAT_MODEL] == MODEL_PRINCIPLED and mat[MAT_TEXTURE] >= 0.0:
        return principled_coeffs_filtered(tex, mat, u, v, p, dudx, dvdx, dudy, dvdy)
    return _classic_coeffs(tex, mat, u, v, p, dudx, dvdx, dudy, dvdy)


@njit_inline
def _classic_coeffs(tex, mat, u, v, p, dudx, dvdx, dudy, dvdy):
    """The row's coefficients with its textures applied in list order, filtered over the footprint."""
    if tex is None:  # (a scene without textures)
        return _row_coeffs(mat)
    ka, kd, ks, kr, ke, shininess = _row_coeffs(mat)
    first = np.int64(mat[MAT_TEXTURE])
    if first < 0:
        return ka, kd, ks, kr, ke, shininess
    for row in range(first, first + np.int64(mat[MAT_TEXTURE_COUNT])):
        mask = np.int64(tex.tex_info[row, TEX_APPLY])
        if (mask & APPLY_COEFFS) == 0:
            continue  # a coverage row
        color = texture_rgb_filtered(tex, row, u, v, p, dudx, dvdx, dudy, dvdy)
        mode = tex.tex_info[row, TEX_MODE]
        if mask & APPLY_KA:
            ka = _apply(mode, ka, color)
        if mask & APPLY_KD:
            kd = _apply(mode, kd, color)
        if mask & APPLY_KS:
            ks = _apply(mode, ks, color)
        if mask & APPLY_KR:
            kr = _apply(mode, kr, color)
        if mask & APPLY_EMISSION:
            ke = _apply(mode, ke, color)
    return ka, kd, ks, kr, ke, shininess


@njit
def principled_coeffs_filtered(tex, mat, u, v, p, dudx, dvdx, dudy, dvdy):
    """`material_coeffs_filtered` of a textured principled material: its classic reading at the point
    (`principled_classic`) from its base colour, metallic and roughness there, its occlusion rows (APPLY_KA)
    multiplying ka and its emission rows the emission; no other coefficient texture applies to it (as in `path`).
    (Called, not inlined: the classic materials' loop stays as small as it was.)"""
    ke = (mat[MAT_EMISSION], mat[MAT_EMISSION + 1], mat[MAT_EMISSION + 2])
    base = (mat[MAT_BASE], mat[MAT_BASE + 1], mat[MAT_BASE + 2])
    metallic, roughness = mat[MAT_METALLIC], mat[MAT_ROUGHNESS]
    occlusion = (1.0, 1.0, 1.0)
    first = np.int64(mat[MAT_TEXTURE])
    for row in range(first, first + np.int64(mat[MAT_TEXTURE_COUNT])):
        mask = np.int64(tex.tex_info[row, TEX_APPLY])
        if (mask & (APPLY_BASE | APPLY_METAL_ROUGH | APPLY_KA | APPLY_EMISSION)) == 0:
            continue
        color = texture_rgb_filtered(tex, row, u, v, p, dudx, dvdx, dudy, dvdy)
        mode = tex.tex_info[row, TEX_MODE]
        if mask & APPLY_METAL_ROUGH:  # (raw texels: metallic in blue, roughness in green, as glTF's)
            metallic *= color[2]
            roughness *= color[1]
        elif mask & APPLY_BASE:
            base = _apply(mode, base, color)
        else:
            if mask & APPLY_KA:
                occlusion = _apply(mode, occlusion, color)
            if mask & APPLY_EMISSION:
                ke = _apply(mode, ke, color)
    ka, kd, ks, kr, shininess = principled_classic(mat, base, metallic, roughness)
    return (ka[0] * occlusion[0], ka[1] * occlusion[1], ka[2] * occlusion[2]), kd, ks, kr, ke, shininess


@njit_inline
def has_cutout(tex, mat):
    """Whether the material has an opacity texture (its surface may have holes); False where `tex` is None (a
    scene without textures)."""
    if tex is None:
        return False
    first = np.int64(mat[MAT_TEXTURE])
    if first < 0:
        return False
    for row in range(first, first + np.int64(mat[MAT_TEXTURE_COUNT])):
        if np.int64(tex.tex_info[row, TEX_APPLY]) & APPLY_OPACITY:
            return True
    return False


@njit
def material_alpha(tex, mat, u, v, p):
    """The coverage α at (u, v): 1, then each opacity texture in list order replacing or multiplying it by its
    channel 0 (an image's alpha or luminance, a pattern's luminance). α < ALPHA_CUTOFF is a hole."""
    if tex is None:  # (a scene without textures)
        return 1.0
    alpha = 1.0
    first = np.int64(mat[MAT_TEXTURE])
    if first < 0:
        return alpha
    for row in range(first, first + np.int64(mat[MAT_TEXTURE_COUNT])):
        if np.int64(tex.tex_info[row, TEX_APPLY]) & APPLY_OPACITY:
            a = texture_rgb(tex, row, u, v, p)[0]
            alpha = alpha * a if tex.tex_info[row, TEX_MODE] == MODE_MULTIPLY else a
    return alpha


@njit_inline
def lighting_textures(lit):
    """The textures of a `layout.Lighting` view as the `Textures` view the readers here take, without tangents
    (shape (0, 12)): the shadow rays' and the cut-out walk's holes read the same compiled `is_hole` as
    shading does, not a second one typed for the other view. None for a scene without textures."""
    return opacity_view(lit.tex_info, lit.tex_pixels)


@njit_inline
def is_hole(tex, mat, u, v, p):
    """True where the material's opacity textures cut the surface away (α < ALPHA_CUTOFF)."""
    return has_cutout(tex, mat) and material_alpha(tex, mat, u, v, p) < ALPHA_CUTOFF


# ------------------------------------------------------------------------------------------------ ray cones


@njit
def cone_footprint(surf, ref, part, p, n, d, width, time):
    """(du/dx, dv/dx, du/dy, dv/dy) of a ray cone of `width` (one pixel's spacing across the ray, world units)
    along unit direction d that meets the surface at p, unit geometric normal n (module doc: ray cones): the
    cone's cross-section, two axes of length `width` at right angles to d, carried along d onto the tangent plane
    and into (u, v) through the surface's (∂p/∂u, ∂p/∂v). Zeros (the point lookup) for width 0."""
    if width == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    dpdu, dpdv = surface_tangents(surf, ref, part, p, n, time)
    a = dot(dpdu, dpdu)
    b = dot(dpdu, dpdv)
    c = dot(dpdv, dpdv)
    det = a * c - b * b
    if not det > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    cos = dot(n, d)
    cos = math.copysign(max(abs(cos), 1e-9), cos)
    e1 = (n[0] - cos * d[0], n[1] - cos * d[1], n[2] - cos * d[2])  # the axis the slant stretches
    l1 = length(e1)
    if l1 < 1e-12:  # head-on: any axis at right angles to d
        e1, _ = orthonormal_basis(d)
        l1 = 0.0
    else:
        e1 = (e1[0] / l1, e1[1] / l1, e1[2] / l1)
    e2 = cross(d, e1)
    k = width * l1 / cos  # along d back onto the tangent plane: x − d·(n·x)/(n·d), n·e1 = l1, n·e2 = 0
    x = (width * e1[0] - k * d[0], width * e1[1] - k * d[1], width * e1[2] - k * d[2])
    y = (width * e2[0], width * e2[1], width * e2[2])
    inv = 1.0 / det
    xu, xv = dot(x, dpdu), dot(x, dpdv)
    yu, yv = dot(y, dpdu), dot(y, dpdv)
    return ((c * xu - b * xv) * inv, (a * xv - b * xu) * inv, (c * yu - b * yv) * inv, (a * yv - b * yu) * inv)
