"""The light tree (`kernels.light_tree`, built by `compile.light_tree`): its probabilities form a distribution at
every shading point, sampling follows them (χ²), the probability found by walking up from a leaf is the one the
descent used, an emitter that cannot light a point is neither picked there nor given an MIS weight from there,
and the tree holds its emitters (bounds, power, normal cones). The renders themselves (tree against power table,
the Cornell box against Mitsuba) are in tests/methods."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from chi2 import chi2_discrete, significance_level

import lumos
from lumos.kernels import layout as L
from lumos.kernels.emitters import emitter_pdf, select_emitter, selection_pmf
from lumos.kernels.light_tree import importance, tree_pick
from lumos.kernels.views import lighting_of, surfaces_of
from lumos.methods import compile_for

LEVEL = significance_level(0.01, 3)

EMISSIVE = {"kd": 0.0, "emission": 2.0}
#: Every kind of emitter the tree holds, and two it leaves outside (the default point light, the directional one).
SCENE = {
    "objects": [
        {"type": "mesh", "material": EMISSIVE, "vertices": [[-2, 1, -2], [-1, 1, -2], [-2, 1, -1], [-1, 1.5, -1],
                                                            [-2, 2, -1.5]],
         "faces": [[0, 1, 2], [1, 3, 2], [2, 3, 4], [0, 2, 4]]},
        {"type": "triangle", "vertices": [[1, -1, 1], [2, -1, 1], [1, -1, 2]], "two_sided": False,
         "material": {"kd": 0.0, "emission": 5.0}},
        {"type": "sphere", "center": [2, 2, -2], "radius": 0.3, "material": EMISSIVE},
        {"type": "box", "min": [-3, -1, 2], "max": [-2.5, -0.5, 2.6], "material": EMISSIVE},
        {"type": "disk", "center": [0, 3, 0], "normal": [0, -1, 0.2], "radius": 0.4, "two_sided": False,
         "material": EMISSIVE},
    ],
    "lights": [
        {"type": "area", "shape": "rect", "corner": [-0.5, 2.5, -0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1],
         "radiance": 3.0},
        {"type": "area", "shape": "sphere", "center": [0, 0, -3], "radius": 0.2, "radiance": 10.0},
        {"type": "area", "shape": "disk", "center": [3, 0, 0], "normal": [-1, 0, 0], "radius": 0.5, "radiance": 4.0,
         "two_sided": True},
        {"type": "spot", "position": [0, 4, 2], "direction": [0, -1, 0], "intensity": 6.0, "angle": 40,
         "inner_angle": 20, "attenuation": [0, 0, 1]},
        {"type": "point", "position": [-3, 3, 3], "intensity": 2.0, "attenuation": [0, 0, 1]},
        {"type": "point", "position": [3, 3, 3], "intensity": 0.5},  # no fall-off: outside the tree
        {"type": "directional", "direction": [0, -1, 0.2], "intensity": 0.3},  # outside the tree
    ],
}


@pytest.fixture(scope="module")
def compiled():
    scene = lumos.load_scene(SCENE)
    return compile_for(scene, scene.render.model_copy(update={"method": "path"}))


def _points(n, seed):
    """n shading points in the scene's box and unit normals."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(-3.5, 3.5, (n, 3))
    nrm = rng.normal(size=(n, 3))
    return p, nrm / np.linalg.norm(nrm, axis=1, keepdims=True)


@numba.njit(cache=True)
def _pmfs(em, points, normals):
    """selection_pmf (the tree's, or the power table's) of every entry at every point: (n, ne)."""
    out = np.zeros((points.shape[0], em.emit_kind.shape[0]))
    for i in range(points.shape[0]):
        p = (points[i, 0], points[i, 1], points[i, 2])
        n = (normals[i, 0], normals[i, 1], normals[i, 2])
        for e in range(em.emit_kind.shape[0]):
            out[i, e] = selection_pmf(em, e, p, n)
    return out


@numba.njit(cache=True)
def _picks(em, p, n, us):
    """tree_pick at (p, n) for each u: entries and the probabilities the descent multiplied."""
    entries = np.empty(us.shape[0], np.int64)
    pmfs = np.empty(us.shape[0])
    for i in range(us.shape[0]):
        entries[i], pmfs[i] = tree_pick(em, p, n, us[i])
    return entries, pmfs


@numba.njit(cache=True)
def _importances(em, p, n):
    out = np.empty(em.tree_nodes.shape[0])
    for k in range(em.tree_nodes.shape[0]):
        out[k] = importance(em.tree_nodes, k, p, n)
    return out


