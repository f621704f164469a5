"""The scan-line renderer (`method: raster`) against its twins and closed forms.

* coverage and depth of the scan-line algorithm against a per-pixel inside test (`naive.inside_polygon`);
* no cracks and no double coverage where polygons share edges (samples exactly on the edges included);
* flat, Gouraud and Phong pixels on one triangle against the closed forms of the classic model;
* raster Phong against `raycast` on a smooth mesh; near-plane clipping against `raycast`;
* perspective-correct against screen-space (affine) interpolation on a slanted plane.
"""

import math

import numpy as np
import pytest
import trimesh
from naive import classic_local, inside_polygon, unit

import lumos
from lumos.api import resolve_settings
from lumos.methods import compile_for
from lumos.methods.raster import Rasterizer

MAT = {"ka": [0.2, 0.15, 0.1], "kd": [0.7, 0.5, 0.3], "ks": [0.4, 0.4, 0.4], "shininess": 20.0}
LIGHTS = [
    {"type": "point", "position": [2.0, 3.0, 4.0], "intensity": [1.0, 0.9, 0.8], "attenuation": [1.0, 0.05, 0.0]},
    {"type": "directional", "direction": [-0.3, -1.0, -0.5], "intensity": 0.4},
]


def ortho(width, height, position=(0.0, 0.0, 10.0)):
    """An orthographic camera where one world unit is one pixel, looking down −z at the origin."""
    return {"type": "orthographic", "position": list(position), "look_at": [position[0], position[1], 0.0],
            "size": float(height)}


def mesh_scene(camera, vertices, faces, normals=None, material=None, lights=(), ambient=0.0, **mesh_keys):
    obj = {"type": "mesh", "vertices": np.asarray(vertices, float), "faces": faces, "material": material or MAT}
    if normals is not None:
        obj["normals"] = np.asarray(normals, float)
    obj.update(mesh_keys)
    return {"camera": camera, "ambient": ambient, "lights": list(lights), "objects": [obj]}


def rasterizer(scene_dict, width, height, cull=False, persp=True, **settings):
    scene = lumos.load_scene(scene_dict)
    cfg = resolve_settings(scene, dict(method="raster", width=width, height=height, **settings))
    mesh = compile_for(scene, cfg).raster
    attrs = np.hstack([mesh.positions, mesh.normals])
    return Rasterizer(mesh, attrs, scene.camera, width, height, cull=cull, persp=persp), mesh


def screen_polygons(r, mesh):
    s = r.screen
    return [(s[mesh.prim_index[a:b], 0], s[mesh.prim_index[a:b], 1])
            for a, b in zip(mesh.prim_start[:-1], mesh.prim_start[1:])]


def samples(width, height, jx=0.5, jy=0.5):
    x, y = np.meshgrid(np.arange(width) + jx, np.arange(height) + jy)
    return x, y


# --------------------------------------------------------------------------------- the scan-line twin


