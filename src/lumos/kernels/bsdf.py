"""The materials read physically, for the path tracer (DESIGN.md §4): one BSDF from the classic coefficients.

    f(wo, wi) = kd/π                                   Lambertian albedo kd
              + ks·(n+2)/(2π)·cosⁿα                    normalised modified Phong lobe, α the angle between wi and
                                                       the mirror direction of wo (Lafortune & Willems 1994)
              + kr·δ(wi = mirror of wo)                 perfect mirror
              + kt·(smooth dielectric of index ior)     Fresnel-weighted reflection and refraction

A metal (MODEL_CONDUCTOR) replaces the Phong lobe by a GGX microfacet lobe with the conductor's Fresnel factor
(`kernels.microfacet`), ks its tint; a smooth one is the mirror lobe weighted by that Fresnel factor. A plastic
(MODEL_PLASTIC) is a Lambertian base of albedo kd under a dielectric coat of index η: the coat reflects by a GGX
lobe (or the mirror lobe) with the dielectric's Fresnel factor, and the base's light is what the coat lets in and
out, t(cos θi)·t(cos θo)·kd/(π·η²·(1 − Fdr)), t = 1 − the coat's directional reflectance and Fdr its internal
diffuse reflectance (the tables `compile.plastic` writes into the row), as Mitsuba 3's `roughplastic` reads it.
glTF's metallic–roughness material (MODEL_PRINCIPLED) is `kernels.principled`'s diffuse and glossy lobes.
Glass (MODEL_DIELECTRIC) is one lobe: when rough, the glossy one (ks = 1), GGX reflection and refraction
(`microfacet.eval_ggx_dielectric`, Walter et al. 2007) on both sides of the surface, times its reflected or
transmitted tint; when smooth, the dielectric one (kt = 1) with its own indices and tints (`methods.path_trace`).
The functions take the material row `mat` for these parameters.

The first two are the smooth part (`eval_smooth`); the last two are delta lobes, reached only by sampling.
`sample_*` functions return the sampled direction with its pdf (solid angle), so each sampler can be checked
against its pdf by a χ² test. A lobe is chosen with probability `lobe_probs` (proportional to the mean of its
coefficient), and the smooth part's pdf is the mixture p_d·pdf_cosine + p_s·pdf_phong (one-sample MIS over the
lobes, the balance heuristic), which is also the pdf the light-sampling MIS weights use.

All vectors are unit tuples; `n` is the shading normal on the side of wo (wo·n >= 0).
"""

import math

from .jit import njit, njit_inline
from .layout import (
    MAT_ALPHA,
    MAT_COAT,
    MAT_COAT_SIZE,
    MAT_ETA,
    MAT_FDR,
    MAT_K,
    MAT_MODEL,
    MAT_SHININESS,
    MAT_TANGENT,
    MAT_TINT,
    MAT_TINT_T,
    MODEL_CLASSIC,
    MODEL_CONDUCTOR,
    MODEL_DIELECTRIC,
    MODEL_PLASTIC,
    MODEL_PRINCIPLED,
)
from .microfacet import (
    eval_ggx,
    eval_ggx_dielectric,
    fresnel_conductor,
    fresnel_dielectric,
    sample_ggx,
    sample_ggx_dielectric,
)
from .principled import eval_principled, sample_principled
from .sampling import turn
from .vec import dot, madd, mul, orthonormal_basis

_INV_PI = 1.0 / math.pi
_INV_2PI = 0.5 / math.pi


@njit_inline
def lobe_probs(kd, ks, kr, kt):
    """Probabilities (p_d, p_s, p_r, p_t) of sampling the diffuse, Phong, mirror and dielectric lobes: each
    proportional to the mean of its RGB coefficient (to its sum: the thirds cancel, and one division is left of
    five); all 0 for a black material."""
    wd = kd[0] + kd[1] + kd[2]
    ws = ks[0] + ks[1] + ks[2]
    wr = kr[0] + kr[1] + kr[2]
    wt = kt[0] + kt[1] + kt[2]
    total = wd + ws + wr + wt
    if not total > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    inv = 1.0 / total
    return wd * inv, ws * inv, wr * inv, wt * inv


