"""The radiosity solvers' kernels: the light point, spot and directional lights deliver, form factors by ray casting
(a progressive shot, a row of the matrix), and Monte Carlo shooting.

All work in radiance (a Lambertian patch's radiosity is B = π·L), on `layout.PatchArrays` `pa`, with the
patches' own BVH (`geo`, a `layout.Geometry` whose triangles carry their polygon as object id):

    L_i = Le_i + ρ_i · Σ_j F_ij · L_j                       (the radiosity equation, per RGB channel)

where F_ij is the form factor from patch i to patch j (the fraction of the light leaving i that reaches j
equals, by reciprocity A_i F_ij = A_j F_ji, the weight of j's radiance in what i receives). Random numbers
come from (seed, patch, stream, index) hashes, so results do not depend on the thread count.
"""

import math

import numpy as np

from .. import config
from .formfactor import patch_ff, polygon_point, visibility
from .hemicube import hemicube_form_factors
from .camera import camera_ray
from .bsdf import sample_cosine
from .environment import env_pdf, env_radiance, env_sample
from .illumination import sample_light
from .optics import reflect, refract, schlick
from .jit import njit, njit_alloc, njit_inline, njit_serial
from .layout import LIGHT_DIRECTIONAL, LV_DIFFUSE
from .rng import rand2_key, rand_key, sample_key
from .sampling import stratified_2d, turn
from .surface import offset_origin
from .traverse import any_triangle_hit, closest_hit
from .views import geometry_of, lighting_of

_CHUNK = 256
_SKY_STREAM = 1 << 30  # sample_key's stream for the sky's rays (the lights' streams are their indices)
#: A receiver's point is lifted this far (relative) off its patch before its shadow rays leave.
_LIFT = config.RAY_EPSILON


@njit_alloc
def _scratch():
    return np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK), np.empty((8, 3))


@njit_inline
def _lifted(pa, i):
    c = (pa.centre[i, 0], pa.centre[i, 1], pa.centre[i, 2])
    n = (pa.normal[i, 0], pa.normal[i, 1], pa.normal[i, 2])
    return offset_origin(c, n, n, _LIFT), n


@njit_serial
def direct_light(sa, lights_sa, pa, samples, seed, out, rays_out, c0, c1):
    """out (n, 3) += ρ·E/π of every point, spot and directional light (`lights_sa`: the scene's lighting arrays, the
    patches' BVH in `sa`): E = π·I·cos θ/att(d) at `samples` stratified points of each patch, shadow rays to the
    light, averaged over the patch (DESIGN.md §3: a diffuse surface then shows ρ·I·cos θ/att, as in whitted).
    Chunks c0 … c1−1 of _CHUNK patches (`threads.parallel_for`); rays_out[c]: chunk c's shadow rays."""
    stack, stack_t, scratch = _scratch()
    _direct_chunks(sa, lights_sa, pa, samples, seed, out, rays_out, c0, c1, stack, stack_t, scratch)


@njit_serial
def sky_light(sa, sky, pa, samples, seed, out, rays_out, c0, c1):
    """out (n, 3) += ρ·E/π of the environment (`sky`: a `layout.EnvironmentTable`), E = ∫ L·cos θ dω over what
    each patch sees of it: at `samples` stratified points of the patch, two directions, one drawn in proportion to
    the environment's radiance (`environment.env_sample`: a sun), one cosine-weighted (a wide sky), combined by
    the balance heuristic (each sample weighs L·cos θ/(p_env + cos θ/π)), with a shadow ray to infinity each.
    Chunks c0 … c1−1 of _CHUNK patches; rays_out[c]: chunk c's shadow rays."""
    stack, stack_t, scratch = _scratch()
    _sky_chunks(sa, sky, pa, samples, seed, out, rays_out, c0, c1, stack)


