"""Rendering animations (`lumos.animate`): frame k is the render of the scene at k / fps, bit for bit; frame
selections; a camera-only radiosity animation is solved once."""

import copy

import numpy as np
import pytest
import yaml

from helpers import EXAMPLES
import lumos
from lumos.animate import frame_indices, render_frame, render_frames
from lumos.errors import LumosError
from lumos.scene.animation import scene_at

SCENE = {
    "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 40},
    "render": {"method": "raycast", "width": 32, "height": 24},
    "lights": [{"type": "point", "name": "key", "position": [2, 3, 4], "intensity": 1}],
    "materials": {"red": {"kd": [0.8, 0.1, 0.1], "ks": 0.3, "shininess": 20}},
    "objects": [{"type": "sphere", "name": "ball", "radius": 1, "material": "red"},
                {"type": "plane", "point": [0, -1, 0], "material": {"kd": 0.5}}],
    "animation": {"fps": 12, "frames": 6, "tracks": [
        {"target": "camera.position", "interpolation": "catmull-rom",
         "keys": [{"time": 0, "value": [0, 1, 5]}, {"time": 0.25, "value": [3, 1.5, 4]},
                  {"frame": 5, "value": [5, 2, 0], "ease": "in-out"}]},
        {"target": "objects[ball].transform.translate",
         "keys": [{"time": 0, "value": [0, 0, 0]}, {"time": 0.4, "value": [0.5, 0.3, 0]}]},
        {"target": "lights[key].intensity", "keys": [{"time": 0, "value": 1}, {"time": 0.4, "value": [1, 0.5, 0.2]}]},
        {"target": "materials.red.shininess", "keys": [{"time": 0, "value": 20}, {"time": 0.4, "value": 80}]},
    ]},
}


@pytest.fixture(scope="module")
def scene():
    return lumos.load_scene(copy.deepcopy(SCENE))


def test_frame_k_is_the_render_of_the_scene_at_k_over_fps(scene):
    images = list(render_frames(scene, spp=2))
    assert len(images) == 6
    for k, image in enumerate(images):
        alone = lumos.render(scene_at(scene, k / 12), spp=2)
        assert image.array.tobytes() == alone.array.tobytes(), k
        assert image.stats["frame"] == k and image.stats["time"] == k / 12
        assert image.stats["radiosity_solves"] == 0
    assert not np.array_equal(images[0].array, images[-1].array)  # it moves
    frame3 = render_frame(scene, 3, spp=2)
    assert frame3.array.tobytes() == images[3].array.tobytes()


def test_frame_selections(scene):
    assert frame_indices(scene) == [0, 1, 2, 3, 4, 5]
    assert frame_indices(scene, range(1, 6, 2)) == [1, 3, 5]
    assert frame_indices(scene, slice(4, None)) == [4, 5]
    assert frame_indices(scene, slice(None, 2)) == [0, 1]
    assert frame_indices(scene, [5, 0, 2]) == [5, 0, 2]
    assert frame_indices(scene, 4) == [4]
    assert [img.stats["frame"] for img in render_frames(scene, frames=[4, 1])] == [4, 1]


@pytest.mark.parametrize("frames, message", [
    (range(0, 7), "scene: frames 0:7 are outside the animation: the animation has 6 frames (0 to 5)"),
    (6, "scene: frame 6 is outside the animation: the animation has 6 frames (0 to 5)"),
    ([0, 9], "scene: frame 9 is outside the animation"),
    (slice(3, 3), "frames 3:3: selects no frames"),
    (slice(-1, 3), "frames -1:3: frame numbers count from 0"),
    (slice(0, 4, 0), "frames 0:4:0: the step must be at least 1"),
    ([], "frames: the list of frames is empty"),
    ([1.5], "frames [1.5]: frame numbers are integers"),
])
def test_frames_outside_the_animation_are_one_line_errors(scene, frames, message):
    with pytest.raises(LumosError) as info:
        render_frames(scene, frames=frames)  # raised at the call, before any frame renders
    assert str(info.value).startswith(message) and "\n" not in str(info.value)


def test_a_scene_without_animation_is_one_frame():
    data = copy.deepcopy(SCENE)
    del data["animation"]
    plain = lumos.load_scene(data)
    assert frame_indices(plain) == [0]
    with pytest.raises(LumosError, match="the scene has no animation: block, so one frame"):
        frame_indices(plain, range(0, 2))
    (image,) = render_frames(plain)
    assert image.array.tobytes() == lumos.render(plain).array.tobytes()


