"""Slow, obviously-correct twins of the kernels, written from the maths (never by calling `lumos.kernels`).

Everything here is plain Python or vectorised NumPy in float64 and works in WORLD space from an object's own
parameters (centre and radius, min/max, base/top…), never through the canonical shapes the compile step uses:

* `rand01_ref` — SplitMix64 (Steele, Lea & Flood 2014) with Python integers.
* `chi2_sf` — the χ² survival function (regularised incomplete gamma), so the χ² tests need no SciPy.
* `hit_*` — ray–primitive intersection for arrays of rays: o, d float64 (n, 3) → (t (n,), normal (n, 3)),
  t = inf on a miss, normal the outward geometric normal (unit). A hit needs t_min < t < t_max, as in the
  kernels; boundaries (tangent rays, edges, rims) count as hits (closed sets).
* `hit_object` — the same for a scene-file object dict (with its optional `transform`).
* `camera_rays`, `render_classic` — DESIGN.md §3 camera and the classic illumination model, vectorised over
  pixels; no shadow rays (what `raycast` promises).
"""

from __future__ import annotations

import math

import numpy as np

# ---------------------------------------------------------------------------------------------------- RNG

_MASK64 = (1 << 64) - 1


def splitmix64_mix(z: int) -> int:
    """One SplitMix64 step from state z: advance by the golden gamma, then the variant-13 finaliser."""
    z = (z + 0x9E3779B97F4A7C15) & _MASK64
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK64
    return z ^ (z >> 31)


def splitmix64_stream(state: int, n: int) -> list[int]:
    """The first n outputs of the SplitMix64 generator started at `state` (the published test vectors)."""
    out = []
    for _ in range(n):
        out.append(splitmix64_mix(state))
        state = (state + 0x9E3779B97F4A7C15) & _MASK64
    return out


def rand01_ref(seed: int, pixel: int, sample: int, dim: int) -> float:
    """The documented key → uniform map: mix each key component into the hash in turn, keep the top 53 bits."""
    h = splitmix64_mix(seed)
    h = splitmix64_mix(h ^ pixel)
    h = splitmix64_mix(h ^ sample)
    h = splitmix64_mix(h ^ dim)
    return (h >> 11) / float(1 << 53)


# --------------------------------------------------------------------------------------------- statistics


def chi2_sf(x: float, dof: int) -> float:
    """P(X >= x) for X ~ χ²(dof): 1 − P(dof/2, x/2), with P the regularised lower incomplete gamma (series)."""
    if x <= 0.0:
        return 1.0
    a, z = 0.5 * dof, 0.5 * x
    term = 1.0 / a
    total = term
    n = 1
    while term > total * 1e-15 and n < 100000:
        term *= z / (a + n)
        total += term
        n += 1
    log_p = a * math.log(z) - z - math.lgamma(a) + math.log(total)
    return max(0.0, 1.0 - math.exp(log_p))


def chi2_uniform(counts, expected=None) -> tuple[float, float]:
    """Pearson χ² of observed bin counts against expected counts (equal bins by default): (statistic, p)."""
    counts = np.asarray(counts, dtype=np.float64).ravel()
    if expected is None:
        expected = np.full(counts.shape, counts.sum() / counts.size)
    expected = np.asarray(expected, dtype=np.float64).ravel()
    stat = float(((counts - expected) ** 2 / expected).sum())
    return stat, chi2_sf(stat, counts.size - 1)


# ----------------------------------------------------------------------------------------------- geometry


def unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def transform_matrix(translate=(0.0, 0.0, 0.0), rotate=(0.0, 0.0, 0.0), scale=1.0) -> np.ndarray:
    """world_from_object = T · Rz · Ry · Rx · S, angles in degrees (the scene format's `transform`)."""
    s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,))
    ax, ay, az = (math.radians(a) for a in rotate)

    def rot(axis, angle):
        c, si = math.cos(angle), math.sin(angle)
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        r = np.eye(3)
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -si, si, c
        return r

    m = np.eye(4)
    m[:3, :3] = rot(2, az) @ rot(1, ay) @ rot(0, ax) @ np.diag(s)
    m[:3, 3] = translate
    return m


def _xform_of(obj) -> np.ndarray | None:
    tr = obj.get("transform")
    if tr is None:
        return None
    if "matrix" in tr:
        return np.array(tr["matrix"], dtype=np.float64)
    return transform_matrix(tr.get("translate", (0, 0, 0)), tr.get("rotate", (0, 0, 0)), tr.get("scale", 1.0))


def _dot(a, b):
    return np.einsum("...i,...i->...", a, b)


def _arrays(o, d):
    o = np.atleast_2d(np.asarray(o, dtype=np.float64))
    d = np.atleast_2d(np.asarray(d, dtype=np.float64))
    return np.broadcast_arrays(o, d)


def _nearest(candidates, n_rays):
    """Pick the smallest valid t among candidates [(t (n,), normal (n, 3)), ...] (invalid = inf)."""
    t_best = np.full(n_rays, np.inf)
    n_best = np.zeros((n_rays, 3))
    for t, nrm in candidates:
        closer = t < t_best
        t_best = np.where(closer, t, t_best)
        n_best = np.where(closer[:, None], nrm, n_best)
    return t_best, n_best


def _in_range(t, t_min, t_max):
    with np.errstate(invalid="ignore"):
        ok = (t > t_min) & (t < t_max)
    return np.where(ok, t, np.inf)


def quadratic_roots(a, b, c):
    """Real roots of a·t² + b·t + c = 0 (arrays), smaller first; nan where there is none. a = 0 → the linear
    root (both slots). Uses the cancellation-free pair q/a, c/q (Numerical Recipes §5.6)."""
    a, b, c = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (a, b, c)))
    with np.errstate(all="ignore"):
        disc = b * b - 4.0 * a * c
        sq = np.sqrt(np.maximum(disc, 0.0))
        q = -0.5 * (b + np.where(b >= 0.0, sq, -sq))
        r0 = q / a
        r1 = c / q
        r1 = np.where(q == 0.0, r0, r1)
        t0 = np.minimum(r0, r1)
        t1 = np.maximum(r0, r1)
        lin = -c / b
    none = (disc < 0.0) | ((a == 0.0) & (b == 0.0))
    t0 = np.where(a == 0.0, lin, t0)
    t1 = np.where(a == 0.0, lin, t1)
    return np.where(none, np.nan, t0), np.where(none, np.nan, t1)


