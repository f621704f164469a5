"""BVH build and traversal: `trace_closest` / `trace_any` against brute force over every primitive, and the
structure invariants of the built tree (every primitive in exactly one leaf, nested boxes, bounded depth)."""

import numpy as np
import pytest
from conftest import compile_dict, trace, trace_any
from naive import hit_object, hit_triangle, shape_bounds

from lumos.kernels import layout as L

MAT = {"kd": 0.5}


def _f32(x):
    """Values exactly representable in float32 (the precision the compile step stores triangles in)."""
    return np.asarray(x, dtype=np.float32).astype(np.float64)


def random_scene(rng, n_tri=300, n_each=8):
    """A mesh of random triangles, random spheres/boxes/cylinders/cones/disks and one plane, inside [-5, 5]^3."""
    centers = rng.uniform(-4.5, 4.5, (n_tri, 1, 3))
    tris = _f32(centers + rng.normal(scale=0.35, size=(n_tri, 3, 3)))
    objects = [{"type": "mesh", "vertices": tris.reshape(-1, 3).tolist(),
                "faces": np.arange(3 * n_tri).reshape(-1, 3).tolist(), "material": MAT}]
    for _ in range(2 * n_each):
        objects.append({"type": "sphere", "center": rng.uniform(-4, 4, 3).tolist(),
                        "radius": float(rng.uniform(0.1, 0.6)), "material": MAT})
    for _ in range(n_each):
        lo = rng.uniform(-4.5, 4, 3)
        objects.append({"type": "box", "min": lo.tolist(), "max": (lo + rng.uniform(0.05, 1.0, 3)).tolist(),
                        "material": MAT})
    for kind in ("cylinder", "cone"):
        for i in range(n_each):
            base = rng.uniform(-4, 4, 3)
            objects.append({"type": kind, "base": base.tolist(), "top": (base + rng.normal(scale=0.6, size=3)).tolist(),
                            "radius": float(rng.uniform(0.1, 0.5)), "capped": bool(i % 2), "material": MAT})
    for _ in range(n_each):
        objects.append({"type": "disk", "center": rng.uniform(-4, 4, 3).tolist(), "normal": rng.normal(size=3).tolist(),
                        "radius": float(rng.uniform(0.1, 0.7)), "material": MAT})
    objects.append({"type": "plane", "point": [0.0, -4.8, 0.0], "normal": [0.05, 1.0, -0.02], "material": MAT})
    return {"objects": objects}, tris


def random_rays(rng, n, tris):
    o = rng.uniform(-6.0, 6.0, (n, 3))  # many origins lie inside the scene (some inside closed shapes)
    d = rng.normal(size=(n, 3))
    aim = np.arange(n) % 3 == 0  # a third aimed at triangle centroids, to make triangle hits common
    d[aim] = tris[rng.integers(len(tris), size=aim.sum())].mean(axis=1) - o[aim]
    axial = np.arange(n) % 7 == 1  # some rays with exact zero components (the slab test's 1/0 case)
    d[axial] = np.eye(3)[rng.integers(3, size=axial.sum())] * rng.choice([-1.0, 1.0], size=(axial.sum(), 1))
    planar = np.arange(n) % 7 == 2
    d[planar, rng.integers(3)] = 0.0
    return o, d


def brute_force(scene, tris, o, d):
    """t of every primitive for every ray, (n_prims, n_rays), and the primitive keys: ('tri', k) or ('obj', i)."""
    rows, keys = [], []
    for k, v in enumerate(tris):
        rows.append(hit_triangle(o, d, v[0], v[1], v[2])[0])
        keys.append(("tri", k))
    for i, obj in enumerate(scene["objects"]):
        if obj["type"] != "mesh":
            rows.append(hit_object(obj, o, d)[0])
            keys.append(("obj", i))
    return np.array(rows), keys


def kernel_keys(arrays, refs, tris):
    """Map the kernels' refs (triangle index in leaf order, or ~shape) back to brute-force keys."""
    by_bytes = {_f32(v).astype(np.float32).tobytes(): k for k, v in enumerate(tris.reshape(len(tris), 9))}
    out = []
    for r in refs:
        if r >= 0:
            out.append(("tri", by_bytes[np.asarray(arrays.tri_verts[r], dtype=np.float32).tobytes()]))
        else:
            out.append(("obj", int(arrays.shape_info[~r, L.INFO_OBJECT])))
    return out


