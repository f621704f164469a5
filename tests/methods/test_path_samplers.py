"""The path tracer's samplers against their pdfs (χ² tests, as Mitsuba checks its BSDFs and emitters), and the
energy of the Phong lobe (the white furnace).

Every sampler here is the kernel the path tracer calls (`kernels.bsdf`, `kernels.emitters`), driven by a small
batch loop; every pdf is the one its MIS weights use. A sampler and its pdf that disagree anywhere by more than
noise fail the test.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from chi2 import chi2_directions, chi2_discrete, frame_z, significance_level

import lumos
from lumos.methods import compile_for
from lumos.kernels import bsdf
from lumos.kernels.emitters import emitter_pdf, sample_emitter
from lumos.kernels import layout as L
from lumos.kernels.layout import LIGHT_SPHERE
from lumos.kernels.surface import surface_at
from lumos.kernels.traverse import closest_hit
from lumos.kernels.views import geometry_of, lighting_of, surfaces_of

#: Independent χ² tests in this file: each passes at the level that keeps the chance of a false alarm among all
#: of them at 1%.
N_TESTS = 31
LEVEL = significance_level(0.01, N_TESTS)
#: The shading normal given to light selection: none (the light tree then leaves out the cosine at p)
NO_NORMAL = (0.0, 0.0, 0.0)

# ---------------------------------------------------------------------------------------------- BSDF lobes


@numba.njit(cache=True)
def _smooth_batch(kd, ks, lobe, p_d, p_s, n, wo, u):
    """`bsdf.sample_smooth` on each row of u (m, 3): (directions (m, 3), NaN where it fails; weights (m, 3))."""
    m = u.shape[0]
    dirs = np.full((m, 3), np.nan)
    weights = np.zeros((m, 3))
    for i in range(m):
        wi, w, pdf = bsdf.sample_smooth(kd, ks, lobe, p_d, p_s, 1.0, n, wo, u[i, 0] * (p_d + p_s), u[i, 1], u[i, 2])
        if pdf > 0.0:
            for c in range(3):
                dirs[i, c] = wi[c]
                weights[i, c] = w[c]
    return dirs, weights


@numba.njit(cache=True)
def _smooth_pdf(kd, ks, lobe, p_d, p_s, n, wo, dirs):
    out = np.empty(dirs.shape[0])
    for i in range(dirs.shape[0]):
        wi = (dirs[i, 0], dirs[i, 1], dirs[i, 2])
        out[i] = bsdf.eval_smooth(kd, ks, lobe, p_d, p_s, 1.0, n, wo, wi)[2]
    return out


def _phong(exponent):
    """A material row (`kernels.layout`) whose glossy lobe is the classic Phong lobe of this exponent."""
    row = np.zeros(L.MAT_SIZE)
    row[L.MAT_SHININESS] = exponent
    return row


def _ggx(au, av=None, eta=(0.0,) * 3, k=(0.0,) * 3):
    """A material row of a GGX metal (η = k = 0: F = 1)."""
    row = _phong(1.0)
    row[L.MAT_MODEL] = L.MODEL_CONDUCTOR
    row[L.MAT_ALPHA:L.MAT_ALPHA + 2] = au, au if av is None else av
    row[L.MAT_ETA:L.MAT_ETA + 3] = eta
    row[L.MAT_K:L.MAT_K + 3] = k
    return row


def _plastic(alpha, ior=1.5):
    """A material row of a plastic's coat (its tables from `compile.plastic`)."""
    from lumos.compile.plastic import coat_tables

    row = _phong(1.0)
    row[L.MAT_MODEL] = L.MODEL_PLASTIC
    row[L.MAT_ALPHA:L.MAT_ALPHA + 2] = alpha
    row[L.MAT_ETA] = ior
    t, row[L.MAT_FDR] = coat_tables(alpha, ior)
    row[L.MAT_COAT:L.MAT_COAT + L.MAT_COAT_SIZE] = t
    return row


def _unit(v):
    v = np.asarray(v, np.float64)
    return tuple(v / np.linalg.norm(v))