def test_bad_values_between_keys_stop_before_the_first_frame():
    data = copy.deepcopy(SCENE)
    data["animation"]["tracks"] = [{"target": "lights[key].intensity", "interpolation": "catmull-rom",
                                    "keys": [{"time": 0, "value": 1}, {"frame": 1, "value": 0},
                                             {"frame": 5, "value": 0}]}]
    scene = lumos.load_scene(data)
    rendered = []
    with pytest.raises(LumosError, match=r"animation.tracks\[0\] \(lights\[key\].intensity\) at 0.1666"):
        for image in render_frames(scene):
            rendered.append(image)
    assert rendered == []


# ------------------------------------------------------------------------------------------ radiosity


def cornell(tracks, frames=3):
    with open(EXAMPLES / "path" / "cornell.yaml") as f:
        data = yaml.safe_load(f)
    data["render"] = {"method": "radiosity", "width": 32, "height": 24, "radiosity": {"patch_size": 0.5}}
    data["animation"] = {"fps": 24, "frames": frames, "tracks": tracks}
    return lumos.load_scene(data)


CAMERA_MOVES = [{"target": "camera.position", "keys": [{"frame": 0, "value": [0, 0, 3.9]},
                                                       {"frame": 2, "value": [0.4, 0.2, 3.5]}]},
                {"target": "camera.fov", "keys": [{"frame": 0, "value": 39.3}, {"frame": 2, "value": 45}]}]


def test_a_camera_only_radiosity_animation_is_solved_once(monkeypatch):
    import importlib

    solve_module = importlib.import_module("lumos.radiosity.solve")
    calls = []
    original = solve_module.solve_compiled

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(solve_module, "solve_compiled", counting)
    scene = cornell(CAMERA_MOVES)
    images = list(render_frames(scene))
    assert [img.stats["radiosity_solves"] for img in images] == [1, 0, 0]
    assert len(calls) == 1
    assert not np.array_equal(images[0].array, images[2].array)
    # each frame is still the render of the scene at its time, which solves again on its own
    for k in (0, 2):
        alone = lumos.render(scene_at(scene, k / 24))
        assert images[k].array.tobytes() == alone.array.tobytes()
    assert len(calls) == 3


def test_a_radiosity_animation_that_moves_a_light_solves_every_frame():
    with open(EXAMPLES / "path" / "cornell.yaml") as f:
        materials = yaml.safe_load(f)["materials"]
    name = next(iter(materials))
    tracks = [{"target": f"materials[{name}].kd", "keys": [{"frame": 0, "value": 0.2}, {"frame": 1, "value": 0.6}]}]
    images = list(render_frames(cornell(tracks, frames=2)))
    assert [img.stats["radiosity_solves"] for img in images] == [1, 1]


# ------------------------------------------------------------------------------------------ motion blur


def blurred(motion_samples, shutter=(0.0, 1.0)):
    data = copy.deepcopy(SCENE)
    data["camera"]["shutter"] = list(shutter)
    data["objects"] = data["objects"][:1] + [{"type": "plane", "point": [0, -1, 0], "material": {"kd": 0.5}}]
    data["animation"] = {"fps": 1, "frames": 2, "motion_samples": motion_samples, "tracks": [
        {"target": "lights[key].intensity", "keys": [{"time": 0, "value": 0.0}, {"time": 1, "value": 2.0}]}]}
    return lumos.load_scene(data)


def test_motion_samples_blur_every_track_along_its_curve_over_the_shutter():
    """A light ramping 0 → 2 while the shutter is open: sub-frames average it to the light at its mean, 1 (the
    image is linear in the light); without sub-frames a light does not blur (the frame shows it at time 0)."""
    still = lumos.render(scene_at(blurred(1, shutter=(0.0, 0.0)), 0.5))  # the light at 1, shutter closed
    blur = render_frame(blurred(8), 0)
    assert blur.stats["motion_samples"] == 8
    np.testing.assert_allclose(blur.array, still.array, rtol=1e-5, atol=1e-6)
    unblurred = render_frame(blurred(1), 0)
    assert unblurred.array.max() < 0.5 * still.array.max()  # the light at 0: only the ambient
    assert [img.array.tobytes() for img in render_frames(blurred(8), frames=[0])] == [blur.array.tobytes()]
