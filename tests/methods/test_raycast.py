"""`lumos.render(method="raycast")` against closed forms and against an independent implementation of
DESIGN.md §3 (`naive.render_classic`: NumPy camera rays, per-object analytic intersection, the classic model).

The done criterion of the project is `test_matches_independent_implementation`: raycast on scenes of spheres,
boxes and planes under point and directional lights agrees with the naive renderer to within 2e-3 on at least
99 % of the pixels.
"""

import math

import numpy as np
import numba
import pytest
from conftest import render
from naive import camera_basis, camera_rays, hit_disk, hit_rect, hit_sphere, render_classic

import lumos
from lumos.compile.camera import camera_arrays
from lumos.kernels.camera import camera_ray

# ------------------------------------------------------------------------------------- a Lambert sphere

SPHERE_C, SPHERE_R = np.array([0.2, -0.1, 0.0]), 1.0
KD = np.array([0.6, 0.5, 0.4])
LIGHT_P, LIGHT_I, ATT = np.array([3.0, 4.0, 5.0]), 2.0, (1.0, 0.1, 0.02)


def lambert_scene(camera):
    return {
        "camera": camera,
        "lights": [{"type": "point", "position": LIGHT_P.tolist(), "intensity": LIGHT_I, "attenuation": list(ATT)}],
        "objects": [{"type": "sphere", "center": SPHERE_C.tolist(), "radius": SPHERE_R,
                     "material": {"kd": KD.tolist()}}],
    }


def lambert_closed_form(camera, width, height):
    """Kd·I·max(N·L, 0)/att(d) per pixel, N = (p − c)/r from the pixel's ray; also a silhouette mask (rays
    passing within 1e-6·r of the sphere's outline, where hit or miss is a matter of rounding)."""
    o, d = camera_rays(camera, width, height)
    t, _ = hit_sphere(o, d, SPHERE_C, SPHERE_R)
    hit = np.isfinite(t)
    p = o + np.where(hit, t, 0.0)[:, None] * d
    N = (p - SPHERE_C) / SPHERE_R
    to = LIGHT_P - p
    dist = np.linalg.norm(to, axis=1)
    att = ATT[0] + ATT[1] * dist + ATT[2] * dist**2
    value = KD * (LIGHT_I * np.maximum((N * to).sum(axis=1) / dist, 0.0) / att)[:, None]
    value[~hit] = 0.0
    impact = np.linalg.norm(np.cross(SPHERE_C - o, d), axis=1) / np.linalg.norm(d, axis=1)
    silhouette = np.abs(impact - SPHERE_R) < 1e-6 * SPHERE_R
    return value.reshape(height, width, 3), hit.reshape(height, width), silhouette.reshape(height, width)


CAMERAS = {
    "perspective": {"position": [0.5, 0.8, 5.0], "look_at": [0.1, 0.0, 0.0], "fov": 40.0},
    "orthographic": {"type": "orthographic", "position": [0.3, 2.0, 4.0], "look_at": [0.2, -0.1, 0.0],
                     "size": 3.0},
}


@pytest.mark.parametrize("cam", list(CAMERAS))
def test_lambert_sphere_matches_closed_form(cam):
    camera = CAMERAS[cam]
    img = render(lambert_scene(camera), width=64, height=48).array
    want, hit, silhouette = lambert_closed_form(camera, 64, 48)
    assert hit.sum() > 300 and (want > 0.05).sum() > 100
    ok = ~silhouette
    assert np.array_equal((img > 0).any(axis=2)[ok], (want > 0).any(axis=2)[ok])
    np.testing.assert_allclose(img[ok], want[ok], rtol=1e-5, atol=1e-7)


@pytest.mark.nojit
def test_tiny_lambert_sphere_render():
    # 8×6 pixels: small enough to run with the JIT off (see test_nojit.py)
    camera = {"position": [0.0, 0.0, 5.0], "look_at": [0.0, 0.0, 0.0], "fov": 40.0}
    img = render(lambert_scene(camera), width=8, height=6).array
    want, hit, silhouette = lambert_closed_form(camera, 8, 6)
    assert hit.sum() >= 4 and not silhouette.any()
    np.testing.assert_allclose(img, want, rtol=1e-5, atol=1e-7)


# ------------------------------------------------------------------------------------ the done criterion


