"""The daylight sky (`compile.sky`, `environment: {sky: ...}`): Preetham's model tabulated into a lat-long image."""

import math

import numpy as np
import pytest
from helpers import interior_of

import lumos
from lumos.mesh.directions import lat_long_directions
from lumos.compile.sky import (
    SUN_RADIUS_DEG,
    rgb_from_xyY,
    sky_image,
    sky_luminance_unit,
    sky_xyY,
    sun_direction,
    sun_transmittance,
    zenith_xyY,
)
from lumos.scene.model import Sky

Y_FROM_RGB = np.array([0.2126729, 0.7151522, 0.0721750])  # the luminance of linear sRGB (D65)


def _solid_angles(h, w):
    edges = np.cos(np.arange(h + 1) / h * np.pi)
    return ((edges[:-1] - edges[1:]) * 2 * np.pi / w)[:, None]


def _horizontal_irradiance(image):
    h, w = image.shape[:2]
    d = lat_long_directions(h, w)
    return (image.astype(float) * (np.maximum(d[..., 1], 0) * _solid_angles(h, w))[..., None]).sum(axis=(0, 1))


def test_the_perez_distribution_is_the_zenith_value_at_the_zenith():
    sun = sun_direction(Sky(elevation=35))
    got = sky_xyY(3.0, sun, np.array([[0.0, 1.0, 0.0]]))[0]
    np.testing.assert_allclose(got, zenith_xyY(3.0, math.radians(55)), rtol=1e-12)


def test_zenith_values_of_the_paper():
    """Preetham et al.'s zenith formulas at T = 2, θs = 0 (the sun overhead): Y_z = (4.0453·2 − 4.9710)·tan(4π/9 −
    π/60) − 0.431 + 2.4192, x_z = 0.00394·2 + 0.25886, y_z = 0.00516·2 + 0.26688 (every θs term vanishes)."""
    x, y, lum = zenith_xyY(2.0, 0.0)
    chi = (4 / 9 - 2 / 120) * math.pi
    assert lum == pytest.approx((4.0453 * 2 - 4.9710) * math.tan(chi) - 0.2155 * 2 + 2.4192, rel=1e-12)
    assert (x, y) == pytest.approx((0.00394 * 2 + 0.25886, 0.00516 * 2 + 0.26688), rel=1e-12)
    # a clear sky's zenith is bluish white: x, y below D65's (0.3127, 0.3290)
    assert x < 0.3127 and y < 0.3290


def test_a_white_horizontal_plane_in_the_open_sees_irradiance_pi():
    """The image's scale: E_h = ∫ L·cos θ dω over the upper hemisphere, sun included, has luminance π (a white
    Lambertian floor shows radiance 1), for any sun and haze."""
    for kw in ({"elevation": 60}, {"elevation": 8, "turbidity": 7}, {"direction": [1, 3, -1]}, {"elevation": 0.5}):
        image = sky_image(Sky(**kw))
        assert Y_FROM_RGB @ _horizontal_irradiance(image) == pytest.approx(math.pi, rel=2e-3), kw


def test_the_sun_disk_holds_its_solid_angle_and_sits_where_asked():
    sky = Sky(elevation=40, azimuth=70, resolution=2048)
    with_sun, without = sky_image(sky), sky_image(sky.model_copy(update={"sun": False}))
    disk = (with_sun - without).astype(float)
    h, w = disk.shape[:2]
    solid = 2 * np.pi * (1 - np.cos(np.radians(SUN_RADIUS_DEG)))
    sun = sun_direction(sky)
    # its radiance times its solid angle: the energy it adds is the disk's, whatever the pixels it covers
    lum = disk @ Y_FROM_RGB
    peak = np.unravel_index(np.argmax(lum), lum.shape)
    d = lat_long_directions(h, w)[peak]
    assert np.degrees(np.arccos(np.clip(d @ sun, -1, 1))) < 0.2  # the brightest pixel is the sun's
    nonzero = lum > 0
    assert np.degrees(np.arccos(np.clip(lat_long_directions(h, w)[nonzero] @ sun, -1, 1))).max() < 0.6
    sun_rgb = (disk * _solid_angles(h, w)[..., None]).sum(axis=(0, 1)) / solid  # its mean radiance
    unit = sky_luminance_unit(sky) / 1000.0  # kcd/m² per image unit
    expected = 1.9e6 * sun_transmittance(3.0, np.radians(50)) / unit
    np.testing.assert_allclose(sun_rgb, expected, rtol=1e-3)


def test_low_suns_are_redder_and_dimmer():
    ratios, lums = [], []
    for elevation in (80, 40, 15, 5, 1):
        t = sun_transmittance(3.0, np.radians(90 - elevation))
        ratios.append(t[0] / t[2])
        lums.append(t[1])
    assert np.all(np.diff(ratios) > 0) and np.all(np.diff(lums) < 0)
    assert sun_transmittance(3.0, 0.0)[1] > sun_transmittance(8.0, 0.0)[1]  # haze dims the sun too