def _smooth_test(p_d, p_s, lobe, wo, seed=0):
    n = (0.0, 0.0, 1.0)
    kd, ks = (p_d,) * 3, (p_s,) * 3
    rng = np.random.default_rng(seed)
    u = rng.random((200_000, 3))

    def sample(u2):
        return _smooth_batch(kd, ks, lobe, p_d, p_s, n, wo, np.column_stack([u[: len(u2), 0], u2]))[0]

    def pdf(dirs):
        return _smooth_pdf(kd, ks, lobe, p_d, p_s, n, wo, np.ascontiguousarray(dirs))

    return chi2_directions(sample, pdf, n_samples=len(u), frame=frame_z(n), sphere=False, seed=seed)


@pytest.mark.parametrize("p_d, p_s, exponent, wo", [
    (1.0, 0.0, 1.0, (0.0, 0.0, 1.0)),                 # cosine hemisphere
    (0.0, 1.0, 20.0, _unit((0.0, 0.0, 1.0))),          # Phong lobe at normal incidence
    (0.0, 1.0, 8.0, _unit((1.0, 0.3, 0.6))),           # Phong lobe at 60°: part of it falls below the surface
    (0.4, 0.6, 50.0, _unit((-0.5, 0.2, 0.8))),         # the mixture, as the path tracer samples it
])
def test_smooth_lobes_follow_their_pdf(p_d, p_s, exponent, wo):
    result = _smooth_test(p_d, p_s, _phong(exponent), wo)
    assert result.p_value > LEVEL, result.message


def test_a_wrong_phong_exponent_is_detected():
    """The test has the power to see a lobe drawn with exponent 16 while its pdf says 20."""
    n, wo = (0.0, 0.0, 1.0), (0.0, 0.0, 1.0)
    rng = np.random.default_rng(3)
    u = rng.random((200_000, 3))

    def sample(u2):
        return _smooth_batch((0.0,) * 3, (1.0,) * 3, _phong(16), 0.0, 1.0, n, wo, np.column_stack([u[:, 0], u2]))[0]

    def pdf(dirs):
        return _smooth_pdf((0.0,) * 3, (1.0,) * 3, _phong(20), 0.0, 1.0, n, wo, np.ascontiguousarray(dirs))

    assert chi2_directions(sample, pdf, n_samples=len(u), frame=frame_z(n), sphere=False).p_value < 1e-6


@pytest.mark.parametrize("exponent", [1.0, 10.0, 100.0, 1000.0])
def test_white_furnace_phong_lobe(exponent):
    """ks = 1: the lobe reflects all the light at normal incidence (its (n+2)/2π normalisation) and never more
    than all of it (at 70° part of the lobe is below the surface and is lost)."""
    n = (0.0, 0.0, 1.0)
    rng = np.random.default_rng(int(exponent))
    u = rng.random((400_000, 3))
    for angle, expect_one in ((0.0, True), (45.0, False), (70.0, False)):
        a = math.radians(angle)
        wo = (math.sin(a), 0.0, math.cos(a))
        _, w = _smooth_batch((0.0,) * 3, (1.0,) * 3, _phong(exponent), 0.0, 1.0, n, wo, u)
        albedo = w[:, 0].mean()
        err = 4.0 * w[:, 0].std() / math.sqrt(len(u)) + 1e-12
        assert albedo <= 1.0 + err, (angle, albedo)
        if expect_one:
            assert abs(albedo - 1.0) <= max(err, 1e-3), albedo


@pytest.mark.parametrize("alpha, wo", [
    ((0.5, 0.5), _unit((0.0, 0.0, 1.0))),            # GGX at normal incidence
    ((0.2, 0.2), _unit((1.0, 0.2, 0.5))),            # narrow, at 64°: visible-normal sampling
    ((0.9, 0.9), _unit((-0.3, 0.8, 0.2))),           # wide, grazing: much of the lobe falls below the surface
    ((0.1, 0.6), _unit((0.5, -0.4, 0.7))),           # anisotropic
])
def test_ggx_lobe_follows_its_pdf(alpha, wo):
    """A metal's lobe (`microfacet.sample_ggx`) draws directions with the density `eval_ggx` says."""
    result = _smooth_test(0.0, 1.0, _ggx(*alpha), wo)
    assert result.p_value > LEVEL, result.message


def test_the_ggx_mixture_with_a_diffuse_lobe_follows_its_pdf():
    result = _smooth_test(0.3, 0.7, _ggx(0.3), _unit((0.4, 0.1, 0.9)))
    assert result.p_value > LEVEL, result.message


