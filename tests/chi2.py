"""χ² goodness-of-fit tests for direction samplers, in the manner of Mitsuba 3's `ChiSquareTest`.

A sampler maps uniform points u ∈ [0,1)² to unit directions; its claimed density is a pdf per steradian. The test
draws `n_samples` directions, bins them over the sphere (or the upper hemisphere of a frame) in equal steps of
cos θ and φ, integrates the pdf numerically over every bin to get the expected counts, pools the bins whose
expected count is small, and runs Pearson's χ² test. One extra cell, "outside", holds the samples that are not in
the domain (failed samples: rows of NaN or zeros; in hemisphere mode also directions with z < 0), and is expected
to receive n_samples × (1 − ∫ pdf) of them, so a sampler that fails some of the time passes when its pdf is
scaled down by its success rate.

NumPy and SciPy only: this module knows nothing about lumos or Numba. Use it from tests as
`from chi2 import chi2_directions, chi2_discrete` (tests/ is on sys.path).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import stats

__all__ = ["Chi2Result", "chi2_directions", "chi2_discrete", "pooled_chi2", "significance_level", "frame_z"]


def significance_level(alpha: float = 0.01, n_tests: int = 1) -> float:
    """Per-test level at which `n_tests` independent tests of right samplers all pass with probability 1 − alpha
    (Šidák, as Mitsuba does; ≈ alpha / n_tests)."""
    return 1.0 - (1.0 - alpha) ** (1.0 / n_tests)


def frame_z(normal) -> np.ndarray:
    """3×3 orthonormal frame whose columns are (tangent, bitangent, normal), with the normal along `normal` (3,)."""
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t = np.cross(a, n)
    t /= np.linalg.norm(t)
    return np.column_stack([t, np.cross(n, t), n])


@dataclasses.dataclass
class Chi2Result:
    """Outcome of `chi2_directions`. `observed` and `expected` are (res[0], res[1]) arrays indexed [cos θ bin, φ bin]
    (cos θ increasing from −1, or 0 in hemisphere mode, to 1; φ from 0 to 2π)."""

    p_value: float
    statistic: float
    dof: int
    observed: np.ndarray  # (res0, res1) int64 counts of samples per bin
    expected: np.ndarray  # (res0, res1) float64 n_samples × ∫_bin pdf dω
    observed_outside: int  # failed samples (+ below-horizon ones in hemisphere mode)
    expected_outside: float  # n_samples × max(0, 1 − pdf_integral)
    pdf_integral: float  # ∫_domain pdf dω (≈ 1, or ≈ the success rate)
    message: str

    def passed(self, alpha: float = 0.01, n_tests: int = 1) -> bool:
        """True when p exceeds the level `significance_level(alpha, n_tests)`."""
        return bool(self.p_value > significance_level(alpha, n_tests))

    def __str__(self) -> str:
        return self.message


def pooled_chi2(observed, expected, min_expected: float = 5.0):
    """Pearson's χ² over cells, pooling small ones as Mitsuba does.

    observed (k,) counts and expected (k,) counts (same total, or the test is meaningless). Cells with expected 0
    and observed 0 are dropped; cells are sorted by expected count and those below `min_expected` are merged, in
    that order, into pooled cells of at least `min_expected` (a remainder joins the last pool, or the smallest
    big cell). Returns (statistic, dof, n_pooled_in, n_pooled_out, n_impossible); n_impossible counts cells that
    expect nothing but got samples, which rejects outright (statistic = inf)."""
    o = np.asarray(observed, np.float64).ravel()
    e = np.asarray(expected, np.float64).ravel()
    impossible = int(np.count_nonzero((e <= 0) & (o > 0)))
    keep = e > 0
    order = np.argsort(e[keep], kind="stable")
    o, e = o[keep][order], e[keep][order]
    n_small = int(np.searchsorted(e, min_expected))
    pools_o, pools_e = [], []
    po = pe = 0.0
    for oi, ei in zip(o[:n_small], e[:n_small]):
        po += oi
        pe += ei
        if pe >= min_expected:
            pools_o.append(po)
            pools_e.append(pe)
            po = pe = 0.0
    big_o, big_e = o[n_small:].copy(), e[n_small:].copy()
    if pe > 0:
        if pools_o:
            pools_o[-1] += po
            pools_e[-1] += pe
        elif len(big_o):
            big_o[0] += po
            big_e[0] += pe
        else:
            pools_o, pools_e = [po], [pe]
    cells_o = np.concatenate([pools_o, big_o])
    cells_e = np.concatenate([pools_e, big_e])
    stat = math.inf if impossible else float(np.sum((cells_o - cells_e) ** 2 / cells_e))
    return stat, len(cells_o) - 1, n_small, len(pools_o), impossible


def chi2_discrete(observed_counts, expected_probabilities, min_expected: float = 5.0) -> float:
    """p-value of the counts `observed_counts` (k,) of k outcomes against their probabilities (k,) (normalised
    here), e.g. k = 2 for a dielectric's reflect / refract choice with probabilities (F, 1 − F). Counts in an
    outcome of probability 0 give 0; a single possible outcome (total internal reflection: F = 1) gives 1."""
    o = np.asarray(observed_counts, np.float64)
    p = np.asarray(expected_probabilities, np.float64)
    stat, dof, _, _, impossible = pooled_chi2(o, o.sum() * p / p.sum(), min_expected)
    if impossible:
        return 0.0
    return 1.0 if dof < 1 else float(stats.chi2.sf(stat, dof))


# --- quadrature of the pdf over (cos θ, φ) rectangles ---------------------------------------------------------


def _pdf_at(pdf, frame, c, cos_p, sin_p):
    """pdf at polar cosines `c` and azimuths of cosines `cos_p`, sines `sin_p` in `frame` (broadcast to shape S).
    (Rotations here are written out rather than `@`: a threaded BLAS makes (n, 3) @ (3, 3) several times slower.)"""
    sin = np.sqrt(np.maximum(0.0, 1.0 - c * c))
    c, cos_p, sin_p, sin = np.broadcast_arrays(c, cos_p, sin_p, sin)
    world = (sin * cos_p)[..., None] * frame[:, 0] + (sin * sin_p)[..., None] * frame[:, 1] + c[..., None] * frame[:, 2]
    f = np.asarray(pdf(world.reshape(-1, 3)), np.float64).reshape(c.shape)
    if not (np.isfinite(f).all() and (f >= 0).all()):
        raise ValueError("pdf returned negative or non-finite values")
    return f


def _rule(pdf, frame, rects, x01, w01, n_edge=4, chunk=1 << 20):
    """∫ pdf dω over rectangles `rects` (r, 4) = (c0, c1, φ0, φ1), with the tensor Gauss–Legendre rule of nodes
    `x01` (q,) and weights `w01` (q,) on [0, 1]. Also evaluates the pdf at n_edge + 1 points along each side
    (corners included), which neighbouring rectangles share, so that a rectangle cut by an edge of the pdf's
    support is noticed even when the cut misses every interior node. Returns (integrals (r,), edge (r,): the
    largest value seen × area where the values seen are partly zero and partly not, else 0)."""
    q = len(x01)
    out, edge = np.empty(len(rects)), np.empty(len(rects))
    t = np.linspace(0.0, 1.0, n_edge + 1)
    step = max(1, chunk // (q * q + 4 * len(t)))
    for s in range(0, len(rects), step):
        c0, c1, p0, p1 = (v[:, None] for v in rects[s : s + step].T)
        dc, dp = c1 - c0, p1 - p0
        c, p = c0 + dc * x01, p0 + dp * x01  # (r, q) nodes
        f = _pdf_at(pdf, frame, c[:, :, None], np.cos(p)[:, None, :], np.sin(p)[:, None, :])  # (r, q, q)
        zero, one = np.zeros_like(t), np.ones_like(t)
        cs = np.concatenate([zero, one, t, t]) * dc + c0  # (r, 4(n_edge+1)) points on the 4 sides
        ps = np.concatenate([t, t, zero, one]) * dp + p0
        g = np.concatenate([f.reshape(len(c0), -1), _pdf_at(pdf, frame, cs, np.cos(ps), np.sin(ps))], 1)
        area = (dc * dp)[:, 0]
        out[s : s + step] = area * np.einsum("rij,i,j->r", f, w01, w01)
        nz = g > 0
        edge[s : s + step] = np.where(nz.any(1) & ~nz.all(1), g.max(1) * area, 0.0)
    return out, edge


def _split(rects):
    """The 4 quarters of each rectangle: (r, 4) -> (4r, 4), quarters of rectangle i at rows 4i … 4i+3."""
    c0, c1, p0, p1 = rects.T
    cm, pm = 0.5 * (c0 + c1), 0.5 * (p0 + p1)
    q = np.stack(
        [np.stack(a, -1) for a in ((c0, cm, p0, pm), (c0, cm, pm, p1), (cm, c1, p0, pm), (cm, c1, pm, p1))], 1
    )
    return q.reshape(-1, 4)


def _integrate_bins(pdf, frame, rects, n_samples, order, quad_tol, max_depth, force_depth=0):
    """n_samples × ∫ pdf dω over each rectangle of `rects` (b, 4), adaptively. A rectangle at depth d (a piece
    2^-d × 2^-d of its bin) is split in 4 while, with tol = quad_tol × sqrt(expected count of its bin) / 2^d samples,
      its one-piece and four-piece rules differ by more than tol, or
      it is cut by a support edge and its largest pdf value × area exceeds tol (a jump the rule cannot resolve),
    up to depth max_depth, and always while d < force_depth. The four-piece rule is kept.
    Returns (expected (b,), number of rectangles still to refine at max_depth, the sum of their |four-piece −
    one-piece| differences in samples, a rough bound on the error left)."""
    x, w = np.polynomial.legendre.leggauss(order)
    x01, w01 = 0.5 * (x + 1.0), 0.5 * w
    coarse, edge = _rule(pdf, frame, rects, x01, w01)
    tol = quad_tol * np.sqrt(np.maximum(n_samples * coarse, 1.0)) / n_samples  # per bin, in probability
    expected = np.zeros(len(rects))
    owner = np.arange(len(rects))
    n_bad, bad_err = 0, 0.0
    for depth in range(max_depth + 1):
        kids = _split(rects)
        fine_k, edge_k = _rule(pdf, frame, kids, x01, w01)
        fine = fine_k.reshape(-1, 4).sum(1)
        diff = np.abs(fine - coarse)
        err = np.maximum(diff, np.maximum(edge, edge_k.reshape(-1, 4).max(1)))
        again = (err > tol[owner] / 2**depth) | (depth < force_depth)
        if depth == max_depth:
            n_bad, bad_err = int(np.count_nonzero(again)), float(diff[again].sum() * n_samples)
            again[:] = False
        np.add.at(expected, owner[~again], fine[~again])
        if not again.any():
            break
        sel = np.repeat(again, 4)
        rects, coarse, edge = kids[sel], fine_k[sel], edge_k[sel]
        owner = np.repeat(owner[again], 4)
    return n_samples * expected, n_bad, bad_err


# --- the test ----------------------------------------------------------------------------------------------------


def chi2_directions(
    sample,
    pdf,
    n_samples: int = 200_000,
    res=(32, 64),
    frame=None,
    sphere: bool = True,
    min_expected: float = 5.0,
    seed: int = 0,
    quad_order: int = 4,
    quad_tol: float = 0.05,
    max_depth: int = 6,
) -> Chi2Result:
    """χ² test that the directions `sample` draws follow the density `pdf` (in solid angle).

    sample(u (n, 2) float64 uniform in [0,1)²) -> dirs (n, 3) float64 unit vectors, rows of NaN or zeros meaning
        "no sample" (a tuple is accepted too: its first element is dirs, the rest is ignored).
    pdf(dirs (m, 3) float64 unit vectors) -> (m,) float64 density per steradian, 0 where the sampler never goes.
    frame: (3, 3) orthonormal, columns (tangent, bitangent, normal) (identity by default); θ is measured from the
        normal and φ from the tangent. sphere=False restricts the domain to the upper hemisphere of the frame.
    res: (bins of cos θ, bins of φ). u comes from numpy.random.default_rng(seed), so the outcome is deterministic.

    Expected counts: each bin's n_samples × ∫ pdf dω, with dω = d(cos θ) dφ, by a tensor Gauss–Legendre rule of
    `quad_order`² nodes per rectangle, refined adaptively (2 × 2 splits, at most `max_depth` levels) until the
    estimated error is below quad_tol × the bin's Poisson standard deviation; rectangles that a jump of the pdf
    (an edge of its support, where values fall to 0) crosses are refined to `max_depth` in practice. Bins
    expecting less than `min_expected` are pooled.
    """
    frame = np.eye(3) if frame is None else np.asarray(frame, np.float64)
    if not np.allclose(frame.T @ frame, np.eye(3), atol=1e-9):
        raise ValueError("frame must be orthonormal (columns tangent, bitangent, normal)")
    nc, nphi = int(res[0]), int(res[1])
    c_lo = -1.0 if sphere else 0.0
    c_edges = np.linspace(c_lo, 1.0, nc + 1)
    p_edges = np.linspace(0.0, 2 * math.pi, nphi + 1)

    # histogram of the samples
    u = np.random.default_rng(seed).random((n_samples, 2))
    dirs = sample(u)
    if isinstance(dirs, tuple):
        dirs = dirs[0]
    dirs = np.asarray(dirs, np.float64).reshape(n_samples, 3)
    norm = np.linalg.norm(dirs, axis=1)
    ok = np.isfinite(norm) & (norm > 0)
    n_failed = n_samples - int(np.count_nonzero(ok))
    n_not_unit = int(np.count_nonzero(ok & (np.abs(norm - 1.0) > 1e-4)))
    inside = dirs[ok]  # (k, 3) the directions that land in the domain
    local = inside[:, :1] * frame[0] + inside[:, 1:2] * frame[1] + inside[:, 2:] * frame[2]  # (k, 3) in the frame
    if not sphere:
        below = local[:, 2] < 0
        n_below = int(np.count_nonzero(below))
        inside, local = inside[~below], local[~below]
    else:
        n_below = 0
    cos = np.clip(local[:, 2] / np.linalg.norm(local, axis=1), -1.0, 1.0)
    phi = np.arctan2(local[:, 1], local[:, 0]) % (2 * math.pi)
    ic = np.clip(((cos - c_lo) / (1.0 - c_lo) * nc).astype(np.int64), 0, nc - 1)
    ip = np.clip((phi / (2 * math.pi) * nphi).astype(np.int64), 0, nphi - 1)
    bin_of = ic * nphi + ip  # (k,) flat bin index of each sample
    observed = np.bincount(bin_of, minlength=nc * nphi)
    observed_outside = n_failed + n_below

    # expected counts
    cg, pg = np.meshgrid(np.arange(nc), np.arange(nphi), indexing="ij")
    rects = np.stack([c_edges[cg], c_edges[cg + 1], p_edges[pg], p_edges[pg + 1]], -1).reshape(-1, 4)
    args = (pdf, frame, rects, n_samples, quad_order, quad_tol, max_depth)
    expected, n_bad, bad_err = _integrate_bins(*args)
    # a bin that got samples but expects none may hold a sliver of support missed by every node: look closer
    rescue = np.flatnonzero((expected <= 0) & (observed > 0))
    if len(rescue):
        expected[rescue] = _integrate_bins(pdf, frame, rects[rescue], *args[3:], force_depth=4)[0]
    pdf_integral = float(expected.sum() / n_samples)
    expected_outside = n_samples * max(0.0, 1.0 - pdf_integral)

    stat, dof, pooled_in, pooled_out, impossible = pooled_chi2(
        np.append(observed, observed_outside), np.append(expected, expected_outside), min_expected
    )
    p_value = 0.0 if (impossible or dof < 1 or n_not_unit) else float(stats.chi2.sf(stat, dof))

    lines = [
        f"χ² = {stat:.1f}, dof = {dof}, p = {p_value:.4g}",
        f"∫ pdf dω = {pdf_integral:.6f}; samples outside the domain: {observed_outside} of {n_samples} "
        f"({n_failed} failed{f', {n_below} below the horizon' if not sphere else ''}), "
        f"expected {expected_outside:.1f}",
        f"pooled {pooled_in} cells expecting < {min_expected:g} into {pooled_out}",
    ]
    if n_bad:
        lines.append(
            f"quadrature: {n_bad} rectangles reached depth {max_depth} unconverged or on a jump of the pdf; "
            f"Σ|4-piece − 1-piece| there = {bad_err:.2f} samples"
        )
    if n_not_unit:
        lines.append(f"FAIL: {n_not_unit} sampled directions are not unit vectors")
    zero = np.flatnonzero((expected <= 0) & (observed > 0))
    if len(zero):
        there = np.isin(bin_of, zero)
        n_pos = int(np.count_nonzero(np.asarray(pdf(inside[there]), np.float64) > 0))
        lines.append(
            f"FAIL: {int(observed[zero].sum())} samples in {len(zero)} bins where ∫ pdf = 0"
            + (f" (yet pdf > 0 at {n_pos} of them: a sliver the quadrature missed? raise max_depth)" if n_pos else "")
        )
    if observed_outside and expected_outside <= 0:
        lines.append(f"FAIL: {observed_outside} samples outside the domain but ∫ pdf dω ≥ 1")
    if dof < 1:
        lines.append("FAIL: fewer than 2 cells after pooling")
    # the worst bins, to point at where the sampler and the pdf disagree
    contrib = (observed - expected) ** 2 / np.maximum(expected, min_expected)
    for b in np.argsort(contrib)[::-1][:3]:
        i, j = divmod(int(b), nphi)
        lines.append(
            f"  bin cosθ∈[{c_edges[i]:.3f},{c_edges[i + 1]:.3f}] φ∈[{p_edges[j]:.3f},{p_edges[j + 1]:.3f}]: "
            f"observed {observed[b]}, expected {expected[b]:.1f}"
        )
    return Chi2Result(
        p_value=p_value,
        statistic=stat,
        dof=dof,
        observed=observed.reshape(nc, nphi),
        expected=expected.reshape(nc, nphi),
        observed_outside=observed_outside,
        expected_outside=expected_outside,
        pdf_integral=pdf_integral,
        message="\n".join(lines),
    )
