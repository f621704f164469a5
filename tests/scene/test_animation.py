"""The animation block: keyframe curves (exact at keys, linear, Catmull–Rom, Bézier, easing), targets, the scene
at a time (`scene_at`), motion blur from a curve, and one-line errors for bad tracks. Pure Python: no render."""

import copy
import math
import textwrap

import numpy as np
import pytest

import lumos
from lumos.errors import LumosError
from lumos.scene.animation import frame_count, frame_times, scene_at
from lumos.scene.keyframes import EASES, Curve, ease, rotate_about

BASE = {
    "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 40},
    "render": {"width": 32, "height": 24},
    "lights": [{"type": "point", "name": "key", "position": [2, 3, 4], "intensity": 1},
               {"type": "directional", "direction": [0, -1, 0], "intensity": 0.2}],
    "materials": {"red": {"kd": [0.8, 0.1, 0.1], "ks": 0.2, "shininess": 20}},
    "objects": [{"type": "sphere", "name": "ball", "radius": 1, "material": "red"},
                {"type": "plane", "name": "floor", "point": [0, -1, 0]}],
}


def animated(*tracks, **block):
    scene = copy.deepcopy(BASE)
    scene["animation"] = {"fps": 24, **block, "tracks": list(tracks)}
    return scene


def load(*tracks, **block):
    return lumos.load_scene(animated(*tracks, **block))


# ------------------------------------------------------------------------------------------------ curves


@pytest.mark.parametrize("interpolation", ["linear", "step", "catmull-rom", "bezier"])
@pytest.mark.parametrize("key_ease", EASES)
def test_value_at_a_key_is_the_key_bit_for_bit(interpolation, key_ease):
    values = [[0.1, 1.0 / 3.0, 5.0], [5.0, 1.7, -0.3], [-2.2, 0.7, 1e-7], [0.3, 2.0 / 7.0, 4.0]]
    times = [0.0, 0.37, 1.0, 1.0 + 1.0 / 3.0]
    keys = [{"time": t, "value": v, "ease": key_ease} for t, v in zip(times, values)]
    scene = load({"target": "camera.position", "interpolation": interpolation, "keys": keys},
                 {"target": "camera.fov", "interpolation": interpolation,
                  "keys": [{"frame": 0, "value": 40}, {"frame": 7, "value": 55.5, "ease": key_ease},
                           {"frame": 13, "value": 30.1}]})
    for t, v in zip(times, values):
        assert scene_at(scene, t).camera.position == tuple(v)
    for frame, fov in ((0, 40.0), (7, 55.5), (13, 30.1)):
        assert scene_at(scene, frame / 24).camera.fov == fov


def test_linear_midpoint_and_hold_outside_the_keys():
    scene = load({"target": "lights[key].intensity", "keys": [{"time": 1, "value": [0, 1, 2]},
                                                               {"time": 3, "value": [2, 1, 0]}]})
    assert scene_at(scene, 2.0).lights[0].intensity == (1.0, 1.0, 1.0)
    assert scene_at(scene, 1.5).lights[0].intensity == (0.5, 1.0, 1.5)
    assert scene_at(scene, 0.0).lights[0].intensity == (0.0, 1.0, 2.0)  # before the first key: held
    assert scene_at(scene, -4.0).lights[0].intensity == (0.0, 1.0, 2.0)
    assert scene_at(scene, 9.0).lights[0].intensity == (2.0, 1.0, 0.0)  # after the last: held


def test_step_holds_until_the_next_key():
    curve = Curve([0.0, 1.0, 2.0], [[1.0], [5.0], [2.0]], "step")
    assert curve(0.999)[0] == 1.0 and curve(1.0)[0] == 5.0 and curve(1.5)[0] == 5.0