@njit_inline
def conserve_energy(kd, ks, kr, kt):
    """The coefficients scaled down by one factor so that kd + ks + kr + kt <= 1 in every channel (a textured
    colour may push a material over; the compile step already scaled the untextured rows, with a warning)."""
    m = max(kd[0] + ks[0] + kr[0] + kt[0], kd[1] + ks[1] + kr[1] + kt[1], kd[2] + ks[2] + kr[2] + kt[2])
    if m <= 1.0:
        return kd, ks, kr, kt
    s = 1.0 / m
    return mul(kd, s), mul(ks, s), mul(kr, s), mul(kt, s)


@njit_inline
def surface_fresnel(mat, cos_o):
    """The Fresnel factor per channel of a physical model's lobe at cos_o = wo·h (a metal's complex one, a
    plastic coat's dielectric one); 1 for the classic model, whose coefficients are the lobe's weight."""
    model = mat[MAT_MODEL]
    if model == MODEL_CONDUCTOR:
        return (fresnel_conductor(cos_o, mat[MAT_ETA], mat[MAT_K]),
                fresnel_conductor(cos_o, mat[MAT_ETA + 1], mat[MAT_K + 1]),
                fresnel_conductor(cos_o, mat[MAT_ETA + 2], mat[MAT_K + 2]))
    if model == MODEL_PLASTIC:
        f = fresnel_dielectric(max(cos_o, 0.0), 1.0 / mat[MAT_ETA])[0]
        return f, f, f
    return 1.0, 1.0, 1.0


@njit_inline
def tangent_of(mat):
    """The direction a (hit's) row's GGX width αu lies along (MAT_TANGENT; (0, 0, 0): none given, and always for
    a plastic, whose coat is isotropic and whose row holds its coat's table there)."""
    if mat[MAT_MODEL] == MODEL_PLASTIC:
        return 0.0, 0.0, 0.0
    return mat[MAT_TANGENT], mat[MAT_TANGENT + 1], mat[MAT_TANGENT + 2]


@njit_inline
def coat_transmittance(mat, cos_t):
    """A plastic coat's t(cos θ) = 1 − its directional reflectance, from the row's table (linear in cos θ)."""
    x = min(max(cos_t, 0.0), 1.0) * (MAT_COAT_SIZE - 1)
    i = min(int(x), MAT_COAT_SIZE - 2)
    w = x - i
    return (1.0 - w) * mat[MAT_COAT + i] + w * mat[MAT_COAT + i + 1]


@njit
def mirror(wo, n):
    """wo reflected about n: 2(n·wo)n − wo."""
    return madd(mul(wo, -1.0), n, 2.0 * dot(n, wo))


@njit_inline
def relative_eta(mat, entering):
    """η = n_t/n_i across a dielectric's surface (MODEL_DIELECTRIC) for a ray arriving from outside (entering)
    or from inside: its int_ior/ext_ior or the inverse; 1 for the other models (not read by them)."""
    if mat[MAT_MODEL] != MODEL_DIELECTRIC:
        return 1.0
    return mat[MAT_ETA] if entering else 1.0 / mat[MAT_ETA]


@njit
def eval_dielectric(kd, ks, mat, p_d, p_s, eta, n, wo, wi):
    """`eval_smooth` for a rough dielectric: its GGX reflection and refraction (`microfacet.eval_ggx_dielectric`)
    times ks and the reflected or transmitted tint, on either side of the surface; kd/π above it. (Called, not
    inlined: the lobes of the other models stay small where they are inlined.)"""
    g, pdf_g, through = eval_ggx_dielectric(mat[MAT_ALPHA], mat[MAT_ALPHA + 1], eta, n, tangent_of(mat), wo, wi)
    tint = MAT_TINT_T if through else MAT_TINT
    fs = (ks[0] * mat[tint] * g, ks[1] * mat[tint + 1] * g, ks[2] * mat[tint + 2] * g)
    pdf = p_s * pdf_g
    fd = (0.0, 0.0, 0.0)
    cos_i = dot(n, wi)
    if cos_i > 0.0 and p_d > 0.0:
        fd = (kd[0] * _INV_PI, kd[1] * _INV_PI, kd[2] * _INV_PI)
        pdf += p_d * cos_i * _INV_PI
    return fd, fs, pdf