@pytest.mark.parametrize("camera", ["ortho", "perspective"])
def test_coverage_and_depth_match_per_pixel_inside_test(rng, camera):
    W, H = 72, 56
    n = 40
    if camera == "ortho":
        cam = ortho(W, H)
        centres = rng.uniform([-40, -32, -5], [40, 32, 5], (n, 3))
        verts = centres[:, None, :] + rng.uniform([-14, -14, -3], [14, 14, 3], (n, 3, 3))
    else:
        cam = {"position": [0.0, 0.0, 6.0], "look_at": [0.0, 0.0, 0.0], "fov": 50.0}
        centres = rng.uniform([-2.5, -2, -3], [2.5, 2, 2], (n, 3))
        verts = centres[:, None, :] + rng.uniform(-1.8, 1.8, (n, 3, 3))
    faces = np.arange(3 * n).reshape(n, 3)
    r, mesh = rasterizer(mesh_scene(cam, verts.reshape(-1, 3), faces), W, H)
    xs, ys = samples(W, H, 0.5, 0.5)
    expected_count = np.zeros((H, W), int)
    best_key = np.full((H, W), -np.inf)
    best_id = np.full((H, W), -1)
    on_edge = np.zeros((H, W), bool)
    keys = r.screen[:, 2]
    for p, (px, py) in enumerate(screen_polygons(r, mesh)):
        inside, dist = inside_polygon(px, py, xs, ys)
        on_edge |= dist < 1e-7
        expected_count += inside
        # the depth key is linear in screen space: interpolate it with screen-space barycentrics
        (x0, x1, x2), (y0, y1, y2) = px, py
        det = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if det == 0:
            continue
        b1 = ((xs - x0) * (y2 - y0) - (x2 - x0) * (ys - y0)) / det
        b2 = ((x1 - x0) * (ys - y0) - (xs - x0) * (y1 - y0)) / det
        k = mesh.prim_index[3 * p: 3 * p + 3]
        key = keys[k[0]] * (1 - b1 - b2) + keys[k[1]] * b1 + keys[k[2]] * b2
        nearer = inside & (key > best_key)
        best_key = np.where(nearer, key, best_key)
        best_id = np.where(nearer, p, best_id)
    count = r.coverage()
    assert expected_count.sum() > W * H // 2  # the test covers a real part of the image, with overlaps
    assert np.array_equal(count[~on_edge], expected_count[~on_edge])
    zbuf, ids, _ = r.draw()
    covered = (best_id >= 0) & ~on_edge
    assert np.allclose(zbuf[covered], best_key[covered], rtol=1e-9, atol=1e-9)
    # ids agree wherever two polygons are not at (nearly) the same depth
    assert np.mean(ids[covered] == best_id[covered]) > 0.995


def grid_mesh(nx, ny, x0, y0, cell, rng, jitter=0.0):
    """A triangulated grid in the z = 0 plane, interior vertices jittered, diagonals in both directions."""
    xs = x0 + cell * np.arange(nx + 1)
    ys = y0 + cell * np.arange(ny + 1)
    X, Y = np.meshgrid(xs, ys)
    V = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    interior = (X.ravel() > xs[0]) & (X.ravel() < xs[-1]) & (Y.ravel() > ys[0]) & (Y.ravel() < ys[-1])
    V[interior, :2] += rng.uniform(-jitter, jitter, (interior.sum(), 2))
    faces = []
    for j in range(ny):
        for i in range(nx):
            a, b, c, d = j * (nx + 1) + i, j * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i
            faces += [[a, b, c], [a, c, d]] if (i + j) % 2 else [[a, b, d], [b, c, d]]
    return V, faces


@pytest.mark.nojit
@pytest.mark.parametrize("jitter", [0.0, 1.3])
def test_shared_edges_leave_no_crack_and_cover_no_sample_twice(rng, jitter):
    # vertices on pixel centres: many samples lie exactly on shared edges and vertices
    W = H = 64
    V, faces = grid_mesh(8, 6, -30.0 + 0.5 - 0.5, -24.0, 7.0, rng, jitter)
    V[:, 0] += 0.5  # world x = k + 0.5 - 32 is the centre of pixel k
    V[:, 1] -= 0.5
    r, _ = rasterizer(mesh_scene(ortho(W, H), V, faces), W, H)
    count = r.coverage()
    # inside the grid's outline every sample is covered exactly once
    xs, ys = samples(W, H)
    px, py = xs - 32.0, 32.0 - ys  # pixel centre → world
    inside = (px >= V[:, 0].min()) & (px < V[:, 0].max()) & (py > V[:, 1].min()) & (py <= V[:, 1].max())
    assert inside.sum() > 1500
    assert np.all(count[inside] == 1)
    assert np.all(count[~inside] == 0)


def icosphere(subdivisions):
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(m.vertices), np.asarray(m.faces)


