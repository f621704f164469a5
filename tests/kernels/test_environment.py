"""The environment light (kernels/environment.py, compile/environment.py): lookups in the lat-long image, sampling
that follows its density (χ²), and what `path` makes of it against closed forms."""

import math

import numba
import numpy as np
import pytest
from chi2 import chi2_directions
from helpers import interior_of

import lumos
from lumos.compile.emitters import build_emitters
from lumos.compile import compile_scene
from lumos.compile.environment import image_arrays, mean_radiance
from lumos.kernels.environment import env_bilinear, env_pdf, env_radiance, env_sample
from lumos.kernels.layout import ENV_COS, ENV_SIN


def table(image, rotation=0.0):
    """An emitter table holding a sphere's scene and the environment `image` (H, W, 3)."""
    compiled = compile_scene(lumos.load_scene({"objects": [{"type": "sphere"}]}))
    return build_emitters(compiled.arrays, compiled.bounds, image_arrays(image, rotation))


@numba.njit(cache=True)
def _samples(em, u):
    out = np.full((u.shape[0], 3), np.nan)
    for k in range(u.shape[0]):
        d, pdf = env_sample(em, u[k, 0], u[k, 1])
        if pdf > 0.0:
            out[k, 0], out[k, 1], out[k, 2] = d
    return out


@numba.njit(cache=True)
def _pdfs(em, dirs):
    out = np.empty(dirs.shape[0])
    for k in range(dirs.shape[0]):
        out[k] = env_pdf(em, (dirs[k, 0], dirs[k, 1], dirs[k, 2]))
    return out


@numba.njit(cache=True)
def _radiance(em, d):
    return env_radiance(em, (d[0], d[1], d[2]))


def sky(h=32, w=64, seed=0):
    rng = np.random.default_rng(seed)
    img = rng.random((h, w, 3)).astype(np.float32) * 0.5
    img[5:8, 40:44] = 50.0  # a sun
    img[h // 2:] *= 0.2
    img[:, 3] = 0.0  # a black column: never drawn
    return img


@pytest.mark.parametrize("rotation", [0.0, 70.0])
def test_environment_sampling_follows_its_pdf(rotation):
    em = table(sky(), rotation)
    frame = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])  # θ from +y
    result = chi2_directions(lambda u: _samples(em, np.ascontiguousarray(u)),
                             lambda d: _pdfs(em, np.ascontiguousarray(d)), frame=frame, sphere=True, seed=1)
    assert result.p_value > 1e-3, result.message