def test_catmull_rom_passes_through_the_keys_and_is_c1():
    times = np.array([0.0, 0.5, 1.7, 2.0, 3.5])
    values = np.array([[0.0, 1.0], [2.0, -1.0], [1.0, 0.5], [3.0, 3.0], [-1.0, 0.0]])
    curve = Curve(times, values, "catmull-rom")
    for t, v in zip(times, values):
        assert np.array_equal(curve(t), v)
    h = 1e-6
    for t in times[1:-1]:  # the slope from the left equals the slope from the right at every inner key
        left = (curve(t) - curve(t - h)) / h
        right = (curve(t + h) - curve(t)) / h
        np.testing.assert_allclose(left, right, atol=1e-4)
        k = int(np.searchsorted(times, t))  # and it is the central difference of the neighbouring keys
        slope = (values[k + 1] - values[k - 1]) / (times[k + 1] - times[k - 1])
        np.testing.assert_allclose(right, slope, atol=1e-4)
    # continuous: no jump anywhere along the curve
    ts = np.linspace(0.0, 3.5, 2001)
    samples = np.array([curve(t) for t in ts])
    assert np.abs(np.diff(samples, axis=0)).max() < 0.05


def test_bezier_takes_the_given_tangents():
    curve = Curve([0.0, 2.0], [[0.0], [1.0]], "bezier", slope_in=[None, [0.0]], slope_out=[[3.0], None])
    h = 1e-7
    assert (curve(h)[0] - curve(0.0)[0]) / h == pytest.approx(3.0, rel=1e-4)
    assert (curve(2.0)[0] - curve(2.0 - h)[0]) / h == pytest.approx(0.0, abs=1e-4)
    # a Bézier whose tangents are the chord's slope is the straight line
    line = Curve([0.0, 2.0], [[0.0], [1.0]], "bezier", slope_in=[None, [0.5]], slope_out=[[0.5], None])
    assert line(0.5)[0] == pytest.approx(0.25)


def test_bezier_tangents_in_a_scene_file():
    scene = load({"target": "objects[ball].transform.translate", "interpolation": "bezier",
                  "keys": [{"time": 0, "value": [0, 0, 0], "tangent_out": [0, 3, 0]},
                           {"time": 1, "value": [1, 0, 0], "tangent": 0}]})
    h = 1e-6
    y0 = scene_at(scene, 0.0).objects[0].transform.translate[1]
    yh = scene_at(scene, h).objects[0].transform.translate[1]
    assert (yh - y0) / h == pytest.approx(3.0, rel=1e-3)


@pytest.mark.parametrize("kind", EASES)
def test_easing_endpoints(kind):
    assert ease(kind, 0.0) == 0.0 and ease(kind, 1.0) == 1.0
    s = np.linspace(0, 1, 101)
    e = np.array([ease(kind, x) for x in s])
    assert np.all(np.diff(e) >= 0)  # monotonic
    mid = ease(kind, 0.25)
    assert {"linear": mid == 0.25, "in": mid < 0.25, "out": mid > 0.25, "in-out": mid < 0.25}[kind]


def test_ease_shapes_the_way_into_its_key():
    scene = load({"target": "camera.fov", "keys": [{"time": 0, "value": 40}, {"time": 1, "value": 60, "ease": "in"},
                                                   {"time": 2, "value": 80}]})
    assert scene_at(scene, 0.5).camera.fov == pytest.approx(40 + 20 * 0.25)   # eased in: s² = 0.25
    assert scene_at(scene, 1.5).camera.fov == pytest.approx(70)               # the next segment is linear


def test_orbit_turns_about_the_axis():
    scene = load({"target": "camera.position", "orbit": {"center": [0, 0, 0], "axis": [0, 1, 0]},
                  "keys": [{"time": 0, "value": 0}, {"time": 4, "value": 360}]})
    assert scene_at(scene, 0).camera.position == (0.0, 1.0, 5.0)  # angle 0: the camera as the scene gives it
    p = np.array(scene_at(scene, 1).camera.position)  # 90° counter-clockwise seen from above: +z to +x
    np.testing.assert_allclose(p, [5, 1, 0], atol=1e-12)
    for t in np.linspace(0, 4, 17):
        q = np.array(scene_at(scene, t).camera.position)
        assert math.hypot(q[0], q[2]) == pytest.approx(5.0) and q[1] == pytest.approx(1.0)
    np.testing.assert_allclose(rotate_about([1, 0, 0], [0, 0, 0], [0, 0, 1], 90), [0, 1, 0], atol=1e-15)


# ------------------------------------------------------------------------------------------ the scene at t


