"""Constructive solid geometry (`kernels.csg`, `compile.csg`) against the NumPy twins in `naive.py`.

Walking a ray through a csg object (closest hit, then again from the same origin with t_min = that hit's t) must
give crossings that alternate entering and leaving, with the twin's point-in-solid test agreeing between and
around them; the normal there is the hit solid's, turned outward of the combined solid; the material is the
hit solid's (or the nearest csg node's); raycast renders of a die match the naive renderer.
"""

import numpy as np
import pytest
import trimesh
from conftest import compile_dict, geometry, render, trace_any
from naive import csg_solids, hit_csg, inside_solid, render_classic_csg, transform_matrix, unit

import lumos
from lumos.kernels import layout as L
from lumos.kernels.surface import surface_at
from lumos.kernels.traverse import closest_hit
from lumos.kernels.views import surfaces_of


def walk(arrays, o, d, time=0.0, max_steps=200):
    """Every crossing of the ray o + t·d (t > 0), nearest first: a list of dicts (t, entering, n, material,
    object, ref, part), each hit found by `closest_hit` with t_min = the previous hit's t."""
    geo, surf = geometry(arrays), surfaces_of(arrays)
    stack, stack_t = np.empty(64, np.int64), np.empty(64)
    o = tuple(float(x) for x in o)
    d = tuple(float(x) for x in d)
    out, t_min = [], 0.0
    for _ in range(max_steps):
        t, ref, b1, b2, part = closest_hit(geo, o, d, t_min, 1e30, stack, stack_t, float(time))
        if t < 0.0:
            break
        p, n_geo, n_sh, u, v, mat, obj, light = surface_at(surf, o, d, t, ref, b1, b2, part, float(time))
        out.append(dict(t=t, entering=b1 > 0.0, n=np.array(n_geo), n_sh=np.array(n_sh), material=int(mat),
                        object=int(obj), light=int(light), ref=int(ref), part=int(part)))
        t_min = t
    return out


def scene_of(*objects):
    return {"objects": list(objects)}


# ------------------------------------------------------------------------------- random trees and rays


def random_transform(rng):
    return {"translate": rng.uniform(-0.3, 0.3, 3).tolist(), "rotate": rng.uniform(-60, 60, 3).tolist(),
            "scale": rng.uniform(0.7, 1.3, 3).tolist()}


def random_leaf(rng):
    if rng.random() < 0.5:
        leaf = {"type": "sphere", "center": rng.uniform(-0.4, 0.4, 3).tolist(), "radius": float(rng.uniform(0.5, 1.1))}
    else:
        lo = rng.uniform(-1.0, -0.1, 3)
        leaf = {"type": "box", "min": lo.tolist(), "max": (lo + rng.uniform(0.7, 1.6, 3)).tolist()}
    if rng.random() < 0.5:
        leaf["transform"] = random_transform(rng)
    if rng.random() < 0.5:
        leaf["material"] = {"kd": rng.uniform(0, 1, 3).tolist()}
    return leaf


def random_tree(rng, depth):
    if depth == 0:
        return random_leaf(rng)
    node = {"type": "csg", "op": str(rng.choice(["union", "intersection", "difference"])),
            "left": random_tree(rng, depth - 1), "right": random_tree(rng, depth - 1 if rng.random() < 0.7 else 0)}
    if rng.random() < 0.6:
        node["transform"] = random_transform(rng)
    return node


def icosphere(center, radius, subdivisions=2):
    s = trimesh.creation.icosphere(subdivisions=subdivisions)
    return {"type": "mesh", "vertices": (s.vertices * radius + center).tolist(), "faces": s.faces.tolist()}


def mesh_tree():
    """A closed mesh in a two-level tree, under a rotated, scaled node."""
    return {"type": "csg", "op": "difference", "material": {"kd": 0.5},
            "transform": {"rotate": [20, 35, 0], "scale": [1.2, 1.0, 0.9]},
            "left": {"type": "csg", "op": "union",
                     "left": {"type": "box", "min": [-1, -0.6, -0.6], "max": [0.4, 0.6, 0.6]},
                     "right": icosphere([0.5, 0.0, 0.0], 0.75)},
            "right": {"type": "sphere", "center": [0.9, 0.3, 0.2], "radius": 0.45, "material": {"kd": 0.1}}}