def done_scene(camera):
    return {
        "camera": camera,
        "ambient": [0.1, 0.12, 0.15],
        "background": [0.02, 0.03, 0.05],
        "lights": [
            {"type": "point", "position": [4.0, 6.0, 5.0], "intensity": [1.2, 1.1, 1.0],
             "attenuation": [1.0, 0.02, 0.005]},
            {"type": "point", "position": [-5.0, 3.0, 2.0], "diffuse": [0.3, 0.35, 0.5], "specular": 0.8},
            {"type": "directional", "direction": [0.3, -1.0, -0.4], "intensity": [0.5, 0.45, 0.4]},
        ],
        "materials": {
            "red": {"ka": [0.4, 0.1, 0.1], "kd": [0.7, 0.15, 0.1], "ks": 0.5, "shininess": 40},
            "blue": {"ka": 0.1, "kd": [0.1, 0.2, 0.8], "ks": [0.3, 0.3, 0.6], "shininess": 8},
            "matte": {"ka": 0.3, "kd": 0.6},
            "gold": {"ka": [0.2, 0.15, 0.05], "kd": [0.6, 0.45, 0.1], "ks": [0.8, 0.7, 0.3], "shininess": 120},
        },
        "objects": [
            {"type": "plane", "point": [0.0, -1.0, 0.0], "normal": [0.0, 1.0, 0.0], "material": "matte"},
            {"type": "plane", "point": [0.0, 0.0, -6.0], "normal": [0.1, 0.0, 1.0], "material": "blue"},
            {"type": "sphere", "center": [-1.2, 0.0, 0.0], "radius": 1.0, "material": "red"},
            {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0, "material": "gold",
             "transform": {"translate": [1.4, 0.2, -0.8], "rotate": [0.0, 30.0, 20.0], "scale": [0.6, 1.1, 0.8]}},
            {"type": "box", "min": [-0.5, -1.0, -0.5], "max": [0.5, 0.0, 0.5], "material": "blue",
             "transform": {"translate": [0.6, 0.0, 1.3], "rotate": [0.0, 35.0, 0.0], "scale": [1.2, 1.0, 0.7]}},
            {"type": "box", "min": [-3.0, -1.0, -4.0], "max": [-2.2, 1.5, -3.0], "material": "gold"},
            {"type": "sphere", "center": [2.2, -0.6, 1.2], "radius": 0.4, "material": "matte"},
            # a plane tilted by a transform (its normal must follow the inverse transpose)
            {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "material": "red",
             "transform": {"translate": [4.5, 0.0, 0.0], "rotate": [0.0, -70.0, 0.0], "scale": [1.0, 2.0, 1.0]}},
        ],
    }


@pytest.mark.parametrize("cam", ["perspective", "orthographic"])
def test_matches_independent_implementation(cam):
    camera = {
        "perspective": {"position": [1.0, 2.5, 7.0], "look_at": [0.2, -0.2, 0.0], "up": [0.0, 1.0, 0.1],
                        "fov": 50.0},
        "orthographic": {"type": "orthographic", "position": [3.0, 4.0, 6.0], "look_at": [0.0, -0.3, 0.0],
                         "size": 6.0},
    }[cam]
    scene = done_scene(camera)
    W, H = 160, 120
    img = render(scene, width=W, height=H, aov=["object_id"])
    want, _, obj = render_classic(scene, W, H)
    close = (np.abs(img.array - want) <= 2e-3).all(axis=2)
    assert close.mean() >= 0.99, f"only {close.mean():.4f} of the pixels agree to 2e-3"
    # the scene is not trivial: every object is seen, and the two renderers agree on which is where
    assert set(np.unique(obj)) >= set(range(len(scene["objects"])))
    assert (img.aovs["object_id"] == obj).mean() >= 0.99
    assert want.std() > 0.1 and (want.max(axis=2) > 1.0).any()  # bright highlights as well as shadows


# ---------------------------------------------------------------------------- background and emitters


@pytest.mark.nojit
def test_background_where_nothing_is_hit():
    camera = CAMERAS["perspective"]
    scene = {**lambert_scene(camera), "background": [0.1, 0.2, 0.3]}
    img = render(scene, width=48, height=36).array
    _, hit, silhouette = lambert_closed_form(camera, 48, 36)
    miss = ~hit & ~silhouette
    assert miss.sum() > 500
    assert (img[miss] == np.float32([0.1, 0.2, 0.3])).all()
    assert not (img[hit & ~silhouette] == np.float32([0.1, 0.2, 0.3])).all(axis=1).any()