@pytest.fixture(scope="module")
def mixed(request):
    rng = np.random.default_rng(7)
    scene, tris = random_scene(rng)
    compiled = compile_dict(scene)
    o, d = random_rays(rng, 3000, tris)
    t_all, keys = brute_force(scene, tris, o, d)
    return scene, tris, compiled, o, d, t_all, keys


def test_closest_hit_equals_brute_force(mixed):
    scene, tris, compiled, o, d, t_all, keys = mixed
    t_k, ref_k, _ = trace(compiled.arrays, o, d)
    order = np.argsort(t_all, axis=0)
    best = np.take_along_axis(t_all, order[:1], axis=0)[0]
    second = np.take_along_axis(t_all, order[1:2], axis=0)[0]
    hit = np.isfinite(best)
    assert 0.3 < hit.mean() < 0.95
    assert np.array_equal(t_k >= 0.0, hit), np.flatnonzero((t_k >= 0.0) != hit)
    np.testing.assert_allclose(t_k[hit], best[hit], rtol=1e-9)
    # the same primitive wherever the nearest hit is not a near-tie
    with np.errstate(invalid="ignore"):
        unambiguous = hit & (second - best > 1e-7 * best)
    got = kernel_keys(compiled.arrays, ref_k[unambiguous], tris)
    want = [keys[i] for i in order[0][unambiguous]]
    assert got == want
    # every kind of primitive was the answer for some ray
    kinds = {k[0] if k[0] == "tri" else scene["objects"][k[1]]["type"] for k in want}
    assert kinds == {"tri", "sphere", "box", "cylinder", "cone", "disk", "plane"}


def test_any_hit_equals_brute_force(mixed, rng):
    _, _, compiled, o, d, t_all, _ = mixed
    best = t_all.min(axis=0)
    t_max = np.where(np.isfinite(best), best * rng.uniform(0.3, 1.7, len(best)), rng.uniform(1.0, 50.0, len(best)))
    clear = ~(np.abs(best - t_max) <= 1e-9 * t_max)
    got = trace_any(compiled.arrays, o, d, t_max)
    want = best < t_max
    assert 0.2 < want.mean() < 0.8
    assert np.array_equal(got[clear], want[clear])