def hit_sphere(o, d, center, radius, t_min=0.0, t_max=np.inf):
    """|o + t·d − c|² = r²; normal (p − c)/r."""
    o, d = _arrays(o, d)
    oc = o - np.asarray(center, dtype=np.float64)
    t0, t1 = quadratic_roots(_dot(d, d), 2.0 * _dot(oc, d), _dot(oc, oc) - radius * radius)
    cands = []
    for t in (t0, t1):
        t = _in_range(t, t_min, t_max)
        with np.errstate(invalid="ignore"):
            p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
        cands.append((t, (p - center) / radius))
    return _nearest(cands, len(o))


def ellipsoid_from_sphere(center, radius, world_from_object):
    """(C, Q): the ellipsoid (x − C)ᵀQ(x − C) = 1 that a sphere becomes under an affine map, built from the
    map's SVD (semi-axes r·σᵢ along the left singular vectors), not from its inverse."""
    m = np.asarray(world_from_object, dtype=np.float64)
    c = m[:3, :3] @ np.asarray(center, dtype=np.float64) + m[:3, 3]
    u, sigma, _ = np.linalg.svd(m[:3, :3])
    semi = radius * sigma
    return c, u @ np.diag(1.0 / semi**2) @ u.T


def hit_ellipsoid(o, d, center, Q, t_min=0.0, t_max=np.inf):
    """(x − C)ᵀQ(x − C) = 1 solved for t; normal ∝ Q(p − C) (the gradient)."""
    o, d = _arrays(o, d)
    oc = o - center
    Qd = d @ Q.T
    t0, t1 = quadratic_roots(_dot(d, Qd), 2.0 * _dot(oc, Qd), _dot(oc, oc @ Q.T) - 1.0)
    cands = []
    for t in (t0, t1):
        t = _in_range(t, t_min, t_max)
        p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
        g = (p - center) @ Q.T
        cands.append((t, g / np.linalg.norm(g, axis=1, keepdims=True)))
    return _nearest(cands, len(o))


def parallelepiped_planes(corner, e1, e2, e3):
    """Half-spaces n·x <= h (unit outward n) bounding {corner + a·e1 + b·e2 + c·e3 : a, b, c in [0, 1]}."""
    corner = np.asarray(corner, dtype=np.float64)
    edges = [np.asarray(e, dtype=np.float64) for e in (e1, e2, e3)]
    normals, offsets = [], []
    for i in range(3):
        j, k = [x for x in range(3) if x != i]
        n = np.cross(edges[j], edges[k])
        n /= np.linalg.norm(n)
        if n @ edges[i] < 0:
            n = -n
        normals += [n, -n]
        offsets += [n @ (corner + edges[i]), -n @ corner]
    return np.array(normals), np.array(offsets)


def box_planes(bmin, bmax):
    bmin, bmax = np.asarray(bmin, dtype=np.float64), np.asarray(bmax, dtype=np.float64)
    size = bmax - bmin
    return parallelepiped_planes(bmin, (size[0], 0, 0), (0, size[1], 0), (0, 0, size[2]))


def hit_convex(o, d, normals, offsets, t_min=0.0, t_max=np.inf):
    """A convex polytope {x : nᵢ·x <= hᵢ} by Cyrus–Beck clipping; from inside, the exit face is the hit."""
    o, d = _arrays(o, d)
    n = len(o)
    t_in = np.full(n, -np.inf)
    t_out = np.full(n, np.inf)
    n_in = np.zeros((n, 3))
    n_out = np.zeros((n, 3))
    outside = np.zeros(n, bool)
    for nrm, h in zip(normals, offsets):
        denom = d @ nrm
        num = h - o @ nrm
        with np.errstate(divide="ignore", invalid="ignore"):
            t = num / denom
        entering = denom < 0.0
        leaving = denom > 0.0
        outside |= (denom == 0.0) & (num < 0.0)
        upd = entering & (t > t_in)
        t_in = np.where(upd, t, t_in)
        n_in[upd] = nrm
        upd = leaving & (t < t_out)
        t_out = np.where(upd, t, t_out)
        n_out[upd] = nrm
    hit = ~outside & (t_in <= t_out)
    near = np.where(hit, _in_range(t_in, t_min, t_max), np.inf)
    far = np.where(hit, _in_range(t_out, t_min, t_max), np.inf)
    t = np.where(np.isfinite(near), near, far)
    nrm = np.where(np.isfinite(near)[:, None], n_in, n_out)
    return t, nrm


def _disk_candidate(o, d, center, normal, radius, t_min, t_max):
    normal = unit(normal)
    t, _ = hit_plane(o, d, center, normal, t_min, t_max)
    p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
    inside = ((p - center) ** 2).sum(axis=1) <= radius * radius
    return np.where(inside, t, np.inf), np.broadcast_to(normal, o.shape)


def hit_plane(o, d, point, normal, t_min=0.0, t_max=np.inf):
    """(p − point)·n = 0; normal n (as given, normalised)."""
    o, d = _arrays(o, d)
    normal = unit(normal)
    denom = d @ normal
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((np.asarray(point, dtype=np.float64) - o) @ normal) / denom
    t = np.where(denom == 0.0, np.inf, t)
    return _in_range(t, t_min, t_max), np.broadcast_to(normal, o.shape).copy()


def hit_disk(o, d, center, normal, radius, t_min=0.0, t_max=np.inf):
    o, d = _arrays(o, d)
    t, n = _disk_candidate(o, d, np.asarray(center, dtype=np.float64), normal, radius, t_min, t_max)
    return t, n.copy()


def hit_rect(o, d, corner, edge_u, edge_v, t_min=0.0, t_max=np.inf):
    """{corner + a·edge_u + b·edge_v : a, b in [0, 1]}; normal along cross(edge_u, edge_v)."""
    o, d = _arrays(o, d)
    corner = np.asarray(corner, dtype=np.float64)
    eu, ev = np.asarray(edge_u, dtype=np.float64), np.asarray(edge_v, dtype=np.float64)
    normal = unit(np.cross(eu, ev))
    t, n = hit_plane(o, d, corner, normal, t_min, t_max)
    q = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d - corner
    gram = np.array([[eu @ eu, eu @ ev], [eu @ ev, ev @ ev]])
    ab = np.linalg.solve(gram, np.stack([q @ eu, q @ ev]))
    inside = (ab >= 0.0).all(axis=0) & (ab <= 1.0).all(axis=0)
    return np.where(inside, t, np.inf), n