@pytest.mark.parametrize("shape", ["rect", "disk", "sphere"])
def test_area_light_seen_directly(shape):
    Le = [2.0, 3.0, 4.0]
    camera = {"position": [0.3, 0.2, 5.0], "look_at": [0.0, 0.0, 0.0], "fov": 40.0}
    if shape == "rect":
        light = {"type": "area", "shape": "rect", "corner": [-1.0, -0.7, 0.1], "edge_u": [2.0, 0.0, 0.2],
                 "edge_v": [0.0, 1.4, 0.0]}
        footprint = lambda o, d: hit_rect(o, d, [-1.0, -0.7, 0.1], [2.0, 0.0, 0.2], [0.0, 1.4, 0.0])  # noqa: E731
    elif shape == "disk":
        light = {"type": "area", "shape": "disk", "center": [0.1, 0.0, 0.0], "normal": [0.1, 0.2, 1.0],
                 "radius": 1.1}
        footprint = lambda o, d: hit_disk(o, d, [0.1, 0.0, 0.0], [0.1, 0.2, 1.0], 1.1)  # noqa: E731
    else:
        light = {"type": "area", "shape": "sphere", "center": [0.1, 0.0, 0.0], "radius": 1.0}
        footprint = lambda o, d: hit_sphere(o, d, [0.1, 0.0, 0.0], 1.0)  # noqa: E731
    light.update(radiance=Le, samples=4)
    scene = {"camera": camera, "lights": [light]}
    img = render(scene, width=48, height=36).array
    o, d = camera_rays(camera, 48, 36)
    seen = np.isfinite(footprint(o, d)[0]).reshape(36, 48)
    assert seen.sum() > 200
    np.testing.assert_array_equal(img[seen], np.broadcast_to(np.float32(Le), img[seen].shape))
    assert (img[~seen] == 0.0).all()
    # from behind: rect and disk are one-sided (black), a sphere light glows all round
    back = {**camera, "position": [0.2, -0.3, -5.0]}
    img = render({**scene, "camera": back}, width=48, height=36).array
    o, d = camera_rays(back, 48, 36)
    seen = np.isfinite(footprint(o, d)[0]).reshape(36, 48)
    assert seen.sum() > 200
    if shape == "sphere":
        np.testing.assert_array_equal(img[seen], np.broadcast_to(np.float32(Le), img[seen].shape))
    else:
        assert (img == 0.0).all()


# ------------------------------------------------------------------------------------------------- AOVs


def test_aovs_depth_normal_object_albedo():
    camera = {"position": [0.5, 1.5, 6.0], "look_at": [0.0, 0.0, 0.0], "fov": 45.0}
    scene = {
        "camera": camera,
        "lights": [{"type": "directional", "direction": [0.0, -1.0, -1.0]}],
        "objects": [
            {"type": "sphere", "center": [-0.8, 0.0, 0.0], "radius": 0.9, "material": {"kd": [0.9, 0.1, 0.2]}},
            {"type": "box", "min": [0.3, -1.0, -0.5], "max": [1.6, 0.6, 0.7], "material": {"kd": [0.1, 0.8, 0.3]}},
            {"type": "plane", "point": [0.0, -1.0, 0.0], "normal": [0.0, 1.0, 0.0], "material": {"kd": 0.5}},
        ],
    }
    W, H = 64, 48
    img = render(scene, width=W, height=H, aov=["depth", "normal", "object_id", "albedo"])
    depth, normal, obj, albedo = (img.aovs[k] for k in ("depth", "normal", "object_id", "albedo"))
    _, t_want, obj_want = render_classic({**scene, "objects": [
        {**o, "material": {"kd": 1.0}} for o in scene["objects"]]}, W, H)
    assert set(np.unique(obj_want)) == {-1, 0, 1, 2}
    agree = obj == obj_want
    assert agree.mean() > 0.99
    hit = (obj_want >= 0) & agree
    # depth: the distance along the (unit) camera ray
    np.testing.assert_allclose(depth[hit], t_want[hit], rtol=1e-5)
    assert np.isinf(depth[obj_want < 0]).all() and (obj[obj_want < 0] == -1).all()
    # normal: unit, facing the camera, and the analytic one
    o, d = camera_rays(camera, W, H)
    d = d.reshape(H, W, 3)
    np.testing.assert_allclose(np.linalg.norm(normal[hit], axis=1), 1.0, atol=1e-6)
    assert ((normal[hit] * d[hit]).sum(axis=1) < 0).all()
    sphere = hit & (obj == 0)
    p = o.reshape(H, W, 3)[sphere] + depth[sphere][:, None] * d[sphere]
    np.testing.assert_allclose(normal[sphere], (p - [-0.8, 0.0, 0.0]) / 0.9, atol=1e-5)
    np.testing.assert_allclose(normal[hit & (obj == 2)], np.broadcast_to([0, 1, 0], normal[hit & (obj == 2)].shape),
                               atol=1e-7)
    box_n = normal[hit & (obj == 1)]
    assert np.allclose(np.sort(np.abs(box_n), axis=1), [0, 0, 1], atol=1e-7)  # axis-aligned faces
    # albedo = kd of the object hit
    kd = np.array([[0.9, 0.1, 0.2], [0.1, 0.8, 0.3], [0.5, 0.5, 0.5]], np.float32)
    np.testing.assert_array_equal(albedo[hit], kd[obj[hit]])
    # the image does not depend on which AOVs are asked for (without any, their buffers are not filled at all)
    bare = render(scene, width=W, height=H)
    assert bare.aovs == {}
    np.testing.assert_array_equal(bare.array, img.array)
    one = render(scene, width=W, height=H, aov=["normal"])
    assert set(one.aovs) == {"normal"}
    np.testing.assert_array_equal(one.aovs["normal"], normal)