def test_every_emitter_has_its_place(compiled):
    """Lights without useful bounds (the point light with no fall-off, the directional one) are outside the tree;
    every other emitter has a leaf that names it; the children of a node are inside its bounds and its normal
    cone, and its power is theirs."""
    em = compiled.emitters
    unbounded = em.emit_unbounded
    assert sorted(em.emit_kind[unbounded]) == [L.EMIT_LIGHT, L.EMIT_LIGHT]
    assert sorted(compiled.arrays.light_kind[em.emit_ref[unbounded]]) == [L.LIGHT_POINT, L.LIGHT_DIRECTIONAL]
    inside = np.flatnonzero(em.emit_node >= 0)
    assert len(inside) + len(unbounded) == len(em.emit_kind)
    assert len(em.tree_nodes) == 2 * len(inside) - 1
    assert np.array_equal(em.tree_link[em.emit_node[inside], L.TREE_ITEM], inside)
    nodes, link = em.tree_nodes, em.tree_link
    for k in np.flatnonzero(link[:, L.TREE_FIRST] >= 0):
        for c in (link[k, L.TREE_FIRST], link[k, L.TREE_FIRST] + 1):
            assert link[c, L.TREE_PARENT] == k
            assert np.all(nodes[c, L.TREE_MIN:L.TREE_MIN + 3] >= nodes[k, L.TREE_MIN:L.TREE_MIN + 3])
            assert np.all(nodes[c, L.TREE_MAX:L.TREE_MAX + 3] <= nodes[k, L.TREE_MAX:L.TREE_MAX + 3])
            # the child's cone inside the parent's: angle between axes + child's half-angle <= parent's
            between = math.acos(np.clip(nodes[c, L.TREE_W:L.TREE_W + 3] @ nodes[k, L.TREE_W:L.TREE_W + 3], -1, 1))
            half = math.acos(np.clip(nodes[c, L.TREE_COS_O], -1, 1))
            assert nodes[k, L.TREE_COS_O] == -1.0 or between + half <= math.acos(nodes[k, L.TREE_COS_O]) + 1e-9
        kids = nodes[link[k, L.TREE_FIRST]:link[k, L.TREE_FIRST] + 2, L.TREE_PHI]
        assert nodes[k, L.TREE_PHI] == pytest.approx(kids.sum(), rel=1e-12)


def _descent(em, p, n):
    """The naive twin of the descent: (each entry's probability, the probability of reaching a node whose two
    children both have importance 0, where `tree_pick` returns no emitter), by following every branch."""
    imp = _importances(em, tuple(p), tuple(n))
    cdf = em.unbounded_cdf
    p_unb = cdf[-1] if len(cdf) else 0.0
    probs = np.zeros(len(em.emit_kind))
    probs[em.emit_unbounded] = np.diff(cdf, prepend=0.0)
    dead = 0.0
    todo = [(0, 1.0 - p_unb)]
    while todo:
        k, mass = todo.pop()
        first = em.tree_link[k, L.TREE_FIRST]
        if first < 0:
            probs[em.tree_link[k, L.TREE_ITEM]] += mass
            continue
        i0, i1 = imp[first], imp[first + 1]
        if i0 + i1 == 0.0:
            dead += mass
            continue
        todo += [(first, mass * i0 / (i0 + i1)), (first + 1, mass * i1 / (i0 + i1))]
    return probs, dead


def test_lights_outside_the_tree_keep_their_power_share(compiled):
    """The directional light and the point light without fall-off are picked with their power-table
    probabilities; the tree has the rest."""
    em = compiled.emitters
    np.testing.assert_allclose(np.diff(em.unbounded_cdf, prepend=0.0), em.emit_pmf[em.emit_unbounded], rtol=1e-12)
    points, normals = _points(3, 8)
    pmfs = _pmfs(em, points, normals)
    np.testing.assert_allclose(pmfs[:, em.emit_unbounded],
                               np.broadcast_to(em.emit_pmf[em.emit_unbounded], (3, len(em.emit_unbounded))), rtol=1e-12)


def test_probabilities_sum_to_one_at_every_point(compiled):
    """Σ_e pmf(e | p, n) = 1 at random shading points, less the probability of a dead end: a node whose merged
    normal cone reaches p while neither child's does (pbrt's tree has them too: that sample finds no light, as
    none below the node can light p). tree_pmf equals the naive descent's probabilities everywhere."""
    em = compiled.emitters
    points, normals = _points(150, 1)
    pmfs = _pmfs(em, points, normals)
    deads = []
    for p, n, pmf in zip(points, normals, pmfs):
        probs, dead = _descent(em, p, n)
        np.testing.assert_allclose(pmf, probs, rtol=1e-12, atol=1e-300)
        assert pmf.sum() + dead == pytest.approx(1.0, rel=1e-12)
        deads.append(dead)
    deads = np.array(deads)
    assert np.mean(deads == 0.0) > 0.8 and deads.max() < 0.2
    np.testing.assert_allclose(pmfs[deads == 0.0].sum(axis=1), 1.0, rtol=1e-12)