def test_the_sky_is_symmetric_about_the_suns_azimuth_and_brightest_near_it():
    image = sky_image(Sky(elevation=30, azimuth=0, sun=False, resolution=256)).astype(float)
    h, w = image.shape[:2]
    # azimuth 0 is the image's middle column; columns j and w−1−j mirror each other about it
    np.testing.assert_allclose(image[: h // 2], image[: h // 2, ::-1], rtol=1e-9)
    lum = image[: h // 2] @ Y_FROM_RGB
    i, j = np.unravel_index(np.argmax(lum), lum.shape)
    assert abs(j + 0.5 - w / 2) <= 2 and abs((i + 0.5) / h * 180 - 60) < 15  # circumsolar brightening
    # the sky opposite the sun is darker than next to it, and its zenith bluer than its horizon there
    row = int(h * (90 - 30) / 180)
    assert lum[row, w // 2] > 3 * lum[row, 2]
    zenith, horizon = image[0, w // 2], image[h // 2 - 1, 2]
    assert zenith[2] / zenith[0] > horizon[2] / horizon[0]


def test_the_ground_is_a_diffuse_floor_lit_by_the_sky():
    image = sky_image(Sky(elevation=50, ground=[0.4, 0.2, 0.1], resolution=1024))
    below = image[image.shape[0] // 2:].reshape(-1, 3).astype(float)
    np.testing.assert_allclose(below, np.broadcast_to(below[0], below.shape))  # one radiance below the horizon
    e_h = _horizontal_irradiance(image)
    # (E_h of the model's sun direction; the image's disk pixels see it at their centres' cos θ)
    np.testing.assert_allclose(below[0], np.array([0.4, 0.2, 0.1]) * e_h / np.pi, rtol=3e-3)


def test_rgb_from_xyY_keeps_the_luminance():
    xyY = np.array([[0.3127, 0.3290, 2.0], [0.25, 0.27, 0.7]])
    np.testing.assert_allclose(rgb_from_xyY(xyY) @ Y_FROM_RGB, xyY[:, 2], rtol=1e-5)
    np.testing.assert_allclose(rgb_from_xyY(xyY[:1]), 2.0, rtol=1e-3)  # D65 white is grey


@pytest.mark.slow
def test_path_under_the_sky_shows_a_floor_of_albedo_rho_at_rho():
    """A floor of albedo ρ, seen from above, open to the whole sky and sun: radiance ρ·E_h/π = ρ in luminance (the
    sky's scale), by the path tracer's sampling of the tabulated sky and its sun."""
    rho = 0.5
    scene = {"camera": {"position": [0, 3, 0.01], "look_at": [0, 0, 0], "fov": 10},
             "render": {"width": 16, "height": 16, "method": "path", "spp": 64, "max_depth": 0},
             "environment": {"sky": {"elevation": 35, "azimuth": 30, "resolution": 512}},
             "objects": [{"type": "disk", "radius": 1000, "normal": [0, 1, 0], "material": {"kd": rho}}]}
    img = lumos.render(scene, aov=["variance", "object_id"], seed=3)
    hit = interior_of(img.aovs["object_id"])
    lum = img.array[hit] @ Y_FROM_RGB
    err = np.sqrt(img.aovs["variance"][hit].sum(axis=0) @ Y_FROM_RGB ** 2) / hit.sum()
    assert lum.mean() == pytest.approx(rho, abs=4 * err + 2e-3), (lum.mean(), err)


@pytest.mark.parametrize("sky, message", [
    ({"elevation": -5}, "elevation"),
    ({"turbidity": 1.0}, "turbidity"),
    ({"direction": [0, -1, 0]}, "below the horizon"),
    ({"direction": [0, 1, 0], "elevation": 30}, "not both"),
    ({"resolution": 101}, "even"),
])
def test_bad_skies_are_one_line_errors(tmp_path, capsys, sky, message):
    from conftest import run_cli

    path = tmp_path / "s.yaml"
    import yaml

    path.write_text(yaml.safe_dump({"camera": {"position": [0, 1, 3], "look_at": [0, 0, 0]},
                                    "environment": {"sky": sky}, "objects": [{"type": "sphere"}]}))
    code, out, err = run_cli(capsys, "render", path, "-o", tmp_path / "x.png")
    assert code == 2 and message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x.png").exists()


def test_a_sky_and_a_file_together_are_refused():
    with pytest.raises(lumos.LumosError, match="one of a file"):
        lumos.load_scene({"camera": {"position": [0, 1, 3], "look_at": [0, 0, 0]},
                          "environment": {"sky": {}, "color": 1.0}, "objects": []})
