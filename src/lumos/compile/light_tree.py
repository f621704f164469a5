"""The light tree of the path tracer's emitter table (`kernels.light_tree`, after pbrt-v4's BVHLightSampler):
each emitter's bounds, then the tree over them.

    em = with_light_tree(em, arrays)      # layout.Emitters with tree_nodes, tree_link, emit_node, emit_unbounded

Each emitter's `LightBounds` (layout.TREE_*), with φ in units where φ·cosθ/d² is π times the irradiance it
delivers at distance d (so that lights of different kinds are weighed alike):
    triangle, rect or disk (light or shape)   box of its corners; its normal, θo = 0, θe = π/2; φ = π·L̄·A;
                                             two-sided unless it emits on one side only
    sphere, box, cylinder, cone (convex)      its box; every direction (cos θo = −1); φ = π·L̄·A/4 (a convex
                                             body's mean projected area is A/4, Cauchy)
    point light of attenuation [0, 0, q]      its position; every direction; φ = π²·Ī/q (E = π·I/(q·d²))
    spot light of attenuation [0, 0, q]       the same about its axis, θo its inner angle, θe outer − inner
L̄ and Ī are the means over RGB (Ī of the diffuse and specular intensities, as the power table). Directional
lights, the environment, and point and spot lights with a constant or linear attenuation term (whose light does not
fall off as 1/d²) have no useful bounds: they are picked outside the tree (`emit_unbounded`), each with its
probability in the power table (`emit_pmf`), the tree with the rest. (pbrt gives each of its infinite lights
1/(n + 1) whatever its power: a dim fill light then takes half the light samples, and on a test scene with a dim
directional light and a dim point light beside five bounded ones the median pixel's variance was 40× the power
table's.) Emitters of no power are never picked (`emit_node` −1). A shape that moves is bounded where it is at
time 0 (its importance is then only a worse guess: emitters are picked by the same probability in light sampling
and in the MIS weights, so the image is unbiased whatever the guess).
"""

from __future__ import annotations

import numpy as np

from ..kernels import layout as L

#: Canonical bounding boxes (min, max) of the shapes an emitter entry may be (`layout.SHAPE_*`).
_CANONICAL_BOX = {
    L.SHAPE_SPHERE: ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0)),
    L.SHAPE_BOX: ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
    L.SHAPE_CYLINDER: ((-1.0, -1.0, 0.0), (1.0, 1.0, 1.0)),
    L.SHAPE_CONE: ((-1.0, -1.0, 0.0), (1.0, 1.0, 1.0)),
    L.SHAPE_DISK: ((-1.0, -1.0, 0.0), (1.0, 1.0, 0.0)),
    L.SHAPE_RECT: ((0.0, 0.0, 0.0), (1.0, 1.0, 0.0)),
}
_EVERY_DIRECTION = (0.0, 0.0, 1.0, -1.0)  # (w, cos θo) of a cone that holds every direction


def _row(lo, hi, w_cos, phi, cos_e=0.0, two_sided=False) -> np.ndarray:
    row = np.zeros(L.TREE_SIZE)
    row[L.TREE_MIN : L.TREE_MIN + 3] = lo
    row[L.TREE_MAX : L.TREE_MAX + 3] = hi
    row[L.TREE_W : L.TREE_W + 3] = w_cos[:3]
    row[L.TREE_COS_O] = w_cos[3]
    row[L.TREE_PHI] = phi
    row[L.TREE_COS_E] = cos_e
    row[L.TREE_TWO_SIDED] = 1.0 if two_sided else 0.0
    return row


def _unit(v) -> tuple:
    v = np.asarray(v, np.float64)
    n = float(np.linalg.norm(v))
    return tuple(v / n) if n > 0 else (0.0, 0.0, 1.0)


