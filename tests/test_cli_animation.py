"""`lumos render --frames`: frame files from a pattern, videos, frame 0 without --frames, and bad input as one
line with exit code 2 and nothing written."""

import json
import textwrap

import numpy as np
import pytest

from conftest import run_cli as run
from helpers import EXAMPLES
import lumos
from lumos.io.image_files import read_image
from lumos.scene.animation import scene_at

ANIMATED = """\
camera: {position: [0, 1, 5], look_at: [0, 0, 0], fov: 40}
render: {method: raycast, width: 32, height: 24}
lights:
  - {type: point, name: key, position: [2, 3, 4], intensity: 1}
objects:
  - {type: sphere, name: ball, radius: 1, material: {kd: [0.8, 0.2, 0.1]}}
animation:
  fps: 10
  frames: 6
  tracks:
    - target: objects[ball].transform.translate
      keys:
        - {time: 0, value: [-1, 0, 0]}
        - {time: 0.5, value: [1, 0, 0]}
    - target: lights[key].intensity
      keys: [{frame: 0, value: 0.5}, {frame: 5, value: 1.5}]
"""


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "anim.yaml"
    path.write_text(ANIMATED)
    return path


def one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lumos: error: "), err
    return lines[0][len("lumos: error: "):]


def test_frames_are_written_from_the_pattern(tmp_path, scene_file, capsys):
    code, _, err = run(capsys, "render", scene_file, "--frames", "1:6:2", "-o", tmp_path / "out" / "f_%03d.npy",
                       "--stats", tmp_path / "stats.json")
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["f_001.npy", "f_003.npy", "f_005.npy"]
    scene = lumos.load_scene(scene_file)
    for k in (1, 3, 5):
        alone = lumos.render(scene_at(scene, k / 10))
        assert np.array_equal(np.load(tmp_path / "out" / f"f_{k:03d}.npy"), alone.array)
    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["frames"] == 3 and [f["frame"] for f in stats["per_frame"]] == [1, 3, 5]
    assert "3 frames (raycast 32x24" in err


def test_one_frame_and_frame_zero_without_frames(tmp_path, scene_file, capsys):
    code, _, err = run(capsys, "render", scene_file, "--frames", "4", "-o", tmp_path / "four.npy")
    assert code == 0, err
    code, _, err = run(capsys, "render", scene_file, "-o", tmp_path / "plain.npy")
    assert code == 0, err
    scene = lumos.load_scene(scene_file)
    assert np.array_equal(np.load(tmp_path / "plain.npy"), lumos.render(scene_at(scene, 0.0)).array)
    assert np.array_equal(np.load(tmp_path / "four.npy"), lumos.render(scene_at(scene, 0.4)).array)


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_a_video_output_encodes_every_frame(tmp_path, scene_file, capsys, suffix):
    imageio = pytest.importorskip("imageio.v3")
    if suffix == ".mp4":
        pytest.importorskip("imageio_ffmpeg")
    out = tmp_path / f"anim{suffix}"
    code, _, err = run(capsys, "render", scene_file, "-o", out, "--width", "30", "--height", "20")
    assert code == 0, err
    read = imageio.imread(out, index=None, **({"plugin": "FFMPEG"} if suffix == ".mp4" else {}))
    assert read.shape[:3] == (6, 20, 30)
    code, _, err = run(capsys, "render", scene_file, "--frames", "2:4", "-o", out)
    assert code == 0, err
    read = imageio.imread(out, index=None, **({"plugin": "FFMPEG"} if suffix == ".mp4" else {}))
    assert read.shape[:3] == (2, 24, 32)
    assert [p.name for p in tmp_path.iterdir() if p.name != "anim.yaml"] == [out.name]


