"""The χ² harness of tests/chi2.py against NumPy samplers whose densities are known.

Each sampler takes u (n, 2) uniform in [0,1)² and returns unit directions (n, 3); each pdf takes directions (m, 3)
and returns densities per steradian (m,). Right pdfs must pass at the corrected level; wrong ones must fail with a
tiny p-value for every seed tried.
"""

import math

import numpy as np
import pytest
from chi2 import chi2_directions, chi2_discrete, frame_z, significance_level

N_TESTS = 5  # χ² tests of right samplers in this file, for the multiple-test correction
SEEDS = [0, 1, 2, 3]
AXIS = np.array([1.0, -2.0, 2.0]) / 3.0  # tilted, so lobes and cone edges cut across many (cos θ, φ) bins
FRAME = frame_z(AXIS)


def _around(frame, cos, phi):
    """Directions (n, 3) at polar cosine `cos` (n,) and azimuth `phi` (n,) in `frame` (3, 3)."""
    sin = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
    x, y = sin * np.cos(phi), sin * np.sin(phi)
    return x[:, None] * frame[:, 0] + y[:, None] * frame[:, 1] + cos[:, None] * frame[:, 2]  # no BLAS threads


def _cos_to_axis(d):
    """cos α of directions d (m, 3) to AXIS: (m,)."""
    return d[:, 0] * AXIS[0] + d[:, 1] * AXIS[1] + d[:, 2] * AXIS[2]


def uniform_sphere(u):
    return _around(np.eye(3), 1.0 - 2.0 * u[:, 0], 2 * math.pi * u[:, 1])


def cosine_hemisphere(u):
    return _around(np.eye(3), np.sqrt(1.0 - u[:, 0]), 2 * math.pi * u[:, 1])


def phong(n):
    """Sampler of the lobe cos^n α about AXIS (cos α = u^(1/(n+1)))."""
    return lambda u: _around(FRAME, u[:, 0] ** (1.0 / (n + 1)), 2 * math.pi * u[:, 1])


def phong_pdf(n):
    return lambda d: (n + 1) / (2 * math.pi) * np.maximum(_cos_to_axis(d), 0.0) ** n


COS_CONE = math.cos(math.radians(20.0))


def cone(u):
    return _around(FRAME, 1.0 - u[:, 0] * (1.0 - COS_CONE), 2 * math.pi * u[:, 1])


def cone_pdf(d):
    return np.where(_cos_to_axis(d) >= COS_CONE, 1.0 / (2 * math.pi * (1.0 - COS_CONE)), 0.0)


def test_uniform_sphere_passes():
    r = chi2_directions(uniform_sphere, lambda d: np.full(len(d), 1 / (4 * math.pi)))
    assert r.passed(0.01, N_TESTS), r.message
    assert abs(r.pdf_integral - 1.0) < 1e-9 and r.observed.sum() == 200_000
    assert r.observed.shape == r.expected.shape == (32, 64) and r.dof > 1000


def test_cosine_hemisphere_passes_against_cos_over_pi():
    r = chi2_directions(cosine_hemisphere, lambda d: np.maximum(d[:, 2], 0.0) / math.pi, sphere=False)
    assert r.passed(0.01, N_TESTS), r.message
    assert abs(r.pdf_integral - 1.0) < 1e-9


@pytest.mark.parametrize("seed", SEEDS)
def test_cosine_hemisphere_fails_against_uniform_hemisphere(seed):
    r = chi2_directions(cosine_hemisphere, lambda d: np.full(len(d), 1 / (2 * math.pi)), sphere=False, seed=seed)
    assert r.p_value < 1e-12, r.message


def test_phong_lobe_passes():
    r = chi2_directions(phong(20), phong_pdf(20))
    assert r.passed(0.01, N_TESTS), r.message
    assert abs(r.pdf_integral - 1.0) < 1e-6


@pytest.mark.parametrize("seed", SEEDS)
def test_phong_lobe_fails_with_the_wrong_exponent(seed):
    r = chi2_directions(phong(20), phong_pdf(15), seed=seed)
    assert r.p_value < 1e-12, r.message


def test_cone_passes_despite_its_sharp_edge():
    r = chi2_directions(cone, cone_pdf)
    assert r.passed(0.01, N_TESTS), r.message
    assert abs(r.pdf_integral - 1.0) < 2e-5  # the edge bins are integrated to ≪ 1 sample in total


@pytest.mark.parametrize("seed", SEEDS)
def test_cone_fails_when_too_wide_or_too_narrow(seed):
    # sampler 20°, pdf of a 21° cone: the samples miss the outer ring; pdf of 19°: samples land where pdf = 0
    for deg in (21.0, 19.0):
        c = math.cos(math.radians(deg))
        r = chi2_directions(cone, lambda d: np.where(_cos_to_axis(d) >= c, 1 / (2 * math.pi * (1 - c)), 0.0), seed=seed)
        assert r.p_value < 1e-12, r.message


def _cone_sometimes_failing(u):
    d = cone(u)
    d[np.random.default_rng(99).random(len(u)) < 0.3] = np.nan  # 30% fail, independently of the direction
    return d


def test_failure_mass_counts_against_the_pdf_integral():
    ok = chi2_directions(_cone_sometimes_failing, lambda d: 0.7 * cone_pdf(d))  # pdf scaled by the success rate
    assert ok.passed(0.01, N_TESTS), ok.message
    assert abs(ok.pdf_integral - 0.7) < 2e-5 and abs(ok.observed_outside - 60_000) < 1000
    bad = chi2_directions(_cone_sometimes_failing, cone_pdf)  # pdf not scaled: the failures are unexpected
    assert bad.p_value == 0.0, bad.message


@pytest.mark.parametrize("seed", SEEDS)
def test_discrete_fair_and_biased_coin(seed):
    rng = np.random.default_rng(seed)
    f = 0.3  # e.g. a Fresnel reflectance: reflect with probability F, refract with 1 − F
    fair = np.bincount((rng.random(100_000) >= f).astype(int), minlength=2)
    biased = np.bincount((rng.random(100_000) >= f + 0.01).astype(int), minlength=2)
    assert chi2_discrete(fair, [f, 1 - f]) > significance_level(0.01, len(SEEDS))
    assert chi2_discrete(biased, [f, 1 - f]) < 1e-4  # a 1% bias is 6.9 σ at n = 1e5
    assert chi2_discrete([10, 0], [1.0, 0.0]) == 1.0  # a single possible outcome (F = 1) is no evidence against
    assert chi2_discrete([9, 1], [1.0, 0.0]) == 0.0  # an impossible outcome happened