def hit_cylinder(o, d, base, top, radius, capped=True, t_min=0.0, t_max=np.inf):
    """Points whose distance from the axis base→top is `radius`, between the two end planes; caps optional."""
    o, d = _arrays(o, d)
    base, top = np.asarray(base, dtype=np.float64), np.asarray(top, dtype=np.float64)
    height = np.linalg.norm(top - base)
    axis = (top - base) / height
    ob = o - base
    r0 = ob - np.outer(ob @ axis, axis)  # the ray's offset from the axis, perpendicular part
    rd = d - np.outer(d @ axis, axis)
    t0, t1 = quadratic_roots(_dot(rd, rd), 2.0 * _dot(r0, rd), _dot(r0, r0) - radius * radius)
    cands = []
    for t in (t0, t1):
        t = _in_range(t, t_min, t_max)
        tt = np.where(np.isfinite(t), t, 0.0)
        h = ob @ axis + tt * (d @ axis)
        radial = r0 + tt[:, None] * rd
        t = np.where((h >= 0.0) & (h <= height), t, np.inf)
        cands.append((t, radial / radius))
    if capped:
        cands.append(_disk_candidate(o, d, base, -axis, radius, t_min, t_max))
        cands.append(_disk_candidate(o, d, top, axis, radius, t_min, t_max))
    return _nearest(cands, len(o))


