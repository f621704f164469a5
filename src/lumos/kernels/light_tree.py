"""Light selection by a light BVH (pbrt-v4's `BVHLightSampler`, Pharr, Jakob & Humphreys, *Physically Based
Rendering*, 4th ed., §12.6.3): the emitter for a shading point p with normal n is picked by descending a binary
tree over the emitters, choosing each child in proportion to an estimate of the light it sends to p.

    e, pmf = tree_pick(em, p, n, u)          # an emitter entry and its probability (-1, 0.0: none)
    pmf = tree_pmf(em, e, p, n)              # the same probability, for an entry found otherwise (MIS)
    imp = importance(em.tree_nodes, k, p, n) # the estimate for node k

A node's row of `tree_nodes` (layout.TREE_*) holds the `LightBounds` of its emitters: their bounding box, their
summed power φ, the cone (w, cos θo) that bounds their normals (the directions they emit around), the angle θe
beyond the normal over which they still emit (π/2 for area emitters: cos θe = 0), and whether one of them emits on
both sides. `importance` is pbrt's `LightBounds::Importance`: φ·cos θ′/d², θ′ the smallest angle between the
cone's directions and the direction to p once the box's extent as seen from p (θb) is taken off, zero beyond θe,
times the cosine at p itself with θb taken off (|cos|: two-sided, so light sampling for transmission is served
too). d² is the squared distance to the box's centre, clamped below at half its diagonal (pbrt's clamp).

Lights with no useful bounds (directional lights, the environment, point and spot lights whose attenuation is not
the inverse square) are sampled outside the tree, as pbrt samples its infinite lights, but each with its
probability in the power table (`unbounded_cdf`; pbrt gives each 1/(n + 1)), the tree with the rest. A node's
children are its first child and the node after it. `tree_pmf` walks from the emitter's leaf up to the root
(`TREE_PARENT`), which needs no bit trail and no depth limit, and multiplies the same factors `tree_pick`
multiplied on its way down (in the other order: equal to rounding). A lone emitter in the tree is picked without
looking at its importance (where it is zero the emitter's own sampler finds nothing there either), as pbrt's
`PMF` does. The tree is built at compile time by `kernels.light_tree_build` (called by `compile.light_tree`).
"""

import math

import numpy as np

from .jit import njit_inline
from .layout import TREE_COS_E, TREE_COS_O, TREE_FIRST, TREE_ITEM, TREE_MAX, TREE_MIN, TREE_PARENT, TREE_PHI
from .layout import TREE_TWO_SIDED, TREE_W

#: The largest float64 below 1: a random number rescaled inside a child stays in [0, 1).
ONE_BELOW = 1.0 - 2.0 ** -53


@njit_inline
def _cos_sub(sin_a, cos_a, sin_b, cos_b):
    """cos(max(0, a − b)) from the sines and cosines of a, b in [0, π] (pbrt's cosSubClamped)."""
    if cos_a > cos_b:
        return 1.0
    return cos_a * cos_b + sin_a * sin_b


@njit_inline
def _sin_sub(sin_a, cos_a, sin_b, cos_b):
    """sin(max(0, a − b)) (pbrt's sinSubClamped)."""
    if cos_a > cos_b:
        return 0.0
    return sin_a * cos_b - cos_a * sin_b