# --------------------------------------------------------------------------------- pixels and samples


def _cam_arrays(camera):
    return camera_arrays(lumos.load_scene({"camera": camera}).camera)


@pytest.mark.parametrize("kind", ["perspective", "orthographic"])
@pytest.mark.nojit
def test_camera_ray_pixel_centres_follow_design(kind):
    camera = {**CAMERAS[kind], "up": [0.1, 1.0, 0.0]}
    vecs, params = _cam_arrays(camera)
    W, H = 7, 5
    o_want, d_want = camera_rays(camera, W, H)
    for y in range(H):
        for x in range(W):
            o, d = camera_ray(vecs, params, W, H, x, y, 0, 1, 0, y * W + x)
            np.testing.assert_allclose(o, o_want[y * W + x], atol=1e-12)
            np.testing.assert_allclose(d, d_want[y * W + x], atol=1e-12)


@pytest.mark.parametrize("kind", ["perspective", "orthographic"])
def test_samples_stay_inside_their_pixel(kind):
    camera = CAMERAS[kind]
    vecs, params = _cam_arrays(camera)
    pos, u, v, w = camera_basis(camera)
    W, H, spp = 16, 12, 16
    aspect = W / H
    for x, y in [(0, 0), (15, 11), (7, 4), (3, 9)]:
        cells = set()
        for s in range(spp):
            o, d = camera_ray(vecs, params, W, H, x, y, s, spp, 11, y * W + x)
            if kind == "orthographic":
                sx = (np.subtract(o, pos) @ u) / (aspect * camera["size"] / 2)
                sy = (np.subtract(o, pos) @ v) / (camera["size"] / 2)
            else:
                t = math.tan(math.radians(camera["fov"]) / 2)
                sx = (np.array(d) @ u) / (-np.array(d) @ w) / (aspect * t)
                sy = (np.array(d) @ v) / (-np.array(d) @ w) / t
            px, py = (sx + 1) * W / 2, (1 - sy) * H / 2  # continuous pixel coordinates
            assert x <= px < x + 1 and y <= py < y + 1
            cells.add((int((px - x) * 4), int((py - y) * 4)))  # stratified: one sample per 4×4 sub-cell
        assert len(cells) == spp


@pytest.mark.nojit
def test_supersampling_does_not_leak_across_pixel_edges():
    # orthographic, 2 world units over 8 pixels: the box's edge x = 0 lies exactly on a pixel boundary
    camera = {"type": "orthographic", "position": [0.0, 0.0, 5.0], "look_at": [0.0, 0.0, 0.0], "size": 2.0}
    scene = {"camera": camera, "ambient": 0.5, "background": [0.0, 0.0, 1.0],
             "objects": [{"type": "box", "min": [-5.0, -5.0, -1.0], "max": [0.0, 5.0, 0.0], "material": {"ka": 1.0}},
                         {"type": "plane", "point": [0, 0, -3.0], "normal": [0, 0, 1.0],
                          "material": {"ka": [0.0, 2.0, 0.0]}}]}
    one = render(scene, width=8, height=8, spp=1).array
    many = render(scene, width=8, height=8, spp=16, seed=3).array
    assert (one[:, :4] == 0.5).all() and (one[:, 4:] == np.float32([0, 1, 0])).all()
    np.testing.assert_array_equal(many, one)