def hit_cone(o, d, base, top, radius, capped=True, t_min=0.0, t_max=np.inf):
    """Radius `radius` at base shrinking linearly to 0 at the apex `top`: |radial| = k·(H − h), k = r/H."""
    o, d = _arrays(o, d)
    base, top = np.asarray(base, dtype=np.float64), np.asarray(top, dtype=np.float64)
    height = np.linalg.norm(top - base)
    axis = (top - base) / height
    k = radius / height
    ob = o - base
    h0, hd = ob @ axis, d @ axis
    r0 = ob - np.outer(h0, axis)
    rd = d - np.outer(hd, axis)
    a = _dot(rd, rd) - k * k * hd * hd
    b = 2.0 * _dot(r0, rd) + 2.0 * k * k * (height - h0) * hd
    c = _dot(r0, r0) - k * k * (height - h0) ** 2
    t0, t1 = quadratic_roots(a, b, c)
    cands = []
    for t in (t0, t1):
        t = _in_range(t, t_min, t_max)
        tt = np.where(np.isfinite(t), t, 0.0)
        h = h0 + tt * hd
        radial = r0 + tt[:, None] * rd
        t = np.where((h >= 0.0) & (h <= height), t, np.inf)
        rlen = np.linalg.norm(radial, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            g = radial / rlen + k * axis  # gradient of |radial| − k(H − h)
        cands.append((t, unit(g)))
    if capped:
        cands.append(_disk_candidate(o, d, base, -axis, radius, t_min, t_max))
    return _nearest(cands, len(o))


def hit_triangle(o, d, v0, v1, v2, t_min=0.0, t_max=np.inf):
    """Möller–Trumbore (1997) in float64, edges and vertices included; normal along (v1 − v0) × (v2 − v0).

    Returns (t, normal, b1, b2) with b1, b2 the barycentric weights of v1 and v2."""
    o, d = _arrays(o, d)
    v0, v1, v2 = (np.asarray(v, dtype=np.float64) for v in (v0, v1, v2))
    e1, e2 = v1 - v0, v2 - v0
    pvec = np.cross(d, e2)
    det = pvec @ e1
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        tvec = o - v0
        b1 = _dot(tvec, pvec) * inv
        qvec = np.cross(tvec, e1)
        b2 = _dot(d, qvec) * inv
        t = (qvec @ e2) * inv
    ok = (det != 0.0) & (b1 >= 0.0) & (b2 >= 0.0) & (b1 + b2 <= 1.0)
    t = np.where(ok, _in_range(t, t_min, t_max), np.inf)
    normal = np.broadcast_to(unit(np.cross(e1, e2)), o.shape).copy()
    return t, normal, b1, b2


# ------------------------------------------------------------------------------------------ scene objects


def hit_object(obj: dict, o, d, t_min=0.0, t_max=np.inf):
    """(t, normal) for a scene-file object dict. Transforms are supported for spheres (→ ellipsoid), boxes
    (→ parallelepiped) and planes; for the other analytic shapes only a pure translation."""
    kind = obj["type"]
    m = _xform_of(obj)
    if kind == "sphere":
        c, r = obj.get("center", (0, 0, 0)), obj.get("radius", 1.0)
        if m is None:
            return hit_sphere(o, d, c, r, t_min, t_max)
        C, Q = ellipsoid_from_sphere(c, r, m)
        return hit_ellipsoid(o, d, C, Q, t_min, t_max)
    if kind == "box":
        lo = np.asarray(obj.get("min", (-1, -1, -1)), dtype=np.float64)
        hi = np.asarray(obj.get("max", (1, 1, 1)), dtype=np.float64)
        if m is None:
            return hit_convex(o, d, *box_planes(lo, hi), t_min=t_min, t_max=t_max)
        size = hi - lo
        corner = m[:3, :3] @ lo + m[:3, 3]
        edges = [m[:3, :3] @ (size * e) for e in np.eye(3)]
        return hit_convex(o, d, *parallelepiped_planes(corner, *edges), t_min=t_min, t_max=t_max)
    if kind == "plane":
        p = np.asarray(obj.get("point", (0, 0, 0)), dtype=np.float64)
        n = unit(obj.get("normal", (0, 1, 0)))
        if m is not None:
            # carry the point and two tangents with cross(t1, t2) = n through the map; the new normal is the
            # cross product of the mapped tangents (its sign flips with a mirroring map)
            t1 = unit(np.cross([1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0], n))
            t2 = np.cross(n, t1)
            p = m[:3, :3] @ p + m[:3, 3]
            n = np.sign(np.linalg.det(m[:3, :3])) * np.cross(m[:3, :3] @ t1, m[:3, :3] @ t2)
        return hit_plane(o, d, p, n, t_min, t_max)
    offset = np.zeros(3)
    if m is not None:
        if not np.allclose(m[:3, :3], np.eye(3)):
            raise NotImplementedError(f"naive {kind}: only translations")
        offset = m[:3, 3]
    if kind == "cylinder" or kind == "cone":
        base = np.asarray(obj.get("base", (0, 0, 0)), dtype=np.float64) + offset
        top = np.asarray(obj.get("top", (0, 1, 0)), dtype=np.float64) + offset
        fn = hit_cylinder if kind == "cylinder" else hit_cone
        return fn(o, d, base, top, obj.get("radius", 1.0), obj.get("capped", True), t_min, t_max)
    if kind == "disk":
        c = np.asarray(obj.get("center", (0, 0, 0)), dtype=np.float64) + offset
        return hit_disk(o, d, c, obj.get("normal", (0, 1, 0)), obj.get("radius", 1.0), t_min, t_max)
    if kind == "triangle":
        v = np.asarray(obj["vertices"], dtype=np.float64) + offset
        t, n, _, _ = hit_triangle(o, d, v[0], v[1], v[2], t_min, t_max)
        return t, n
    raise NotImplementedError(kind)


def shape_bounds(obj: dict) -> np.ndarray:
    """Tight axis-aligned bounds (min xyz, max xyz) of an untransformed analytic object or triangle."""
    kind = obj["type"]
    if kind == "sphere":
        c, r = np.asarray(obj["center"], dtype=np.float64), obj["radius"]
        return np.concatenate([c - r, c + r])
    if kind == "box":
        return np.concatenate([obj["min"], obj["max"]]).astype(np.float64)
    if kind == "triangle":
        v = np.asarray(obj["vertices"], dtype=np.float64)
        return np.concatenate([v.min(axis=0), v.max(axis=0)])

    def disk_extent(n, r):  # a circle of radius r in the plane ⊥ n reaches r·sqrt(1 − nᵢ²) along axis i
        n = unit(n)
        return r * np.sqrt(np.maximum(0.0, 1.0 - n * n))

    if kind == "disk":
        c = np.asarray(obj["center"], dtype=np.float64)
        e = disk_extent(obj["normal"], obj["radius"])
        return np.concatenate([c - e, c + e])
    base, top = np.asarray(obj["base"], dtype=np.float64), np.asarray(obj["top"], dtype=np.float64)
    e = disk_extent(top - base, obj["radius"])
    if kind == "cylinder":
        return np.concatenate([np.minimum(base, top) - e, np.maximum(base, top) + e])
    return np.concatenate([np.minimum(base - e, top), np.maximum(base + e, top)])  # cone


# ------------------------------------------------------------------------------------ camera and shading


def camera_basis(cam: dict):
    pos = np.asarray(cam.get("position", (0, 0, 5)), dtype=np.float64)
    look = np.asarray(cam.get("look_at", (0, 0, 0)), dtype=np.float64)
    up = np.asarray(cam.get("up", (0, 1, 0)), dtype=np.float64)
    w = unit(pos - look)
    u = unit(np.cross(up, w))
    v = np.cross(w, u)
    return pos, u, v, w


def camera_rays(cam: dict, width: int, height: int):
    """DESIGN.md §3 pixel-centre rays, row 0 at the top: origins and unit directions, each (H·W, 3)."""
    pos, u, v, w = camera_basis(cam)
    x, y = np.meshgrid(np.arange(width), np.arange(height))
    sx = (2.0 * (x.ravel() + 0.5) / width - 1.0)[:, None]
    sy = (1.0 - 2.0 * (y.ravel() + 0.5) / height)[:, None]
    a = width / height
    if cam.get("type", "perspective") == "orthographic":
        half = cam.get("size", 2.0) / 2.0
        o = pos + sx * a * half * u + sy * half * v
        return o, np.broadcast_to(-w, o.shape).copy()
    t = math.tan(math.radians(cam.get("fov", 45.0)) / 2.0)
    d = unit(sx * a * t * u + sy * t * v - w)
    return np.broadcast_to(pos, d.shape).copy(), d


def _rgb(value, default=0.0):
    if value is None:
        value = default
    return np.broadcast_to(np.asarray(value, dtype=np.float64), (3,)).copy()


def material_of(scene: dict, obj: dict) -> dict:
    m = obj.get("material")
    if isinstance(m, str):
        m = scene["materials"][m]
    if m is None:
        raise NotImplementedError("give every object a material in naive scenes")
    return {
        "ka": _rgb(m.get("ka")),
        "kd": _rgb(m.get("kd")),
        "ks": _rgb(m.get("ks")),
        "shininess": float(m.get("shininess", 1.0)),
    }


def closest(objects, o, d, t_max=np.inf):
    """Brute force over `objects` (dicts): (t (n,), object index (n,) or -1, normal (n, 3))."""
    n = len(o)
    t_best = np.full(n, np.inf)
    idx = np.full(n, -1)
    n_best = np.zeros((n, 3))
    for i, obj in enumerate(objects):
        t, nrm = hit_object(obj, o, d, 0.0, t_max)
        closer = t < t_best
        t_best = np.where(closer, t, t_best)
        idx = np.where(closer, i, idx)
        n_best = np.where(closer[:, None], nrm, n_best)
    return t_best, idx, n_best


def spot_falloff(light: dict, L):
    """A spot light's falloff towards points that see it along the unit rows of L (n, 3): s², s = clamp((cosθ −
    cos angle)/(cos inner_angle − cos angle), 0, 1), cosθ = −axis·L; a step when the two angles are equal."""
    cos_t = -(L @ unit(light["direction"]))
    co = math.cos(math.radians(light.get("angle", 45.0)))
    ci = math.cos(math.radians(light.get("inner_angle", 0.0)))
    if ci - co < 1e-9:
        return np.where(cos_t >= co, 1.0, 0.0)
    return np.clip((cos_t - co) / (ci - co), 0.0, 1.0) ** 2


def classic_local(p, n, V, mat, lights, ambient):
    """Ka·Ia + Σ [Kd·Id·max(N·L,0) + Ks·Is·max(R·V,0)^n] / att(d), R = 2(N·L)N − L (DESIGN.md §3); a spot
    light's term times its falloff."""
    out = np.zeros(p.shape) + mat["ka"] * _rgb(ambient)
    for light in lights:
        intensity = light.get("intensity", 1.0)
        Id = _rgb(light.get("diffuse", intensity))
        Is = _rgb(light.get("specular", intensity))
        if light["type"] in ("point", "spot"):
            to = np.asarray(light["position"], dtype=np.float64) - p
            dist = np.linalg.norm(to, axis=1)
            L = to / dist[:, None]
            c, lin, q = light.get("attenuation", (1.0, 0.0, 0.0))
            att = c + lin * dist + q * dist * dist
            gain = spot_falloff(light, L) if light["type"] == "spot" else np.ones(len(p))
        elif light["type"] == "directional":
            L = np.broadcast_to(-unit(light["direction"]), p.shape)
            att = np.ones(len(p))
            gain = np.ones(len(p))
        else:
            raise NotImplementedError(light["type"])
        n_dot_l = _dot(n, L)
        lit = n_dot_l > 0.0
        R = 2.0 * n_dot_l[:, None] * n - L
        spec = np.maximum(_dot(R, V), 0.0) ** mat["shininess"]
        term = (mat["kd"] * Id * n_dot_l[:, None] + mat["ks"] * Is * spec[:, None]) * (gain / att)[:, None]
        out += np.where(lit[:, None], term, 0.0)
    return out


def render_classic(scene: dict, width: int, height: int):
    """Ray casting by the book: (H, W, 3) radiance, (H, W) depth (inf on a miss) and (H, W) object index."""
    o, d = camera_rays(scene.get("camera", {}), width, height)
    objects = scene["objects"]
    t, idx, n = closest(objects, o, d)
    img = np.broadcast_to(_rgb(scene.get("background", 0.0)), o.shape).copy()
    hit = np.isfinite(t)
    p = o + np.where(hit, t, 0.0)[:, None] * d
    V = -d
    n = np.where((_dot(n, V) < 0.0)[:, None], -n, n)  # the shading normal faces the viewer
    for i, obj in enumerate(objects):
        sel = idx == i
        if sel.any():
            mat = material_of(scene, obj)
            img[sel] = classic_local(p[sel], n[sel], V[sel], mat, scene.get("lights", []), scene.get("ambient", 0.0))
    shape = (height, width)
    return img.reshape(height, width, 3), t.reshape(shape), idx.reshape(shape)


# ------------------------------------------------------------------------------------------- irradiance


def polygon_irradiance(p, n, vertices, radiance):
    """Irradiance at p (unit normal n) from a Lambertian polygon of constant radiance lying wholly above p's
    tangent plane: Lambert's formula E = (Le/2)·|Σ Θᵢ·(n · Γᵢ)|, Θᵢ the angle each edge subtends at p and Γᵢ the
    unit normal of the plane through p and that edge (Arvo 1995, "Applications of irradiance tensors")."""
    v = unit(np.asarray(vertices, dtype=np.float64) - np.asarray(p, dtype=np.float64))
    total = 0.0
    for i in range(len(v)):
        a, b = v[i], v[(i + 1) % len(v)]
        theta = math.acos(max(-1.0, min(1.0, float(a @ b))))
        gamma = np.cross(a, b)
        total += theta * float(np.asarray(n, dtype=np.float64) @ (gamma / np.linalg.norm(gamma)))
    return 0.5 * radiance * abs(total)


def sphere_irradiance(p, n, center, radius, radiance):
    """Irradiance at p (unit normal n) from a uniform sphere wholly above the tangent plane: π·Le·sin²α·cos β,
    α the half-angle it subtends and β the angle between n and the direction to its centre."""
    to = np.asarray(center, dtype=np.float64) - np.asarray(p, dtype=np.float64)
    dist = np.linalg.norm(to)
    return math.pi * radiance * (radius / dist) ** 2 * float(np.asarray(n, dtype=np.float64) @ (to / dist))


# ------------------------------------------------------------------------------------------- rasterization


def inside_polygon(px, py, xs, ys):
    """Per-pixel inside test (the twin of the scan-line rasterizer): which sample points (xs, ys) lie inside the
    screen polygon (px, py) by the even–odd rule with the top-left convention — a point on an edge is inside
    when the edge is a left or top one (the polygon's interior lies to its right, or below a horizontal edge).

    Evaluated by crossing counts on the horizontal line through each point, with half-open y intervals; returns
    (inside bool array, distance to the nearest edge) so that callers can ignore points on edges up to rounding.
    """
    xs = np.asarray(xs, dtype=np.float64)
    ys = np.asarray(ys, dtype=np.float64)
    crossings_left = np.zeros(xs.shape, dtype=np.int64)
    near = np.full(xs.shape, np.inf)
    n = len(px)
    for k in range(n):
        x0, y0, x1, y1 = px[k], py[k], px[(k + 1) % n], py[(k + 1) % n]
        ex, ey = x1 - x0, y1 - y0
        length2 = ex * ex + ey * ey
        if length2 > 0:
            t = np.clip(((xs - x0) * ex + (ys - y0) * ey) / length2, 0.0, 1.0)
            near = np.minimum(near, np.hypot(xs - (x0 + t * ex), ys - (y0 + t * ey)))
        if y0 == y1:
            continue
        top_x, top_y, bot_x, bot_y = (x0, y0, x1, y1) if y0 < y1 else (x1, y1, x0, y0)
        active = (top_y <= ys) & (ys < bot_y)
        x_cross = top_x + (ys - top_y) * (bot_x - top_x) / (bot_y - top_y)
        # a crossing at or left of the point: the point is right of (or on) a left edge
        crossings_left += active & (x_cross <= xs)
    return crossings_left % 2 == 1, near


# --------------------------------------------------------------------------------------- Whitted tracing
#
# `render_whitted` is the twin of `method="whitted"` (DESIGN.md §3, "Recursion"), written from the rules below and
# from nothing in lumos. A ray queue is processed level by level (all rays of one depth at once, vectorised over
# rays); each queued ray carries its pixel, its path weight (per channel) and the ordered tuple of the solids it
# is inside (innermost last; () = air, index 1). Per level:
#
#   1. nearest hit over every object (`closest`); a miss adds weight·background to its pixel;
#   2. at a hit p with outward geometric normal n_g: V = −d, n = n_g turned to face V; the pixel gets
#      weight·(emission + Ka·Ia + Σ_lights T·[Kd·Id·max(N·L,0) + Ks·Is·max(R·V,0)^n]/att), T the shadow
#      transmittance (`shadow_transmittance`);
#   3. below max_depth: a reflected ray (reflect(d, n), weight·w_r, same media) and a transmitted one (Snell for
#      solids with η = n1/n2 from the media tuple, straight on through planes, disks and triangles), w_r = kr,
#      w_t = kt, or with `fresnel` w_r = kr + kt·F, w_t = kt·(1 − F), F Schlick's (F = 1 on total internal
#      reflection). On total internal reflection the transmitted part takes the mirror direction: it joins the
#      reflected ray (w_r + w_t, the incident media), which matters only for the cut-off. A child whose path
#      weight (max over channels) is below WHITTED_CUTOFF is not traced. Children start at p offset by
#      WHITTED_EPSILON·max(1, |p|∞) along n_g on the side they leave to.
#
# Solids are spheres, boxes and capped cylinders and cones (convex, so the nearest hit on a segment tells whether
# it enters); planes, disks and triangles are surfaces. Only point and directional lights.

#: Origin offset of secondary and shadow rays, relative to max(1, |p|∞).
WHITTED_EPSILON = 1e-7
#: A secondary ray whose path weight (max over channels) is below this is not traced.
WHITTED_CUTOFF = 1e-3

_SOLIDS = ("sphere", "box", "cylinder", "cone")
_SURFACES = ("plane", "disk", "triangle")


def whitted_material_of(scene: dict, obj: dict) -> dict:
    """`material_of` plus the keys recursion needs: kr, kt, emission (RGB), ior, fresnel."""
    m = obj["material"]
    if isinstance(m, str):
        m = scene["materials"][m]
    return {
        **material_of(scene, obj),
        "kr": _rgb(m.get("kr")),
        "kt": _rgb(m.get("kt")),
        "emission": _rgb(m.get("emission")),
        "ior": float(m.get("ior", 1.0)),
        "fresnel": bool(m.get("fresnel", False)),
    }


def is_solid(obj: dict) -> bool:
    """True for the closed convex shapes a ray can be inside of; False for planes, disks and triangles."""
    kind = obj["type"]
    if kind in ("cylinder", "cone") and not obj.get("capped", True):
        raise NotImplementedError("naive whitted: uncapped cylinders and cones are neither solid nor flat")
    if kind in _SOLIDS:
        return True
    if kind in _SURFACES:
        return False
    raise NotImplementedError(f"naive whitted: {kind}")


def offset_origin(p, n_g, side):
    """p + side·WHITTED_EPSILON·max(1, |p|∞)·n_g, side = ±1 per ray (the side of n_g the new ray leaves to)."""
    eps = WHITTED_EPSILON * np.maximum(1.0, np.abs(p).max(axis=1))
    return p + (np.asarray(side, dtype=np.float64) * eps)[:, None] * n_g


def shadow_transmittance(objects, mats, solid, origin, L, dist):
    """Per-channel transmittance (n, 3) of shadow rays origin + s·L, 0 < s < dist (an array, inf for directional
    lights). An object with kt = 0 in every channel blocks (0) wherever the segment meets it; a transparent solid
    multiplies by its kt where the segment ENTERS it (L·n_g < 0; it meets a convex solid's boundary entering at
    most once, and then first); a transparent surface multiplies by its kt where the segment crosses it."""
    T = np.ones(origin.shape)
    for obj, mat, is_sol in zip(objects, mats, solid):
        t, n_g = hit_object(obj, origin, L, 0.0, dist)
        hit = np.isfinite(t)
        if not mat["kt"].any():
            T[hit] = 0.0
            continue
        if is_sol:
            hit &= _dot(L, n_g) < 0.0
        T[hit] *= mat["kt"]
    return T


def whitted_local(p, n, V, mat, scene, objects, mats, solid):
    """Ka·Ia + Σ_lights T·[Kd·Id·max(N·L,0) + Ks·Is·max(R·V,0)^n]/att: `classic_local` one light at a time,
    each scaled by the shadow transmittance from p (moved off the surface along n, the side of every light
    with N·L > 0) towards that light."""
    out = mat["ka"] * _rgb(scene.get("ambient", 0.0)) + np.zeros(p.shape)
    origin = offset_origin(p, n, np.ones(len(p)))
    for light in scene.get("lights", []):
        if light["type"] in ("point", "spot"):
            to = np.asarray(light["position"], dtype=np.float64) - origin
            dist = np.linalg.norm(to, axis=1)
            L = to / dist[:, None]
        elif light["type"] == "directional":
            L = np.broadcast_to(-unit(light["direction"]), p.shape).copy()
            dist = np.full(len(p), np.inf)
        else:
            raise NotImplementedError(f"naive whitted: {light['type']} lights")
        T = shadow_transmittance(objects, mats, solid, origin, L, dist)
        out += T * classic_local(p, n, V, mat, [light], 0.0)
    return out


def refract_np(d, n, eta):
    """Snell's law for arrays: (tir (k,), t (k, 3), cos_i, cos_t), n facing the incident side (d·n <= 0),
    eta = n1/n2 per ray. cos_t = √(1 − η²(1 − cos_i²)); t = η·d + (η·cos_i − cos_t)·n; the mirror direction
    where tir."""
    cos_i = -_dot(d, n)
    sin2_t = eta * eta * np.maximum(0.0, 1.0 - cos_i * cos_i)
    tir = sin2_t > 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    t = unit(eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * n)
    mirror = d + 2.0 * cos_i[:, None] * n
    return tir, np.where(tir[:, None], mirror, t), cos_i, cos_t


def schlick_np(cos_i, cos_t, eta, tir):
    """Schlick (1994): R0 + (1 − R0)(1 − c)^5, R0 = ((1 − η)/(1 + η))², c the cosine on the thinner side
    (cos_i when η <= 1, cos_t when η > 1); 1 on total internal reflection."""
    r0 = ((1.0 - eta) / (1.0 + eta)) ** 2
    c = np.where(eta <= 1.0, cos_i, cos_t)
    return np.where(tir, 1.0, r0 + (1.0 - r0) * (1.0 - c) ** 5)


def _media_leaving(media, x, ior):
    """Leaving solid x from inside `media` (object indices, innermost last): n1 = ior of the innermost (x when x
    is innermost; 1 in air), n2 = ior of the innermost of media − x (1 if none); the transmitted ray's media."""
    n1 = ior[media[-1]] if media else 1.0
    rest = tuple(m for m in media if m != x)
    n2 = ior[rest[-1]] if rest else 1.0
    return n1, n2, rest


def _spawn(objects, mats, solid, ior, i, o, d, p, n_g, n, weight, pixel, media):
    """Children of the rays (all of them hitting object i): reflected and transmitted rays with their weights."""
    mat = mats[i]
    k = len(p)
    tmedia = list(media)
    if solid[i]:
        entering = _dot(d, n_g) < 0.0
        n1, n2 = np.empty(k), np.empty(k)
        for j in range(k):
            if entering[j]:
                n1[j] = ior[media[j][-1]] if media[j] else 1.0
                n2[j] = ior[i]
                tmedia[j] = media[j] + (i,)
            else:
                n1[j], n2[j], tmedia[j] = _media_leaving(media[j], i, ior)
        eta = n1 / n2
        tir, t_dir, cos_i, cos_t = refract_np(d, n, eta)
    else:
        if mat["fresnel"] and mat["kt"].any():
            raise NotImplementedError("naive whitted: fresnel on a transparent plane, disk or triangle")
        t_dir = d.copy()
    w_r = np.broadcast_to(mat["kr"], (k, 3))
    w_t = np.broadcast_to(mat["kt"], (k, 3))
    if mat["fresnel"] and solid[i]:
        F = schlick_np(cos_i, cos_t, eta, tir)[:, None]
        w_r = mat["kr"] + mat["kt"] * F
        w_t = mat["kt"] * (1.0 - F)
    if solid[i]:
        # total internal reflection: the transmitted part joins the reflected ray (one ray, one path weight)
        w_r = np.where(tir[:, None], w_r + w_t, w_r)
        w_t = np.where(tir[:, None], 0.0, w_t)
    r_dir = d - 2.0 * _dot(d, n)[:, None] * n
    children = []
    for direction, w, med in ((r_dir, w_r, list(media)), (t_dir, w_t, tmedia)):
        cw = weight * w
        keep = cw.max(axis=1) >= WHITTED_CUTOFF
        if not keep.any():
            continue
        side = np.where(_dot(direction, n_g) >= 0.0, 1.0, -1.0)
        origin = offset_origin(p, n_g, side)
        kept_media = [m for m, kp in zip(med, keep) if kp]
        children.append((origin[keep], direction[keep], cw[keep], pixel[keep], kept_media))
    return children


def render_whitted(scene: dict, width: int, height: int, max_depth: int | None = None):
    """Whitted ray tracing by the book (see the section comment): (H, W, 3) float64 radiance.

    `max_depth` defaults to the scene's `render: max_depth` (5 when absent); a hit at depth k (the primary hit
    is depth 0) spawns secondary rays only while k < max_depth.
    """
    if max_depth is None:
        max_depth = scene.get("render", {}).get("max_depth", 5)
    objects = scene["objects"]
    mats = [whitted_material_of(scene, obj) for obj in objects]
    solid = [is_solid(obj) for obj in objects]
    ior = np.array([m["ior"] for m in mats])
    background = _rgb(scene.get("background", 0.0))
    o, d = camera_rays(scene.get("camera", {}), width, height)
    img = np.zeros((width * height, 3))
    # the queue of one level: origins, directions, path weights, pixel indices, media tuples
    queue = (o, d, np.ones(o.shape), np.arange(len(o)), [()] * len(o))
    for depth in range(max_depth + 1):
        o, d, weight, pixel, media = queue
        if len(o) == 0:
            break
        # stage 1: nearest hits; misses see the background
        t, idx, n_g = closest(objects, o, d)
        miss = idx < 0
        np.add.at(img, pixel[miss], weight[miss] * background)
        # stage 2: emission + local term with shadow rays, per object hit
        p = o + np.where(miss, 0.0, t)[:, None] * d
        V = -d
        n = np.where((_dot(n_g, V) < 0.0)[:, None], -n_g, n_g)
        children = []
        for i in np.unique(idx[~miss]):
            sel = np.flatnonzero(idx == i)
            local = mats[i]["emission"] + whitted_local(p[sel], n[sel], V[sel], mats[i], scene, objects, mats, solid)
            np.add.at(img, pixel[sel], weight[sel] * local)
            # stage 3: secondary rays, below max_depth
            if depth < max_depth:
                children += _spawn(objects, mats, solid, ior, i, o[sel], d[sel], p[sel], n_g[sel], n[sel],
                                   weight[sel], pixel[sel], [media[j] for j in sel])
        if not children:
            break
        queue = (np.concatenate([c[0] for c in children]), np.concatenate([c[1] for c in children]),
                 np.concatenate([c[2] for c in children]), np.concatenate([c[3] for c in children]),
                 [m for c in children for m in c[4]])
    return img.reshape(height, width, 3)


# ------------------------------------------------------------------------------------------ csg solids
#
# Constructive solid geometry from the object dicts (scene-file keys), written from the set operations and never
# through the kernels' layout: `inside_solid` is point membership (closed sets: the boundary counts as inside),
# `hit_csg` casts rays by enumerating every boundary crossing of every solid with t > 0 (`hit_object` called
# again from each crossing, or every triangle of a mesh) and testing membership half-way between successive
# crossings: a crossing is a hit of the combined solid where membership before and after it differ.


def _compose(parent, obj):
    """world_from_object of a solid inside csg nodes: the parents' transforms, then its own."""
    m = _xform_of(obj)
    if m is None:
        return parent
    return m if parent is None else parent @ m


def mesh_world_triangles(obj, world_from_object=None):
    """(m, 3, 3) world-space triangles of an inline mesh dict (vertices + triangular faces)."""
    v = np.asarray(obj["vertices"], dtype=np.float64)
    if world_from_object is not None:
        v = v @ world_from_object[:3, :3].T + world_from_object[:3, 3]
    return v[np.asarray(obj["faces"], dtype=np.int64)]


#: an arbitrary direction for parity counts (no mesh edge or vertex of a test lies on a ray along it)
_PARITY_DIR = unit([0.5377, 0.3127, 0.7831])


def inside_solid(obj: dict, points, world_from_parent=None):
    """(n,) bool: which world points lie in the solid `obj` (sphere, box, cylinder, cone, closed mesh or csg)."""
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    m = _compose(world_from_parent, obj)
    kind = obj["type"]
    if kind == "csg":
        a = inside_solid(obj["left"], points, m)
        b = inside_solid(obj["right"], points, m)
        return {"union": a | b, "intersection": a & b, "difference": a & ~b}[obj["op"]]
    if kind == "mesh":  # the Jordan parity of a ray from each point
        count = np.zeros(len(points), np.int64)
        for v0, v1, v2 in mesh_world_triangles(obj, m):
            t, _, _, _ = hit_triangle(points, _PARITY_DIR, v0, v1, v2)
            count += np.isfinite(t)
        return count % 2 == 1
    q = points if m is None else np.linalg.solve(m[:3, :3], (points - m[:3, 3]).T).T  # object space
    if kind == "sphere":
        c = np.asarray(obj.get("center", (0, 0, 0)), dtype=np.float64)
        return ((q - c) ** 2).sum(axis=1) <= obj.get("radius", 1.0) ** 2
    if kind == "box":
        lo = np.asarray(obj.get("min", (-1, -1, -1)), dtype=np.float64)
        hi = np.asarray(obj.get("max", (1, 1, 1)), dtype=np.float64)
        return ((q >= lo) & (q <= hi)).all(axis=1)
    if kind in ("cylinder", "cone"):
        base = np.asarray(obj.get("base", (0, 0, 0)), dtype=np.float64)
        top = np.asarray(obj.get("top", (0, 1, 0)), dtype=np.float64)
        height = np.linalg.norm(top - base)
        axis = (top - base) / height
        h = (q - base) @ axis
        radial = np.linalg.norm(q - base - np.outer(h, axis), axis=1)
        r = obj.get("radius", 1.0) * (1.0 if kind == "cylinder" else (1.0 - h / height))
        return (h >= 0.0) & (h <= height) & (radial <= r)
    raise NotImplementedError(kind)


def csg_solids(obj: dict, world_from_parent=None, material=None):
    """The solids of a csg dict as [(solid dict placed in the world by a `matrix` transform, material)]; a solid
    without a material takes the nearest csg node's."""
    m = _compose(world_from_parent, obj)
    material = obj.get("material") if obj.get("material") is not None else material
    if obj["type"] == "csg":
        return csg_solids(obj["left"], m, material) + csg_solids(obj["right"], m, material)
    placed = {k: v for k, v in obj.items() if k not in ("transform", "material")}
    if m is not None:
        placed["transform"] = {"matrix": m.tolist()}
    return [(placed, material)]


def _solid_crossings(solid: dict, o, d, t_max):
    """Every boundary crossing of one solid with 0 < t < t_max: [(t (n,), normal (n, 3))]."""
    if solid["type"] == "mesh":
        out = []
        for v0, v1, v2 in mesh_world_triangles(solid, _xform_of(solid)):
            t, nrm, _, _ = hit_triangle(o, d, v0, v1, v2, 0.0, t_max)
            out.append((t, nrm))
        return out
    out = []
    t_min = np.zeros(len(o))
    for _ in range(2):  # a convex solid: at most an entry and an exit
        t, nrm = hit_object(solid, o, d, t_min, t_max)
        out.append((t, nrm))
        t_min = t
    return out


def hit_csg(obj: dict, o, d, t_max=np.inf):
    """Nearest boundary point of a csg dict on rays o + t·d, 0 < t < t_max: (t (n,), inf on a miss; normal (n, 3),
    the solid's normal turned outward of the combined solid; solid (n,), an index into `csg_solids(obj)`;
    entering (n,) bool)."""
    o, d = _arrays(o, d)
    n = len(o)
    ts, normals, owners = [], [], []
    for k, (solid, _) in enumerate(csg_solids(obj)):
        for t, nrm in _solid_crossings(solid, o, d, np.inf):
            ts.append(t)
            normals.append(nrm)
            owners.append(np.full(n, k))
    T = np.stack(ts, axis=1)
    order = np.argsort(T, axis=1)
    T = np.take_along_axis(T, order, axis=1)
    N = np.take_along_axis(np.stack(normals, axis=1), order[:, :, None], axis=1)
    K = np.take_along_axis(np.stack(owners, axis=1), order, axis=1)
    used = max(1, int(np.isfinite(T).sum(axis=1).max()))  # sorted: the misses (inf) are at the end
    T, N, K = T[:, :used], N[:, :used], K[:, :used]
    # membership half-way along each segment (segment k ends at crossing k); beyond the last crossing: outside
    inside = np.zeros((n, T.shape[1] + 1), bool)
    prev = np.zeros(n)
    for k in range(T.shape[1]):
        live = np.isfinite(T[:, k])
        mid = np.where(live, 0.5 * (prev + T[:, k]), 0.0)
        inside[:, k] = live & inside_solid(obj, o + mid[:, None] * d)
        prev = np.where(live, T[:, k], prev)
    change = (inside[:, :-1] != inside[:, 1:]) & np.isfinite(T) & (T < t_max)
    first = np.argmax(change, axis=1)
    rows = np.arange(n)
    hit = change[rows, first]
    t = np.where(hit, T[rows, first], np.inf)
    entering = hit & inside[rows, first + 1]
    nrm = N[rows, first]
    towards = np.where(entering, -1.0, 1.0)  # outward: against d entering, along d leaving
    nrm = nrm * np.where(_dot(nrm, d) * towards < 0.0, -1.0, 1.0)[:, None]
    return t, nrm, np.where(hit, K[rows, first], -1), entering


def render_classic_csg(scene: dict, width: int, height: int):
    """`render_classic` for scenes that may hold csg objects (each hit shaded with the material of the solid it
    lies on): (H, W, 3) radiance and (H, W) depth."""
    o, d = camera_rays(scene.get("camera", {}), width, height)
    n = len(o)
    t_best = np.full(n, np.inf)
    n_best = np.zeros((n, 3))
    mat_best = np.full(n, -1)
    materials = []
    for obj in scene["objects"]:
        if obj["type"] == "csg":
            t, nrm, solid, _ = hit_csg(obj, o, d)
            mats = [material_of(scene, {"material": m}) for _, m in csg_solids(obj)]
            which = len(materials) + solid
        else:
            t, nrm = hit_object(obj, o, d)
            mats = [material_of(scene, obj)]
            which = np.full(n, len(materials))
        materials += mats
        closer = t < t_best
        t_best = np.where(closer, t, t_best)
        n_best = np.where(closer[:, None], nrm, n_best)
        mat_best = np.where(closer, which, mat_best)
    img = np.broadcast_to(_rgb(scene.get("background", 0.0)), o.shape).copy()
    p = o + np.where(np.isfinite(t_best), t_best, 0.0)[:, None] * d
    V = -d
    n_best = np.where((_dot(n_best, V) < 0.0)[:, None], -n_best, n_best)
    for k, mat in enumerate(materials):
        sel = mat_best == k
        if sel.any():
            img[sel] = classic_local(p[sel], n_best[sel], V[sel], mat, scene.get("lights", []),
                                     scene.get("ambient", 0.0))
    return img.reshape(height, width, 3), t_best.reshape(height, width)