@njit
def _sky_chunks(sa, sky, pa, samples, seed, out, rays_out, c0, c1, stack):
    n = pa.area.shape[0]
    geo = geometry_of(sa)
    for c in range(c0, c1):
        rays = 0
        for i in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            rho = pa.rho[i]
            if rho[0] <= 0.0 and rho[1] <= 0.0 and rho[2] <= 0.0:
                continue
            nrm = (pa.normal[i, 0], pa.normal[i, 1], pa.normal[i, 2])
            key = sample_key(seed, i, _SKY_STREAM)
            r = g = b = 0.0
            for s in range(samples):
                u1, u2 = rand2_key(key, 3 * s)
                u, v = stratified_2d(s, samples, u1, u2)
                p = polygon_point(pa.corners[i], pa.k[i], u, v)
                for strategy in range(2):
                    u3, u4 = rand2_key(key, 3 * s + 1 + strategy)
                    if strategy == 0:
                        d, pdf = env_sample(sky, u3, u4)
                    else:
                        d = sample_cosine(nrm, u3, u4)
                        pdf = env_pdf(sky, d)
                    cos = nrm[0] * d[0] + nrm[1] * d[1] + nrm[2] * d[2]
                    if cos <= 0.0 or (strategy == 0 and not pdf > 0.0):
                        continue
                    rays += 1
                    if any_triangle_hit(geo, offset_origin(p, nrm, d, _LIFT), d, 0.0, math.inf, stack):
                        continue
                    le = env_radiance(sky, d)
                    k = cos / ((pdf + cos / math.pi) * samples * math.pi)
                    r += le[0] * k
                    g += le[1] * k
                    b += le[2] * k
            out[i, 0] += rho[0] * r
            out[i, 1] += rho[1] * g
            out[i, 2] += rho[2] * b
        rays_out[c] = rays


@njit
def _direct_chunks(sa, lights_sa, pa, samples, seed, out, rays_out, c0, c1, stack, stack_t, scratch):
    n = pa.area.shape[0]
    geo, lit = geometry_of(sa), lighting_of(lights_sa)
    for c in range(c0, c1):
        rays = 0
        for i in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            rho = pa.rho[i]
            if rho[0] <= 0.0 and rho[1] <= 0.0 and rho[2] <= 0.0:
                continue
            nrm = (pa.normal[i, 0], pa.normal[i, 1], pa.normal[i, 2])
            r = g = b = 0.0
            for j in range(lit.light_kind.shape[0]):
                if lit.light_kind[j] > LIGHT_DIRECTIONAL:
                    continue  # area lights are emitting patches
                for s in range(samples):
                    u1, u2 = rand2_key(sample_key(seed, i, j), s)
                    u, v = stratified_2d(s, samples, u1, u2)
                    p = polygon_point(pa.corners[i], pa.k[i], u, v)
                    L, dist, w = sample_light(lit, j, p, 0.5, 0.5)
                    cos = nrm[0] * L[0] + nrm[1] * L[1] + nrm[2] * L[2]
                    if w == 0.0 or cos <= 0.0:
                        continue
                    origin = offset_origin(p, nrm, L, _LIFT)
                    rays += 1
                    if any_triangle_hit(geo, origin, L, 0.0, dist * (1.0 - config.RAY_EPSILON), stack):
                        continue
                    k = cos * w / samples
                    r += lit.light_vecs[j, LV_DIFFUSE, 0] * k
                    g += lit.light_vecs[j, LV_DIFFUSE, 1] * k
                    b += lit.light_vecs[j, LV_DIFFUSE, 2] * k
            out[i, 0] += rho[0] * r
            out[i, 1] += rho[1] * g
            out[i, 2] += rho[2] * b
        rays_out[c] = rays


#: A receiver larger than the shooter and closer to it than this many times its own size (squared: times its
#: area) takes the form factor of a shot as the mean over 3×3 points of it, not at its centre alone: a large
#: receiver beside a small shooter (neighbouring triangles at a crease of a mesh) otherwise takes far more
#: than the shooter sends.
_NEAR_RECEIVER = 4.0


@njit_inline
def _receiver_ff(recv, i, x, n_i, src, j, cj, nj, scratch):
    """F from receiving element i (its lifted centre x, normal n_i) to shooting patch j, unoccluded."""
    dx, dy, dz = cj[0] - x[0], cj[1] - x[1], cj[2] - x[2]
    if recv.area[i] <= 2.0 * src.area[j] or dx * dx + dy * dy + dz * dz > _NEAR_RECEIVER * recv.area[i]:
        return patch_ff(x, n_i, src.corners[j], src.k[j], src.area[j], cj, nj, scratch)
    lift = x[0] - recv.centre[i, 0], x[1] - recv.centre[i, 1], x[2] - recv.centre[i, 2]
    total = 0.0
    for a in range(3):
        for b in range(3):
            p = polygon_point(recv.corners[i], recv.k[i], (a + 0.5) / 3.0, (b + 0.5) / 3.0)
            y = (p[0] + lift[0], p[1] + lift[1], p[2] + lift[2])
            if nj[0] * (y[0] - cj[0]) + nj[1] * (y[1] - cj[1]) + nj[2] * (y[2] - cj[2]) > 0.0:
                total += patch_ff(y, n_i, src.corners[j], src.k[j], src.area[j], cj, nj, scratch)
    return total / 9.0