def random_rays(rng, n, obj, inside_fraction=0.3):
    """Rays from a sphere of radius 4 aimed at points of the solid (found by the twin), and some starting
    anywhere near the middle; None if the solid seems empty."""
    candidates = rng.uniform(-1.5, 1.5, (20000, 3))
    targets = candidates[inside_solid(obj, candidates)]
    if len(targets) < 10:
        return None
    target = targets[rng.integers(0, len(targets), n)]
    o = unit(rng.normal(size=(n, 3))) * 4.0
    near = rng.random(n) < inside_fraction
    o[near] = rng.uniform(-1.0, 1.0, (near.sum(), 3))
    d = unit(target - o + 0.1 * rng.normal(size=(n, 3)))
    return o, d


def check_walks(obj, arrays, o, d):
    """Walk every ray and test the crossings against the twin; returns (number of crossings, first hits)."""
    points, expect, where = [], [], []
    first_t = np.full(len(o), np.inf)
    total = 0
    for i, (oi, di) in enumerate(zip(o, d)):
        hits = walk(arrays, oi, di)
        total += len(hits)
        if not hits:
            points.append(oi + di)  # a ray that hits nothing never passes through the solid
            expect.append(False)
            where.append((i, "miss"))
            continue
        first_t[i] = hits[0]["t"]
        ts = np.array([h["t"] for h in hits])
        entering = np.array([h["entering"] for h in hits])
        assert (np.diff(ts) > 0).all()
        assert (entering[1:] != entering[:-1]).all(), f"ray {i}: crossings do not alternate: {entering}"
        assert not entering[-1], f"ray {i}: the last crossing enters"
        # the normal is outward of the combined solid: against d entering, along d leaving
        dots = np.array([h["n"] @ di for h in hits])
        assert ((dots < 0) == entering).all(), f"ray {i}: normals {dots} entering {entering}"
        bounds = np.concatenate([[0.0], ts, [ts[-1] + 10.0]])
        for k in range(len(ts) + 1):  # half-way along each segment: inside exactly after an entering crossing
            if bounds[k + 1] - bounds[k] > 1e-6:
                points.append(oi + 0.5 * (bounds[k] + bounds[k + 1]) * di)
                expect.append(bool(entering[k - 1]) if k > 0 else not entering[0])
                where.append((i, f"segment {k}"))
        for k, t in enumerate(ts):  # just before and just after each crossing
            gap = min(bounds[k + 1] - bounds[k], bounds[k + 2] - bounds[k + 1])
            if gap > 1e-6:
                delta = min(1e-5, gap / 3)
                points += [oi + (t - delta) * di, oi + (t + delta) * di]
                expect += [not entering[k], bool(entering[k])]
                where += [(i, f"before crossing {k}"), (i, f"after crossing {k}")]
    got = inside_solid(obj, np.array(points))
    bad = [w for w, g, e in zip(where, got, expect) if g != e]
    assert not bad, f"{len(bad)} of {len(points)} points disagree with the twin, e.g. {bad[:5]}"
    return total, first_t


def agree(t_got, t_want, tol):
    """Fraction of rays where both miss or both hit at the same t (relative tolerance)."""
    both_miss = np.isinf(t_got) & np.isinf(t_want)
    with np.errstate(invalid="ignore"):
        close = np.abs(np.where(both_miss, 0.0, t_got - t_want)) <= tol * (1.0 + np.abs(t_want))
    return (both_miss | close).mean()


def test_membership_random_trees(rng):
    total = trees = 0
    while trees < 6:
        obj = random_tree(rng, 2)
        obj["material"] = {"kd": 0.7}
        rays = random_rays(rng, 60, obj)
        if rays is None:
            continue
        trees += 1
        o, d = rays
        arrays = compile_dict(scene_of(obj)).arrays
        n, first_t = check_walks(obj, arrays, o, d)
        total += n
        # the first hit is the twin's (rays through near-coincident crossings aside)
        t_want, _, _, _ = hit_csg(obj, o, d)
        assert agree(first_t, t_want, 1e-7) >= 0.97
    assert total > 500


def test_membership_with_a_closed_mesh(rng):
    obj = mesh_tree()
    arrays = compile_dict(scene_of(obj)).arrays
    n_bvh = compile_dict(scene_of(obj)).n_triangles
    assert n_bvh == 0  # the mesh's triangles stay out of the BVH
    o, d = random_rays(rng, 120, obj)
    n, first_t = check_walks(obj, arrays, o, d)
    assert n > 200
    t_want, _, _, _ = hit_csg(obj, o, d)
    assert agree(first_t, t_want, 1e-5) >= 0.97


