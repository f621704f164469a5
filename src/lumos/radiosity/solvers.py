"""The four radiosity solvers, one function each, over the same patches (`layout.PatchArrays`) and the same E.

    L_i = E_i + ρ_i · Σ_j F_ij · L̄_j       (per element i and channel; F_ij from element i to patch j)

Two levels (Cohen, Greenberg, Immel & Brock 1986, "An efficient radiosity approach for realistic image
synthesis"): **elements** receive and are drawn; **patches** shoot and are gathered from, each with the
area-weighted mean radiance L̄ of its elements. Unrefined, every patch is its own single element; adaptive
subdivision splits elements where the solution varies, and a refined patch still shoots and is gathered from
as one, so refining costs receivers, not shooters.

- **gauss_seidel** and **jacobi** (gathering): the whole matrix F first (ray-cast or hemicube form factors),
  then sweeps; Jacobi computes every patch from the previous iterate, Gauss–Seidel uses each new value at once
  (it converges about twice as fast). They stop when the distance left to the solution, estimated from the
  last two sweeps' largest changes (`remaining`), is below `tolerance` times the mean radiance of the surfaces. Only for scenes whose matrix fits in memory.
- **progressive** refinement (Cohen, Chen, Wallace & Greenberg 1988): shoot the unshot light of the patch with
  the most unshot power (ΔL·A) to every other patch, form factors computed on the fly and forgotten; stop when
  the unshot power is below `tolerance` of the power sent out. Until then the display adds Cohen's ambient term
  (the unshot power spread evenly, times 1/(1 − mean ρ)).
- **stochastic** (Monte Carlo) radiosity: stochastic Jacobi iterations (Neumann et al. 1995; Bekaert's
  RenderPark): each iteration sends the unshot power of every patch by random rays (as many as its share of
  the power), the surfaces they hit keep ρ of it as their next unshot power; its error falls as 1/√rays.
  The light still unshot when it stops is added as progressive refinement's ambient term.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..errors import LumosError
from ..kernels.threads import parallel_for

#: solver: auto takes progressive refinement up to this many patches, stochastic radiosity beyond.
AUTO_PROGRESSIVE_MAX = 20_000
#: Full-matrix solvers refuse scenes whose float32 matrix would take more than this share of free memory.
MATRIX_MEMORY_SHARE = 0.5
#: Progressive: a receiver whose share of a shot, unoccluded, would stay below this fraction of the scene's
#: brightest emitter receives it by Russian roulette (with probability share/threshold, weighted by the
#: inverse, and one shadow ray): unbiased, and dim shots of a finely meshed scene cost few rays (skipping them
#: outright would lose light: each is below any fixed threshold, not their sum).
SHOT_THRESHOLD = 1e-5
#: Progressive: patches shot together in one pass over the receivers (fewer passes, the same light), those
#: with at least this share of the brightest one's unshot power.
SHOT_BATCH = 16
SHOT_BATCH_SHARE = 0.5
#: Progressive: a shooter's form factors (what every receiver takes of its light) are kept, float32, for its next
#: shots, up to this many bytes in all: a bright closed scene shoots each patch many times (the furnace: about
#: ten), and recomputing the same column with its shadow rays each time made progressive refinement ten times
#: slower than building the whole matrix. A fixed budget, not the free memory: which columns are kept, and so
#: the image, must not depend on the machine.
SHOT_CACHE_BYTES = 512 << 20
#: Stochastic: chunks of rays (each with its own accumulation buffer, summed in order: thread-count
#: independence), and the rays per patch of an iteration unless `rays` is given.
STOCHASTIC_CHUNKS = 16
RAYS_PER_PATCH = 100


@dataclass
class Result:
    radiance: np.ndarray  # float64 (n_elements, 3)
    iterations: int
    residual: float  # unshot power / power sent (progressive, stochastic); the estimated distance left over the
    # mean radiance (gauss_seidel, jacobi)
    rays: int
    form_factor_s: float
    columns: object = None  # progressive ray-cast shots: their `Kept` columns, for the next level to inherit


@dataclass
class Level:
    """What the solvers work on: receiving elements and shooting patches, and the elements' BVH."""

    recv: object  # layout.PatchArrays of the elements
    src: object  # layout.PatchArrays of the patches
    recv_patch: np.ndarray  # int64 (n_elements,): the patch each element belongs to
    bvh: object  # CompiledScene of the elements' polygons (None where the occluders serve every ray)
    tri_poly: np.ndarray  # int32 (m,): the element polygon of each BVH triangle
    src_patches: object = None  # compile.patches.Patches of the patches (the hemicube renders their polygons)
    recv_patches: object = None  # and of the elements
    occluders: object = None  # CompiledScene of the surfaces that may block visibility (`solve.occluder_bvh`)
    inherited: np.ndarray | None = None  # int64 (n_elements,): an element's index at the previous level where it
    # is the same element (its polygon was not cut), else -1
    columns: object = None  # the previous level's `Result.columns` (`Kept`)

    def visibility_arrays(self):
        """The scene arrays the form factors' visibility rays traverse: the occluders where they are known."""
        return (self.bvh if self.occluders is None else self.occluders).arrays

    def patch_sums(self, values: np.ndarray) -> np.ndarray:
        """Σ A_i·values_i over each patch's elements i, for `values` (n_elements, 3): (n_patches, 3)."""
        n = len(self.src.area)
        return np.stack([np.bincount(self.recv_patch, self.recv.area * values[:, c], minlength=n)
                         for c in range(3)], axis=1)

    def patch_means(self, values: np.ndarray) -> np.ndarray:
        """The area-weighted mean of `values` (n_elements, 3) over each patch's elements: (n_patches, 3)."""
        return self.patch_sums(values) / self.src.area[:, None]