def test_the_walk_up_gives_the_probability_the_descent_used(compiled):
    """For every pick, tree_pmf of the picked entry equals the product tree_pick multiplied on its way down."""
    em = compiled.emitters
    points, normals = _points(20, 2)
    us = np.random.default_rng(3).random(500)
    for p, n in zip(points, normals):
        entries, pmfs = _picks(em, tuple(p), tuple(n), us)
        walked = _pmfs(em, p[None], n[None])[0]
        assert np.all(entries >= 0)
        np.testing.assert_allclose(walked[entries], pmfs, rtol=1e-12)


@pytest.mark.parametrize("where", [0, 1, 2])
def test_picks_follow_the_probabilities(compiled, where):
    """χ²: the entries picked by uniform u at a point are distributed as tree_pmf says."""
    em = compiled.emitters
    points, normals = _points(3, 4)
    p, n = points[where], normals[where]
    entries, _ = _picks(em, tuple(p), tuple(n), np.random.default_rng(5 + where).random(100_000))
    counts = np.bincount(entries, minlength=len(em.emit_kind))
    assert chi2_discrete(counts, _pmfs(em, p[None], n[None])[0]) > LEVEL


def test_selection_prefers_what_is_near():
    """Two equal lights, one near the point and one far: the tree gives the near one most of the picks, the power
    table half."""
    lights = [{"type": "area", "shape": "sphere", "center": [x, 0, 0], "radius": 0.1, "radiance": 1.0}
              for x in (1.0, 20.0)]
    scene = lumos.load_scene({"lights": lights})
    for selection, near in (("tree", 0.99), ("power", 0.5)):
        settings = scene.render.model_copy(update={"method": "path", "light_selection": selection})
        em = compile_for(scene, settings).emitters
        pmfs = _pmfs(em, np.zeros((1, 3)), np.array([[0.0, 1.0, 0.0]]))[0]
        assert pmfs[em.light_emit[0]] >= near if selection == "tree" else pmfs[em.light_emit[0]] == near


@numba.njit(cache=True)
def _selection(em, lit, surf, e, p, n, us, wi, dist, n_geo):
    """(how often select_emitter at (p, n) picks e over us, selection_pmf of e, emitter_pdf of the direction wi)."""
    hits = 0
    for i in range(us.shape[0]):
        if select_emitter(em, p, n, us[i])[0] == e:
            hits += 1
    return hits, selection_pmf(em, e, p, n), emitter_pdf(em, lit, surf, e, p, n, wi, dist, n_geo, 0, 0, 0.0)


def test_an_emitter_that_cannot_light_a_point_is_never_picked_there(compiled):
    """Behind the one-sided emissive triangle (its front is the side its normal faces, -y), its importance is 0:
    select_emitter never picks it, its pmf is 0, and emitter_pdf is 0, so the emission that a BSDF
    ray finds there gets the full weight (path_trace._emission_weight); in front of it, it is picked."""
    em, sa = compiled.emitters, compiled.arrays
    tris = np.flatnonzero(em.emit_kind == L.EMIT_TRIANGLE)
    one_sided = sa.materials[sa.tri_info[em.emit_ref[tris], L.INFO_MATERIAL], L.MAT_ONE_SIDED] != 0
    tri = int(tris[one_sided][0])
    v = sa.tri_verts[em.emit_ref[tri]].astype(np.float64).reshape(3, 3)
    normal = np.cross(v[1] - v[0], v[2] - v[0])
    normal /= np.linalg.norm(normal)
    centre = v.mean(axis=0)
    us = np.random.default_rng(6).random(20_000)
    for side, expect_picked in ((-1.0, False), (1.0, True)):
        p = centre + side * 3.0 * normal + np.array([0.05, 0.0, 0.02])  # (farther than its box's bounding sphere)
        to = centre - p
        dist = float(np.linalg.norm(to))
        hits, pmf, pdf = _selection(em, lighting_of(sa), surfaces_of(sa), tri, tuple(p), (1.0, 0.0, 0.0), us,
                                    tuple(to / dist), dist, tuple(normal))
        if expect_picked:
            assert hits > 0 and pmf > 0.0 and pdf > 0.0
        else:
            assert hits == 0 and pmf == 0.0 and pdf == 0.0
            imp = _importances(em, tuple(p), (1.0, 0.0, 0.0))
            assert imp[em.emit_node[tri]] == 0.0


def test_power_selection_keeps_the_table():
    """light_selection: power builds no tree: selection is the power table's."""
    scene = lumos.load_scene(SCENE)
    em = compile_for(scene, scene.render.model_copy(update={"method": "path", "light_selection": "power"})).emitters
    assert len(em.tree_nodes) == 0 and len(em.emit_unbounded) == 0
    points, normals = _points(5, 7)
    pmfs = _pmfs(em, points, normals)
    assert np.all(pmfs == em.emit_pmf[None, :])