def test_membership_cylinders_and_cones(rng):
    """Capped cylinders and cones (spans clipped by their caps; a cone's lower nappe only) under rotations."""
    obj = {"type": "csg", "op": "difference", "material": {"kd": 0.5}, "transform": {"rotate": [30, 10, -20]},
           "left": {"type": "csg", "op": "union",
                    "left": {"type": "cylinder", "base": [0, -1, 0], "top": [0, 0.6, 0], "radius": 0.5},
                    "right": {"type": "cone", "base": [-0.2, 0.2, 0.1], "top": [1.0, 0.9, 0.3], "radius": 0.6,
                              "transform": {"scale": [1.0, 1.3, 0.8]}}},
           "right": {"type": "csg", "op": "intersection",
                     "left": {"type": "box", "min": [-1, -0.3, -1], "max": [1, 0.0, 1]},
                     "right": {"type": "cone", "base": [0, -0.6, 0], "top": [0, 0.4, 0], "radius": 0.8}}}
    arrays = compile_dict(scene_of(obj)).arrays
    o, d = random_rays(rng, 150, obj)
    # and rays along the cylinder's axis (parallel to its side)
    axis = transform_matrix(rotate=[30, 10, -20])[:3, :3] @ [0.0, 1.0, 0.0]
    starts = rng.uniform(-0.6, 0.6, (30, 3)) - 3.0 * axis
    o, d = np.concatenate([o, starts]), np.concatenate([d, np.tile(axis, (30, 1))])
    n, _ = check_walks(obj, arrays, o, d)
    assert n > 300


def test_mesh_rays_through_shared_edges_count_once():
    """Rays through the diagonals of a mesh cube's faces meet two triangles at the same point: one crossing."""
    cube = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    obj = {"type": "csg", "op": "union", "material": {"kd": 0.5},
           "left": {"type": "mesh", "vertices": cube.vertices.tolist(), "faces": cube.faces.tolist()},
           "right": {"type": "sphere", "center": [2.0, 2.0, 2.0], "radius": 0.5}}
    arrays = compile_dict(scene_of(obj)).arrays
    o, d = [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            for a, b in [(0.0, 0.0), (0.25, 0.25), (0.25, -0.25)]:  # the centre lies on both diagonals
                dd = np.zeros(3)
                dd[axis] = -sign
                oo = np.zeros(3)
                oo[axis] = 4.0 * sign
                oo[(axis + 1) % 3], oo[(axis + 2) % 3] = a, b
                o.append(oo)
                d.append(dd)
    o, d = np.array(o), np.array(d)
    check_walks(obj, arrays, o, d)
    for oi, di in zip(o, d):
        assert [round(h["t"], 12) for h in walk(arrays, oi, di)] == [3.5, 4.5]


def test_crossings_beyond_one_sweep_pass():
    """40 spheres in a row minus a thin slab: more crossings on one line than a sweep pass holds."""
    chain = {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 0.3}
    for k in range(1, 40):
        chain = {"type": "csg", "op": "union", "left": chain,
                 "right": {"type": "sphere", "center": [0.7 * k, 0.0, 0.0], "radius": 0.3}}
    obj = {"type": "csg", "op": "difference", "material": {"kd": 0.5}, "left": chain,
           "right": {"type": "box", "min": [-1, -1, -0.02], "max": [30, 1, 0.02]}}
    arrays = compile_dict(scene_of(obj)).arrays
    o = np.array([[-2.0, 0.05, 0.1], [-2.0, 0.0, -0.01]])
    d = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    n, _ = check_walks(obj, arrays, o, d)
    hits = walk(arrays, o[0], d[0])
    assert len(hits) == 80  # 40 separate spheres (0.7 apart, radius 0.3): an entry and an exit each
    assert walk(arrays, o[1], d[1]) == []  # inside the removed slab all the way


# ----------------------------------------------------------------------------------- normals and materials

SPHERE_C = np.array([0.3, 0.2, 1.0])
SPHERE_R = 0.6


def cut_box(sphere_material=True, transform=None):
    sphere = {"type": "sphere", "center": SPHERE_C.tolist(), "radius": SPHERE_R}
    if sphere_material:
        sphere["material"] = {"kd": [0.9, 0.1, 0.1]}
    obj = {"type": "csg", "op": "difference", "material": {"kd": [0.2, 0.3, 0.4]},
           "left": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]}, "right": sphere}
    if transform:
        obj["transform"] = transform
    return obj


