"""Samplers against their densities (χ² tests, Mitsuba style) and their stratification.

`concentric_disk` must be uniform over the unit disk; `stratified_2d` must put exactly one point in each stratum;
`sample_light` must draw sphere-light directions uniformly in the subtended cone and rect/disk light points
uniformly over the emitter, with the documented weights.
"""

import math

import numpy as np
import pytest
from conftest import compile_dict
from naive import chi2_uniform, unit

from lumos.kernels.illumination import sample_light
from lumos.kernels.views import lighting_of
from lumos.kernels.sampling import concentric_disk, stratified_2d, turn

P_MIN = 1e-3  # significance level of every χ² test here (the seeds are fixed, so the outcome is too)


def _disk_bins(x, y, rings=8, sectors=12):
    """Counts over equal-area cells of the unit disk: rings of equal area (r² in equal steps) × sectors."""
    r2 = x * x + y * y
    ring = np.minimum((r2 * rings).astype(int), rings - 1)
    sector = np.minimum(((np.arctan2(y, x) + math.pi) / (2 * math.pi) * sectors).astype(int), sectors - 1)
    return np.bincount(ring * sectors + sector, minlength=rings * sectors)


def test_turn_is_the_cosine_and_sine_of_a_whole_turn(rng):
    """turn(u) replaces math.cos/sin(2πu) in the samplers: it must agree with them everywhere in [0, 1), at the
    quarter-turn boundaries where it changes quadrant above all, and stay on the unit circle."""
    u = np.concatenate([np.linspace(0.0, 1.0, 40001)[:-1], rng.random(20000),
                        [k / 8 + e for k in range(8) for e in (-1e-12, 0.0, 1e-12) if 0.0 <= k / 8 + e < 1.0],
                        [1.0 - 2.0**-53]])
    got = np.array([turn(x) for x in u])
    want = np.stack([np.cos(2 * np.pi * u), np.sin(2 * np.pi * u)], axis=1)
    assert np.abs(got - want).max() < 3e-14
    assert np.abs(np.hypot(got[:, 0], got[:, 1]) - 1.0).max() < 3e-14


def test_concentric_disk_is_uniform(rng):
    u = rng.random((40000, 2))
    xy = np.array([concentric_disk(a, b) for a, b in u])
    assert (np.hypot(xy[:, 0], xy[:, 1]) <= 1.0 + 1e-12).all()
    stat, p = chi2_uniform(_disk_bins(xy[:, 0], xy[:, 1]))
    assert p > P_MIN, stat


def test_disk_chi2_rejects_a_nonuniform_mapping(rng):
    # the classic mistake r = u1 (instead of sqrt(u1)) crowds the centre: the same test must reject it
    u = rng.random((40000, 2))
    r, phi = u[:, 0], 2 * math.pi * u[:, 1]
    assert chi2_uniform(_disk_bins(r * np.cos(phi), r * np.sin(phi)))[1] < 1e-9


@pytest.mark.nojit
def test_concentric_disk_maps_square_boundary_to_circle():
    # the corners and edge midpoints of [0,1]^2 land on the unit circle; the centre on the origin
    for a, b in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.5, 1.0), (1.0, 0.5), (0.5, 0.0), (0.0, 0.5)]:
        x, y = concentric_disk(a, b)
        assert math.hypot(x, y) == pytest.approx(1.0, abs=1e-12)
    assert concentric_disk(0.5, 0.5) == (0.0, 0.0)


@pytest.mark.parametrize("n", [1, 4, 9, 16, 64])
@pytest.mark.nojit
def test_stratified_square_one_point_per_cell(n, rng):
    m = math.isqrt(n)
    cells = set()
    for s in range(n):
        x, y = stratified_2d(s, n, *rng.random(2))
        assert 0.0 <= x < 1.0 and 0.0 <= y < 1.0
        cells.add((int(x * m), int(y * m)))
    assert len(cells) == n


@pytest.mark.parametrize("n", [2, 3, 5, 12, 50, 2 * 7919])
def test_stratified_non_square_is_a_latin_hypercube(n, rng):
    r = rng.random((n, 2))
    pts = np.array([stratified_2d(s, n, r[s, 0], r[s, 1]) for s in range(n)])
    assert ((pts >= 0.0) & (pts < 1.0)).all()
    # one point in each of the n strata along u, and (the scrambled order) one in each along v
    assert len(np.unique((pts[:, 0] * n).astype(int))) == n
    assert len(np.unique((pts[:, 1] * n).astype(int))) == n


def _light_samples(scene, p, u):
    arrays = compile_dict(scene).arrays
    p = tuple(float(x) for x in p)
    out = [sample_light(lighting_of(arrays), 0, p, float(a), float(b)) for a, b in u]
    L = np.array([s[0] for s in out])
    dist = np.array([s[1] for s in out])
    w = np.array([s[2] for s in out])
    return L, dist, w