def test_closed_mesh_perspective_no_holes_and_culling_covers_once():
    V, F = icosphere(5)  # 20,480 triangles
    assert len(F) == 20480
    cam = {"position": [0.3, 0.4, 3.2], "look_at": [0.0, 0.0, 0.0], "fov": 45.0}
    W, H = 160, 120
    scene = mesh_scene(cam, V, F.tolist())
    r, _ = rasterizer(scene, W, H)
    both = r.coverage()
    r_cull, _ = rasterizer(scene, W, H, cull=True)
    front = r_cull.coverage()
    # the silhouette, from ray casting the same mesh
    img = lumos.render(scene, method="raycast", width=W, height=H, aov=["object_id"])
    hit = img.aovs["object_id"] >= 0
    interior = hit.copy()
    for axis in (0, 1):
        for shift in (1, -1):
            interior &= np.roll(hit, shift, axis=axis)
    assert interior.sum() > 4000
    assert np.all(front[interior] == 1)  # no crack: every sample inside the silhouette is covered, once
    assert np.all(both[interior] == 2)  # front and back surface, each once
    assert np.all(front <= 1)
    # and the shaded image has no background pixel inside the silhouette
    raster = lumos.render(scene, method="raster", width=W, height=H, aov=["object_id"])
    assert np.all(raster.aovs["object_id"][interior] == 0)


# ------------------------------------------------------------------------------------ closed forms


TRI = np.array([[-20.0, -15.0, 0.0], [22.0, -10.0, -3.0], [-5.0, 18.0, 2.0]])
TRI_N = unit(np.array([[-0.3, -0.2, 1.0], [0.4, -0.1, 1.0], [0.0, 0.5, 1.0]]))


@pytest.mark.nojit
@pytest.mark.parametrize("shading", ["flat", "gouraud", "phong"])
def test_one_triangle_matches_closed_form(shading):
    W, H = 64, 48
    cam = ortho(W, H)
    lights = [{"type": "point", "position": [10.0, 20.0, 40.0], "intensity": [0.9, 1.0, 1.1],
               "attenuation": [1.0, 0.0, 0.0002]},
              {"type": "directional", "direction": [0.4, -0.3, -1.0], "intensity": 0.35}]
    scene = mesh_scene(cam, TRI, [[0, 1, 2]], normals=TRI_N, lights=lights, ambient=0.1)
    img = lumos.render(scene, method="raster", shading=shading, width=W, height=H)
    xs, ys = samples(W, H)
    px, py = xs.ravel() - W / 2, H / 2 - ys.ravel()
    # barycentrics of each pixel centre in the (orthographic) image plane
    (x0, y0), (x1, y1), (x2, y2) = TRI[:, :2]
    det = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    b1 = ((px - x0) * (y2 - y0) - (x2 - x0) * (py - y0)) / det
    b2 = ((x1 - x0) * (py - y0) - (px - x0) * (y1 - y0)) / det
    b = np.stack([1 - b1 - b2, b1, b2], axis=1)
    interior = np.all(b > 0.02, axis=1)
    P = b @ TRI
    V = np.broadcast_to([0.0, 0.0, 1.0], P.shape)
    mat = {k: np.broadcast_to(np.asarray(v, float), (3,)) for k, v in MAT.items() if k != "shininess"}
    mat["shininess"] = MAT["shininess"]
    if shading == "flat":
        c = TRI.mean(axis=0, keepdims=True)
        fn = unit(np.cross(TRI[1] - TRI[0], TRI[2] - TRI[0])[None])
        expected = np.broadcast_to(classic_local(c, fn, V[:1], mat, lights, 0.1), P.shape)
    elif shading == "gouraud":
        at_vertices = classic_local(TRI, TRI_N, V[:3], mat, lights, 0.1)
        expected = b @ at_vertices
    else:
        expected = classic_local(P, unit(b @ TRI_N), V, mat, lights, 0.1)
    got = img.array.reshape(-1, 3)
    assert interior.sum() > 400
    err = np.abs(got[interior] - expected[interior])
    assert err.max() < 2e-3, err.max()