def test_a_wrong_ggx_width_is_detected():
    """The test has the power to see normals drawn for α = 0.27 while the pdf says 0.3."""
    n, wo = (0.0, 0.0, 1.0), _unit((0.3, 0.0, 1.0))
    u = np.random.default_rng(5).random((200_000, 3))

    def sample(u2):
        return _smooth_batch((0.0,) * 3, (1.0,) * 3, _ggx(0.27), 0.0, 1.0, n, wo, np.column_stack([u[:, 0], u2]))[0]

    def pdf(dirs):
        return _smooth_pdf((0.0,) * 3, (1.0,) * 3, _ggx(0.3), 0.0, 1.0, n, wo, np.ascontiguousarray(dirs))

    assert chi2_directions(sample, pdf, n_samples=len(u), frame=frame_z(n), sphere=False).p_value < 1e-6


#: The white furnace of the GGX lobe with F = 1 at normal incidence: the share of the light it keeps (what
#: single scattering between microfacets returns), by α; the rest would scatter more than once and is lost.
#: (Measured here, 200,000 samples; the quadrature agrees to 0.3%. The loss grows fast: of the light reflected off
#: one microfacet, the share sent into the surface at normal incidence is tan²45°/(α² + tan²45°)'s complement,
#: 8% at α = 0.3 and half at α = 1; separable Smith masking takes a little more.)
GGX_FURNACE = {0.01: 1.0, 0.1: 0.988, 0.3: 0.878, 0.6: 0.591, 1.0: 0.307}


@pytest.mark.parametrize("alpha", sorted(GGX_FURNACE))
def test_white_furnace_ggx(alpha):
    """A metal of F = 1 reflects at most all the light: its directional albedo (the mean of f·cos/pdf over its
    own samples) is 1 for a smooth surface and falls with α (energy lost to multiple scattering, not modelled),
    never above 1; the numbers match a quadrature of f·cos over the hemisphere (the two estimators agree)."""
    n = (0.0, 0.0, 1.0)
    u = np.random.default_rng(11).random((200_000, 3))
    for angle in (0.0, 60.0):
        a = math.radians(angle)
        wo = (math.sin(a), 0.0, math.cos(a))
        _, w = _smooth_batch((0.0,) * 3, (1.0,) * 3, _ggx(alpha), 0.0, 1.0, n, wo, u)
        albedo = w[:, 0].mean()
        err = 4.0 * w[:, 0].std() / math.sqrt(len(u)) + 1e-9
        assert albedo <= 1.0 + err, (angle, albedo)
        if angle == 0.0:
            assert albedo == pytest.approx(GGX_FURNACE[alpha], abs=max(0.01, err)), albedo
        if alpha < 0.1:
            continue  # (uniform directions cannot resolve a lobe this narrow)
        # the same albedo by quadrature of f·cos over the hemisphere (uniform directions)
        d = rng_hemisphere(400_000, seed=int(100 * alpha) + int(angle))
        f = _ggx_f(_ggx(alpha), n, wo, d)
        quad = 2.0 * math.pi * np.mean(f * d[:, 2])
        assert quad == pytest.approx(albedo, abs=max(3 * err, 0.01 * albedo)), (angle, quad, albedo)