@njit_inline
def _gather_ff(geo, src, j, x, n_i, samples, key, stack, scratch):
    """F from the (lifted) receiver point x with normal n_i to shooting patch j of `src`, with occlusion: the
    contour form factor times the visibility of j from x; (F, rays). 0 when j's sending side faces away. (At
    the receiver's centre: a row of these sums to exactly 1 in a closed scene, whatever the patch sizes.)"""
    cj = src.centre[j]
    nj = (src.normal[j, 0], src.normal[j, 1], src.normal[j, 2])
    if nj[0] * (x[0] - cj[0]) + nj[1] * (x[1] - cj[1]) + nj[2] * (x[2] - cj[2]) <= 0.0:
        return 0.0, 0
    f = patch_ff(x, n_i, src.corners[j], src.k[j], src.area[j], cj, nj, scratch)
    if f == 0.0:
        return 0.0, 0
    v, rays = visibility(geo, x, n_i, src.corners[j], src.k[j], nj, samples, key, stack)
    return f * v, rays


@njit_serial
def shoot_raycast(sa, recv, src, recv_patch, rows, shooters, cols, unshot_of, samples, seed, shot, threshold, out,
                  rays_out, c0, c1):
    """Progressive-refinement shots (Cohen et al. 1988) from the patches `shooters` (int64 (m,), rows of `src`)
    with unshot radiance `unshot_of` (m, 3): the form factor F_ij from every receiving element i of `recv`
    (whose patch, `recv_patch[i]`, is not the shooter) to each, by ray casting, written to
    out[rows[i], cols[q]] (float32 (n_elements, k): `recv` may be some of the elements, and `rows` their
    indices; the caller scales and applies them). `shot` numbers the first shooter (random streams). A receiver
    whose share of a shot would stay below `threshold` (radiance, unoccluded) takes it only with probability
    share/threshold, weighted by the inverse, and then with one shadow ray instead of `samples`. Chunks c0 …
    c1−1 of _CHUNK receivers."""
    stack, stack_t, scratch = _scratch()
    _shoot_chunks(sa, recv, src, recv_patch, rows, shooters, cols, unshot_of, samples, seed, shot, threshold, out,
                  rays_out, c0, c1, stack, scratch)


@njit
def _shoot_chunks(sa, recv, src, recv_patch, rows, shooters, cols, unshot_of, samples, seed, shot, threshold, out,
                  rays_out, c0, c1, stack, scratch):
    n = recv.area.shape[0]
    m = shooters.shape[0]
    geo = geometry_of(sa)
    for c in range(c0, c1):
        rays = 0
        for i in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            e = rows[i]
            for q in range(m):
                out[e, cols[q]] = 0.0
            rho = recv.rho[i]
            rmax = max(rho[0], rho[1], rho[2])
            if rmax <= 0.0:
                continue
            x, n_i = _lifted(recv, i)
            for q in range(m):
                j = shooters[q]
                if recv_patch[i] == j:
                    continue
                cj = src.centre[j]
                nj = (src.normal[j, 0], src.normal[j, 1], src.normal[j, 2])
                if nj[0] * (x[0] - cj[0]) + nj[1] * (x[1] - cj[1]) + nj[2] * (x[2] - cj[2]) <= 0.0:
                    continue  # j sends its light the other way
                d0, d1, d2 = unshot_of[q, 0], unshot_of[q, 1], unshot_of[q, 2]
                f = _receiver_ff(recv, i, x, n_i, src, j, cj, nj, scratch)
                if f == 0.0:
                    continue
                share = f * rmax * max(d0, d1, d2)
                key = sample_key(seed, e, shot + q)
                k = samples
                if share < threshold:
                    # a faint share: one shadow ray, and only with probability share/threshold (weighted by
                    # its inverse: Russian roulette, unbiased), so that dim shots cost few rays
                    keep = share / threshold
                    if rand_key(key, 1 << 20) >= keep:
                        continue
                    f /= keep
                    k = 1
                v, r = visibility(geo, x, n_i, src.corners[j], src.k[j], nj, k, key, stack)
                out[e, cols[q]] = f * v
                rays += r
        rays_out[c] += rays