def test_shadings_differ_where_the_textbook_says():
    """Gouraud misses a highlight between vertices that Phong catches; flat is constant per polygon."""
    W, H = 64, 48
    light = [{"type": "directional", "direction": [0.0, 0.0, -1.0], "intensity": 1.0}]
    normals = unit(np.array([[-0.6, 0.0, 1.0], [0.6, 0.0, 1.0], [0.0, 0.6, 1.0]]))
    mat = {"kd": 0.2, "ks": 0.8, "shininess": 200.0}
    scene = mesh_scene(ortho(W, H), TRI, [[0, 1, 2]], normals=normals, material=mat, lights=light)
    flat, gouraud, phong = (lumos.render(scene, method="raster", shading=s, width=W, height=H).array
                            for s in ("flat", "gouraud", "phong"))
    covered = phong.sum(axis=2) > 0
    assert np.ptp(flat[covered], axis=0).max() < 1e-6
    assert phong.max() > 0.9  # the highlight where the interpolated normal faces the light
    assert gouraud.max() < 0.5  # missed: no vertex sees it


# ------------------------------------------------------------------------------- across methods


def smooth_sphere_scene(camera):
    V, F = icosphere(4)
    return mesh_scene(camera, V, F.tolist(), normals=V, lights=LIGHTS, ambient=0.05)


@pytest.mark.parametrize("camera", [
    {"position": [0.6, 0.9, 3.4], "look_at": [0.0, 0.0, 0.0], "fov": 42.0},
    {"type": "orthographic", "position": [1.0, 0.5, 4.0], "look_at": [0.0, 0.0, 0.0], "size": 2.6},
])
def test_raster_phong_equals_raycast_on_smooth_mesh(camera):
    scene = smooth_sphere_scene(camera)
    W, H = 160, 120
    ray = lumos.render(scene, method="raycast", width=W, height=H, aov=["object_id", "depth"])
    ras = lumos.render(scene, method="raster", shading="phong", width=W, height=H, aov=["object_id", "depth"])
    hit = ray.aovs["object_id"] >= 0
    interior = hit.copy()
    for axis in (0, 1):
        for shift in (1, -1):
            interior &= np.roll(hit, shift, axis=axis)
    assert interior.sum() > 3000
    assert np.array_equal(ras.aovs["object_id"][interior], ray.aovs["object_id"][interior])
    err = np.abs(ras.array - ray.array).max(axis=2)[interior]
    assert np.mean(err < 3e-3) >= 0.99, np.quantile(err, 0.99)
    assert np.allclose(ras.aovs["depth"][interior], ray.aovs["depth"][interior], rtol=1e-4)


def test_near_plane_clipping_of_a_triangle_through_the_camera():
    # a floor triangle that passes under and behind the eye: two vertices behind the camera
    cam = {"position": [0.0, 1.0, 0.0], "look_at": [0.0, 0.6, -3.0], "fov": 60.0}
    verts = [[-3.0, 0.0, 4.0], [3.0, 0.0, 4.0], [0.0, 0.0, -12.0]]
    scene = mesh_scene(cam, verts, [[0, 1, 2]], normals=[[0, 1, 0]] * 3, lights=LIGHTS, ambient=0.1)
    W, H = 96, 72
    ray = lumos.render(scene, method="raycast", width=W, height=H, aov=["object_id"])
    ras = lumos.render(scene, method="raster", width=W, height=H, aov=["object_id"])
    hit_ray = ray.aovs["object_id"] >= 0
    hit_ras = ras.aovs["object_id"] >= 0
    assert hit_ray.sum() > W * H // 4
    assert np.mean(hit_ray == hit_ras) > 0.99  # only edge pixels may differ
    both = hit_ray & hit_ras
    err = np.abs(ras.array - ray.array).max(axis=2)[both]
    assert np.mean(err < 3e-3) > 0.99
    assert np.isfinite(ras.array).all()