def test_uniform_plane_same_value_at_any_spp():
    camera = {"position": [0.0, 3.0, 0.0], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 0.0, -1.0], "fov": 30.0}
    scene = {"camera": camera, "ambient": 0.25,
             "lights": [{"type": "directional", "direction": [0.0, -1.0, 0.0], "intensity": 0.5}],
             "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1.0, 0],
                          "material": {"ka": 1.0, "kd": 0.5}}]}
    for spp in (1, 4, 9, 5):
        img = render(scene, width=16, height=12, spp=spp).array
        np.testing.assert_allclose(img, 0.25 + 0.25, rtol=1e-6)


def test_thin_lens_focus():
    # flat-shaded white spheres (ambient only) on black: the image is their coverage of each pixel
    def image(center, aperture):
        scene = {"camera": {"position": [0.0, 0.0, 0.0], "look_at": [0.0, 0.0, -1.0], "fov": 30.0,
                            "aperture": aperture, "focus_distance": 5.0},
                 "ambient": 1.0,
                 "objects": [{"type": "sphere", "center": center, "radius": 0.3, "material": {"ka": 1.0}}]}
        return render(scene, width=48, height=48, spp=16, seed=5).array[:, :, 0]

    sharp_pin, sharp_lens = image([0.2, 0.1, -5.0], 0.0), image([0.2, 0.1, -5.0], 0.25)
    near_pin, near_lens = image([0.1, 0.05, -2.0], 0.0), image([0.1, 0.05, -2.0], 0.25)
    # at the focus distance the lens changes the image by well under a pixel's worth along the outline
    assert np.abs(sharp_lens - sharp_pin).sum() < 0.3 * np.abs(np.diff(sharp_pin, axis=1)).sum()
    # far from it the disc is blurred: many more partly covered pixels, yet about the same total light
    partial = lambda img: ((img > 0.05) & (img < 0.95)).sum()  # noqa: E731
    assert partial(near_lens) > 3 * partial(near_pin)
    assert near_lens.sum() == pytest.approx(near_pin.sum(), rel=0.1)
    assert np.abs(near_lens - near_pin).sum() > 5 * np.abs(sharp_lens - sharp_pin).sum()


# -------------------------------------------------------------------------------------------- determinism


