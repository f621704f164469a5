"""The tables a plastic's coat needs (`kernels.bsdf`, MODEL_PLASTIC): how much light its dielectric coat lets through
at each angle, and how much of the light under it the coat sends back down.

    t(μ) = ∫ (1 − F(wi·m))·G1(wt, m) over the normals m visible from wi (wi at cos θ = μ, from outside; wt the
           direction refracted into the coat, masked by the microfacets it heads for); 1 − F(μ) when smooth
    Fdr  = 2·mean_k R'(μk)·μk   over the table's μk, R'(μ) = ∫ F(wi·m)·G1(wr, m) over the visible normals the
           coat's directional reflectance from inside (index 1/η: total internal reflection; wr reflected)

as Mitsuba 3's `roughplastic` computes them (its eval_transmittance and eval_reflectance). Estimated with the lobe's own visible-normal samples on a stratified grid, so a
table is the same on every machine; Fdr is Mitsuba 3's `roughplastic` sum over the same 64 angles (for a smooth
coat, the integral itself, as its `plastic` has it).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..kernels.layout import MAT_COAT_SIZE

_GRID = 96  # stratified samples per side of the unit square, per angle


def _fresnel(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance, eta = n_incident/n_transmitted (as `kernels.bsdf.fresnel_dielectric`)."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    sin2_t = eta * eta * (1.0 - cos_i * cos_i)
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))


def _g1(w: np.ndarray, alpha: float) -> np.ndarray:
    t = alpha * alpha * (w[:, 0] ** 2 + w[:, 1] ** 2) / np.maximum(w[:, 2] ** 2, 1e-300)
    return 2.0 / (1.0 + np.sqrt(1.0 + t))


def _visible_normals(wo: np.ndarray, alpha: float, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """`kernels.microfacet.sample_visible_normal` for one wo and many (u1, u2), isotropic."""
    v = np.array([alpha * wo[0], alpha * wo[1], wo[2]])
    v /= np.linalg.norm(v)
    lensq = v[0] ** 2 + v[1] ** 2
    t1 = np.array([-v[1], v[0], 0.0]) / np.sqrt(lensq) if lensq > 0 else np.array([1.0, 0.0, 0.0])
    t2 = np.cross(v, t1)
    r = np.sqrt(u1)
    phi = 2.0 * np.pi * u2
    p1, p2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + v[2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
    p3 = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
    n = p1[:, None] * t1 + p2[:, None] * t2 + p3[:, None] * v
    m = np.column_stack([alpha * n[:, 0], alpha * n[:, 1], np.maximum(n[:, 2], 1e-9)])
    return m / np.linalg.norm(m, axis=1)[:, None]


def _reflectance(mu: float, alpha: float, eta: float) -> float:
    """R(μ) of the coat seen from the side where light arrives in a medium eta times less dense (eta =
    n_incident/n_transmitted)."""
    if alpha == 0.0:
        return float(_fresnel(np.array([mu]), eta)[0])
    wo = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    g = (np.arange(_GRID) + 0.5) / _GRID
    u1, u2 = (a.ravel() for a in np.meshgrid(g, g))
    h = _visible_normals(wo, alpha, u1, u2)
    o_h = h @ wo
    wi = 2.0 * o_h[:, None] * h - wo
    up = wi[:, 2] > 0.0
    weight = np.where(up, _fresnel(o_h, eta) * _g1(np.where(up[:, None], wi, wo), alpha), 0.0)
    return float(weight.mean())


def _transmittance(mu: float, alpha: float, eta: float) -> float:
    """t(μ): the share of the light arriving at cos θ = μ from outside that the coat of index η (inside over
    outside) lets into it: over the visible normals m, (1 − F(wi·m))·G1(wt, m), wt the refracted direction (what
    a rough coat refracts towards a masked microfacet is lost); 1 − F(μ) when smooth."""
    if alpha == 0.0:
        return float(1.0 - _fresnel(np.array([mu]), 1.0 / eta)[0])
    wi = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    g = (np.arange(_GRID) + 0.5) / _GRID
    u1, u2 = (a.ravel() for a in np.meshgrid(g, g))
    m = _visible_normals(wi, alpha, u1, u2)
    c = m @ wi
    f = _fresnel(c, 1.0 / eta)
    sin2_t = (1.0 - c * c) / (eta * eta)
    cos_t = -np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    wt = m * (c / eta + cos_t)[:, None] - wi / eta  # refracted into the coat (Snell, η_t/η_i = η)
    below = wt[:, 2] < 0.0
    masked = np.where(below, _g1(np.where(below[:, None], wt, -wi), alpha), 0.0)
    masked = np.where((wt @ np.array([0.0, 0.0, 1.0])) * np.sum(wt * m, axis=1) > 0.0, masked, 0.0)
    return float(np.mean((1.0 - f) * masked))


@lru_cache(maxsize=64)
def coat_tables(alpha: float, eta: float) -> tuple[np.ndarray, float]:
    """(t at μ = i/(MAT_COAT_SIZE − 1), Fdr) of a coat of GGX width α and index η (inside over outside)."""
    mus = np.maximum(np.arange(MAT_COAT_SIZE) / (MAT_COAT_SIZE - 1), 1e-6)
    t = np.array([_transmittance(mu, alpha, eta) for mu in mus])
    if alpha == 0.0:  # the smooth coat: 2∫ F(μ)·μ dμ from inside, by a fine midpoint rule
        mu = (np.arange(20000) + 0.5) / 20000
        fdr = float(2.0 * np.mean(_fresnel(mu, eta) * mu))
    else:
        fdr = float(2.0 * np.mean([_reflectance(mu, alpha, eta) * mu for mu in mus]))
    return t, fdr