@njit
def inherit_columns(old, old_cols, same_from, same, out, cols):
    """out[same[r], cols[q]] = old[same_from[r], old_cols[q]]: the form factors of the elements a refined level
    keeps (`same`, and their indices at the previous level, `same_from`), taken from the previous level's
    columns (`radiosity.solvers.Columns`)."""
    for q in range(cols.shape[0]):
        a, b = old_cols[q], cols[q]
        for r in range(same.shape[0]):
            out[same[r], b] = old[same_from[r], a]


@njit_serial
def ff_rows_raycast(sa, recv, src, recv_patch, rows, samples, seed, out, rays_out, r0, r1):
    """out[r, j] = F from receiving element rows[r] of `recv` to every shooting patch j of `src` (float32
    (len(rows), n_src)), by ray casting: a band of the form-factor matrix of the Gauss–Seidel and Jacobi solvers. Rows r0 … r1−1 of `out`."""
    stack, stack_t, scratch = _scratch()
    _ff_rows(sa, recv, src, recv_patch, rows, samples, seed, out, rays_out, r0, r1, stack, stack_t, scratch)


@njit
def _ff_rows(sa, recv, src, recv_patch, rows, samples, seed, out, rays_out, r0, r1, stack, stack_t, scratch):
    n = src.area.shape[0]
    geo = geometry_of(sa)
    for r in range(r0, r1):
        i = rows[r]
        x, n_i = _lifted(recv, i)
        count = 0
        for j in range(n):
            out[r, j] = 0.0
            if recv_patch[i] == j:
                continue
            f, rays = _gather_ff(geo, src, j, x, n_i, samples, sample_key(seed, i, j), stack, scratch)
            out[r, j] = f
            count += rays
        rays_out[r] = count


@njit
def _cosine_dir(n, u1, u2):
    r = math.sqrt(u1)
    cp, sp = turn(u2)
    x = r * cp
    y = r * sp
    z = math.sqrt(max(0.0, 1.0 - u1))
    s = 1.0 if n[2] >= 0.0 else -1.0
    a = -1.0 / (s + n[2])
    bb = n[0] * n[1] * a
    t = (1.0 + s * n[0] * n[0] * a, s * bb, -s * n[0])
    b2 = (bb, s + n[1] * n[1] * a, -n[1])
    return (x * t[0] + y * b2[0] + z * n[0], x * t[1] + y * b2[1] + z * n[1], x * t[2] + y * b2[2] + z * n[2])


@njit_serial
def shoot_stochastic(sa, recv, src, tri_poly, shooters, counts, first_ray, power, seed, iteration, n_chunks,
                     received, rays_out, c0, c1):
    """One iteration of stochastic Jacobi radiosity (Neumann et al. 1995; Bekaert's *Advanced Global
    Illumination* ch. 6): patch shooters[s] of `src` sends counts[s] rays from uniform points, cosine-distributed,
    each carrying power[s] (its unshot power ΔΦ = π·A·ΔL over its ray count, per channel); the first surface hit
    (the receiving elements `recv`, whose polygons the BVH `sa` holds) receives it, on the side the ray arrives
    on, times its reflectance. `received` (n_chunks, n_recv, 3) is summed over its first axis by the caller: each
    chunk of rays adds into its own row, so the sum does not depend on the thread count. `tri_poly` maps a BVH
    triangle to its polygon; `first_ray` numbers each shooter's first ray (the chunks split that numbering).
    Chunks c0 … c1−1 of the n_chunks."""
    stack, stack_t, scratch = _scratch()
    _stochastic_chunks(sa, recv, src, tri_poly, shooters, counts, first_ray, power, seed, iteration, n_chunks,
                       received, rays_out, c0, c1, stack, stack_t, scratch)