def test_any_triangle_hit_equals_any_hit_on_a_tree_of_triangles(rng):
    """`any_triangle_hit`, the traversal compiled without the analytic shapes (radiosity's visibility rays over
    its trees of triangles), answers as `any_hit` does, and as brute force, on a tree of triangles only."""
    from conftest import geometry

    from lumos.compile import triangle_arrays
    from lumos.kernels.traverse import any_hit, any_triangle_hit

    centers = rng.uniform(-4.5, 4.5, (200, 1, 3))
    tris = _f32(centers + rng.normal(scale=0.5, size=(200, 3, 3)))
    compiled = triangle_arrays(tris.reshape(-1, 9), np.arange(200, dtype=np.int32))
    geo = geometry(compiled.arrays)
    stack = np.empty(64, np.int64)
    o = rng.uniform(-6, 6, (300, 3))
    d = rng.normal(size=(300, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t_max = rng.uniform(0.5, 12.0, 300)
    best = np.min([hit_triangle(o, d, *tri)[0] for tri in tris], axis=0)
    want = best < t_max
    clear = ~(np.abs(best - t_max) <= 1e-9 * t_max)
    got = np.array([any_triangle_hit(geo, tuple(o[i]), tuple(d[i]), 0.0, t_max[i], stack) for i in range(300)])
    general = np.array([any_hit(geo, tuple(o[i]), tuple(d[i]), 0.0, t_max[i], stack, 0.0) for i in range(300)])
    assert 0.1 < want.mean() < 0.9
    assert np.array_equal(got, general) and np.array_equal(got[clear], want[clear])


def test_closest_hit_respects_t_max(mixed):
    _, _, compiled, o, d, t_all, _ = mixed
    best = t_all.min(axis=0)
    t_k, _, _ = trace(compiled.arrays, o, d, t_max=3.0)
    sure = np.abs(best - 3.0) > 1e-9
    np.testing.assert_array_equal((t_k >= 0)[sure], (best < 3.0)[sure])


# ------------------------------------------------------------------------------------------ tree structure


def tree(arrays):
    """(bounds float64 (nn, 6), first (nn,), count (nn,)) whichever node layout `kernels.layout` uses."""
    boxes = np.asarray(arrays.node_box)[:, :6].astype(np.float64)
    link = np.asarray(arrays.node_link)
    first = link[:, getattr(L, "NODE_FIRST", 0)].astype(np.int64)
    count = link[:, getattr(L, "NODE_COUNT", 1)].astype(np.int64)
    return boxes, first, count


def check_tree(compiled, prim_boxes):
    """Walk the tree from the root and assert every invariant; returns the depth found."""
    arrays = compiled.arrays
    boxes, first, count = tree(arrays)
    n_prims = len(arrays.prim_ref)
    seen_nodes = np.zeros(len(boxes), int)
    seen_slots = np.zeros(n_prims, int)
    max_depth = 0
    stack = [(0, 0)]
    while stack:
        node, depth = stack.pop()
        seen_nodes[node] += 1
        max_depth = max(max_depth, depth)
        if count[node] > 0:
            lo, hi = first[node], first[node] + count[node]
            assert 0 <= lo and hi <= n_prims
            seen_slots[lo:hi] += 1
            if (arrays.prim_ref[lo:hi] < 0).any():  # shapes are tested one by one: each has a leaf of its own
                assert count[node] == 1, (node, arrays.prim_ref[lo:hi])
            for r in arrays.prim_ref[lo:hi]:
                pb = prim_boxes[int(r)]
                assert (boxes[node, :3] <= pb[:3]).all() and (pb[3:] <= boxes[node, 3:]).all(), (node, r)
        else:
            c = first[node]
            assert 0 < c and c + 1 < len(boxes)
            for child in (c, c + 1):
                assert (boxes[node, :3] <= boxes[child, :3]).all() and (boxes[child, 3:] <= boxes[node, 3:]).all()
                stack.append((child, depth + 1))
    # a tree: no node reached twice (unreached slots are allowed: the builder may pad for alignment)
    assert seen_nodes[0] == 1 and seen_nodes.max() == 1
    assert (seen_slots == 1).all()  # leaves partition prim_ref
    # prim_ref holds every triangle and every bounded shape exactly once
    refs = arrays.prim_ref.astype(np.int64)
    assert sorted(refs[refs >= 0]) == list(range(len(arrays.tri_verts)))
    bounded = [s for s in range(len(arrays.shape_info)) if arrays.shape_info[s, L.INFO_KIND] != L.SHAPE_PLANE]
    assert sorted(~refs[refs < 0]) == bounded
    assert max_depth <= 60 and compiled.bvh_depth <= 60
    return max_depth


def _prim_boxes(scene, arrays):
    """Tight bounds per prim_ref value: triangles from their stored vertices, shapes from the object's own
    parameters (not the compile step's corner bounds)."""
    out = {}
    for r in arrays.prim_ref:
        r = int(r)
        if r >= 0:
            v = np.asarray(arrays.tri_verts[r], dtype=np.float64).reshape(3, 3)
            out[r] = np.concatenate([v.min(axis=0), v.max(axis=0)])
        else:
            out[r] = shape_bounds(scene["objects"][int(arrays.shape_info[~r, L.INFO_OBJECT])])
    return out


def check_wide_tree(arrays, prim_boxes):
    """The wide tree that traversal walks: every leaf of the binary tree is one child slot, each slot's box
    is that leaf's (so every primitive lies in it), empty slots are inverted boxes, and no node is shared."""
    width = L.WIDE
    wide = np.asarray(arrays.wide_nodes)
    link = np.asarray(arrays.wide_link)
    assert wide.ctypes.data % 64 == 0 and wide.shape[1] == L.WIDE_SIZE and L.WIDE_SIZE * 4 % 64 == 0  # whole lines
    assert 1 << L.WIDE_SHIFT == width
    boxes = wide[:, :6 * width].reshape(-1, 6, width).astype(np.float64)
    child, count = link[:, L.WIDE_CHILD:L.WIDE_CHILD + width], link[:, L.WIDE_COUNT:L.WIDE_COUNT + width]
    seen_nodes = np.zeros(len(wide), int)
    seen_slots = np.zeros(len(arrays.prim_ref), int)
    slot_of = {int(r): k for k, r in enumerate(arrays.prim_ref)}
    leaf_link = np.asarray(arrays.leaf_link)
    stack = [0]
    while stack:
        w = stack.pop()
        seen_nodes[w] += 1
        for k in range(L.WIDE):
            lo, hi = boxes[w, :3, k], boxes[w, 3:, k]
            if count[w, k] == L.LEAF_PACKED:  # a packed row of triangles (see check_packed_leaves)
                row = child[w, k]
                base, mask = leaf_link[row, L.LEAF_BASE], leaf_link[row, L.LEAF_MASK]
                for r in range(base, base + int(mask).bit_length()):
                    seen_slots[slot_of[r]] += 1
                    pb = prim_boxes[r]
                    assert (lo <= pb[:3]).all() and (pb[3:] <= hi).all(), (w, k, r)
            elif count[w, k] < 0:  # empty: +inf min, -inf max
                assert np.all(lo == np.inf) and np.all(hi == -np.inf)
            elif count[w, k] == 0:
                sub = boxes[child[w, k]]
                used = count[child[w, k]] != -1
                assert (lo[:, None] <= sub[:3, used]).all() and (sub[3:, used] <= hi[:, None]).all()  # nested
                stack.append(int(child[w, k]))
            else:
                first, n = child[w, k], count[w, k]
                seen_slots[first:first + n] += 1
                for r in arrays.prim_ref[first:first + n]:
                    pb = prim_boxes[int(r)]
                    assert (lo <= pb[:3]).all() and (pb[3:] <= hi).all(), (w, k, r)
    assert seen_nodes.max() == 1 and (seen_nodes == 1).all()  # every wide node reached exactly once
    assert (seen_slots == 1).all()  # the leaves partition prim_ref


def check_packed_leaves(arrays, faces=None):
    """Each packed leaf row holds exactly its triangles' vertices, lane by lane, with their object ids, face
    indices (`faces`, the compiled scene's triangle_faces, when given) and uv flags, and its slot no longer points
    into prim_ref; every triangle of the BVH is in one packed row or one plain leaf."""
    link, leaves, leaf_link = np.asarray(arrays.wide_link), np.asarray(arrays.leaf_tris), np.asarray(arrays.leaf_link)
    count = link[:, L.WIDE_COUNT:L.WIDE_COUNT + L.WIDE]
    rows = link[:, L.WIDE_CHILD:L.WIDE_CHILD + L.WIDE][count == L.LEAF_PACKED]
    assert sorted(rows) == list(range(len(leaves)))  # every packed row belongs to exactly one slot
    covered = []
    for row in rows:
        base, mask = leaf_link[row, L.LEAF_BASE], leaf_link[row, L.LEAF_MASK]
        assert mask in (1, 3, 7, 15)
        for lane in range(int(mask).bit_length()):
            np.testing.assert_array_equal(leaves[row, lane:36:4], arrays.tri_verts[base + lane])
            assert leaf_link[row, L.LEAF_OBJECT + lane] == arrays.tri_info[base + lane, L.INFO_OBJECT]
            if faces is not None:
                assert leaf_link[row, L.LEAF_FACE + lane] == faces[base + lane]
            has_uvs = bool(arrays.tri_info[base + lane, L.INFO_FLAGS] & L.FLAG_UVS)
            assert bool(leaf_link[row, L.LEAF_UVS] & (1 << lane)) == has_uvs
            covered.append(base + lane)
    plain = [(f, c) for f, c in zip(link[:, L.WIDE_CHILD:L.WIDE_CHILD + L.WIDE][count > 0], count[count > 0])]
    refs = arrays.prim_ref
    covered += [int(r) for f, c in plain for r in refs[f:f + c] if r >= 0]
    assert sorted(covered) == sorted(int(r) for r in refs if r >= 0)
    assert len(rows) > 0


def test_tree_invariants_mixed_scene(mixed):
    scene, _, compiled, *_ = mixed
    depth = check_tree(compiled, _prim_boxes(scene, compiled.arrays))
    assert depth >= 5  # a real tree, not one leaf
    check_wide_tree(compiled.arrays, _prim_boxes(scene, compiled.arrays))
    check_packed_leaves(compiled.arrays, compiled.triangle_faces)
    # each wide node takes up to WIDE - 1 binary interior nodes: about log2(WIDE) binary levels per wide level
    assert len(compiled.arrays.wide_nodes) < len(compiled.arrays.node_box) / (0.6 * L.WIDE)


def test_a_room_of_shapes_gives_each_wall_its_own_box():
    """Mitsuba's Cornell box is eight shapes (five walls, the light, two blocks): the eight fill the 8-wide root,
    one per slot. (When the SAH priced shapes as packed triangles, four went into one leaf whose box was the
    whole room, and every ray in the room tested all four.)"""
    from helpers import EXAMPLES

    import lumos
    from lumos.compile import compile_scene

    scene = lumos.load_scene(EXAMPLES / "path" / "cornell.yaml")
    arrays = compile_scene(scene).arrays
    link = np.asarray(arrays.wide_link)
    counts = link[:, L.WIDE_COUNT:L.WIDE_COUNT + L.WIDE]
    assert len(arrays.prim_ref) == 8
    assert sorted(counts[counts > 0]) == [1] * 8  # eight leaf slots of one primitive each
    if L.WIDE >= 8:
        assert len(link) == 1


def test_packed_triangle_test_vector_code_equals_scalar_twin(rng):
    """`simd.tri4_test` compiled (<4 x double> code) against its interpreted body and against the scalar
    watertight test of each lane: same hits at bit-identical distances and barycentrics, for rays aimed at the triangles, at their
    edges and vertices (where the watertight rule decides), and with a t_max that cuts some hits off."""
    import numba

    from lumos.kernels.intersect import intersect_triangle, triangle_setup
    from lumos.kernels.simd import tri4_test

    @numba.njit
    def compiled(leaves, j, o, setup, t_max):
        kx, ky, kz, sx, sy, sz = setup
        return tri4_test(leaves, j, kx, ky, kz, sx, sy, sz, o[kx], o[ky], o[kz], t_max)

    n = 300
    tris = _f32(rng.normal(size=(n, 4, 3, 3)))
    tris[:, 1] = tris[:, 0]  # shared edges: lane 1 is lane 0 with its vertices cycled, lane 2 shares an edge
    tris[:, 1] = tris[:, 0][:, [1, 2, 0]]
    tris[:, 2, 0], tris[:, 2, 1] = tris[:, 0, 1], tris[:, 0, 0]
    leaves = np.zeros((n, 48), np.float32)
    for c in range(9):
        leaves[:, 4 * c:4 * c + 4] = tris[:, :, c // 3, c % 3]
    hits = 0
    for i in range(n):
        target = tris[i, i % 3]
        w = rng.dirichlet([1, 1, 1]) if i % 4 else np.array([0.5, 0.5, 0.0])  # some through an edge
        o = rng.normal(size=3) * 3
        d = w @ target - o
        setup = triangle_setup(d)
        t_max = 1e30 if i % 3 else float(rng.uniform(0.3, 1.2))
        got = compiled(leaves, i, (o[0], o[1], o[2]), setup, t_max)
        kx, ky, kz, sx, sy, sz = setup
        twin = tri4_test(leaves, i, kx, ky, kz, sx, sy, sz, o[kx], o[ky], o[kz], t_max)
        assert got[0] == twin[0]
        lanes = [k for k in range(4) if got[0] >> k & 1]
        for start in (1, 5, 9):
            np.testing.assert_array_equal(np.array(got[start:start + 4])[lanes],
                                          np.array(twin[start:start + 4])[lanes])
        for k in range(4):
            v = tris[i, k].reshape(1, 9).astype(np.float32)
            t, b1, b2 = intersect_triangle((o[0], o[1], o[2]), setup, v, 0, t_max)
            assert bool(got[0] >> k & 1) == (t != -1.0), (i, k)
            if t != -1.0:
                assert (got[1 + k], got[5 + k], got[9 + k]) == (t, b1, b2)  # distance and barycentrics
                hits += 1
    assert hits > 200


def test_wide_box_test_vector_code_equals_scalar_twin(rng):
    """`simd.wide_box_test` compiled (LLVM <WIDE x double> code) against its interpreted body and against the
    binary tree's scalar slab test, lane by lane: same mask, same entry distances, on random boxes, rays from
    inside and outside, axis-parallel directions, empty slots and finite t_max; `wide_box_mask` gives the same
    mask."""
    import numba

    from lumos.kernels.intersect import box_setup, intersect_node_box
    from lumos.kernels.simd import wide_box_mask, wide_box_test, wide_setup

    w = L.WIDE

    @numba.njit
    def compiled(nodes, j, rb, t_max, entry):
        nx, ny, nz = wide_setup(rb)
        mask = wide_box_test(nodes, j, nx, ny, nz, rb[3], rb[4], rb[5], rb[0], rb[1], rb[2], t_max, entry, 3)
        return mask, wide_box_mask(nodes, j, nx, ny, nz, rb[3], rb[4], rb[5], rb[0], rb[1], rb[2], t_max)

    n = 200
    lo = rng.uniform(-2, 1, (n, 3, w))
    hi = lo + rng.uniform(0.0, 1.5, (n, 3, w))
    nodes = np.zeros((n, L.WIDE_SIZE), np.float32)
    nodes[:, :3 * w] = lo.reshape(n, 3 * w)
    nodes[:, 3 * w:6 * w] = hi.reshape(n, 3 * w)
    empty = [(r, k) for r in range(6) for k in (0, w - 1)]  # empty slots 0 and w - 1 in every 7th node
    for r, k in empty:
        nodes[::7, r * w + k] = np.inf if r < 3 else -np.inf
    agree = 0
    for i in range(n):
        o = rng.uniform(-3, 3, 3)
        aim = (lo[i, :, i % w] + hi[i, :, i % w]) / 2  # towards one of the boxes, give or take
        d = aim - o + rng.normal(scale=0.3, size=3)
        if i % 5 == 0:
            d[rng.integers(3)] = 0.0  # axis-parallel in one coordinate
        rb = box_setup(o, d)
        t_max = 1e30 if i % 2 else float(rng.uniform(0.5, 4))
        got, entry = np.full(w + 4, -7.0), np.full(w + 4, -7.0)
        mask, mask_only = compiled(nodes, i, rb, t_max, got)
        twin = wide_box_test(nodes, i, w * rb[6], w * rb[7], w * rb[8], rb[3], rb[4], rb[5], rb[0], rb[1], rb[2],
                             t_max, entry, 3)
        assert mask == twin == mask_only
        np.testing.assert_array_equal(got, entry)  # every lane stored, nothing outside entry[3:3 + w]
        assert (got[:3] == -7.0).all() and got[-1] == -7.0
        for k in range(w):  # against the binary tree's scalar test of the same box
            box = np.zeros((1, 8), np.float32)
            box[0, :6] = nodes[i, k:6 * w:w]
            t = intersect_node_box(box, 0, rb, t_max)
            assert bool(mask >> k & 1) == (t != -1.0)
            if t != -1.0:
                assert got[3 + k] == t
                agree += 1
    assert 100 < agree < 0.9 * n * w  # the test saw hits as well as misses


def test_lowest_bit_compiled_equals_twin():
    """`simd.lowest_bit` (LLVM cttz) walks the set bits of every mask a wide node can return, lowest first."""
    import numba

    from lumos import config
    from lumos.kernels.simd import lowest_bit

    @numba.njit
    def bits(mask):
        out = []
        while mask != 0:
            out.append(lowest_bit(mask))
            mask &= mask - 1
        return out

    for mask in range(1 << L.WIDE):
        assert list(bits(np.int64(mask))) == [k for k in range(L.WIDE) if mask >> k & 1]
        if mask:
            assert lowest_bit(mask) == bits(np.int64(mask))[0]
    from lumos.kernels.bvh_build import MAX_DEPTH

    assert (L.WIDE - 1) * MAX_DEPTH + 1 <= config.BVH_STACK - L.WIDE  # the deepest stack stays below the scratch


def test_tree_invariants_and_traversal_on_degenerate_inputs(rng):
    # 40 identical spheres (all centroids equal: no SAH split exists) + exponentially spaced tiny triangles
    # (binning puts nearly all of them in the first bin, level after level)
    spheres = [{"type": "sphere", "center": [1.0, 2.0, 3.0], "radius": 0.5, "material": MAT} for _ in range(40)]
    n = 200
    xs = _f32(1.5 ** np.arange(n))  # up to 1e35: still finite in float32
    v = np.zeros((n, 3, 3))
    v[:, 0, 0], v[:, 1, 0], v[:, 2, 0] = xs, xs * 1.05, xs
    v[:, 1, 1], v[:, 2, 2] = 0.05 * xs, 0.05 * xs
    tris = _f32(v)
    mesh = {"type": "mesh", "vertices": tris.reshape(-1, 3).tolist(), "faces": np.arange(3 * n).reshape(-1, 3).tolist(),
            "material": MAT}
    scene = {"objects": spheres + [mesh]}
    compiled = compile_dict(scene)
    assert check_tree(compiled, _prim_boxes(scene, compiled.arrays)) >= 30  # a deep, lopsided tree
    # rays aimed at each triangle's centroid from the side its normal (1, -1, 0) points to, and at the spheres
    target = tris.mean(axis=1)
    o = target + xs[:, None] * np.array([0.3, -0.5, 0.2])
    d = target - o
    t_k, _, _ = trace(compiled.arrays, o, d)
    t_all, _ = brute_force(scene, tris, o, d)
    assert np.isfinite(t_all.min(axis=0)).all()
    np.testing.assert_allclose(t_k, t_all.min(axis=0), rtol=1e-9)
    t_k, ref, _ = trace(compiled.arrays, [[1.0, 2.0, 10.0]], [[0.0, 0.0, -1.0]])
    assert t_k[0] == pytest.approx(6.5) and ref[0] < 0


@pytest.mark.nojit
def test_single_primitive_and_plane_only_scenes():
    one = compile_dict({"objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "material": MAT}]})
    check_tree(one, {-1: np.array([-1.0, -1, -1, 1, 1, 1])})
    t, ref, _ = trace(one.arrays, [[0.0, 0.0, 3.0], [2.0, 0.0, 3.0]], [[0.0, 0.0, -1.0]] * 2)
    assert t[0] == 2.0 and ref[0] == -1 and t[1] == -1.0
    plane = compile_dict({"objects": [{"type": "plane", "point": [0, -1, 0], "normal": [0, 1, 0], "material": MAT}]})
    assert len(plane.arrays.prim_ref) == 0
    t, ref, _ = trace(plane.arrays, [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]], [[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    assert t[0] == 2.0 and ref[0] == -1 and t[1] == -1.0
    assert list(trace_any(plane.arrays, [[0.0, 1.0, 0.0]] * 2, [[0.0, -1.0, 0.0]] * 2, [2.5, 1.5])) == [True, False]


@pytest.mark.nojit
def test_axis_aligned_rays_through_bvh():
    # regression (interpreted kernels): a float32 bound times the 1e100 standing in for 1/0 stayed float32 under
    # NumPy (NEP 50), overflowed to inf and culled every node for rays with a zero direction component
    scene = {"objects": [{"type": "sphere", "center": [1.0, 1.5, 2.0], "radius": 0.5, "material": MAT},
                         {"type": "box", "min": [3.0, 0.25, 0.5], "max": [4.0, 1.0, 1.5], "material": MAT}]}
    arrays = compile_dict(scene).arrays
    o = [[1.0, 1.5, 9.0], [1.0, -4.0, 2.0], [-3.0, 1.5, 2.0], [3.5, 0.5, 9.0], [9.0, 0.5, 1.0]]
    d = [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]]
    t, _, _ = trace(arrays, o, d)
    np.testing.assert_array_equal(t, [6.5, 5.0, 3.5, 7.5, 5.0])


def test_large_tree_built_in_tasks_is_the_same_on_any_number_of_threads(rng):
    """Above 4096 primitives the top of the tree is built first and its subtrees as tasks on Python threads
    (`compile.bvh.build`), each into a region of its own, closed up in task order: the same tree on 1, 2 or 3
    threads, and every invariant holds across the seams between the top and the tasks' regions."""
    from lumos.compile.bvh import build

    n_tri = 6000
    centers = rng.uniform(-4.5, 4.5, (n_tri, 1, 3))
    tris = _f32(centers + rng.normal(scale=0.1, size=(n_tri, 3, 3)))
    bounds = np.concatenate([tris.min(axis=1), tris.max(axis=1)], axis=1)
    one = build(bounds, threads=1)
    for threads in (2, 3):
        for a, b in zip(one, build(bounds, threads=threads)):
            np.testing.assert_array_equal(a, b)
    scene = {"objects": [{"type": "mesh", "vertices": tris.reshape(-1, 3).tolist(),
                          "faces": np.arange(3 * n_tri).reshape(-1, 3).tolist(), "material": MAT}]}
    compiled = compile_dict(scene)
    assert check_tree(compiled, _prim_boxes(scene, compiled.arrays)) >= 10
    check_wide_tree(compiled.arrays, _prim_boxes(scene, compiled.arrays))
    o, d = random_rays(rng, 300, tris)
    t_k, _, _ = trace(compiled.arrays, o, d)
    best = brute_force(scene, tris, o, d)[0].min(axis=0)
    hit = np.isfinite(best)
    assert 0.2 < hit.mean() and np.array_equal(t_k >= 0.0, hit)
    np.testing.assert_allclose(t_k[hit], best[hit], rtol=1e-9)