def test_perspective_correct_interpolation_on_a_slanted_plane():
    # a long quad receding from the camera: its depth along each ray, interpolated per pixel
    cam = {"position": [0.0, 1.0, 2.0], "look_at": [0.0, 0.0, -6.0], "fov": 50.0}
    verts = [[-2.0, 0.0, 1.0], [2.0, 0.0, 1.0], [2.0, 0.0, -30.0], [-2.0, 0.0, -30.0]]
    scene = mesh_scene(cam, verts, [[0, 1, 2, 3]], normals=[[0, 1, 0]] * 4, lights=LIGHTS)
    W, H = 96, 72
    ray = lumos.render(scene, method="raycast", width=W, height=H, aov=["depth"]).aovs["depth"]
    good = lumos.render(scene, method="raster", width=W, height=H, aov=["depth"]).aovs["depth"]
    affine = lumos.render(scene, method="raster", width=W, height=H, aov=["depth"],
                          perspective_correct=False).aovs["depth"]
    both = np.isfinite(ray) & np.isfinite(good)
    assert both.sum() > 1000
    rel = np.abs(good[both] - ray[both]) / ray[both]
    assert np.quantile(rel, 0.99) < 1e-5
    rel_affine = np.abs(affine[both] - ray[both]) / ray[both]
    assert rel_affine.max() > 0.05  # the textbook's distortion, clearly visible


# ---------------------------------------------------------------------------------- the rest


def test_back_face_culling_drops_triangles_facing_away():
    W, H = 32, 24
    front = [[-8.0, -6.0, 0.0], [8.0, -6.0, 0.0], [0.0, 8.0, 0.0]]  # counter-clockwise seen from +z
    for faces, visible in (([[0, 1, 2]], True), ([[0, 2, 1]], False)):
        scene = mesh_scene(ortho(W, H), front, faces, lights=LIGHTS)
        img = lumos.render(scene, method="raster", width=W, height=H, cull_backfaces=True, aov=["object_id"])
        assert (img.aovs["object_id"] >= 0).any() == visible
        both = lumos.render(scene, method="raster", width=W, height=H, aov=["object_id"])
        assert (both.aovs["object_id"] >= 0).any()


def test_concave_polygons_drawn_as_polygons_cover_what_their_triangles_cover():
    W = H = 48
    star = [[20 * math.cos(a) * (1.0 if k % 2 == 0 else 0.4), 20 * math.sin(a) * (1.0 if k % 2 == 0 else 0.4), 0.0]
            for k, a in enumerate(np.linspace(0, 2 * math.pi, 10, endpoint=False) + 0.1)]
    faces = [list(range(10))]
    r_poly, _ = rasterizer(mesh_scene(ortho(W, H), star, faces, triangulate=False), W, H)
    r_tris, _ = rasterizer(mesh_scene(ortho(W, H), star, faces), W, H)
    poly, tris = r_poly.coverage(), r_tris.coverage()
    assert tris.sum() > 300
    assert np.mean(poly == tris) > 0.995 and poly.max() == 1


def test_same_image_on_any_number_of_threads():
    scene = smooth_sphere_scene({"position": [0.6, 0.9, 3.4], "look_at": [0.0, 0.0, 0.0], "fov": 42.0})
    scene["lights"].append({"type": "area", "shape": "rect", "corner": [-1, 2, -1], "edge_u": [2, 0, 0],
                            "edge_v": [0, 0, 2], "radiance": 2.0, "samples": 4})
    a = lumos.render(scene, method="raster", width=64, height=48, spp=4, threads=1).array
    b = lumos.render(scene, method="raster", width=64, height=48, spp=4, threads=2).array
    assert np.array_equal(a, b)


def test_analytic_shapes_render_close_to_raycast():
    scene = {
        "camera": {"position": [0.0, 1.5, 6.0], "look_at": [0.0, 0.5, 0.0], "fov": 40.0},
        "ambient": 0.1, "lights": LIGHTS,
        "objects": [
            {"type": "sphere", "center": [-1.2, 0.8, 0.0], "radius": 0.8, "material": MAT},
            {"type": "box", "min": [0.3, 0.0, -0.5], "max": [1.5, 1.0, 0.5], "material": MAT},
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"kd": 0.5, "ka": 0.5}},
        ],
    }
    W, H = 120, 90
    ray = lumos.render(scene, method="raycast", width=W, height=H, aov=["object_id"])
    ras = lumos.render(scene, method="raster", width=W, height=H, tessellation=96, aov=["object_id"])
    same = ray.aovs["object_id"] == ras.aovs["object_id"]
    assert np.mean(same) > 0.98
    err = np.abs(ras.array - ray.array).max(axis=2)[same]
    assert np.mean(err < 2e-2) > 0.97