@njit
def _stochastic_chunks(sa, recv, src, tri_poly, shooters, counts, first_ray, power, seed, iteration, n_chunks,
                       received, rays_out, c0, c1, stack, stack_t, scratch):
    total = first_ray[-1] + counts[-1] if shooters.shape[0] else 0
    geo = geometry_of(sa)
    for c in range(c0, c1):
        lo = total * c // n_chunks
        hi = total * (c + 1) // n_chunks
        rays = 0
        s = np.searchsorted(first_ray, lo, side="right") - 1 if lo < total else 0
        for ray in range(lo, hi):
            while s + 1 < shooters.shape[0] and first_ray[s + 1] <= ray:
                s += 1
            j = shooters[s]
            key = sample_key(seed, iteration, ray)
            u1, u2 = rand2_key(key, 0)
            u3, u4 = rand2_key(key, 1)
            y = polygon_point(src.corners[j], src.k[j], u1, u2)
            nj = (src.normal[j, 0], src.normal[j, 1], src.normal[j, 2])
            d = _cosine_dir(nj, u3, u4)
            o = offset_origin(y, nj, d, _LIFT)
            hit = closest_hit(geo, o, d, 0.0, config.T_FAR, stack, stack_t, 0.0)
            rays += 1
            if hit[0] < 0.0:
                continue
            poly = tri_poly[hit[1]]
            pn = recv.poly_normal[poly]
            side = 0 if pn[0] * d[0] + pn[1] * d[1] + pn[2] * d[2] < 0.0 else 1
            i = recv.side_patch[poly, side]
            if i < 0:
                continue
            rho = recv.rho[i]
            received[c, i, 0] += rho[0] * power[s, 0]
            received[c, i, 1] += rho[1] * power[s, 1]
            received[c, i, 2] += rho[2] * power[s, 2]
        rays_out[c] = rays


@njit
def deliver_shots(kept, slots, w, rho, area, recv_patch, radiance, unshot, patch_unshot, received, g):
    """A batch of progressive shots over kept form factors (`kept` float32 (n_elements, k), one column per
    shooter; `slots` (m,) the columns of the batch's shooters; w (m, 3) each one's unshot radiance times its
    column's scale): every element i receives g_i = ρ_i·Σ_q kept[i, slots[q]]·w[q], added to its radiance and
    unshot radiance, and A_i·g_i to the unshot power of its patch (patch_unshot (n_patches, 3)) and to
    `received` (3,). `g` is a float64 (3, n_elements) work array; the sums run down the columns."""
    n = kept.shape[0]
    g[:] = 0.0
    for q in range(slots.shape[0]):
        col = kept[:, slots[q]]
        w0, w1, w2 = w[q, 0], w[q, 1], w[q, 2]
        for i in range(n):
            f = np.float64(col[i])
            g[0, i] += f * w0
            g[1, i] += f * w1
            g[2, i] += f * w2
    for i in range(n):
        g0, g1, g2 = g[0, i] * rho[i, 0], g[1, i] * rho[i, 1], g[2, i] * rho[i, 2]
        radiance[i, 0] += g0
        radiance[i, 1] += g1
        radiance[i, 2] += g2
        unshot[i, 0] += g0
        unshot[i, 1] += g1
        unshot[i, 2] += g2
        p = recv_patch[i]
        a = area[i]
        patch_unshot[p, 0] += a * g0
        patch_unshot[p, 1] += a * g1
        patch_unshot[p, 2] += a * g2
        received[0] += a * g0
        received[1] += a * g1
        received[2] += a * g2


@njit
def gauss_seidel_sweep(F, rho, emission, recv_area, recv_patch, patch_area, radiance, patch_radiance):
    """One Gauss–Seidel sweep of L_i = E_i + ρ_i Σ_j F_ij L̄_j over the receiving elements i (F float32
    (n_recv, n_src)), L̄_j the area-weighted mean of patch j's elements, kept up to date as each element
    changes; in place. Returns the largest change of an element's radiance (mean of its channels)."""
    n, m = F.shape
    worst = 0.0
    for i in range(n):
        s0 = s1 = s2 = 0.0
        row = F[i]
        for j in range(m):
            f = row[j]
            if f != 0.0:
                s0 += f * patch_radiance[j, 0]
                s1 += f * patch_radiance[j, 1]
                s2 += f * patch_radiance[j, 2]
        n0 = emission[i, 0] + rho[i, 0] * s0
        n1 = emission[i, 1] + rho[i, 1] * s1
        n2 = emission[i, 2] + rho[i, 2] * s2
        d0, d1, d2 = n0 - radiance[i, 0], n1 - radiance[i, 1], n2 - radiance[i, 2]
        worst = max(worst, (abs(d0) + abs(d1) + abs(d2)) / 3.0)
        radiance[i, 0], radiance[i, 1], radiance[i, 2] = n0, n1, n2
        p = recv_patch[i]
        share = recv_area[i] / patch_area[p]
        patch_radiance[p, 0] += share * d0
        patch_radiance[p, 1] += share * d1
        patch_radiance[p, 2] += share * d2
    return worst