def test_sphere_light_directions_uniform_in_cone(rng):
    center, radius = np.array([0.3, -0.2, 0.5]), 0.8
    p = np.array([1.0, 2.0, 3.5])
    scene = {"lights": [{"type": "area", "shape": "sphere", "center": center.tolist(), "radius": radius}]}
    L, dist, w = _light_samples(scene, p, rng.random((20000, 2)))
    to = center - p
    dc = np.linalg.norm(to)
    axis = to / dc
    cos_max = math.sqrt(1.0 - (radius / dc) ** 2)
    assert np.allclose(np.linalg.norm(L, axis=1), 1.0, atol=1e-12)
    cos_t = L @ axis
    assert (cos_t >= cos_max - 1e-12).all()
    # every sampled direction meets the sphere, at the returned distance (the near side)
    y = p + dist[:, None] * L
    assert np.allclose(np.linalg.norm(y - center, axis=1), radius, rtol=1e-6)
    assert (dist <= dc).all()
    # weight = solid angle / π for every sample
    assert np.allclose(w, 2.0 * math.pi * (1.0 - cos_max) / math.pi, rtol=1e-12)
    # uniform in solid angle: cos θ uniform on [cos θmax, 1] and azimuth uniform, jointly
    a = np.minimum(((1.0 - cos_t) / (1.0 - cos_max) * 10).astype(int), 9)
    t1 = unit(np.cross(axis, [1.0, 0.0, 0.0]))
    t2 = np.cross(axis, t1)
    phi = np.arctan2(L @ t2, L @ t1)
    b = np.minimum(((phi + math.pi) / (2 * math.pi) * 10).astype(int), 9)
    stat, pval = chi2_uniform(np.bincount(a * 10 + b, minlength=100))
    assert pval > P_MIN, stat
    stat, pval = chi2_uniform(np.histogram(cos_t, bins=20, range=(cos_max, 1.0))[0])
    assert pval > P_MIN, stat


def test_rect_light_points_uniform_and_weighted(rng):
    corner, eu, ev = np.array([-1.0, 2.0, 0.5]), np.array([2.0, 0.0, 0.0]), np.array([0.0, 0.5, -1.5])
    normal = unit(np.cross(eu, ev))
    scene = {"lights": [{"type": "area", "shape": "rect", "corner": corner.tolist(), "edge_u": eu.tolist(),
                         "edge_v": ev.tolist()}]}
    p = corner + 0.3 * eu + 0.6 * ev + 2.0 * normal + np.array([0.2, 0.1, 0.0])
    L, dist, w = _light_samples(scene, p, rng.random((10000, 2)))
    y = p + dist[:, None] * L
    q = y - corner
    a, b = np.linalg.solve(np.array([[eu @ eu, eu @ ev], [eu @ ev, ev @ ev]]), np.stack([q @ eu, q @ ev]))
    assert np.allclose(q @ normal, 0.0, atol=1e-9)  # on the rect's plane
    assert (a > -1e-9).all() and (a < 1 + 1e-9).all() and (b > -1e-9).all() and (b < 1 + 1e-9).all()
    counts, _, _ = np.histogram2d(a, b, bins=8, range=[[0, 1], [0, 1]])
    assert chi2_uniform(counts)[1] > P_MIN
    # w = cosθ'·A/(π d²), θ' the angle at the light between its normal and the direction to p
    area = np.linalg.norm(np.cross(eu, ev))
    assert np.allclose(w, (-(L @ normal)) * area / (math.pi * dist**2), rtol=1e-9)


def test_disk_light_points_uniform(rng):
    center, normal, radius = np.array([0.5, 1.0, -0.5]), unit([1.0, 2.0, -0.5]), 0.7
    scene = {"lights": [{"type": "area", "shape": "disk", "center": center.tolist(), "normal": normal.tolist(),
                         "radius": radius}]}
    p = center + 3.0 * normal + np.array([0.3, 0.0, 0.4])
    L, dist, w = _light_samples(scene, p, rng.random((20000, 2)))
    q = p + dist[:, None] * L - center
    assert np.allclose(q @ normal, 0.0, atol=1e-9)
    assert (np.linalg.norm(q, axis=1) <= radius * (1 + 1e-9)).all()
    t1 = unit(np.cross(normal, [0.0, 0.0, 1.0]))
    t2 = np.cross(normal, t1)
    stat, pval = chi2_uniform(_disk_bins(q @ t1 / radius, q @ t2 / radius))
    assert pval > P_MIN, stat
    assert np.allclose(w, (-(L @ normal)) * math.pi * radius**2 / (math.pi * dist**2), rtol=1e-9)