@njit
def eval_smooth(kd, ks, mat, p_d, p_s, eta, n, wo, wi):
    """The smooth part of the BSDF for the pair (wo, wi): (f_diffuse rgb, f_glossy rgb, pdf of wi).

    f_diffuse = kd/π (under a plastic's coat, times what the coat lets through) and f_glossy =
    ks·(n+2)/(2π)·cosⁿα (n the row's shininess), or ks times a metal's or a coat's GGX lobe, both 0 where wi is
    below the surface (n·wi <= 0); pdf is the mixture p_d·cosθ/π + p_s·pdf_glossy with which `sample_cosine` and
    `sample_phong` (or `microfacet.sample_ggx`) draw wi. A rough dielectric's lobe reaches below the surface too
    (`eval_dielectric`; eta = n_t/n_i from wo's side, `relative_eta`, read by it alone)."""
    model = mat[MAT_MODEL]
    if model == MODEL_DIELECTRIC:
        return eval_dielectric(kd, ks, mat, p_d, p_s, eta, n, wo, wi)
    if model == MODEL_PRINCIPLED:  # (its Fresnel factors weigh both lobes: ks is not read)
        return eval_principled(kd, mat, p_d, p_s, n, wo, wi)
    cos_i = dot(n, wi)
    if cos_i <= 0.0:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0
    pdf = p_d * cos_i * _INV_PI
    c = _INV_PI
    if model == MODEL_PLASTIC:  # the light the coat lets in and out, and the base's inter-reflection under it
        eta = mat[MAT_ETA]
        c *= coat_transmittance(mat, cos_i) * coat_transmittance(mat, dot(n, wo)) / (eta * eta * (1.0 - mat[MAT_FDR]))
    fd = (kd[0] * c, kd[1] * c, kd[2] * c)
    fs = (0.0, 0.0, 0.0)
    if p_s > 0.0 and model != MODEL_CLASSIC:
        g, pdf_g, o_h = eval_ggx(mat[MAT_ALPHA], mat[MAT_ALPHA + 1], n, tangent_of(mat), wo, wi)
        f = surface_fresnel(mat, o_h)
        fs = (ks[0] * g * f[0], ks[1] * g * f[1], ks[2] * g * f[2])
        pdf += p_s * pdf_g
    elif p_s > 0.0:
        exponent = mat[MAT_SHININESS]
        cos_a = dot(mirror(wo, n), wi)
        if cos_a > 0.0:
            lobe = cos_a**exponent
            c = (exponent + 2.0) * _INV_2PI * lobe
            fs = (ks[0] * c, ks[1] * c, ks[2] * c)
            pdf += p_s * (exponent + 1.0) * _INV_2PI * lobe
    return fd, fs, pdf


@njit
def sample_cosine(n, u1, u2):
    """A cosine-weighted direction about unit n (Malley's method: a uniform disk point lifted to the
    hemisphere); its pdf is cosθ/π."""
    r = math.sqrt(u1)
    c, s = turn(u2)
    x = r * c
    y = r * s
    z = math.sqrt(max(0.0, 1.0 - u1))
    t, b = orthonormal_basis(n)
    return (x * t[0] + y * b[0] + z * n[0], x * t[1] + y * b[1] + z * n[1], x * t[2] + y * b[2] + z * n[2])


@njit
def sample_phong(axis, exponent, u1, u2):
    """A direction about unit `axis` with density (n+1)/(2π)·cosⁿα (α from the axis): cos α = u1^(1/(n+1))."""
    cos_a = u1 ** (1.0 / (exponent + 1.0))
    sin_a = math.sqrt(max(0.0, 1.0 - cos_a * cos_a))
    c, s = turn(u2)
    x = sin_a * c
    y = sin_a * s
    t, b = orthonormal_basis(axis)
    return (x * t[0] + y * b[0] + cos_a * axis[0], x * t[1] + y * b[1] + cos_a * axis[1],
            x * t[2] + y * b[2] + cos_a * axis[2])