def test_the_pdf_integrates_to_one_and_is_zero_only_where_the_sky_is_black():
    em = table(sky())
    rng = np.random.default_rng(3)
    d = rng.normal(size=(400_000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    pdf = _pdfs(em, d)
    assert 4 * math.pi * pdf.mean() == pytest.approx(1.0, abs=0.01)
    lum = np.array([np.mean(_radiance(em, x)) for x in d[:2000]])
    assert np.all((pdf[:2000] > 0) == (lum > 0))  # drawn wherever there is light, never where there is none


def test_lat_long_orientation_and_rotation():
    """The image's top row is +y, its middle column −z, the column a quarter to the right +x; rotation turns the
    middle column from −z towards −x."""
    h, w = 8, 16
    img = np.zeros((h, w, 3), np.float32)
    img[0, :, 0] = 1.0  # top row red
    img[:, w // 2, 1] = 1.0  # middle column green
    img[:, 3 * w // 4, 2] = 1.0  # a quarter to the right: blue
    em = table(img)
    assert _radiance(em, np.array([0.0, 1.0, 0.0]))[0] == 1.0
    assert _radiance(em, np.array([0.0, 0.0, -1.0]))[1] == 1.0
    assert _radiance(em, np.array([1.0, 0.0, 0.0]))[2] == 1.0
    turned = table(img, rotation=90.0)
    assert _radiance(turned, np.array([-1.0, 0.0, 0.0]))[1] == 1.0
    assert _radiance(turned, np.array([0.0, 0.0, -1.0]))[1] == 0.0


def test_a_white_furnace_under_a_constant_sky():
    """A diffuse sphere of albedo 0.8 under a uniform environment of radiance 1 (nothing else) reflects 0.8 of it
    at every point (a convex body sees only the sky); the sky itself is 1 where rays miss."""
    img = lumos.render({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 30},
                        "render": {"width": 32, "height": 32, "method": "path", "spp": 64},
                        "environment": {"color": 1.0},
                        "objects": [{"type": "sphere", "radius": 1, "material": {"kd": 0.8}}]},
                       aov=["variance", "object_id"], seed=2)
    hit = interior_of(img.aovs["object_id"])  # (pixels on the silhouette also see the sky)
    mean = img.array[hit].mean(axis=0)
    err = np.sqrt(img.aovs["variance"][hit].sum(axis=0)) / hit.sum()
    assert np.all(np.abs(mean - 0.8) < 4 * err + 1e-4), (mean, err)
    np.testing.assert_allclose(img.array[:4, :4], 1.0)  # a corner: the sky itself


def test_a_sun_in_the_environment_lights_a_floor_as_its_solid_angle_says():
    """A black environment but for one bright block of pixels (a sun) over a diffuse floor of albedo ρ: the floor's
    radiance is ρ/π·E, E = Σ L·∫cos θ dω over the block's pixels in closed form (per pixel Δφ·(sin²θ1 − sin²θ0)/2,
    θ from the zenith), by light sampling and BSDF sampling together."""
    h, w, L = 32, 64, 40.0
    img = np.zeros((h, w, 3), np.float32)
    rows, cols = slice(4, 7), slice(10, 14)
    img[rows, cols] = L
    np.save("/tmp/lumos_test_sun.npy", img)
    theta = np.arange(h + 1) / h * np.pi
    e = 0.0
    for i in range(4, 7):
        e += L * (cols.stop - cols.start) * (2 * np.pi / w) * (np.sin(theta[i + 1]) ** 2 - np.sin(theta[i]) ** 2) / 2
    rho = 0.5
    scene = {"camera": {"position": [0, 3, 0.01], "look_at": [0, 0, 0], "fov": 20},
             "render": {"width": 16, "height": 16, "method": "path", "spp": 256, "max_depth": 0},
             "environment": {"file": "/tmp/lumos_test_sun.npy"},
             "objects": [{"type": "plane", "material": {"kd": rho}}]}
    img = lumos.render(scene, aov=["variance"], seed=4)
    mean = img.array.mean()
    err = np.sqrt(img.aovs["variance"].sum()) / img.array.size * np.sqrt(3)
    assert mean == pytest.approx(rho / np.pi * e, abs=4 * err), (mean, rho / np.pi * e, err)


def test_mean_radiance_weights_rows_by_solid_angle():
    img = np.zeros((4, 8, 3), np.float32)
    img[:2] = 1.0  # the upper hemisphere
    assert mean_radiance(img) == pytest.approx([0.5] * 3)


@pytest.mark.parametrize("method", ["raycast", "whitted"])
def test_the_ray_methods_see_the_environment_where_rays_leave(tmp_path, method):
    """raycast and whitted look the image up where a ray leaves the scene, bilinear between pixel centres: the
    camera ray along +x reads u = 3/4, the edge between columns 11 and 12, so their mean; whitted's mirror sphere
    ahead sends the centre ray back along −x, to u = 1/4, between columns 3 and 4."""
    h, w = 8, 16
    img = np.zeros((h, w, 3), np.float32)
    img[:, :, 0] = (np.arange(w) + 1.0) / w  # red: the column
    img[:, :, 1] = 0.5
    np.save(tmp_path / "cols.npy", img)
    scene = {"camera": {"position": [0, 0, 0], "look_at": [1, 0, 0], "fov": 5},
             "render": {"width": 3, "height": 3, "method": method, "spp": 1},
             "environment": {"file": str(tmp_path / "cols.npy")}}
    centre = lumos.render(scene).array[1, 1]
    np.testing.assert_allclose(centre, [12.5 / 16, 0.5, 0.0], rtol=1e-6)  # +x: u = 3/4, columns 11 and 12
    if method == "whitted":
        scene["objects"] = [{"type": "sphere", "center": [3, 0, 0], "radius": 1, "material": {"kr": 1.0}}]
        mirrored = lumos.render(scene).array[1, 1]
        np.testing.assert_allclose(mirrored, [4.5 / 16, 0.5, 0.0], rtol=1e-6)  # −x: u = 1/4, columns 3 and 4


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_the_environment_is_the_classic_ambient_light_unless_one_is_given(method):
    """Without an `ambient`, the classic methods' Ia is the environment's irradiance over π: a sphere of ka 0.5
    and nothing else under a uniform sky of 0.4 shows 0.2 (a white matte surface under a uniform sky L reflects
    L); a scene's own ambient wins."""
    scene = {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 20},
             "render": {"width": 9, "height": 9, "method": method},
             "environment": {"color": 0.4},
             "objects": [{"type": "sphere", "material": {"ka": 0.5}}]}
    np.testing.assert_allclose(lumos.render(scene).array[4, 4], 0.2, rtol=1e-5)
    scene["ambient"] = 0.1
    np.testing.assert_allclose(lumos.render(scene).array[4, 4], 0.05, rtol=1e-5)


def test_the_ambient_of_an_environment_follows_the_normal():
    """Ia(n) = E(n)/π in nine spherical harmonics: under a sky of radiance 1 above the horizon and 0 below,
    E(n)/π = (1 + n_y)/2 in closed form (the visible part of the sky, cosine-weighted); the harmonics hold it to
    a few parts in a thousand. Turning the environment turns Ia with it."""
    from lumos.kernels.illumination import ambient_light

    half = np.zeros((32, 64, 3), np.float32)
    half[:16] = 1.0
    half[:16, :32, 0] = 3.0  # red brighter in the image's left half (towards −x, unturned)
    np.save("/tmp/lumos_test_half_sky.npy", half)
    base = {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]}, "objects": [{"type": "sphere"}]}
    rng = np.random.default_rng(5)
    normals = rng.normal(size=(50, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    for rotation in (0.0, 90.0):
        scene = dict(base, environment={"file": "/tmp/lumos_test_half_sky.npy", "rotation": rotation})
        amb = compile_scene(lumos.load_scene(scene)).arrays.ambient
        for n in normals:
            got = np.array(ambient_light(amb, n))
            assert got[1] == pytest.approx((1 + n[1]) / 2, abs=5e-3), n
            assert got[2] == pytest.approx((1 + n[1]) / 2, abs=5e-3), n
        # the bright red half faces −x unturned, and +z turned by 90° (as the middle column goes from −z to −x)
        toward = np.array([-1.0, 0.0, 0.0]) if rotation == 0 else np.array([0.0, 0.0, 1.0])
        assert ambient_light(amb, toward)[0] > ambient_light(amb, -toward)[0] + 0.5


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_a_sphere_under_half_a_sky_is_lit_from_above_by_every_classic_method(method):
    """Each classic method's ambient term reads Ia by the shading normal: a sphere of ka 1 (nothing else) under
    the half sky above, seen along −z by an orthographic camera, shows (1 + n_y)/2 at each pixel."""
    half = np.zeros((32, 64, 3), np.float32)
    half[:16] = 1.0
    np.save("/tmp/lumos_test_half_sky2.npy", half)
    scene = {"camera": {"type": "orthographic", "position": [0, 0, 4], "look_at": [0, 0, 0], "size": 2.2},
             "render": {"width": 33, "height": 33, "method": method, "shading": "phong"},
             "environment": {"file": "/tmp/lumos_test_half_sky2.npy"},
             "objects": [{"type": "sphere", "material": {"ka": 1.0, "kd": 0.0}}]}
    if method != "raster":
        del scene["render"]["shading"]
    img = lumos.render(scene, aov=["object_id"])
    inside = interior_of(img.aovs["object_id"])
    ys = (16 - np.arange(33))[:, None] * (2.2 / 33)  # pixel centres' y (rows go down)
    expected = np.broadcast_to((1 + np.clip(ys, -1, 1)) / 2, (33, 33))
    # raster's sphere is tessellated: its interpolated normals are off by a little near the rim
    np.testing.assert_allclose(img.array[inside][:, 1], expected[inside], atol=0.03 if method == "raster" else 5e-3)


def test_raster_and_radiosity_show_the_environment_where_nothing_is_drawn():
    """The scan-converting methods look the environment up along each pixel's camera ray where no surface is
    drawn, as raycast does (its image turned by its rotation): the sky pixels agree."""
    rng = np.random.default_rng(3)
    np.save("/tmp/lumos_test_env_bg.npy", rng.random((16, 32, 3)).astype(np.float32))
    scene = {"camera": {"position": [0, 0.5, 4], "look_at": [0, 0, 0], "fov": 70},
             "render": {"width": 40, "height": 30, "antialias": "none"},
             "environment": {"file": "/tmp/lumos_test_env_bg.npy", "rotation": 25},
             "objects": [{"type": "sphere", "radius": 0.5, "material": {"kd": 0.5}}]}
    ref = lumos.render(scene, method="raycast", aov=["object_id"])
    sky = ref.aovs["object_id"] < 0
    assert sky.mean() > 0.8
    for method in ("raster", "radiosity"):
        img = lumos.render(scene, method=method).array
        same = np.all(img[sky] == ref.array[sky], axis=1)
        assert same.mean() > 0.98, (method, same.mean())  # (a ray on a texel's edge may round the other way)


def test_compression_noise_below_zero_is_read_as_zero_and_real_negatives_are_refused(tmp_path):
    """Lossy EXR compression (DWA, Blender's own HDRIs) leaves a few values a hair below 0: read as 0 with one
    warning; a value below −1% of the image's mean is an error, as NaN and infinity are."""
    img = np.full((4, 8, 3), 0.5, np.float32)
    img[1, 2, 0] = -1e-4
    np.save(tmp_path / "noisy.npy", img)
    scene = {"render": {"width": 2, "height": 2, "method": "raycast"},
             "environment": {"file": str(tmp_path / "noisy.npy")}}
    with pytest.warns(lumos.LumosWarning, match="1 values slightly below 0"):
        compiled = compile_scene(lumos.load_scene(scene))
    assert compiled.environment is not None
    for value, what in ((-0.1, "negative pixels"), (np.nan, "NaN or infinite")):
        img[1, 2, 0] = value
        np.save(tmp_path / "bad.npy", img)
        with pytest.raises(lumos.LumosError, match=what):
            lumos.render({**scene, "environment": {"file": str(tmp_path / "bad.npy")}})


@numba.njit(cache=True)
def _bilinear(pixels, info, dirs):
    out = np.empty((dirs.shape[0], 3))
    for k in range(dirs.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = env_bilinear(pixels, info, (dirs[k, 0], dirs[k, 1], dirs[k, 2]))
    return out


def test_the_image_seen_directly_is_bilinear_between_pixel_centres():
    """`env_bilinear` (camera rays, rays after mirrors and glass, the raster background's twin) gives each pixel's
    own value at its centre, the mean of two neighbours half-way (across the seam at u = 0 too), and agrees with
    its NumPy twin (`mesh.directions.lat_long_bilinear`) everywhere, the environment's rotation included."""
    from lumos.mesh.directions import lat_long_bilinear, lat_long_directions

    h, w = 8, 16
    pixels, _, _, info = image_arrays(sky(h, w), 0.0)
    centres = lat_long_directions(h, w).reshape(-1, 3)
    np.testing.assert_allclose(_bilinear(pixels, info, centres), pixels.reshape(-1, 3), rtol=1e-5, atol=1e-6)
    seam = np.array([[0.0, 0.0, 1.0]])  # u = 0 (and 1): between the first and the last column, at mid-height
    np.testing.assert_allclose(_bilinear(pixels, info, seam)[0],
                               0.25 * (pixels[3, 0] + pixels[3, -1] + pixels[4, 0] + pixels[4, -1]), rtol=1e-5)
    dirs = np.random.default_rng(4).normal(size=(500, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    pixels, _, _, info = image_arrays(sky(h, w), 30.0)
    c, s = info[ENV_COS], info[ENV_SIN]  # (the direction turned back by the rotation, as the kernels turn it)
    turned = np.column_stack([c * dirs[:, 0] - s * dirs[:, 2], dirs[:, 1], s * dirs[:, 0] + c * dirs[:, 2]])
    np.testing.assert_allclose(_bilinear(pixels, info, dirs), lat_long_bilinear(pixels, turned), rtol=1e-5,
                               atol=1e-6)


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_a_glossy_surface_reflects_ks_of_a_uniform_sky(method):
    """Where the environment lights the classic model, the specular term gains its glossy reflection Ks·L_n(R):
    a sphere of ks 0.7 (nothing else) under a uniform sky of 0.4 shows 0.28 at every exponent, as a glossy
    surface that reflects 0.7 of the light does; a scene's own `ambient` turns the environment's lighting off."""
    for shininess in (3.0, 40.0, 2000.0):
        scene = {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 30},
                 "render": {"width": 9, "height": 9, "method": method},
                 "environment": {"color": 0.4},
                 "objects": [{"type": "sphere", "material": {"ks": 0.7, "shininess": shininess}}]}
        img = lumos.render(scene, aov=["object_id"])
        inside = img.aovs["object_id"] >= 0
        np.testing.assert_allclose(img.array[inside], 0.28, rtol=1e-5)
        scene["ambient"] = 0.1
        assert lumos.render(scene).array[4, 4].max() == 0.0


def test_mirrors_show_the_environment_in_the_local_methods_as_whitted_does():
    """A mirror (kr 1) alone under an environment: raycast and raster reflect the environment along the mirror
    direction (reflection mapping), which is all whitted's reflected rays see when nothing else is there; raster's
    sphere is polygons, its normals interpolated, so it agrees to within its facets."""
    np.save("/tmp/lumos_test_env_mirror.npy", sky(32, 64, seed=8))
    scene = {"camera": {"position": [0, 0.5, 4], "look_at": [0, 0, 0], "fov": 35},
             "render": {"width": 48, "height": 36, "antialias": "none", "shading": "phong", "tessellation": 96},
             "environment": {"file": "/tmp/lumos_test_env_mirror.npy", "rotation": 40},
             "objects": [{"type": "sphere", "material": {"kr": 1.0}}]}
    ref = lumos.render(scene, method="whitted", aov=["object_id"])
    inside = interior_of(ref.aovs["object_id"])
    assert inside.sum() > 300
    raycast = lumos.render(scene, method="raycast", aov=["reflected"])
    np.testing.assert_allclose(raycast.array[inside], ref.array[inside], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(raycast.aovs["reflected"][inside], ref.array[inside], rtol=1e-5, atol=1e-6)
    raster = lumos.render(scene, method="raster").array
    err = np.abs(raster[inside] - ref.array[inside])
    assert err.mean() < 0.01 and np.corrcoef(raster[inside].ravel(), ref.array[inside].ravel())[0, 1] > 0.99, \
        err.mean()
