"""glTF 2.0's metallic–roughness material (MODEL_PRINCIPLED), read exactly by the path tracer.

    kd, kt, wd, ws = principled_at(tex, mat, row, u, v, p, cos_o)   # the material at a hit, into `row`
    fd, fs, pdf = eval_principled(kd, mat, p_d, p_s, n, wo, wi)      # (kernels.bsdf.eval_smooth calls it)
    wi = sample_principled(mat, n, wo, u, u1, u2)                    # (and kernels.bsdf.sample_smooth this)

The BRDF of the glTF specification's Appendix B, with KHR_materials_specular and _ior, for base colour b,
metallic m and perceptual roughness r (GGX α = r², `kernels.microfacet`), h the half vector of wo and wi:

    f = (1 − m)·(1 − t)·(1 − max_c F_d(wo·h))·b/π  +  F(wo·h)·D·G/(4·cos θo·cos θi)
    F_d(c) = F0 + (F90 − F0)·(1 − c)⁵             the dielectric's Schlick Fresnel (F0, F90: the row's MAT_F0, MAT_F90)
    F(c)   = (1 − m)·F_d(c) + m·(b + (1 − b)·(1 − c)⁵)   the metal's Schlick Fresnel has F0 = b

and `transmission` t hands that share of the dielectric's base on to smooth glass of index MAT_IOR (the path
tracer's transmission lobe kt = (1 − m)·t·b·(1 − max F_d(n·wo)): what the glossy lobe does not reflect,
`methods.path_trace._transmit`; on a surface that bounds no solid, as glTF's meshes, it passes straight through,
glTF's thin-walled reading). KHR_materials_clearcoat lays a
clear coat of factor c and width α_c over all of it (the extension's fresnel_coat):

    f_coated = (1 − c·Fc(n·wo))·f + c·Fc(n·wo)·D_c·G_c/(4·cos θo·cos θi),   Fc(x) = 0.04 + 0.96·(1 − x)⁵ G is Smith's separable
masking–shadowing, as in lumos's other GGX lobes (the specification's sample code uses the height-correlated
form, a few per cent brighter at grazing angles on rough surfaces).

b, m and r vary over the surface: the row holds their factors, and the material's textures multiply (or
replace) them per hit: APPLY_BASE rows the base colour, an APPLY_METAL_ROUGH row (raw texels) m by its blue and
r by its green, as glTF's metallicRoughnessTexture. `principled_at` writes the hit's b, m and α into a per-thread
copy of the row (`row`), which the BSDF functions then read like any material row, and returns the lobe
weights: kd = (1 − m)(1 − t)(1 − c·Fc)·b for the diffuse (the Fresnel weight is applied in `eval_principled`,
as is the glossy lobe's Fresnel factor F, which needs no weight), kt for the glass; and the weights (wd, ws) the
lobe choice draws by: the diffuse and glossy albedos estimated at cos θo = n·wo by the Fresnel factors there
(the coat's c·Fc in the glossy one, and in the row the share MAT_COAT_SHARE of the glossy samples that are the
coat's).
"""

import numpy as np

from .jit import njit
from .layout import (
    MAT_ALPHA,
    MAT_BASE,
    MAT_CLEARCOAT,
    MAT_COAT_ALPHA,
    MAT_COAT_SHARE,
    MAT_COAT_WEIGHT,
    MAT_F0,
    MAT_F90,
    MAT_METALLIC,
    MAT_ROUGHNESS,
    MAT_TEXTURE,
    MAT_TEXTURE_COUNT,
    MAT_TRANSMISSION,
)
from .microfacet import eval_ggx, sample_ggx
from .texture import APPLY_BASE, APPLY_METAL_ROUGH, MODE_MULTIPLY, TEX_APPLY, TEX_MODE, texture_rgb
from .vec import dot

_INV_PI = 1.0 / np.pi
#: its lobes are isotropic: any frame about the normal will do
_NO_TANGENT = (0.0, 0.0, 0.0)
#: the narrowest GGX width the model draws (r = 0.03): a smoother surface is a mirror the lobe cannot sample
ALPHA_MIN = 1e-3