def test_shadow_rays_darken_what_an_occluder_hides():
    # a sphere above a floor, a light straight above: the floor point under the sphere is in its shadow
    scene = {
        "camera": {"position": [0.0, 0.3, 4.0], "look_at": [0.0, 0.0, 0.0], "fov": 40.0},
        "ambient": 0.2,
        "lights": [{"type": "point", "position": [0.0, 4.0, 0.0], "intensity": 1.0}],
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": {"ka": 0.5, "kd": 0.5}},
            {"type": "sphere", "center": [0.0, 1.0, 0.0], "radius": 0.5, "material": {"ka": 0.5, "kd": 0.5}},
        ],
    }
    W = H = 65  # odd: the centre pixel looks exactly at look_at, the floor point under the sphere
    lit = lumos.render(scene, method="raster", width=W, height=H).array[32, 32]
    shadowed = lumos.render(scene, method="raster", width=W, height=H, shadows=True)
    assert np.allclose(lit, 0.5 * 0.2 + 0.5 * 1.0, atol=1e-6)
    assert np.allclose(shadowed.array[32, 32], 0.5 * 0.2, atol=1e-6)  # ambient only
    assert shadowed.stats["rays"] > 0
    # a floor point far from the sphere is lit either way
    assert np.allclose(shadowed.array[60, 5], lumos.render(scene, method="raster", width=W, height=H).array[60, 5])


def half_plane_coverage(width, height, a, b, c, n=64):
    """Exact-enough area of each pixel where a·x + b·y + c > 0 (n×n point sampling)."""
    o = (np.arange(n) + 0.5) / n
    x = np.arange(width)[None, :, None, None] + o[None, None, None, :]
    y = np.arange(height)[:, None, None, None] + o[None, None, :, None]
    return (a * x + b * y + c > 0).mean(axis=(2, 3))


def test_supersampling_converges_to_pixel_coverage():
    W, H = 48, 36
    # a white triangle whose long edge crosses the image at a slant; ambient-only material, so value = coverage
    tri = [[-30.0, -30.0, 0.0], [30.0, 12.0, 0.0], [-30.0, 200.0, 0.0]]  # only the first edge crosses the image
    scene = mesh_scene(ortho(W, H), tri, [[0, 1, 2]], material={"ka": 1.0}, ambient=1.0)
    # the edge from (−30, −30) to (30, 12) in world → pixels (x + 24, 18 − y)
    (x0, y0), (x1, y1) = (-30.0 + 24, 18 + 30.0), (30.0 + 24, 18 - 12.0)
    a, b = -(y1 - y0), (x1 - x0)
    c = -(a * x0 + b * y0)
    if a * (-30.0 + 24) + b * (18 - 200.0) + c < 0:  # orient the half-plane towards the third vertex
        a, b, c = -a, -b, -c
    cover = half_plane_coverage(W, H, a, b, c)
    edge = (cover > 0.02) & (cover < 0.98)
    assert edge.sum() > 40
    err = {}
    for spp in (1, 16):
        img = lumos.render(scene, method="raster", width=W, height=H, spp=spp).array[..., 0]
        inside = img[~edge & (cover > 0.5)]
        assert np.allclose(inside, 1.0)
        err[spp] = np.abs(img[edge] - cover[edge]).mean()
    assert err[16] < 0.05 < err[1]


def test_area_lights_are_seen_from_their_emitting_side_only():
    scene = {
        "camera": {"position": [0.0, 0.0, 4.0], "look_at": [0.0, 0.0, 0.0], "fov": 40.0},
        "lights": [{"type": "area", "shape": "rect", "corner": [-1.0, -1.0, 0.0], "edge_u": [2.0, 0.0, 0.0],
                    "edge_v": [0.0, 2.0, 0.0], "radiance": [3.0, 2.0, 1.0]}],
    }
    front = lumos.render(scene, method="raster", width=33, height=33).array
    assert np.allclose(front[16, 16], [3.0, 2.0, 1.0])
    scene["lights"][0]["edge_u"], scene["lights"][0]["edge_v"] = [0.0, 2.0, 0.0], [2.0, 0.0, 0.0]
    back = lumos.render(scene, method="raster", width=33, height=33).array
    assert np.allclose(back[16, 16], 0.0)