def _light_bounds(arrays: L.SceneArrays, j: int):
    """The bounds row of scene light j, or None when it is picked outside the tree."""
    kind = arrays.light_kind[j]
    vecs, sc = arrays.light_vecs[j], arrays.light_scalars[j]
    if kind == L.LIGHT_DIRECTIONAL:
        return None
    if kind in (L.LIGHT_POINT, L.LIGHT_SPOT):
        q = sc[L.LS_ATT_Q]
        if sc[L.LS_ATT_C] != 0.0 or sc[L.LS_ATT_L] != 0.0 or not q > 0.0:
            return None  # its light does not fall off as 1/d²
        pos = vecs[L.LV_POSITION]
        phi = np.pi * np.pi * float(np.mean(vecs[L.LV_DIFFUSE] + vecs[L.LV_SPECULAR])) / 2.0 / q
        if kind == L.LIGHT_POINT:
            return _row(pos, pos, _EVERY_DIRECTION, phi)
        cos_o, cos_i = sc[L.LS_COS_OUTER], sc[L.LS_COS_INNER]
        theta_i, theta_o = np.arccos(np.clip(cos_i, -1, 1)), np.arccos(np.clip(cos_o, -1, 1))
        return _row(pos, pos, (*_unit(vecs[L.LV_DIRECTION]), cos_i), phi, np.cos(max(theta_o - theta_i, 0.0)))
    le = float(np.mean(vecs[L.LV_DIFFUSE]))
    if kind == L.LIGHT_SPHERE:
        c, r = vecs[L.LV_POSITION], sc[L.LS_RADIUS]
        return _row(c - r, c + r, _EVERY_DIRECTION, np.pi * le * sc[L.LS_AREA] / 4.0)
    if kind == L.LIGHT_RECT:
        c, eu, ev = vecs[L.LV_POSITION], vecs[L.LV_EDGE_U], vecs[L.LV_EDGE_V]
        pts = np.array([c, c + eu, c + ev, c + eu + ev])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
    else:  # a disk: centre ± radius along each axis's share of its two tangents
        c = vecs[L.LV_POSITION]
        half = np.sqrt(vecs[L.LV_EDGE_U] ** 2 + vecs[L.LV_EDGE_V] ** 2)
        lo, hi = c - half, c + half
    return _row(lo, hi, (*_unit(vecs[L.LV_DIRECTION]), 1.0), np.pi * le * sc[L.LS_AREA],
                two_sided=sc[L.LS_TWO_SIDED] != 0.0)


def _shape_bounds(arrays: L.SceneArrays, em: L.Emitters, e: int) -> np.ndarray:
    """The bounds row of emissive shape entry e (EMIT_SHAPE or EMIT_SPHERE)."""
    s = em.emit_ref[e]
    info = arrays.shape_info[s]
    mat = arrays.materials[info[L.INFO_MATERIAL]]
    le = float(np.mean(mat[L.MAT_EMISSION : L.MAT_EMISSION + 3]))
    area = em.emit_area[e]
    geom = em.emit_geom[em.emit_slot[e]]
    if em.emit_kind[e] == L.EMIT_SPHERE:
        c, r = geom[3, :3], geom[3, 3]
        return _row(c - r, c + r, _EVERY_DIRECTION, np.pi * le * area / 4.0)
    kind = int(info[L.INFO_KIND])
    lo, hi = _CANONICAL_BOX[kind]
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    world = corners @ geom[:3, :3].T + geom[:3, 3]
    if kind in (L.SHAPE_DISK, L.SHAPE_RECT):  # flat: canonical +z, carried by object_from_world's transpose
        normal = _unit(arrays.shape_xform[s, 2, :3])
        return _row(world.min(axis=0), world.max(axis=0), (*normal, 1.0), np.pi * le * area,
                    two_sided=mat[L.MAT_ONE_SIDED] == 0.0)
    return _row(world.min(axis=0), world.max(axis=0), _EVERY_DIRECTION, np.pi * le * area / 4.0)