def _lum(x: np.ndarray) -> np.ndarray:
    return x.mean(axis=-1)


def chosen(rs, n: int) -> str:
    """The solver `rs.solver` names, with auto resolved for n patches."""
    if rs.solver != "auto":
        return rs.solver
    return "progressive" if n <= AUTO_PROGRESSIVE_MAX else "stochastic"


def run(rs, level: Level, sent, seed, progress=None, say=None) -> Result:
    """Solve with `rs.solver` for the elements' radiance, E = `sent` (n_elements, 3)."""
    rs = rs.model_copy(update={"solver": chosen(rs, len(level.src.area))})
    solver = {"gauss_seidel": gathering, "jacobi": gathering, "progressive": progressive,
              "stochastic": stochastic}[rs.solver]
    return solver(rs, level, sent, int(seed), progress, say)


# ------------------------------------------------------------------------------------------------ gathering


def matrix_limit() -> int:
    """The most patches whose float32 form-factor matrix fits in MATRIX_MEMORY_SHARE of the free memory."""
    from ..methods.common import available_memory

    avail = available_memory() or (8 << 30)
    return int(np.sqrt(MATRIX_MEMORY_SHARE * avail / 4))


def form_factor_matrix(rs, level: Level, seed) -> tuple[np.ndarray, int]:
    """F float32 (n_elements, n_patches) by the chosen method, and the rays it traced."""
    n, m = len(level.recv.area), len(level.src.area)
    limit = matrix_limit()
    if n * m > limit * limit:
        raise LumosError(f"radiosity.solver: {rs.solver} stores the {n:,}×{m:,} form-factor matrix "
                         f"({4 * n * m / 2**30:.1f} GiB), more than this machine can hold (at most about "
                         f"{limit:,} patches here); use solver: progressive or stochastic, which store no matrix")
    F = np.zeros((n, m), np.float32)
    if rs.form_factors == "hemicube":
        from .formfactors import hemicube_matrix

        hemicube_matrix(rs, level, seed, F)
        return F, 0
    from ..kernels.radiosity import ff_rows_raycast

    band = max(1, min(n, (1 << 20) // max(m, 1)))  # rows per kernel call: about a million form factors
    rays = 0
    occluders = level.visibility_arrays()
    for start in range(0, n, band):
        rows = np.arange(start, min(n, start + band), dtype=np.int64)
        counts = np.zeros(len(rows), np.int64)
        out = F[start:start + len(rows)]
        parallel_for(lambda r0, r1: ff_rows_raycast(occluders, level.recv, level.src, level.recv_patch, rows,
                                                    np.int64(rs.visibility_samples), np.int64(seed), out, counts,
                                                    np.int64(r0), np.int64(r1)), 0, len(rows))
        rays += int(counts.sum())
    return F, rays


def gathering(rs, level: Level, sent, seed, progress, say) -> Result:
    from ..kernels.radiosity import gauss_seidel_sweep, jacobi_sweep

    recv = level.recv
    t0 = time.perf_counter()
    F, rays = form_factor_matrix(rs, level, seed)
    ff_s = time.perf_counter() - t0
    radiance = sent.copy()
    means = level.patch_means(radiance)
    limit = rs.max_iterations or 1000
    change = previous = np.inf
    scale = 1.0
    left = np.inf
    it = 0
    nxt = np.empty_like(radiance)
    while it < limit:
        it += 1
        if rs.solver == "gauss_seidel":
            change = gauss_seidel_sweep(F, recv.rho, sent, recv.area, level.recv_patch, level.src.area, radiance,
                                        means)
        else:
            parallel_for(lambda r0, r1: jacobi_sweep(F, recv.rho, sent, means, nxt, np.int64(r0), np.int64(r1)), 0,
                         len(nxt))
            change = float(np.abs(nxt - radiance).mean(axis=1).max())
            radiance, nxt = nxt, radiance
            means = level.patch_means(radiance)
        # relative to the mean radiance of the surfaces (not to the brightest emitter, which would stop the
        # sweeps while the walls are still percents away)
        scale = max(float((_lum(radiance) * recv.area).sum() / recv.area.sum()), 1e-300)
        left = remaining(change, previous) / scale
        previous = change
        if say is not None:
            say(f"sweep {it}: largest change {change / scale:.2e} of the mean radiance, about {left:.2e} left")
        if progress is not None:
            progress(min(1.0, np.log(max(left, 1e-30)) / np.log(rs.tolerance)) if left > 0 else 1.0)
        if left <= rs.tolerance:
            break
    return Result(radiance, it, left, rays, ff_s)


def remaining(change: float, previous: float) -> float:
    """How far the iterate still is from the solution, from the last two sweeps' largest changes: the sweeps
    contract the error by about q = change/previous each, so what is left is about change·q/(1 − q) (a
    geometric series). A bright closed scene (the furnace, ρ = 0.8: q ≈ 0.8) is 4 changes away, not one."""
    if change == 0.0:
        return 0.0
    if not np.isfinite(previous) or previous <= 0.0:
        return np.inf
    q = min(change / previous, 0.999)
    return change * q / (1.0 - q)


# ---------------------------------------------------------------------------------------------- progressive


def progressive(rs, level: Level, sent, seed, progress, say) -> Result:
    """Shoot from the brightest unshot patches until the unshot power is below `tolerance` of the power sent."""
    recv, src = level.recv, level.src
    radiance = sent.copy()
    unshot_e = sent.copy()  # per element
    area = src.area
    total = float((_lum(sent) * recv.area).sum())
    threshold = SHOT_THRESHOLD * float(_lum(sent).max())
    limit = rs.max_iterations or 50 * len(area) + 100
    hemi = None
    if rs.form_factors == "hemicube":
        from .formfactors import HemicubeShooter

        hemi = HemicubeShooter(rs, level, seed, keep=SHOT_CACHE_BYTES // (4 * len(recv.area)))
    ff_s = 0.0
    gain = Gain()
    columns = Columns(rs, level, seed, threshold) if hemi is None else None
    patch_unshot = level.patch_sums(unshot_e)  # (n_patches, 3): Σ A_i·ΔL_i over each patch's elements
    order = np.argsort(level.recv_patch, kind="stable")  # the elements of patch j: order[starts[j]:starts[j + 1]]
    starts = np.searchsorted(level.recv_patch[order], np.arange(len(area) + 1))
    shots = 0
    residual = 1.0
    next_report = 0.0
    third = np.full(3, 1.0 / 3.0)
    while shots < limit:
        power = patch_unshot @ third  # the unshot power of each patch (its mean unshot radiance times its area)
        residual = float(power.sum()) / total
        if residual <= rs.tolerance:
            break
        # the brightest unshot patches, shot together: SHOT_BATCH of them, or fewer once they are dim (a batch
        # does not see its own members' light until the next one, so it holds only the near-brightest)
        m = min(SHOT_BATCH, len(area), limit - shots)
        top = np.argpartition(power, -m)[-m:] if m < len(area) else np.arange(len(area))
        top = top[np.argsort(-power[top], kind="stable")]
        top = top[power[top] >= SHOT_BATCH_SHARE * power[top[0]]].astype(np.int64)
        d = patch_unshot[top] / area[top, None]
        shot_power = d.T @ area[top]  # (3,): what the batch sends
        unshot_e[np.concatenate([order[starts[j]:starts[j + 1]] for j in top])] = 0.0
        patch_unshot[top] = 0.0
        t0 = time.perf_counter()
        if hemi is not None:
            after = patch_unshot.sum(axis=0)
            for q, j in enumerate(top):
                hemi.shoot(int(j), d[q], shots + q, radiance, unshot_e)
            patch_unshot = level.patch_sums(unshot_e)
            returned = patch_unshot.sum(axis=0) - after
        else:
            returned = columns.shoot(top, d, shots, radiance, unshot_e, patch_unshot)
        ff_s += time.perf_counter() - t0
        gain.add(shot_power, returned)
        shots += len(top)
        if progress is not None:
            progress(min(1.0, np.log(max(residual, 1e-30)) / np.log(rs.tolerance)))
        if say is not None and time.perf_counter() >= next_report:
            say(f"shot {shots}: unshot power {residual:.2%} of what was sent")
            next_report = time.perf_counter() + 1.0
    residual = float((_lum(unshot_e) * recv.area).sum()) / total
    radiance = radiance + ambient_term(recv, unshot_e, gain.value())
    if columns is None:
        return Result(radiance, shots, residual, 0, ff_s)
    return Result(radiance, shots, residual, columns.rays, ff_s, Kept(columns.kept, columns.slot))


@dataclass
class Kept:
    """A level's kept form factors, what the next level inherits (`Columns`): the float32 (n_elements, k) columns
    and the column of each shooter (-1: none). Only these arrays: a level's solver state goes with it."""

    kept: np.ndarray
    slot: np.ndarray


class Columns:
    """Progressive refinement's ray-cast shots: each shooter's form factors to every receiving element, F_ij
    for all i, traced at its first shot (`shoot_raycast`) and kept, float32, as a column of `kept` (up to
    SHOT_CACHE_BYTES in all) for its next shots, which `kernels.radiosity.deliver_shots` applies. At a refined
    level, the elements that are the previous level's (`Level.inherited`) take their form factors from the
    previous level's column: only the elements cut from a refined polygon are new, so a level traces the rays
    of its new elements only (the Cornell box: 4,432 of 5,676 elements at the first refined level, 7,636 of
    11,403 at the second)."""

    def __init__(self, rs, level: Level, seed: int, threshold: float):
        self.rs, self.level, self.seed, self.threshold = rs, level, seed, threshold
        n, m = len(level.recv.area), len(level.src.area)
        self.kept = np.empty((n, int(min(m, SHOT_CACHE_BYTES // (4 * n)))), np.float32, order="F")
        self.slot = np.full(m, -1, np.int64)  # the column of `kept` that holds each shooter's form factors
        self.scale = np.ones(m)  # and the factor `_conserving` found for them
        self.used = 0
        self.rays = 0
        self.occluders = level.visibility_arrays()
        self.every = np.arange(n, dtype=np.int64)
        self.work = np.empty((3, n))
        self.old = level.columns if level.inherited is not None else None
        if self.old is not None:
            self.fresh = np.nonzero(level.inherited < 0)[0]
            self.same = np.nonzero(level.inherited >= 0)[0]
            self.same_from = level.inherited[self.same]
            self.fresh_recv = _subset(level.recv, self.fresh)
            self.fresh_patch = np.ascontiguousarray(level.recv_patch[self.fresh])

    def shoot(self, top: np.ndarray, d: np.ndarray, shot: int, radiance, unshot, patch_unshot) -> np.ndarray:
        """Shoot the patches `top` with unshot radiance `d` (len(top), 3) into every receiving element: each
        receives ρ_i·Σ_q F_iq·d_q in `radiance` and `unshot` (n_elements, 3), and its patch the power of it in
        `patch_unshot`; `shot` numbers the first of them (random streams). Returns the power received (3,)."""
        from ..kernels.radiosity import deliver_shots

        recv, area = self.level.recv, self.level.src.area
        received = np.zeros(3)
        new = np.nonzero(self.slot[top] < 0)[0]  # shooters not shot at this level yet
        room = min(len(new), self.kept.shape[1] - self.used)
        if room:
            cols = np.arange(self.used, self.used + room)
            self._fill(top[new[:room]], d[new[:room]], shot, self.kept, cols)
            self.slot[top[new[:room]]] = cols
            self.scale[top[new[:room]]] = _conserving(self.kept[:, self.used:self.used + room], recv.area,
                                                      area[top[new[:room]]])
            self.used += room
        if room < len(new):  # the budget is spent: these shooters' form factors are used once and forgotten
            left = new[room:]
            ff = np.empty((len(recv.area), len(left)), np.float32, order="F")
            self._fill(top[left], d[left], shot, ff, np.arange(len(left)))
            got = recv.rho * ((ff * _conserving(ff, recv.area, area[top[left]])) @ d[left])
            radiance += got
            unshot += got
            patch_unshot += self.level.patch_sums(got)
            received += recv.area @ got
        kept = top[self.slot[top] >= 0]
        w = np.ascontiguousarray(d[self.slot[top] >= 0] * self.scale[kept, None])
        deliver_shots(self.kept, self.slot[kept], w, recv.rho, recv.area, self.level.recv_patch, radiance, unshot,
                      patch_unshot, received, self.work)
        return received

    def _fill(self, shooters, d, shot, out, cols) -> None:
        """out[:, cols] = F (every receiving element to each of `shooters`, never shot at this level): traced,
        or for the elements of the previous level, that level's own where it shot them too."""
        from ..kernels.radiosity import inherit_columns

        level, old = self.level, self.old
        had = np.zeros(len(shooters), bool) if old is None else old.slot[shooters] >= 0
        if had.any():
            self._trace(self.fresh_recv, self.fresh_patch, self.fresh, shooters[had], d[had], shot, out, cols[had])
            inherit_columns(old.kept, old.slot[shooters[had]], self.same_from, self.same, out, cols[had])
        if not had.all():
            self._trace(level.recv, level.recv_patch, self.every, shooters[~had], d[~had], shot, out, cols[~had])

    def _trace(self, recv, recv_patch, rows, shooters, d, shot, out, cols) -> None:
        from ..kernels.radiosity import shoot_raycast

        rays = np.zeros(-(-len(recv.area) // 256), np.int64)
        rs = self.rs
        d = np.ascontiguousarray(d)
        parallel_for(lambda c0, c1: shoot_raycast(self.occluders, recv, self.level.src, recv_patch, rows, shooters,
                                                  cols, d, np.int64(rs.visibility_samples), np.int64(self.seed),
                                                  np.int64(shot), self.threshold, out, rays, np.int64(c0),
                                                  np.int64(c1)), 0, len(rays))
        self.rays += int(rays.sum())


def _subset(pa, rows: np.ndarray):
    """The elements `rows` of PatchArrays `pa` (its per-polygon arrays whole)."""
    return pa._replace(**{f: np.ascontiguousarray(getattr(pa, f)[rows])
                          for f in ("corners", "k", "centre", "normal", "area", "rho", "emission", "poly")})


#: How far a shot's receivers may, by their form-factor estimates, take more than the shooter sends before the
#: shot is scaled down (`_conserving`): the centre estimates' own error where equal patches meet at a corner
#: is within it, and a shot that sends at most this much over ρ < 1 still converges.
SHOT_SLACK = 0.05


def _conserving(ff: np.ndarray, recv_area: np.ndarray, src_area: np.ndarray) -> np.ndarray:
    """The scale of each shooter's form factors F_ij (receiver i, shooter q): 1, or less where needed so that
    what its receivers take, Σ_i A_i·F_ij = A_j·Σ_i F_ji, is at most (1 + SHOT_SLACK)·A_j: with exact form
    factors it is at most A_j, but a form factor taken at a receiver's centre overestimates what a large
    receiver close to a small shooter takes (neighbouring triangles of a mesh at a crease), and a shot that
    sends more power than it has makes progressive refinement diverge."""
    sent = recv_area @ ff
    bound = (1.0 + SHOT_SLACK) * src_area
    return np.where(sent > bound, bound / np.maximum(sent, 1e-300), 1.0)


class Gain:
    """The share of the power shot so far that came back as unshot power (per channel): how much of its light a
    shot hands on, the mean reflectance times how closed the scene is (0.8 in the furnace of ρ = 0.8; about
    0.12 for a lamp above a square of ρ = 0.6, whose light mostly leaves the scene)."""

    def __init__(self):
        self.shot = np.zeros(3)
        self.kept = np.zeros(3)

    def add(self, shot: np.ndarray, kept: np.ndarray) -> None:
        self.shot += shot
        self.kept += kept

    def value(self) -> np.ndarray | None:
        if not np.all(self.shot > 0.0):
            return None
        return np.clip(self.kept / self.shot, 0.0, 0.999)


def ambient_term(pa, unshot: np.ndarray, gain: np.ndarray | None = None) -> np.ndarray:
    """Cohen et al. 1988's ambient correction for a solution not yet converged: the light still unshot, handed
    on by each bounce's `gain` g forever (g + g² + … = g/(1 − g) of it: the area-weighted radiance to come),
    shared among the elements in proportion to ρ_i·A_i. Cohen's closed-scene term takes g = ρ̄, the mean
    reflectance (used when no shot has been measured yet); `Gain` measures it, so that an open scene, whose
    light mostly leaves, gets the little ambient light it has (a lamp above one square: +2.8% with ρ̄)."""
    area = pa.area
    left = area @ unshot  # (3,): the unshot power (area-weighted radiance)
    rho_a = area @ pa.rho
    if gain is None:
        gain = np.clip(rho_a / area.sum(), 0.0, 0.999)
    to_come = left * gain / (1.0 - gain)
    return pa.rho * (to_come / np.maximum(rho_a, 1e-300))


# ----------------------------------------------------------------------------------------------- stochastic


def stochastic(rs, level: Level, sent, seed, progress, say) -> Result:
    """Stochastic Jacobi: iterations of random-ray shooting of all the unshot power at once."""
    from ..kernels.radiosity import shoot_stochastic

    recv, src = level.recv, level.src
    n = len(recv.area)
    area = src.area
    radiance = sent.copy()
    unshot_e = sent.copy()
    total = float((_lum(sent) * recv.area).sum())
    per_iteration = rs.rays or RAYS_PER_PATCH * len(area)
    limit = rs.max_iterations or 64
    gain = Gain()
    received = np.zeros((STOCHASTIC_CHUNKS, n, 3))
    counts_out = np.zeros(STOCHASTIC_CHUNKS, np.int64)
    rays = 0
    it = 0
    residual = 1.0
    while it < limit:
        unshot = level.patch_means(unshot_e)
        power = _lum(unshot) * area
        residual = float(power.sum()) / total
        if residual <= rs.tolerance:
            break
        # rays in proportion to each patch's unshot power (at least one for every patch that has any)
        share = power / power.sum()
        counts = np.floor(share * per_iteration).astype(np.int64)
        counts[(counts == 0) & (power > 0)] = 1
        shooters = np.nonzero(counts)[0].astype(np.int64)
        counts = counts[shooters]
        first = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        ray_power = np.pi * area[shooters, None] * unshot[shooters] / counts[:, None]
        received[:] = 0.0
        parallel_for(lambda c0, c1: shoot_stochastic(level.bvh.arrays, recv, src, level.tri_poly, shooters, counts,
                                                     first, ray_power, np.int64(seed), np.int64(it),
                                                     np.int64(STOCHASTIC_CHUNKS), received, counts_out, np.int64(c0),
                                                     np.int64(c1)), 0, STOCHASTIC_CHUNKS, grain=1)
        rays += int(counts_out.sum())
        gained = received.sum(axis=0) / (np.pi * recv.area[:, None])  # power → radiance of the receiving element
        gain.add(recv.area @ unshot_e, recv.area @ gained)
        unshot_e = gained
        radiance = radiance + gained
        it += 1
        if say is not None:
            say(f"iteration {it}: {int(counts_out.sum()):,} rays, unshot power {residual:.2%} of what was sent")
        if progress is not None:
            progress(min(1.0, np.log(max(residual, 1e-30)) / np.log(rs.tolerance)))
    residual = float((_lum(unshot_e) * recv.area).sum()) / total
    radiance = radiance + ambient_term(recv, unshot_e, gain.value())  # the light not yet shot, as progressive does
    return Result(radiance, it, residual, rays, 0.0)