def rng_hemisphere(m, seed):
    v = np.random.default_rng(seed).normal(size=(m, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    v[:, 2] = np.abs(v[:, 2])
    return v


@numba.njit(cache=True)
def _ggx_f_kernel(lobe, n, wo, dirs):
    out = np.empty(dirs.shape[0])
    for i in range(dirs.shape[0]):
        wi = (dirs[i, 0], dirs[i, 1], dirs[i, 2])
        out[i] = bsdf.eval_smooth((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), lobe, 0.0, 1.0, 1.0, n, wo, wi)[1][0]
    return out


def _ggx_f(lobe, n, wo, dirs):
    return _ggx_f_kernel(lobe, n, wo, np.ascontiguousarray(dirs))


@pytest.mark.parametrize("alpha, wo", [(0.2, _unit((0.3, 0.1, 0.9))), (0.6, _unit((-0.7, 0.2, 0.4)))])
def test_plastic_lobes_follow_their_pdf(alpha, wo):
    """A plastic's base and coat, mixed as the path tracer samples them."""
    result = _smooth_test(0.5, 0.5, _plastic(alpha), wo)
    assert result.p_value > LEVEL, result.message


#: A white plastic's (kd = 1, η = 1.5) directional albedo head-on by GGX width, as Mitsuba 3.9's `roughplastic`
#: gives it (the mean of its own sampler's weights, 20,000 samples; `distribution: ggx`). The model keeps single
#: scattering only: the light a rough coat refracts towards a masked microfacet, or reflects back down into one, is
#: lost, so a rough white plastic is far from white (a smooth one reflects all of it: coat + base = 1).
PLASTIC_FURNACE = {0.05: 0.956, 0.3: 0.692, 0.7: 0.439}


@pytest.mark.parametrize("alpha", sorted(PLASTIC_FURNACE))
def test_white_furnace_plastic(alpha):
    """A white base under a clear coat: at most all the light at any angle, and head-on what Mitsuba's own
    rough plastic reflects (the coat's tables are its: compile/plastic.py)."""
    n = (0.0, 0.0, 1.0)
    u = np.random.default_rng(13).random((200_000, 3))
    for angle in (0.0, 50.0):
        a = math.radians(angle)
        wo = (math.sin(a), 0.0, math.cos(a))
        _, w = _smooth_batch((1.0,) * 3, (1.0,) * 3, _plastic(alpha), 0.5, 0.5, n, wo, u)
        albedo = w[:, 0].mean()
        err = 4.0 * w[:, 0].std() / math.sqrt(len(u)) + 1e-9
        assert albedo <= 1.0 + err, (angle, albedo)
        if angle == 0.0:
            assert albedo == pytest.approx(PLASTIC_FURNACE[alpha], rel=0.01), albedo


def test_a_smooth_white_plastic_keeps_all_the_light():
    """With a smooth coat the base's share, t(μo)·∫t(μ)·2μ dμ/(η²(1 − Fdr)), is exactly what the coat does not
    reflect, 1 − F(μo): reciprocity, η²(1 − Fdr_inside) = 1 − Fdr_outside, holds in the tables."""
    from lumos.compile.plastic import coat_tables

    t, fdr = coat_tables(0.0, 1.5)
    mu = np.linspace(0.0, 1.0, len(t))
    outside = float(np.sum((t[1:] * mu[1:] + t[:-1] * mu[:-1]) * np.diff(mu)))  # ∫ t·2μ dμ, trapezoids
    assert outside / (1.5 ** 2 * (1.0 - fdr)) == pytest.approx(1.0, abs=2e-3)


def test_conductor_fresnel_against_closed_forms():
    """The complex-index Fresnel factor: head-on ((η−1)² + k²)/((η+1)² + k²); a dielectric (k = 0) gives the
    smooth dielectric's value at every angle; 1 at grazing incidence; η = k = 0 is the perfect reflector."""
    from lumos.kernels.microfacet import fresnel_conductor

    for eta, k in ((0.143, 3.983), (1.6575, 9.2238), (2.0, 0.5)):
        assert fresnel_conductor(1.0, eta, k) == pytest.approx(((eta - 1) ** 2 + k * k) / ((eta + 1) ** 2 + k * k))
        assert fresnel_conductor(0.0, eta, k) == pytest.approx(1.0)
    for c in (1.0, 0.7, 0.3, 0.05):
        assert fresnel_conductor(c, 1.5, 0.0) == pytest.approx(bsdf.fresnel_dielectric(c, 1.0 / 1.5)[0], rel=1e-9)
    assert fresnel_conductor(0.5, 0.0, 0.0) == 1.0


def test_white_furnace_lambert():
    n = (0.0, 0.0, 1.0)
    u = np.random.default_rng(7).random((100_000, 3))
    _, w = _smooth_batch((1.0,) * 3, (0.0,) * 3, _phong(1), 1.0, 0.0, n, (0.6, 0.0, 0.8), u)
    np.testing.assert_allclose(w, 1.0, rtol=1e-12)  # cosine sampling: f·cos/pdf = kd exactly


# ------------------------------------------------------------------------------------------------ dielectric


def _fresnel_reference(cos_i, n1, n2):
    """Fresnel's equations for unpolarised light, written out independently of the kernel."""
    sin_t = n1 / n2 * math.sqrt(max(0.0, 1.0 - cos_i**2))
    if sin_t >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin_t**2)
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)
    return 0.5 * (rs**2 + rp**2)