@njit_inline
def sample_smooth(kd, ks, mat, p_d, p_s, eta, n, wo, u_lobe, u1, u2):
    """A direction from the smooth part of the BSDF: the diffuse lobe when u_lobe < p_d, else the glossy lobe
    (u_lobe < p_d + p_s: Phong about the mirror direction, or the visible GGX normals of a metal, a coat or a
    rough dielectric, which reflects or refracts by (u_lobe − p_d)/p_s), with the mixture pdf of `eval_smooth`.
    Returns (wi, f·|cos|/pdf as rgb, pdf); pdf = 0 when the direction falls below the surface (the lobe reaches
    past it; a dielectric's refraction is below it, its reflection must not be)."""
    model = mat[MAT_MODEL]
    if u_lobe < p_d:
        wi = sample_cosine(n, u1, u2)
    elif model == MODEL_DIELECTRIC:
        wi, ok = sample_ggx_dielectric(mat[MAT_ALPHA], mat[MAT_ALPHA + 1], eta, n, tangent_of(mat), wo,
                                       (u_lobe - p_d) / p_s, u1, u2)
        if not ok:
            return wi, (0.0, 0.0, 0.0), 0.0
    elif model == MODEL_PRINCIPLED:  # (its base's or its clear coat's lobe, by (u_lobe − p_d)/p_s)
        wi = sample_principled(mat, n, wo, (u_lobe - p_d) / p_s, u1, u2)
    elif model != MODEL_CLASSIC:
        wi = sample_ggx(mat[MAT_ALPHA], mat[MAT_ALPHA + 1], n, tangent_of(mat), wo, u1, u2)
    else:
        wi = sample_phong(mirror(wo, n), mat[MAT_SHININESS], u1, u2)
    fd, fs, pdf = eval_smooth(kd, ks, mat, p_d, p_s, eta, n, wo, wi)
    if not pdf > 0.0:
        return wi, (0.0, 0.0, 0.0), 0.0
    k = abs(dot(n, wi)) / pdf
    return wi, ((fd[0] + fs[0]) * k, (fd[1] + fs[1]) * k, (fd[2] + fs[2]) * k), pdf


@njit
def refracted(wo, n, eta, cos_i, cos_t):
    """The refracted direction of the ray arriving along −wo (Snell's law, eta = n_i/n_t): −eta·wo +
    (eta·cos_i − cos_t)·n, unit."""
    k = eta * cos_i - cos_t
    t = (-eta * wo[0] + k * n[0], -eta * wo[1] + k * n[1], -eta * wo[2] + k * n[2])
    inv = 1.0 / math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
    return (t[0] * inv, t[1] * inv, t[2] * inv)


@njit
def sample_dielectric(wo, n, eta, u):
    """The smooth dielectric's choice for the ray arriving along −wo at unit normal n (wo's side), eta =
    n_incident/n_transmitted: reflection with probability F (Fresnel), else refraction. Returns (wi, refracted,
    F); every choice carries the weight kt (F/F, (1−F)/(1−F)), and a refracted one also (n1/n2)² = eta²
    (radiance is compressed into the denser medium: Veach 1997, §5.2)."""
    cos_o = max(dot(wo, n), 0.0)
    F, cos_t = fresnel_dielectric(cos_o, eta)
    if u < F:
        return mirror(wo, n), False, F
    return refracted(wo, n, eta, cos_o, cos_t), True, F


@njit
def power_heuristic_over(pdf_a, pdf_b):
    """`power_heuristic(pdf_a, pdf_b) / pdf_a`, the factor a sample of strategy a is weighted by, in one division:
    pdf_a / (pdf_a² + pdf_b²); 0 when both squares vanish, as the heuristic is. pdf_a > 0."""
    s = pdf_a * pdf_a + pdf_b * pdf_b
    if not s > 0.0:
        return 0.0
    return pdf_a / s


@njit
def power_heuristic(pdf_a, pdf_b):
    """Veach's power heuristic (β = 2) weight of the strategy with pdf_a against the one with pdf_b."""
    a = pdf_a * pdf_a
    b = pdf_b * pdf_b
    if not a + b > 0.0:
        return 0.0
    return a / (a + b)