@njit_serial
def jacobi_sweep(F, rho, emission, patch_radiance, out, r0, r1):
    """out = E + ρ·(F @ L̄): one Jacobi sweep (every element from the previous iterate's patch means), rows
    r0 … r1−1."""
    m = F.shape[1]
    for i in range(r0, r1):
        s0 = s1 = s2 = 0.0
        for j in range(m):
            f = F[i, j]
            if f != 0.0:
                s0 += f * patch_radiance[j, 0]
                s1 += f * patch_radiance[j, 1]
                s2 += f * patch_radiance[j, 2]
        out[i, 0] = emission[i, 0] + rho[i, 0] * s0
        out[i, 1] = emission[i, 1] + rho[i, 1] * s1
        out[i, 2] = emission[i, 2] + rho[i, 2] * s2


@njit
def smooth_corners(order, starts, normals, weights, values, cos_limit, out):
    """Within each bucket (corners order[starts[b]:starts[b+1]]), each corner's value: the weighted mean over
    the bucket's corners whose normal is within the angle of its own."""
    for b in range(starts.shape[0] - 1):
        lo, hi = starts[b], starts[b + 1]
        for a in range(lo, hi):
            i = order[a]
            s0 = s1 = s2 = 0.0
            wsum = 0.0
            for c in range(lo, hi):
                j = order[c]
                d = normals[i, 0] * normals[j, 0] + normals[i, 1] * normals[j, 1] + normals[i, 2] * normals[j, 2]
                if d >= cos_limit:
                    w = weights[j]
                    s0 += w * values[j, 0]
                    s1 += w * values[j, 1]
                    s2 += w * values[j, 2]
                    wsum += w
            out[i, 0] = s0 / wsum
            out[i, 1] = s1 / wsum
            out[i, 2] = s2 / wsum


@njit
def gradient_moments(order, starts, owner, normals, centres, values, cos_limit, a_out, b_out):
    """The least-squares moments of each patch's radiance gradient from its neighbours (the patches it shares
    a corner bucket with, turned within the angle): a_out[p] += d·dᵀ and b_out[p] += d ⊗ (L_q − L_p) over them,
    d = c_q − c_p (a_out (n, 3, 3), b_out (n, 3, 3): row = direction component, column = channel)."""
    for b in range(starts.shape[0] - 1):
        lo, hi = starts[b], starts[b + 1]
        for x in range(lo, hi):
            i = order[x]
            p = owner[i]
            for y in range(lo, hi):
                j = order[y]
                q = owner[j]
                if q == p:
                    continue
                if normals[i, 0] * normals[j, 0] + normals[i, 1] * normals[j, 1] + normals[i, 2] * normals[j, 2] \
                        < cos_limit:
                    continue
                d0 = centres[q, 0] - centres[p, 0]
                d1 = centres[q, 1] - centres[p, 1]
                d2 = centres[q, 2] - centres[p, 2]
                d = (d0, d1, d2)
                for r in range(3):
                    for c in range(3):
                        a_out[p, r, c] += d[r] * d[c]
                        b_out[p, r, c] += d[r] * (values[q, c] - values[p, c])


# --------------------------------------------------------------------------------------------- two-pass display