@pytest.mark.parametrize("n1, n2", [(1.0, 1.5), (1.5, 1.0), (1.33, 1.5)])
def test_fresnel_and_snell(n1, n2):
    for cos_i in np.linspace(0.0, 1.0, 41):
        F, cos_t = bsdf.fresnel_dielectric(cos_i, n1 / n2)
        assert F == pytest.approx(_fresnel_reference(cos_i, n1, n2), abs=1e-12)
        if F < 1.0:  # Snell: n1 sin θi = n2 sin θt
            assert n1 * math.sqrt(1 - cos_i**2) == pytest.approx(n2 * math.sqrt(1 - cos_t**2), abs=1e-12)
    assert bsdf.fresnel_dielectric(1.0, 1.0)[0] == 0.0  # ior 1: nothing reflects


@numba.njit(cache=True)
def _dielectric_counts(wo, n, eta, u):
    reflected = 0
    for i in range(u.shape[0]):
        wi, through, F = bsdf.sample_dielectric(wo, n, eta, u[i])
        if not through:
            reflected += 1
    return reflected


@pytest.mark.parametrize("angle, eta", [(0.0, 1 / 1.5), (60.0, 1 / 1.5), (85.0, 1 / 1.5), (30.0, 1.5)])
def test_dielectric_chooses_reflection_with_the_fresnel_weight(angle, eta):
    a = math.radians(angle)
    wo = (math.sin(a), 0.0, math.cos(a))
    u = np.random.default_rng(11).random(200_000)
    reflected = _dielectric_counts(wo, (0.0, 0.0, 1.0), eta, u)
    F = _fresnel_reference(math.cos(a), 1.0, 1.0 / eta)
    p = chi2_discrete(np.array([reflected, len(u) - reflected]), np.array([F, 1.0 - F]))
    assert p > LEVEL, (reflected / len(u), F)


def test_dielectric_refracts_by_snell():
    a = math.radians(40.0)
    wo = (math.sin(a), 0.0, math.cos(a))
    wi, through, F = bsdf.sample_dielectric(wo, (0.0, 0.0, 1.0), 1 / 1.5, 0.999)
    assert through and wi[2] < 0.0
    assert math.sin(a) == pytest.approx(1.5 * math.hypot(wi[0], wi[1]), abs=1e-12)
    assert wi[0] < 0.0  # on the other side of the normal from wo


@pytest.mark.parametrize("a, b", [(1.0, 0.0), (0.3, 2.5), (4.0, 4.0), (1e-300, 2.0), (7.0, 1e-300), (1e150, 3e150)])
def test_power_heuristic_over_is_the_weight_over_the_pdf(a, b):
    """The light sample's MIS factor in one division: the power heuristic divided by its own pdf, a / (a² + b²),
    against the exact rational value (where a² underflows it is still right, as the heuristic then is not)."""
    from fractions import Fraction

    exact = float(Fraction(a) / (Fraction(a) ** 2 + Fraction(b) ** 2))
    assert bsdf.power_heuristic_over(a, b) == pytest.approx(exact, rel=1e-15, abs=0.0)
    if a * a + b * b > 1e-290:
        assert bsdf.power_heuristic_over(a, b) == pytest.approx(bsdf.power_heuristic(a, b) / a, rel=1e-15)


# -------------------------------------------------------------------------------------------------- emitters


def _views(sa):
    """The traversal, surface and lighting views, built in Python (a view made inside a jitted caller that keeps
    Numba's reference counting would be released by it although the view function did not count it)."""
    return geometry_of(sa), surfaces_of(sa), lighting_of(sa)


@numba.njit(cache=True)
def _emitter_batch(em, geo, surf, lit, p, u, check_visible):
    """`sample_emitter` from point p for each row of u (m, 3); directions whose sampled point is not the first
    surface along them (the far side of a solid) come back as NaN (failed, as their shadow ray would be)."""
    stack = np.empty(64, np.int64)
    stack_t = np.empty(64)
    m = u.shape[0]
    dirs = np.full((m, 3), np.nan)
    for i in range(m):
        wi, dist, led, les, pdf, delta = sample_emitter(em, lit, surf, p, NO_NORMAL, u[i, 0], u[i, 1], u[i, 2], 0.0)
        if not pdf > 0.0:
            continue
        if check_visible:
            hit = closest_hit(geo, p, wi, 0.0, 1e30, stack, stack_t, 0.0)
            if hit[0] < 0.0 or abs(hit[0] - dist) > 1e-7 * max(dist, 1.0):
                continue
        dirs[i, 0], dirs[i, 1], dirs[i, 2] = wi
    return dirs


