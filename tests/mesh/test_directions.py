"""Direction maps (`mesh.directions`): lumos's lat-long image and pbrt-v4's equal-area octahedral square."""

import numpy as np

from lumos.mesh.directions import equal_area_sphere_to_square, equal_area_square_to_sphere, lat_long_directions


def test_the_equal_area_map_and_its_inverse():
    rng = np.random.default_rng(1)
    u, v = rng.random(20000), rng.random(20000)
    d = equal_area_square_to_sphere(u, v)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
    u2, v2 = equal_area_sphere_to_square(d)
    np.testing.assert_allclose(u2, u, atol=1e-9)
    np.testing.assert_allclose(v2, v, atol=1e-9)
    # pbrt-v4's layout: the centre is +z, the corners −z, the edges' midpoints the equator, +x to the right
    np.testing.assert_allclose(equal_area_square_to_sphere(0.5, 0.5), [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(equal_area_square_to_sphere(0.0, 0.0), [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(equal_area_square_to_sphere(1.0, 0.5), [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(equal_area_square_to_sphere(0.5, 1.0), [0, 1, 0], atol=1e-12)


def test_equal_areas_equal_solid_angles():
    """Uniform points of the square are uniform on the sphere: each octant of the sphere gets an eighth of them,
    and z is uniform in [−1, 1] (Archimedes)."""
    rng = np.random.default_rng(2)
    d = equal_area_square_to_sphere(rng.random(200000), rng.random(200000))
    octant = (d[:, 0] > 0) * 4 + (d[:, 1] > 0) * 2 + (d[:, 2] > 0)
    counts = np.bincount(octant, minlength=8) / d.shape[0]
    np.testing.assert_allclose(counts, 1 / 8, atol=4e-3)
    hist = np.histogram(d[:, 2], bins=10, range=(-1, 1))[0] / d.shape[0]
    np.testing.assert_allclose(hist, 0.1, atol=4e-3)


def test_lat_long_directions_follow_the_environments_mapping():
    d = lat_long_directions(4, 8)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0)
    assert d[0, 0, 1] > 0.9 and d[-1, 0, 1] < -0.9  # the top row is up
    # u = 1/2 + atan2(x, −z)/2π: the columns just right of the middle look along −z turning towards +x
    u = 0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2 * np.pi)
    np.testing.assert_allclose(u, np.broadcast_to((np.arange(8) + 0.5) / 8, (4, 8)), atol=1e-12)