def test_a_radiosity_animation_that_moves_the_camera_solves_once(tmp_path, capsys):
    import yaml

    with open(EXAMPLES / "path" / "cornell.yaml") as f:
        data = yaml.safe_load(f)
    data["render"] = {"method": "radiosity", "width": 32, "height": 24, "radiosity": {"patch_size": 0.5}}
    data["animation"] = {"frames": 4, "tracks": [{"target": "camera.position", "keys": [
        {"frame": 0, "value": [0, 0, 3.9]}, {"frame": 3, "value": [0.5, 0.3, 3.6]}]}]}
    path = tmp_path / "box.yaml"
    path.write_text(yaml.safe_dump(data))
    code, _, err = run(capsys, "render", path, "--frames", "0:4", "-o", tmp_path / "box_%d.png",
                       "--stats", tmp_path / "stats.json")
    assert code == 0, err
    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["radiosity_solves"] == 1 and [f["radiosity_solves"] for f in stats["per_frame"]] == [1, 0, 0, 0]
    assert "radiosity solved 1 time ->" in err
    assert read_image(tmp_path / "box_3.png").mean() > 0.05


BAD = [
    (["--frames", "0:7"], None,
     "{tmp}/anim.yaml: frames 0:7 are outside the animation: the animation has 6 frames (0 to 5)"),
    (["--frames", "9"], None, "{tmp}/anim.yaml: frame 9 is outside the animation"),
    (["--frames", "x:2"], None, "--frames: expected A:B, A:B:STEP or one frame K (integers), got 'x:2'"),
    (["--frames", "0:3"], "one.png", "-o {tmp}/one.png: 3 frames need a file name each: put the frame number in it, "
                                     "e.g. {tmp}/one_%04d.png"),
    (["--frames", "0:3"], "f_%d_%d.png", "-o {tmp}/f_%d_%d.png: a pattern for frames takes one %d-style number"),
    (["--frames", "0:3"], "f_%d.jpg", "cannot write image '{tmp}/f_0.jpg': unsupported extension '.jpg'"),
    (["--frames", "0:3", "--checkpoint-every", "5"], "f_%d.png", "--checkpoint-every rewrites one image"),
    (["--aov", "depth"], "anim.gif", "--aov writes image files beside the image; a video holds the image only"),
    (["--frames", "0:3", "--method", "nope"], "f_%d.png", "render.method: unknown method 'nope'"),
    ([], "anim.avi", "cannot write image '{tmp}/anim.avi': unsupported extension '.avi'"),
]


@pytest.mark.parametrize("flags, output, message", BAD, ids=[b[2][:40] for b in BAD])
def test_bad_frames_and_outputs_are_one_line_errors_writing_nothing(tmp_path, scene_file, capsys, flags, output,
                                                                   message):
    out = tmp_path / "frames" / (output or "f_%04d.png")
    if output:
        out = tmp_path / output
    code, stdout, err = run(capsys, "render", scene_file, *flags, "-o", out)
    assert code == 2, err
    assert one_error_line(err).startswith(message.format(tmp=tmp_path)), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["anim.yaml"]  # nothing written, no folder made


@pytest.mark.parametrize("track, message", [
    ("""\
     - target: camera.fov
       keys: [{time: 1, value: 40}, {time: 0.5, value: 50}]""",
     "anim.yaml:12: animation.tracks[0].keys[1].time: keyframes out of order: 0.5 s is not after the previous "
     "key's 1 s"),
    ("""\
     - target: lights[key].colour
       keys: [{time: 0, value: 1}]""",
     "anim.yaml:11: animation.tracks[0].target: unknown animated key of a point light 'colour'"),
    ("""\
     - target: objects[ball].transform.translate
       keys: [{time: 0, value: [1, 0]}]""",
     "anim.yaml:12: animation.tracks[0].keys[0].value: must have 3 components, got 2"),
])
def test_bad_tracks_exit_2_writing_nothing(tmp_path, capsys, track, message):
    path = tmp_path / "anim.yaml"
    head = ANIMATED.split("  tracks:")[0]
    path.write_text(head + "  tracks:\n" + textwrap.indent(textwrap.dedent(track), "    ") + "\n")
    for out in (tmp_path / "f_%d.png", tmp_path / "anim.gif", tmp_path / "plain.png"):
        flags = ["--frames", "0:2"] if "%" in out.name else []
        code, _, err = run(capsys, "render", path, *flags, "-o", out)
        assert code == 2
        assert one_error_line(err) == f"{tmp_path}/{message}" or one_error_line(err).startswith(
            f"{tmp_path}/{message}"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["anim.yaml"]