@njit_inline
def _element_radiance_at(p, e, faces, element_face0, element_face1, vertices, vertex_radiance):
    """The solution's radiance at point p of element e: interpolated across whichever of its display triangles
    holds p (barycentric weights of its corners' smoothed radiance)."""
    best0 = best1 = best2 = 0.0
    best_err = 1e300
    for q in range(2):
        f = element_face0[e] if q == 0 else element_face1[e]
        if f < 0:
            break
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        e1 = (vertices[b, 0] - vertices[a, 0], vertices[b, 1] - vertices[a, 1], vertices[b, 2] - vertices[a, 2])
        e2 = (vertices[c, 0] - vertices[a, 0], vertices[c, 1] - vertices[a, 1], vertices[c, 2] - vertices[a, 2])
        r = (p[0] - vertices[a, 0], p[1] - vertices[a, 1], p[2] - vertices[a, 2])
        d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]
        d12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]
        d22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]
        r1 = r[0] * e1[0] + r[1] * e1[1] + r[2] * e1[2]
        r2 = r[0] * e2[0] + r[1] * e2[1] + r[2] * e2[2]
        det = d11 * d22 - d12 * d12
        if det == 0.0:
            continue
        u = (d22 * r1 - d12 * r2) / det
        v = (d11 * r2 - d12 * r1) / det
        w = 1.0 - u - v
        err = max(0.0, -u) + max(0.0, -v) + max(0.0, -w)  # 0 inside the triangle
        if err < best_err:
            best_err = err
            u, v, w = max(u, 0.0), max(v, 0.0), max(w, 0.0)
            s = 1.0 / (u + v + w)
            best0 = (w * vertex_radiance[a, 0] + u * vertex_radiance[b, 0] + v * vertex_radiance[c, 0]) * s
            best1 = (w * vertex_radiance[a, 1] + u * vertex_radiance[b, 1] + v * vertex_radiance[c, 1]) * s
            best2 = (w * vertex_radiance[a, 2] + u * vertex_radiance[b, 2] + v * vertex_radiance[c, 2]) * s
    return best0, best1, best2


@njit_serial
def trace_two_pass(sa, tri_face, faces, face_element, element_face0, element_face1, vertices, vertex_radiance,
                   element_normal, element_optics, element_twin, cam_vecs, cam_params, width, height, spp, seed,
                   max_depth, background, out, rays_out, y0, y1):
    """The two-pass display (Wallace, Cohen & Greenberg 1987): camera rays, traced Whitted-style through the
    mirrors (kr) and glass (kt) of the display mesh (`sa`: its triangles, `tri_face` their faces), read the
    radiosity solution where they land (interpolated), weighted by the kr and kt on their way; out (H, W, 3),
    rows y0 … y1−1."""
    stack, stack_t, scratch = _scratch()
    _two_pass_rows(sa, tri_face, faces, face_element, element_face0, element_face1, vertices, vertex_radiance,
                   element_normal, element_optics, element_twin, cam_vecs, cam_params, width, height, spp, seed,
                   max_depth, background, out, rays_out, y0, y1, stack, stack_t,
                   np.empty((2 * max_depth + 4, 10)))  # the ray stack: origin, direction, weight, depth