@pytest.mark.parametrize("triangulate, differs", [(False, True), (True, False)])
def test_orientation_dependence_of_polygon_interpolation(triangulate, differs):
    """The textbook: interpolating along edges and scan lines makes a polygon's shading depend on its
    orientation on screen; triangles do not."""
    quad = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]
    tilted = unit(np.array([0.8, 0.0, 0.6]))
    normals = [[0.0, 0.0, 1.0], tilted, tilted, tilted]  # one bright corner: intensities 1, 0.6, 0.6, 0.6
    light = [{"type": "directional", "direction": [0.0, 0.0, -1.0], "intensity": 1.0}]
    centres = []
    for up in ([0.0, 1.0, 0.0], [1.0, 1.0, 0.0]):  # the quad upright, then turned 45° on screen
        cam = {"type": "orthographic", "position": [0.0, 0.0, 5.0], "look_at": [0.0, 0.0, 0.0], "up": up,
               "size": 3.0}
        scene = mesh_scene(cam, quad, [[0, 1, 2, 3]], normals=normals, material={"kd": 1.0}, lights=light,
                           triangulate=triangulate)
        img = lumos.render(scene, method="raster", shading="gouraud", width=33, height=33).array
        centres.append(img[16, 16, 0])
    if differs:
        assert abs(centres[0] - 0.7) < 1e-6  # upright: the mean of the four corners (bilinear)
        assert abs(centres[1] - centres[0]) > 0.05
    else:
        assert abs(centres[1] - centres[0]) < 1e-6


def test_bad_raster_keys_are_clear_errors():
    bad = mesh_scene(ortho(8, 8), TRI, [[0, 1, 2]], crease_angle=200)
    with pytest.raises(lumos.LumosError, match="crease_angle"):
        lumos.load_scene(bad)
    with pytest.raises(lumos.LumosError, match="tessellation"):
        lumos.render(mesh_scene(ortho(8, 8), TRI, [[0, 1, 2]]), method="raster", tessellation=2)


@pytest.mark.parametrize("shading", ["flat", "gouraud", "phong"])
def test_interpolated_normals_do_not_light_the_dark_side_at_silhouettes(shading):
    # a coarse sphere lit from the right: near its left outline, vertex normals face slightly away from the eye;
    # turning them towards the eye on their own would light the unlit half
    scene = {"camera": {"position": [0, 0, 5], "fov": 30},
             "lights": [{"type": "directional", "direction": [-1, 0, 0], "intensity": 1}],
             "objects": [{"type": "sphere", "material": {"kd": 1}}]}
    img = lumos.render(scene, method="raster", shading=shading, tessellation=8, width=101, height=101).array
    assert img[:, :50].max() == 0.0
    assert img[:, 51:].max() > 0.8


def test_polygons_kept_whole_honour_the_crease_angle_and_flat_shades_each_polygon_once():
    cube_v = [[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)]
    cube_f = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    cam = {"position": [3.0, 2.5, 4.0], "look_at": [0.0, 0.0, 0.0], "fov": 40.0}
    for triangulate in (False, True):
        scene = lumos.load_scene(mesh_scene(cam, cube_v, cube_f, crease_angle=60, triangulate=triangulate))
        mesh = compile_for(scene, resolve_settings(scene, {"method": "raster"})).raster
        assert len(mesh.positions) == 24  # split: each face its own normals
        assert np.allclose(np.abs(mesh.normals).max(axis=1), 1.0)
        # flat shading: both triangles of a face are shaded at the face's centre with its normal
        assert len(np.unique(np.round(mesh.prim_point, 9), axis=0)) == 6