@pytest.mark.parametrize("sphere_material", [True, False])
def test_cut_face_normal_and_material(sphere_material, rng):
    compiled = compile_dict(scene_of(cut_box(sphere_material)))
    materials = compiled.arrays.materials
    xy = SPHERE_C[:2] + rng.uniform(-0.35, 0.35, (40, 2))  # inside the hole's rim (radius 0.6)
    for x, y in xy:
        o = np.array([x, y, 5.0])
        hits = walk(compiled.arrays, o, np.array([0.0, 0.0, -1.0]))
        first = hits[0]
        p = o + first["t"] * np.array([0.0, 0.0, -1.0])
        assert first["entering"] and first["object"] == 0 and first["light"] == -1
        assert abs(np.linalg.norm(p - SPHERE_C) - SPHERE_R) < 1e-9  # on the sphere, below the box's top
        assert p[2] < 1.0
        want = (SPHERE_C - p) / SPHERE_R  # the sphere's normal turned inward: towards its centre
        assert np.allclose(first["n"], want, atol=1e-9)
        assert np.allclose(first["n_sh"], first["n"])
        kd = materials[first["material"], L.MAT_KD : L.MAT_KD + 3]
        assert np.allclose(kd, [0.9, 0.1, 0.1] if sphere_material else [0.2, 0.3, 0.4])
        # leaving through the bottom of the box: the box's own face and the node's material
        last = hits[-1]
        assert not last["entering"] and np.allclose(last["n"], [0, 0, -1])
        assert np.allclose(materials[last["material"], L.MAT_KD : L.MAT_KD + 3], [0.2, 0.3, 0.4])


def test_normals_under_transforms_match_the_twin(rng):
    tr = {"rotate": [10, 40, 5], "scale": [1.5, 0.8, 1.1], "translate": [0.2, 0, 0]}
    obj = cut_box(transform=tr)
    arrays = compile_dict(scene_of(obj)).arrays
    # rays from above the hole (in the box's own frame) towards points around it, so that many meet the cut
    m = transform_matrix(**tr)
    n = 80
    o = (SPHERE_C + [0.0, 0.0, 4.0] + rng.normal(0, 0.5, (n, 3))) @ m[:3, :3].T + m[:3, 3]
    target = (SPHERE_C + rng.uniform(-0.7, 0.7, (n, 3))) @ m[:3, :3].T + m[:3, 3]
    d = unit(target - o)
    t_want, n_want, solid, entering = hit_csg(obj, o, d)
    solids = csg_solids(obj)
    on_sphere = 0
    for i in range(n):
        hits = walk(arrays, o[i], d[i])
        if not np.isfinite(t_want[i]):
            assert not hits
            continue
        assert abs(hits[0]["t"] - t_want[i]) < 1e-9 * (1 + t_want[i])
        assert hits[0]["entering"] == entering[i]
        assert np.allclose(hits[0]["n"], n_want[i], atol=1e-7)
        on_sphere += solids[solid[i]][0]["type"] == "sphere"
    assert on_sphere > 10


def test_any_hit_agrees_with_closest_hit(rng):
    obj = cut_box()
    arrays = compile_dict(scene_of(obj)).arrays
    o, d = random_rays(rng, 100, obj)
    t_want, _, _, _ = hit_csg(obj, o, d)
    hit = np.isfinite(t_want)
    t_safe = np.where(hit, t_want, 10.0)
    assert (trace_any(arrays, o, d, t_safe * 1.0001 + 1e-9) == hit).all()
    assert not trace_any(arrays, o[hit], d[hit], t_safe[hit] * 0.9999).any()