def test_frames_duration_and_frame_times():
    track = {"target": "camera.fov", "keys": [{"time": 0, "value": 40}, {"time": 2, "value": 50}]}
    assert frame_count(load(track, frames=10)) == 10
    assert frame_count(load(track, duration=1.5)) == 36
    assert frame_count(load(track)) == 49  # up to and including the frame of the last key
    times = frame_times(load(track, fps=10, frames=4))
    assert times == [0.0, 0.1, 0.2, 0.3] and all(t == k / 10 for k, t in enumerate(times))
    assert frame_times(lumos.load_scene(BASE)) == [0.0]


def test_every_kind_of_target():
    scene = load(
        {"target": "camera.look_at", "keys": [{"time": 0, "value": [0, 0, 0]}, {"time": 1, "value": [1, 0, 0]}]},
        {"target": "objects[ball].transform.rotate", "keys": [{"time": 0, "value": [0, 0, 0]},
                                                              {"time": 1, "value": [0, 90, 0]}]},
        {"target": "objects.ball.transform.scale", "keys": [{"time": 0, "value": 1}, {"time": 1, "value": [1, 2, 3]}]},
        {"target": "lights[1].intensity", "keys": [{"time": 0, "value": 0.2}, {"time": 1, "value": 0.4}]},
        {"target": "lights.key.position", "keys": [{"time": 0, "value": [2, 3, 4]}, {"time": 1, "value": [0, 3, 4]}]},
        {"target": "materials[red].shininess", "keys": [{"time": 0, "value": 20}, {"time": 1, "value": 40}]},
        {"target": "materials.red.kd", "keys": [{"time": 0, "value": [0.8, 0.1, 0.1]}, {"time": 1, "value": 0.4}]},
    )
    at = scene_at(scene, 0.5)
    assert at.camera.look_at == (0.5, 0.0, 0.0)
    assert at.objects[0].transform.rotate == (0.0, 45.0, 0.0)
    assert at.objects[0].transform.scale == (1.0, 1.5, 2.0)
    assert at.lights[1].intensity == pytest.approx((0.3, 0.3, 0.3))
    assert at.lights[0].position == (1.0, 3.0, 4.0)
    assert at.materials["red"].shininess == 30.0 and at.materials["red"].kd == pytest.approx((0.6, 0.25, 0.25))
    assert at.animation is None and at.objects[1] is scene.objects[1]  # what is not animated is shared


def test_scene_at_does_not_change_its_input():
    scene = load({"target": "objects[ball].transform.translate",
                  "keys": [{"time": 0, "value": [0, 0, 0]}, {"time": 1, "value": [1, 0, 0]}]},
                 {"target": "materials.red.kd", "keys": [{"time": 0, "value": 0.1}, {"time": 1, "value": 0.9}]})
    before = scene.model_dump(warnings=False)
    at = scene_at(scene, 0.5)
    assert at.objects[0].transform.translate == (0.5, 0.0, 0.0)
    assert scene.model_dump(warnings=False) == before and scene.objects[0].transform is None
    assert scene.animation is not None and scene.materials["red"].kd == (0.8, 0.1, 0.1)


def test_motion_blur_follows_the_curve_over_the_shutter():
    data = animated({"target": "objects[ball].transform.translate", "interpolation": "catmull-rom",
                     "keys": [{"time": 0, "value": [0, 0, 0]}, {"time": 1, "value": [2, 1, 0]},
                              {"time": 2, "value": [2, 3, 1]}]})
    data["camera"]["shutter"] = [0.01, 0.03]
    data["objects"][0]["motion"] = [0.5, 0, 0]  # its own velocity adds to the curve's
    scene = lumos.load_scene(data)
    plain = copy.deepcopy(data)
    plain["camera"]["shutter"] = [0, 0]
    closed = lumos.load_scene(plain)
    for t in (0.3, 1.0, 1.6):
        obj = scene_at(scene, t).objects[0]
        x_open = np.array(scene_at(closed, t + 0.01).objects[0].transform.translate)
        x_close = np.array(scene_at(closed, t + 0.03).objects[0].transform.translate)
        velocity = np.array(obj.motion) - [0.5, 0, 0]
        np.testing.assert_allclose(velocity, (x_close - x_open) / 0.02, rtol=1e-12, atol=1e-12)
        base = np.array(obj.transform.translate)  # at shutter time τ the object is at base + τ·velocity
        np.testing.assert_allclose(base + 0.01 * velocity, x_open, atol=1e-12)
        np.testing.assert_allclose(base + 0.03 * velocity, x_close, atol=1e-12)
    # the shutter closed: no motion from the curve, the translate is the curve's at t
    assert scene_at(closed, 0.3).objects[0].motion == (0.5, 0.0, 0.0)


