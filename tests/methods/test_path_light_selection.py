"""`path`'s light selection in renders: the light tree and the power table draw the same image in expectation
(both strategies unbiased: a z-test on the mean radiance, with MIS and with light sampling alone), the tree's
image does not depend on the thread count, and on a scene where the brightest light is far from what the
camera sees the tree's image has less noise. The tree's own probabilities: tests/kernels/test_light_tree.py."""

from __future__ import annotations

import numpy as np
import pytest

import lumos

#: A floor and a wall, lit by lights of every kind the tree holds and two it does not (the directional light,
#: the point light with no fall-off); one light is bright and far.
MANY_LIGHTS = {
    "camera": {"position": [0, 1.5, 4], "look_at": [0, 0, 0], "fov": 50},
    "lights": [
        {"type": "area", "shape": "sphere", "center": [-1.2, 0.4, 0.3], "radius": 0.08, "radiance": 60.0},
        {"type": "area", "shape": "sphere", "center": [0.8, 0.3, -0.4], "radius": 0.15, "radiance": 15.0},
        {"type": "area", "shape": "sphere", "center": [30, 20, 10], "radius": 2.0, "radiance": 200.0},
        {"type": "area", "shape": "rect", "corner": [-0.3, 1.2, -0.6], "edge_u": [0.4, 0, 0], "edge_v": [0, 0, 0.3],
         "radiance": 4.0},
        {"type": "spot", "position": [0.2, 1.5, 0.5], "direction": [0, -1, 0], "intensity": 1.5, "angle": 30,
         "inner_angle": 15, "attenuation": [0, 0, 1]},
        {"type": "point", "position": [1.5, 1.0, 1.0], "intensity": 0.05},
        {"type": "directional", "direction": [0.3, -1, -0.2], "intensity": 0.05},
    ],
    "objects": [
        {"type": "plane", "point": [0, -0.5, 0], "normal": [0, 1, 0], "material": {"kd": 0.6}},
        {"type": "rect", "corner": [-2, -0.5, -1], "edge_u": [4, 0, 0], "edge_v": [0, 2.5, 0],
         "material": {"kd": 0.4, "ks": 0.3, "shininess": 30}},
        {"type": "mesh", "vertices": [[0.5, -0.4, 0.6], [0.9, -0.4, 0.6], [0.7, -0.1, 0.7], [0.6, -0.2, 0.9]],
         "faces": [[0, 1, 2], [0, 2, 3]], "material": {"kd": 0.0, "emission": 3.0}},
    ],
}
SIZE = dict(width=40, height=30, max_depth=1, aov=["variance"])


def _mean_and_error(img):
    arr = img.array.reshape(-1, 3).astype(np.float64)
    var = img.aovs["variance"].reshape(-1, 3).astype(np.float64)
    return arr.mean(axis=0), np.sqrt(var.sum(axis=0)) / len(arr)


@pytest.mark.parametrize("sampling", ["mis", "light"])
def test_tree_and_power_table_agree_in_expectation(sampling):
    """The two selections are two unbiased estimators of the same image: their mean radiance differs by less
    than 4 standard errors in every channel."""
    scene = lumos.load_scene(MANY_LIGHTS)
    means = {}
    for selection in ("tree", "power"):
        img = lumos.render(scene, method="path", spp=48, sampling=sampling, light_selection=selection, **SIZE)
        assert np.isfinite(img.array).all()
        means[selection] = _mean_and_error(img)
    (a, ea), (b, eb) = means["tree"], means["power"]
    z = np.abs(a - b) / np.sqrt(ea * ea + eb * eb)
    assert z.max() < 4.0, (a, b, z)


def test_tree_image_is_the_same_for_any_thread_count():
    import numba

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread")
    scene = lumos.load_scene(MANY_LIGHTS)
    one = lumos.render(scene, method="path", spp=4, threads=1, seed=3, **SIZE)
    two = lumos.render(scene, method="path", spp=4, threads=2, seed=3, **SIZE)
    np.testing.assert_array_equal(one.array, two.array)


def test_the_tree_has_less_noise_where_the_bright_light_is_far():
    """The far light holds most of the power, so the power table spends most light samples on it; the tree
    spends more of them on the lights near what the camera sees: the variance of the pixels' means, summed over
    the image, is smaller (0.58× here; where the far light alone lights a pixel the power table is the better
    guess, and that pixel is less noisy with it)."""
    scene = lumos.load_scene(MANY_LIGHTS)
    noise = {}
    for selection in ("tree", "power"):
        img = lumos.render(scene, method="path", spp=16, sampler="independent", light_selection=selection, **SIZE)
        noise[selection] = float(img.aovs["variance"].sum())
    assert noise["tree"] < 0.8 * noise["power"], noise