@njit
def _two_pass_rows(sa, tri_face, faces, face_element, element_face0, element_face1, vertices, vertex_radiance,
                   element_normal, element_optics, element_twin, cam_vecs, cam_params, width, height, spp, seed,
                   max_depth, background, out, rays_out, y0, y1, stack, stack_t, st):
    geo = geometry_of(sa)
    size = st.shape[0]
    for y in range(y0, y1):
        rays = 0
        for x in range(width):
            r_sum = g_sum = b_sum = 0.0
            pixel = y * width + x
            for s in range(spp):
                o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, s, spp, seed, pixel)
                st[0, 0], st[0, 1], st[0, 2] = o
                st[0, 3], st[0, 4], st[0, 5] = d
                st[0, 6] = st[0, 7] = st[0, 8] = 1.0
                st[0, 9] = 0.0
                sp = 1
                while sp > 0:
                    sp -= 1
                    o = (st[sp, 0], st[sp, 1], st[sp, 2])
                    d = (st[sp, 3], st[sp, 4], st[sp, 5])
                    w0, w1, w2, depth = st[sp, 6], st[sp, 7], st[sp, 8], np.int64(st[sp, 9])
                    hit = closest_hit(geo, o, d, 0.0, config.T_FAR, stack, stack_t, 0.0)
                    rays += 1
                    if hit[0] < 0.0:
                        r_sum += w0 * background[0]
                        g_sum += w1 * background[1]
                        b_sum += w2 * background[2]
                        continue
                    e = face_element[tri_face[hit[1]]]
                    n = (element_normal[e, 0], element_normal[e, 1], element_normal[e, 2])
                    if n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0:  # its other side
                        e = element_twin[e]
                        if e < 0:
                            continue  # a side that is no patch: black
                        n = (element_normal[e, 0], element_normal[e, 1], element_normal[e, 2])
                    p = (o[0] + hit[0] * d[0], o[1] + hit[0] * d[1], o[2] + hit[0] * d[2])
                    lr, lg, lb = _element_radiance_at(p, e, faces, element_face0, element_face1, vertices,
                                                      vertex_radiance)
                    r_sum += w0 * lr
                    g_sum += w1 * lg
                    b_sum += w2 * lb
                    if depth >= max_depth:
                        continue
                    opt = element_optics[e]
                    kr0, kr1, kr2 = opt[0], opt[1], opt[2]
                    kt0, kt1, kt2 = opt[3], opt[4], opt[5]
                    transmit = kt0 > 0.0 or kt1 > 0.0 or kt2 > 0.0
                    t_dir = d
                    if transmit and opt[8] != 0.0:  # a solid: Snell's law, in on its outside, out on its inside
                        eta = 1.0 / opt[6] if opt[8] > 0.0 else opt[6]
                        ok, t_dir = refract(d, n, eta)
                        if opt[7] != 0.0:
                            cos_i = -(d[0] * n[0] + d[1] * n[1] + d[2] * n[2])
                            cos_t = -(t_dir[0] * n[0] + t_dir[1] * n[1] + t_dir[2] * n[2]) if ok else 0.0
                            F = schlick(max(cos_i, 0.0), eta, max(cos_t, 0.0)) if ok else 1.0
                            kr0, kr1, kr2 = kr0 + kt0 * F, kr1 + kt1 * F, kr2 + kt2 * F
                            kt0, kt1, kt2 = kt0 * (1.0 - F), kt1 * (1.0 - F), kt2 * (1.0 - F)
                        if not ok:  # total internal reflection
                            kr0, kr1, kr2 = kr0 + kt0, kr1 + kt1, kr2 + kt2
                            transmit = False
                    for branch in range(2):
                        if branch == 0:
                            ww0, ww1, ww2 = w0 * kr0, w1 * kr1, w2 * kr2
                            nd = reflect(d, n)
                        else:
                            if not transmit:
                                break
                            ww0, ww1, ww2 = w0 * kt0, w1 * kt1, w2 * kt2
                            nd = t_dir
                        if max(ww0, ww1, ww2) < 1e-3 or sp >= size:
                            continue
                        no = offset_origin(p, n, nd, _LIFT)
                        st[sp, 0], st[sp, 1], st[sp, 2] = no
                        st[sp, 3], st[sp, 4], st[sp, 5] = nd
                        st[sp, 6], st[sp, 7], st[sp, 8] = ww0, ww1, ww2
                        st[sp, 9] = depth + 1
                        sp += 1
            inv = 1.0 / spp
            out[y, x, 0] = r_sum * inv
            out[y, x, 1] = g_sum * inv
            out[y, x, 2] = b_sum * inv
        rays_out[y] = rays


@njit
def hemicube_shot(x, n, phi, verts, polys, poly_normal, side_patch, dF, near, scratch, ff, area_j, d0, d1, d2,
                  recv_area, recv_rho, radiance, unshot):
    """A progressive shot through a hemicube at the shooter (Cohen et al. 1988): the hemicube at x (the shooting
    patch's lifted centre, unit normal n, turned by phi) over the receivers' polygons gives F_j→i for every
    receiver i, reciprocity F_ij = F_ji·A_j/A_i, and each receiver gains ρ_i·F_ij·ΔL_j; `ff` is a float64
    (n_recv,) work array."""
    ff[:] = 0.0
    hemicube_form_factors(x, n, phi, -1, verts, polys, poly_normal, side_patch, dF, near, scratch, ff)
    for i in range(ff.shape[0]):
        f = ff[i]
        if f == 0.0:
            continue
        g = f * area_j / recv_area[i]
        radiance[i, 0] += recv_rho[i, 0] * g * d0
        radiance[i, 1] += recv_rho[i, 1] * g * d1
        radiance[i, 2] += recv_rho[i, 2] * g * d2
        unshot[i, 0] += recv_rho[i, 0] * g * d0
        unshot[i, 1] += recv_rho[i, 1] * g * d1
        unshot[i, 2] += recv_rho[i, 2] * g * d2