def test_a_mesh_moves_between_frames_but_not_within_one():
    data = animated({"target": "objects[tri].transform.translate",
                     "keys": [{"time": 0, "value": [0, 0, 0]}, {"time": 1, "value": [1, 0, 0]}]})
    data["objects"].append({"type": "triangle", "name": "tri", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]})
    data["camera"]["shutter"] = [0, 0.02]
    obj = scene_at(lumos.load_scene(data), 0.5).objects[2]
    assert obj.transform.translate == (0.5, 0.0, 0.0) and obj.motion == (0.0, 0.0, 0.0)


def test_a_curve_that_leaves_the_keys_range_is_an_error_at_its_time():
    scene = load({"target": "lights[key].intensity", "interpolation": "catmull-rom",
                  "keys": [{"time": 0, "value": 1}, {"time": 1, "value": 0}, {"time": 2, "value": 0}]})
    scene_at(scene, 1.0)
    with pytest.raises(LumosError) as info:
        scene_at(scene, 1.5)  # the curve undershoots below 0 between the last two keys
    message = str(info.value)
    assert message.startswith("scene: animation.tracks[0] (lights[key].intensity) at 1.5 s: must be at least 0")
    assert "\n" not in message


def test_scene_digest_ignores_the_animation_block():
    from lumos.scene.digest import scene_digest

    plain = lumos.load_scene(BASE)
    scene = load({"target": "camera.fov", "keys": [{"time": 0, "value": 40}, {"time": 1, "value": 50}]})
    assert scene_digest(plain) == scene_digest(scene) == scene_digest(scene_at(scene, 0.5))
    unnamed = copy.deepcopy(BASE)
    for light in unnamed["lights"]:
        light.pop("name", None)
    lit = lumos.load_scene(unnamed)
    assert "name" not in lit.lights[0].model_fields_set  # (the digest of unnamed lights is as it was)
    assert scene_digest(lit) != scene_digest(plain)      # a name is part of the scene


# ------------------------------------------------------------------------------------------------- errors

BAD = [
    ("keys: [{time: 1, value: 40}, {time: 0.5, value: 50}]", "camera.fov",
     "animation.tracks[0].keys[1].time: keyframes out of order: 0.5 s is not after the previous key's 1 s"),
    ("keys: [{frame: 3, value: 40}, {frame: 3, value: 50}]", "camera.fov",
     "animation.tracks[0].keys[1].frame: keyframes out of order"),
    ("keys: [{time: 0, value: 40}]", "camera.fob",
     "animation.tracks[0].target: unknown animated camera key 'fob' (did you mean 'fov'?"),
    ("keys: [{time: 0, value: 40}]", "camra.fov", "animation.tracks[0].target: unknown target 'camra.fov'"),
    ("keys: [{time: 0, value: [1, 2, 3]}]", "objects[bal].transform.translate",
     "animation.tracks[0].target: no object is named 'bal' (named: ball, floor"),
    ("keys: [{time: 0, value: [1, 2, 3]}]", "objects[0].transform.translate",
     "animation.tracks[0].target: objects are animated by name"),
    ("keys: [{time: 0, value: [1, 2, 3]}]", "objects[ball].center",
     "animation.tracks[0].target: unknown animated object key 'center'"),
    ("keys: [{time: 0, value: 1}]", "lights[5].intensity",
     "animation.tracks[0].target: lights[5]: there is no such light (the scene has 2)"),
    ("keys: [{time: 0, value: 1}]", "lights[key].radiance",
     "animation.tracks[0].target: unknown animated key of a point light 'radiance'"),
    ("keys: [{time: 0, value: 1}]", "materials.blue.kd", "animation.tracks[0].target: unknown material 'blue'"),
    ("keys: [{time: 0, value: [1, 2]}]", "camera.position",
     "animation.tracks[0].keys[0].value: must have 3 components, got 2"),
    ("keys: [{time: 0, value: [0, 1, 5]}, {time: 1, value: up}]", "camera.position",
     "animation.tracks[0].keys[1].value: expected a list of 3 numbers, got 'up' (str)"),
    ("keys: [{time: 0, value: 200}]", "camera.fov", "animation.tracks[0].keys[0].value: must be less than 180"),
    ("keys: [{time: 0, value: -1}]", "materials.red.kd", "animation.tracks[0].keys[0].value[0]: must be at least 0"),
    ("keys: [{time: 0, value: [0, 0, 0]}]", "camera.position",
     "animation.tracks[0].keys[0].value: position and look_at must differ"),
    ("keys: [{time: 0, frame: 1, value: 40}]", "camera.fov",
     "animation.tracks[0].keys[0]: give the key a time (in seconds) or a frame, one of them"),
    ("keys: [{value: 40}]", "camera.fov", "animation.tracks[0].keys[0]: give the key a time"),
    ("keys: [{time: 0, value: 40, ease: inout}]", "camera.fov",
     "animation.tracks[0].keys[0].ease: unknown value 'inout' (did you mean 'in-out'?"),
    ("interpolation: cubic\n      keys: [{time: 0, value: 40}]", "camera.fov",
     "animation.tracks[0].interpolation: unknown value 'cubic'"),
    ("keys: [{time: 0, value: 40, tangent: 1}]", "camera.fov",
     "animation.tracks[0].keys[0].tangent: tangent shapes a bezier curve"),
    ("keys: []", "camera.fov", "animation.tracks[0].keys: "),
    ("orbit: {axis: [0, 1, 0]}\n      keys: [{time: 0, value: 0}]", "camera.fov",
     "animation.tracks[0].orbit: orbit turns a 3-vector"),
    ("keys: [{time: 0, value: 40}]\n      speed: 2", "camera.fov", "animation.tracks[0]: unknown key 'speed'"),
]