@numba.njit(cache=True)
def _emitter_pdfs(em, geo, surf, lit, p, dirs):
    """The MIS pdf `emitter_pdf` of each direction: of the emitter entry first hit along it, 0 if none."""
    stack = np.empty(64, np.int64)
    stack_t = np.empty(64)
    out = np.zeros(dirs.shape[0])
    for i in range(dirs.shape[0]):
        d = (dirs[i, 0], dirs[i, 1], dirs[i, 2])
        hit = closest_hit(geo, p, d, 0.0, 1e30, stack, stack_t, 0.0)
        if hit[0] < 0.0:
            continue
        ref = hit[1]
        q, n_geo, n_sh, uu, vv, mat, obj, light = surface_at(surf, p, d, hit[0], ref, hit[2], hit[3], hit[4], 0.0)
        if light >= 0:
            e = em.light_emit[light]
            if n_geo[0] * d[0] + n_geo[1] * d[1] + n_geo[2] * d[2] >= 0.0 and lit.light_kind[light] != LIGHT_SPHERE:
                continue  # the back of a one-sided light: never sampled
        elif ref >= 0:
            e = em.tri_emit[ref]
        else:
            e = em.shape_emit[~ref]
        if e >= 0:
            out[i] = emitter_pdf(em, lit, surf, e, p, NO_NORMAL, d, hit[0], n_geo, ref, hit[4], 0.0)
    return out


def _emitter_chi2(scene_objects, lights=(), p=(0.0, 0.0, 0.0), seed=0):
    scene = lumos.load_scene({"objects": list(scene_objects), "lights": list(lights)})
    compiled = compile_for(scene, scene.render.model_copy(update={"method": "path"}))
    em, sa = compiled.emitters, compiled.arrays
    rng = np.random.default_rng(seed)
    u_pick = rng.random(200_000)

    def sample(u2):
        return _emitter_batch(em, *_views(sa), p, np.column_stack([u_pick[: len(u2)], u2]), True)

    def pdf(dirs):
        return _emitter_pdfs(em, *_views(sa), p, np.ascontiguousarray(dirs))

    return chi2_directions(sample, pdf, n_samples=len(u_pick), res=(48, 96), seed=seed)


EMISSIVE = {"kd": 0.0, "emission": 1.0}