@njit
def principled_at(tex, mat, row, u, v, p, cos_o):
    """The material `mat` (a MODEL_PRINCIPLED row) at surface point (u, v), seen at cos θo = cos_o: its factors
    times its textures there, copied with the row into `row` (float64 (MAT_SIZE,), the thread's own; not
    returned: a kernel compiled without Numba's runtime must not hand an array back to one compiled with it).
    Returns (kd, kt, wd, ws): the diffuse weight `eval_principled` takes and the transmission lobe's, and the
    weights of the lobe choice (see the module doc)."""
    b0, b1, b2 = mat[MAT_BASE], mat[MAT_BASE + 1], mat[MAT_BASE + 2]
    m = mat[MAT_METALLIC]
    r = mat[MAT_ROUGHNESS]
    if tex is not None:  # (None: a scene without textures, `compile.features`; Numba prunes the lookups)
        first = np.int64(mat[MAT_TEXTURE])
        if first >= 0:
            for k in range(first, first + np.int64(mat[MAT_TEXTURE_COUNT])):
                mask = np.int64(tex.tex_info[k, TEX_APPLY])
                if mask & APPLY_BASE:
                    c = texture_rgb(tex, k, u, v, p)
                    if tex.tex_info[k, TEX_MODE] == MODE_MULTIPLY:
                        b0, b1, b2 = b0 * c[0], b1 * c[1], b2 * c[2]
                    else:
                        b0, b1, b2 = c
                elif mask & APPLY_METAL_ROUGH:
                    c = texture_rgb(tex, k, u, v, p)
                    m *= c[2]
                    r *= c[1]
    m = min(max(m, 0.0), 1.0)
    alpha = max(r * r, ALPHA_MIN)
    for i in range(mat.shape[0]):  # (an explicit loop: slice assignment needs Numba's runtime, which is off)
        row[i] = mat[i]
    row[MAT_BASE], row[MAT_BASE + 1], row[MAT_BASE + 2] = b0, b1, b2
    row[MAT_METALLIC] = m
    row[MAT_ALPHA] = row[MAT_ALPHA + 1] = alpha
    coat = mat[MAT_CLEARCOAT] * (0.04 + 0.96 * (1.0 - min(max(cos_o, 0.0), 1.0)) ** 5)
    row[MAT_COAT_WEIGHT] = coat
    t = mat[MAT_TRANSMISSION]
    d = (1.0 - m) * (1.0 - coat)
    kd = (d * (1.0 - t) * b0, d * (1.0 - t) * b1, d * (1.0 - t) * b2)
    kt = (d * t * b0, d * t * b1, d * t * b2)
    (f0, f1, f2), f_max = principled_fresnel(row, cos_o)
    k = 1.0 - f_max
    under = 1.0 - coat
    ws = (f0 * under + coat, f1 * under + coat, f2 * under + coat)
    row[MAT_COAT_SHARE] = 3.0 * coat / (ws[0] + ws[1] + ws[2]) if coat > 0.0 else 0.0
    # the transmitted share is what the glossy lobe does not reflect, as the base's: 1 − max F_d at n·wo (a smooth
    # lobe has no half vector but the normal)
    return kd, (kt[0] * k, kt[1] * k, kt[2] * k), (kd[0] * k, kd[1] * k, kd[2] * k), ws


@njit
def principled_fresnel(row, c):
    """(F(c) per channel, max_c F_d(c)) of the row's hit values at c = wo·h (see the module doc)."""
    s = (1.0 - min(max(c, 0.0), 1.0)) ** 5
    m = row[MAT_METALLIC]
    f90 = row[MAT_F90]
    fd0 = row[MAT_F0] + (f90 - row[MAT_F0]) * s
    fd1 = row[MAT_F0 + 1] + (f90 - row[MAT_F0 + 1]) * s
    fd2 = row[MAT_F0 + 2] + (f90 - row[MAT_F0 + 2]) * s
    b0, b1, b2 = row[MAT_BASE], row[MAT_BASE + 1], row[MAT_BASE + 2]
    f = ((1.0 - m) * fd0 + m * (b0 + (1.0 - b0) * s), (1.0 - m) * fd1 + m * (b1 + (1.0 - b1) * s),
         (1.0 - m) * fd2 + m * (b2 + (1.0 - b2) * s))
    return f, max(fd0, fd1, fd2)


@njit
def eval_principled(kd, mat, p_d, p_s, n, wo, wi):
    """`kernels.bsdf.eval_smooth` for the principled model (mat: the hit's row from `principled_at`):
    (f_diffuse rgb, f_glossy rgb, pdf of wi under the mixture p_d·cosθ/π + p_s·pdf_GGX)."""
    cos_i = dot(n, wi)
    if cos_i <= 0.0:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0
    g, pdf_g, o_h = eval_ggx(mat[MAT_ALPHA], mat[MAT_ALPHA + 1], n, _NO_TANGENT, wo, wi)
    f, f_max = principled_fresnel(mat, o_h)
    c = (1.0 - f_max) * _INV_PI
    fd = (kd[0] * c, kd[1] * c, kd[2] * c)
    coat = mat[MAT_COAT_WEIGHT]
    if not coat > 0.0:
        return fd, (f[0] * g, f[1] * g, f[2] * g), p_d * cos_i * _INV_PI + p_s * pdf_g
    g_c, pdf_c, _ = eval_ggx(mat[MAT_COAT_ALPHA], mat[MAT_COAT_ALPHA], n, _NO_TANGENT, wo, wi)
    g *= 1.0 - coat
    g_c *= coat
    q = mat[MAT_COAT_SHARE]
    return (fd, (f[0] * g + g_c, f[1] * g + g_c, f[2] * g + g_c),
            p_d * cos_i * _INV_PI + p_s * ((1.0 - q) * pdf_g + q * pdf_c))


@njit
def sample_principled(mat, n, wo, u, u1, u2):
    """A direction from the principled model's glossy lobes: the coat's visible GGX normals with probability
    MAT_COAT_SHARE (u below it), else the base's."""
    if u < mat[MAT_COAT_SHARE]:
        return sample_ggx(mat[MAT_COAT_ALPHA], mat[MAT_COAT_ALPHA], n, _NO_TANGENT, wo, u1, u2)
    return sample_ggx(mat[MAT_ALPHA], mat[MAT_ALPHA + 1], n, _NO_TANGENT, wo, u1, u2)