def test_moving_csg_is_hit_where_it_is_at_that_time():
    moving = dict(cut_box(), motion=[1.0, 0.5, 0.0])
    still = cut_box(transform={"translate": [0.4, 0.2, 0.0]})
    a_moving = compile_dict({"camera": {"shutter": [0.0, 1.0]}, "objects": [moving]}).arrays
    a_still = compile_dict(scene_of(still)).arrays
    o, d = np.array([0.8, 0.5, 5.0]), np.array([0.0, 0.0, -1.0])
    got = walk(a_moving, o, d, time=0.4)
    want = walk(a_still, o, d)
    assert len(got) == len(want) >= 2
    for g, w in zip(got, want):
        assert abs(g["t"] - w["t"]) < 1e-12 and g["entering"] == w["entering"]
        assert np.allclose(g["n"], w["n"], atol=1e-12) and g["material"] == w["material"]


# --------------------------------------------------------------------------------------------- the die

PIPS = {  # face normal → pip positions (u, v) on that face; opposite faces add up to seven
    (0, 0, 1): [(0, 0)],
    (0, 0, -1): [(-0.5, -0.5), (-0.5, 0), (-0.5, 0.5), (0.5, -0.5), (0.5, 0), (0.5, 0.5)],
    (1, 0, 0): [(-0.5, -0.5), (0.5, 0.5)],
    (-1, 0, 0): [(-0.5, -0.5), (-0.5, 0.5), (0, 0), (0.5, -0.5), (0.5, 0.5)],
    (0, 1, 0): [(-0.5, -0.5), (0, 0), (0.5, 0.5)],
    (0, -1, 0): [(-0.5, -0.5), (-0.5, 0.5), (0.5, -0.5), (0.5, 0.5)],
}


def _balanced_union(solids):
    if len(solids) == 1:
        return solids[0]
    half = len(solids) // 2
    return {"type": "csg", "op": "union", "left": _balanced_union(solids[:half]),
            "right": _balanced_union(solids[half:])}


def die(transform=None):
    """A rounded die: box ∩ sphere, minus 21 small spheres for the pips (dark, their own material)."""
    pips = []
    for normal, spots in PIPS.items():
        n = np.array(normal, dtype=float)
        a = np.roll(n, 1)
        b = np.cross(n, a)
        for u, v in spots:
            c = 1.08 * n + u * a + v * b
            pips.append({"type": "sphere", "center": c.tolist(), "radius": 0.2, "material": "pip"})
    body = {"type": "csg", "op": "intersection", "left": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]},
            "right": {"type": "sphere", "center": [0, 0, 0], "radius": 1.45}}
    obj = {"type": "csg", "op": "difference", "material": "ivory", "left": body, "right": _balanced_union(pips)}
    if transform:
        obj["transform"] = transform
    return obj


def die_scene(width_height=None):
    return {
        "camera": {"position": [2.6, 3.0, 4.2], "look_at": [0.0, -0.2, 0.0], "fov": 40.0},
        "ambient": 0.15,
        "lights": [{"type": "point", "position": [4.0, 6.0, 3.0], "intensity": 0.9},
                   {"type": "directional", "direction": [-0.3, -1.0, -0.6], "intensity": 0.3}],
        "materials": {"ivory": {"ka": [0.9, 0.88, 0.8], "kd": [0.9, 0.88, 0.8], "ks": 0.4, "shininess": 40},
                      "pip": {"ka": 0.05, "kd": [0.05, 0.05, 0.08], "ks": 0.2, "shininess": 10},
                      "floor": {"ka": [0.3, 0.35, 0.4], "kd": [0.3, 0.35, 0.4]}},
        "objects": [die({"rotate": [0, 25, 0]}),
                    {"type": "plane", "point": [0, -1.001, 0], "normal": [0, 1, 0], "material": "floor"}],
    }


def test_die_render_matches_naive():
    scene = die_scene()
    W, H = 96, 72
    img = render(scene, width=W, height=H)
    want, t_want = render_classic_csg(scene, W, H)
    close = (np.abs(img.array - want) <= 2e-3).all(axis=2)
    assert close.mean() >= 0.99, f"only {close.mean():.4f} of the pixels agree to 2e-3"
    # the die is in view with its pips
    pip_dark = (want.max(axis=2) < 0.2) & (t_want < 6.5)
    assert pip_dark.sum() > 20 and want.std() > 0.1


def test_open_mesh_in_csg_is_an_error():
    s = icosphere([0, 0, 0], 1.0, 1)
    s["faces"] = s["faces"][1:]
    obj = {"type": "csg", "op": "union", "left": s, "right": {"type": "sphere"}}
    with pytest.raises(lumos.LumosError, match="closed"):
        compile_dict(scene_of(obj))