@njit_inline
def importance(nodes, k, p, n):
    """pbrt's LightBounds::Importance of node k (a row of `nodes`) at point p with unit normal n (a zero n: no
    surface, no cosine at p)."""
    x0, y0, z0 = nodes[k, TREE_MIN], nodes[k, TREE_MIN + 1], nodes[k, TREE_MIN + 2]
    x1, y1, z1 = nodes[k, TREE_MAX], nodes[k, TREE_MAX + 1], nodes[k, TREE_MAX + 2]
    cx, cy, cz = 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)
    dx, dy, dz = p[0] - cx, p[1] - cy, p[2] - cz
    dist2 = dx * dx + dy * dy + dz * dz
    r2 = 0.25 * ((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0) + (z1 - z0) * (z1 - z0))  # the bounding sphere's
    d2 = max(dist2, math.sqrt(r2), 1e-30)  # pbrt clamps d² at half the diagonal
    inv = 1.0 / math.sqrt(dist2) if dist2 > 0.0 else 0.0
    wx, wy, wz = dx * inv, dy * inv, dz * inv  # from the box's centre to p
    # θb: the directions the box subtends from p (all of them from inside it or its bounding sphere)
    inside = x0 <= p[0] <= x1 and y0 <= p[1] <= y1 and z0 <= p[2] <= z1
    if inside or dist2 <= r2:
        cos_b, sin_b = -1.0, 0.0
    else:
        sin2 = r2 / dist2
        cos_b, sin_b = math.sqrt(max(0.0, 1.0 - sin2)), math.sqrt(sin2)
    cos_w = nodes[k, TREE_W] * wx + nodes[k, TREE_W + 1] * wy + nodes[k, TREE_W + 2] * wz
    if nodes[k, TREE_TWO_SIDED] != 0.0:
        cos_w = abs(cos_w)
    sin_w = math.sqrt(max(0.0, 1.0 - cos_w * cos_w))
    cos_o = nodes[k, TREE_COS_O]
    sin_o = math.sqrt(max(0.0, 1.0 - cos_o * cos_o))
    cos_x = _cos_sub(sin_w, cos_w, sin_o, cos_o)  # θw − θo: the cone's nearest direction to p
    sin_x = _sin_sub(sin_w, cos_w, sin_o, cos_o)
    cos_p = _cos_sub(sin_x, cos_x, sin_b, cos_b)  # and the box's extent
    if cos_p <= nodes[k, TREE_COS_E]:
        return 0.0
    imp = nodes[k, TREE_PHI] * cos_p / d2
    if n[0] != 0.0 or n[1] != 0.0 or n[2] != 0.0:
        cos_i = abs(wx * n[0] + wy * n[1] + wz * n[2])
        sin_i = math.sqrt(max(0.0, 1.0 - cos_i * cos_i))
        imp *= _cos_sub(sin_i, cos_i, sin_b, cos_b)
    return max(imp, 0.0)


@njit_inline
def _unbounded_share(em):
    """The probability of picking one of the lights outside the tree."""
    n_unb = em.unbounded_cdf.shape[0]
    return em.unbounded_cdf[n_unb - 1] if n_unb > 0 else 0.0


@njit_inline
def _unbounded_pmf(em, k):
    """The probability of picking the k-th light outside the tree."""
    return em.unbounded_cdf[k] - (em.unbounded_cdf[k - 1] if k > 0 else 0.0)


@njit_inline
def tree_pick(em, p, n, u):
    """The emitter entry for shading point p (unit normal n) from u ∈ [0, 1), and its probability; (-1, 0.0)
    where no emitter can light p."""
    p_unb = _unbounded_share(em)
    if u < p_unb:
        n_unb = em.unbounded_cdf.shape[0]
        k = 0
        while k < n_unb - 1 and not u < em.unbounded_cdf[k]:
            k += 1
        return np.int64(em.emit_unbounded[k]), _unbounded_pmf(em, k)
    nodes = em.tree_nodes
    if nodes.shape[0] == 0:
        return np.int64(-1), 0.0
    u = min((u - p_unb) / (1.0 - p_unb), ONE_BELOW)
    pmf = 1.0 - p_unb
    k = 0
    link = em.tree_link
    while link[k, TREE_FIRST] >= 0:
        c0 = link[k, TREE_FIRST]
        i0 = importance(nodes, c0, p, n)
        i1 = importance(nodes, c0 + 1, p, n)
        total = i0 + i1
        if not total > 0.0:
            return np.int64(-1), 0.0
        p0 = i0 / total
        if u < p0:
            u = min(u / p0, ONE_BELOW)
            pmf *= p0
            k = c0
        else:
            u = min((u - p0) / (1.0 - p0), ONE_BELOW)
            pmf *= i1 / total
            k = c0 + 1
    return np.int64(link[k, TREE_ITEM]), pmf


@njit_inline
def tree_pmf(em, e, p, n):
    """The probability that `tree_pick` at p (normal n) picks emitter entry e."""
    node = em.emit_node[e]
    if node == -1:
        return 0.0  # never picked
    if node == -2:  # outside the tree
        for k in range(em.emit_unbounded.shape[0]):
            if em.emit_unbounded[k] == e:
                return _unbounded_pmf(em, k)
        return 0.0
    p_unb = _unbounded_share(em)
    nodes = em.tree_nodes
    link = em.tree_link
    pmf = 1.0 - p_unb
    while node > 0:
        parent = link[node, TREE_PARENT]
        c0 = link[parent, TREE_FIRST]
        i0 = importance(nodes, c0, p, n)
        i1 = importance(nodes, c0 + 1, p, n)
        mine = i0 if node == c0 else i1
        if not mine > 0.0:
            return 0.0
        pmf *= mine / (i0 + i1)
        node = parent
    return pmf