EMITTER_CASES = {
    "rect light": ([], [{"type": "area", "shape": "rect", "corner": [-1, 0.6, -0.5], "edge_u": [2, 0, 0],
                         "edge_v": [0, 0.3, 1.2], "radiance": 1.0}]),
    "disk light": ([], [{"type": "area", "shape": "disk", "center": [0.3, -0.8, 0.2], "normal": [0.2, 1, 0.1],
                         "radius": 0.9, "radiance": 2.0}]),
    "sphere light": ([], [{"type": "area", "shape": "sphere", "center": [0.5, 0.6, -0.7], "radius": 0.6,
                           "radiance": 1.0}]),
    "emissive triangle": ([{"type": "triangle", "vertices": [[-1, -0.5, 0.8], [1.2, -0.4, 1.0], [0.1, 1.2, 0.7]],
                            "material": EMISSIVE}], []),
    "emissive sphere": ([{"type": "sphere", "center": [0.2, 0.9, 0.6], "radius": 0.5, "material": EMISSIVE}], []),
    "emissive ellipsoid": ([{"type": "sphere", "radius": 1.0, "material": EMISSIVE,
                             "transform": {"scale": [0.9, 0.4, 0.6], "rotate": [30, 40, 0],
                                           "translate": [0.3, 0.2, 1.3]}}], []),
    "emissive box": ([{"type": "box", "min": [-0.5, -0.3, 0.8], "max": [0.6, 0.4, 1.5], "material": EMISSIVE,
                       "transform": {"rotate": [20, 35, 10], "scale": [1.2, 0.8, 1.0]}}], []),
    "emissive cylinder": ([{"type": "cylinder", "base": [-0.6, -0.5, 1.0], "top": [0.5, 0.6, 1.2], "radius": 0.4,
                            "material": EMISSIVE, "transform": {"scale": [1.0, 1.5, 0.8]}}], []),
    "emissive cone": ([{"type": "cone", "base": [0.5, -0.6, -1.0], "top": [-0.4, 0.5, -1.1], "radius": 0.5,
                        "material": EMISSIVE}], []),
    "emissive disk": ([{"type": "disk", "center": [0.0, -0.9, 0.1], "normal": [0.3, 1, 0], "radius": 0.8,
                        "material": EMISSIVE}], []),
    "emissive rect": ([{"type": "rect", "corner": [-0.8, -0.6, 0.9], "edge_u": [1.5, 0.2, 0.3],
                        "edge_v": [0.1, 1.2, -0.4], "material": EMISSIVE}], []),
    "several lights by power": (
        [{"type": "sphere", "center": [0.2, 0.9, 0.6], "radius": 0.4, "material": {"emission": 3.0}}],
        [{"type": "area", "shape": "rect", "corner": [-1, -0.7, -0.6], "edge_u": [0, 0, 1.5], "edge_v": [1.6, 0, 0],
          "radiance": 0.5},
         {"type": "area", "shape": "sphere", "center": [-0.8, 0.2, -0.6], "radius": 0.3, "radiance": 4.0}]),
}


@pytest.mark.parametrize("case", list(EMITTER_CASES))
def test_emitter_sampling_follows_its_pdf(case):
    objects, lights = EMITTER_CASES[case]
    result = _emitter_chi2(objects, lights)
    assert result.p_value > LEVEL, result.message
    assert result.pdf_integral > 0.05  # the case tests something: the emitter is seen from p


def test_a_wrong_emitter_pdf_is_detected():
    """The same test, given a pdf that is off by 10% on part of the sphere, fails."""
    objects = EMITTER_CASES["emissive sphere"][0]
    scene = lumos.load_scene({"objects": objects})
    compiled = compile_for(scene, scene.render.model_copy(update={"method": "path"}))
    em, sa = compiled.emitters, compiled.arrays
    u_pick = np.random.default_rng(0).random(200_000)

    def sample(u2):
        return _emitter_batch(em, *_views(sa), (0.0, 0.0, 0.0), np.column_stack([u_pick, u2]), True)

    def pdf(dirs):
        dirs = np.ascontiguousarray(dirs)
        return _emitter_pdfs(em, *_views(sa), (0.0, 0.0, 0.0), dirs) * np.where(dirs[:, 0] > 0.2, 1.1, 1.0)

    assert chi2_directions(sample, pdf, n_samples=len(u_pick), res=(48, 96)).p_value < 1e-6


def test_emitters_are_picked_by_power():
    """Selection probabilities are proportional to π·Le·A (area lights, emissive primitives)."""
    scene = lumos.load_scene({
        "objects": [{"type": "mesh", "vertices": [[0, 0, 0], [2, 0, 0], [0, 1, 0], [2, 1, 0]],
                     "faces": [[0, 1, 2], [1, 3, 2]], "material": {"emission": 2.0}}],
        "lights": [{"type": "area", "shape": "rect", "corner": [0, 2, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1],
                    "radiance": 1.0},
                   {"type": "area", "shape": "sphere", "center": [0, 5, 0], "radius": 0.5, "radiance": 3.0}]})
    compiled = compile_for(scene, scene.render.model_copy(update={"method": "path"}))
    em = compiled.emitters
    power = {"rect": 1.0 * 1.0, "sphere": 3.0 * 4 * math.pi * 0.25, "tri": 2.0 * 1.0}
    total = power["rect"] + power["sphere"] + 2 * power["tri"]
    np.testing.assert_allclose(em.emit_pmf[em.light_emit], [power["rect"] / total, power["sphere"] / total])
    tri = em.tri_emit[em.tri_emit >= 0]
    np.testing.assert_allclose(em.emit_pmf[tri], power["tri"] / total)
    assert em.emit_cdf[-1] == 1.0 and np.all(np.diff(em.emit_cdf) >= 0)