def _triangle_bounds(arrays: L.SceneArrays, em: L.Emitters, entries: np.ndarray) -> np.ndarray:
    """The bounds rows of emissive triangle entries (vectorised: a mesh may have millions)."""
    tris = em.emit_ref[entries]
    v = arrays.tri_verts[tris].astype(np.float64).reshape(-1, 3, 3)
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    length = np.linalg.norm(n, axis=1)
    mats = arrays.materials[arrays.tri_info[tris, L.INFO_MATERIAL]]
    rows = np.zeros((len(tris), L.TREE_SIZE))
    rows[:, L.TREE_MIN : L.TREE_MIN + 3] = v.min(axis=1)
    rows[:, L.TREE_MAX : L.TREE_MAX + 3] = v.max(axis=1)
    rows[:, L.TREE_W : L.TREE_W + 3] = n / np.maximum(length, 1e-300)[:, None]
    rows[:, L.TREE_COS_O] = 1.0
    rows[:, L.TREE_PHI] = np.pi * mats[:, L.MAT_EMISSION : L.MAT_EMISSION + 3].mean(axis=1) * em.emit_area[entries]
    rows[:, L.TREE_COS_E] = 0.0
    rows[:, L.TREE_TWO_SIDED] = (mats[:, L.MAT_ONE_SIDED] == 0.0).astype(np.float64)
    return rows


def emitter_bounds(em: L.Emitters, arrays: L.SceneArrays) -> tuple[np.ndarray, np.ndarray]:
    """(rows float64 (ne, TREE_SIZE): each entry's bounds, φ 0 for one never picked; unbounded bool (ne,): the
    entries picked outside the tree)."""
    ne = len(em.emit_kind)
    rows = np.zeros((ne, L.TREE_SIZE))
    unbounded = np.zeros(ne, bool)
    tri = np.flatnonzero(em.emit_kind == L.EMIT_TRIANGLE)
    if len(tri):
        rows[tri] = _triangle_bounds(arrays, em, tri)
    for e in np.flatnonzero(em.emit_kind != L.EMIT_TRIANGLE):
        kind = em.emit_kind[e]
        row = None
        if kind == L.EMIT_LIGHT:
            row = _light_bounds(arrays, int(em.emit_ref[e]))
        elif kind in (L.EMIT_SHAPE, L.EMIT_SPHERE):
            row = _shape_bounds(arrays, em, int(e))
        if row is None:
            unbounded[e] = True
        else:
            rows[e] = row
    rows[~np.isfinite(rows[:, L.TREE_PHI]) | (rows[:, L.TREE_PHI] < 0.0), L.TREE_PHI] = 0.0
    return rows, unbounded


def with_light_tree(em: L.Emitters, arrays: L.SceneArrays) -> L.Emitters:
    """The emitter table `em` with its light tree (layout.Emitters tree_nodes, tree_link, emit_node,
    emit_unbounded), for selection by `kernels.light_tree`."""
    from ..kernels.light_tree_build import build_light_tree

    rows, unbounded = emitter_bounds(em, arrays)
    power = np.asarray(em.emit_pmf) > 0.0  # (an emitter of no power is never picked, as in the power table)
    outside = np.flatnonzero(unbounded & power).astype(np.int32)
    inside = np.flatnonzero(~unbounded & (rows[:, L.TREE_PHI] > 0.0) & power)
    emit_node = np.full(len(rows), -1, np.int32)
    emit_node[outside] = -2
    m = len(inside)
    nodes = np.zeros((max(2 * m - 1, 0), L.TREE_SIZE))
    link = np.full((len(nodes), 3), -1, np.int32)
    if m == 1:
        nodes[0] = rows[inside[0]]
        link[0, L.TREE_ITEM] = inside[0]
        emit_node[inside[0]] = 0
    elif m > 1:
        leaf_of = np.full(m, -1, np.int32)
        build_light_tree(np.ascontiguousarray(rows[inside]), nodes, link, leaf_of)
        leaves = link[:, L.TREE_FIRST] < 0
        link[leaves, L.TREE_ITEM] = inside[link[leaves, L.TREE_ITEM]]
        emit_node[inside] = leaf_of
    # the lights outside the tree keep the power table's probabilities; the tree has the rest
    cdf = np.cumsum(np.asarray(em.emit_pmf)[outside])
    if len(cdf) and (m == 0 or cdf[-1] > 1.0):
        cdf /= cdf[-1]
    return em._replace(tree_nodes=nodes, tree_link=link, emit_node=emit_node, emit_unbounded=outside,
                       unbounded_cdf=np.ascontiguousarray(cdf, np.float64))