@pytest.mark.parametrize("keys, target, expected", BAD, ids=[b[2].split(":")[0] + "-" + b[1] for b in BAD])
def test_bad_tracks_are_one_line_errors_at_their_line(tmp_path, keys, target, expected):
    text = textwrap.dedent("""\
        camera: {position: [0, 1, 5], look_at: [0, 0, 0]}
        lights:
          - {type: point, name: key, position: [2, 3, 4]}
          - {type: directional, direction: [0, -1, 0]}
        materials: {red: {kd: 0.5}}
        objects:
          - {type: sphere, name: ball, material: red}
          - {type: plane, name: floor}
        animation:
          tracks:
            - target: TARGET
              KEYS
        """).replace("TARGET", target).replace("KEYS", keys)
    path = tmp_path / "anim.yaml"
    path.write_text(text)
    with pytest.raises(LumosError) as info:
        lumos.load_scene(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:"), message
    assert expected in message, message
    line = int(message.split(":")[1])
    assert 11 <= line <= 13  # the track's lines


def test_two_tracks_on_one_key_and_duplicate_names():
    track = {"target": "camera.fov", "keys": [{"time": 0, "value": 40}]}
    with pytest.raises(LumosError, match=r"^scene: animation.tracks\[1\].target: 'camera.fov' is animated twice"):
        load(track, track)
    data = animated({"target": "objects[ball].transform.translate", "keys": [{"time": 0, "value": [0, 0, 0]}]})
    data["objects"][1]["name"] = "ball"
    with pytest.raises(LumosError, match="2 objects are named 'ball'; an animated object's name must be unique"):
        lumos.load_scene(data)
    with pytest.raises(LumosError, match=r"^scene: animation: give frames \(a count\) or duration"):
        load(track, frames=3, duration=1)
    with pytest.raises(LumosError, match=r"animation.fps: must be greater than 0"):
        load(track, fps=0)


def test_a_model_include_cannot_be_animated(tmp_path):
    from helpers import DATA

    data = copy.deepcopy(BASE)
    data["objects"].append({"type": "model", "name": "box", "file": str(DATA / "tetra.off")})
    data["animation"] = {"tracks": [{"target": "objects[box].transform.translate",
                                     "keys": [{"time": 0, "value": [0, 0, 0]}]}]}
    with pytest.raises(LumosError, match=r"objects\[box\] is a model include: its meshes cannot be animated"):
        lumos.load_scene(data)