def _noisy_scene():
    return {
        "camera": {"position": [0.0, 1.0, 4.0], "look_at": [0.0, 0.0, 0.0], "fov": 45.0},
        "lights": [{"type": "area", "shape": "rect", "corner": [-1.0, 2.0, -1.0], "edge_u": [2.0, 0.0, 0.0],
                    "edge_v": [0.0, 0.0, 2.0], "radiance": 3.0, "samples": 4}],
        "objects": [{"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0, "material": {"kd": 0.8}},
                    {"type": "plane", "point": [0, -1.0, 0], "normal": [0, 1.0, 0], "material": {"kd": 0.5}}],
    }


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two Numba threads")
def test_deterministic_across_threads_and_runs():
    scene = _noisy_scene()
    kw = dict(width=40, height=30, spp=4, seed=9)
    a = render(scene, threads=1, **kw).array
    b = render(scene, threads=2, **kw).array
    c = render(scene, threads=2, **kw).array
    assert np.array_equal(a, b) and np.array_equal(b, c)
    other = render(scene, threads=2, **{**kw, "seed": 10}).array
    diff = other != a
    assert diff.any(axis=2).mean() > 0.3  # the area-light noise moved
    lit = a.max(axis=2) > 0.05
    assert other[lit].mean() == pytest.approx(a[lit].mean(), rel=0.02)  # but not the expected value


def test_antialias_settings_of_raycast():
    scene = {"objects": [{"type": "sphere", "material": {"kd": 0.5}}],
             "lights": [{"type": "directional", "direction": [0, 0, -1]}]}
    img = render(scene, width=8, height=6, spp=4, aov=["samples"])
    assert img.stats["primary_rays"] == 8 * 6 * 4 and np.all(img.aovs["samples"] == 4)
    one = render(scene, width=8, height=6, spp=4, antialias="none")
    assert one.stats["primary_rays"] == 8 * 6
    with pytest.raises(lumos.LumosError, match="adaptive"):
        render(scene, width=8, height=6, antialias="adaptive")
    with pytest.raises(lumos.LumosError, match="adaptive"):
        render(scene, method="raster", width=8, height=6, antialias="adaptive")


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_one_sided_emitters_show_their_emission_on_the_front_only(method):
    """An emissive rect with `two_sided: false`, and a rect area light, seen from the side their normal faces show
    their emission, from behind nothing; two-sided, both sides show it (every local method, the same rule)."""

    def centre(facing_camera: bool, two_sided: bool, light: bool) -> np.ndarray:
        # cross(edge_u, edge_v) is +z (towards the camera) or -z
        eu, ev = ([1, 0, 0], [0, 1, 0]) if facing_camera else ([0, 1, 0], [1, 0, 0])
        panel = {"corner": [-0.5, -0.5, 0], "edge_u": eu, "edge_v": ev, "two_sided": two_sided}
        scene = {"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 30},
                 "render": {"width": 16, "height": 16, "method": method}}
        if light:
            scene["lights"] = [{"type": "area", "shape": "rect", "radiance": [2, 3, 4], **panel}]
        else:
            scene["objects"] = [{"type": "rect", "material": {"kd": 0, "emission": [2, 3, 4]}, **panel}]
        return lumos.render(scene).array[8, 8]

    for light in (False, True):
        np.testing.assert_allclose(centre(True, False, light), [2, 3, 4], rtol=1e-6)
        np.testing.assert_array_equal(centre(False, False, light), [0, 0, 0])
        np.testing.assert_allclose(centre(False, True, light), [2, 3, 4], rtol=1e-6)


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_the_gaussian_pixel_filter_blurs_an_edge_as_its_cdf_says(method):
    """A white half-plane whose edge is a pixel boundary, seen head-on: with the box filter the pixels beside the
    edge are 0 and 1; with the Gaussian (σ = 0.5 pixel, truncated at 2, Mitsuba's) each sample is drawn from the
    filter about the pixel's centre, so the pixel half a pixel left of the edge shows the mass beyond 0.5 pixel,
    (Φ(4) − Φ(1))/(Φ(4) − Φ(−4)) = 0.1587, and the one 1.5 pixels away (Φ(4) − Φ(3))/(…) = 0.0013."""
    from math import erf, sqrt

    def phi(x):
        return 0.5 * (1 + erf(x / sqrt(2)))

    scene = {"camera": {"type": "orthographic", "position": [0, 0, 4], "look_at": [0, 0, 0], "size": 2},
             "render": {"width": 16, "height": 16, "method": method, "spp": 1024, "antialias": "supersample"},
             "ambient": 1.0,
             "objects": [{"type": "rect", "corner": [0, -2, 0], "edge_u": [4, 0, 0], "edge_v": [0, 4, 0],
                          "material": {"ka": 1.0, "kd": 0.0}}]}
    box = lumos.render(scene).array[:, :, 1]
    np.testing.assert_allclose(box[:, 7], 0.0, atol=1e-6)
    np.testing.assert_allclose(box[:, 8], 1.0, atol=1e-6)
    # (mean over rows: a pixel's 32 samples in the stratum the edge cuts are a binomial draw; raster's passes
    # place every pixel's samples alike)
    smooth = lumos.render(scene, filter="gaussian").array[2:14, :, 1].mean(axis=0)
    total = phi(4) - phi(-4)
    assert smooth[7] == pytest.approx((phi(4) - phi(1)) / total, abs=0.01)
    assert smooth[8] == pytest.approx((phi(1) - phi(-4)) / total, abs=0.01)
    assert smooth[6] == pytest.approx((phi(4) - phi(3)) / total, abs=0.003)
    assert smooth[5] == pytest.approx(0.0, abs=1e-6)  # 2.5 pixels: beyond the filter's radius


def test_adaptive_anti_aliasing_refuses_the_gaussian_filter():
    scene = {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]}, "objects": [{"type": "sphere"}]}
    with pytest.raises(lumos.LumosError, match="render.filter: gaussian filtering needs supersample"):
        lumos.render(scene, method="whitted", antialias="adaptive", filter="gaussian", width=8, height=8)
