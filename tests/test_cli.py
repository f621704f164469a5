"""The `lumos` command: exit codes, one-line errors, nothing written on failure, and (slow) real renders."""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from conftest import run_cli as run
from helpers import TINY
from lumos import cli
from lumos.errors import LumosError



@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return path


@pytest.fixture
def bad(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(textwrap.dedent("""\
        objects:
          - type: sphere
            radius: -1
        """))
    return path


def one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lumos: error: "), err
    assert "Traceback" not in err
    return lines[0]


# ---------------------------------------------------------------------------------------------- usage


def test_help(capsys):
    code, out, _ = run(capsys, "--help")
    assert code == 0 and "render" in out and "compare" in out
    code, out, _ = run(capsys, "render", "--help")
    assert code == 0 and "--max-depth" in out and "--stats" in out


def test_no_command_is_a_usage_error(capsys):
    code, _, err = run(capsys)
    assert code == 2 and "usage" in err


def test_bad_flag_value_is_a_usage_error(capsys, tiny):
    code, _, err = run(capsys, "render", tiny, "--width", "wide")
    assert code == 2 and "invalid int value" in err


# ------------------------------------------------------------------------------------------ bad input


def test_bad_scene_exit_2_one_line(capsys, bad, tmp_path):
    code, out, err = run(capsys, "render", bad, "-o", tmp_path / "out.png")
    line = one_error_line(err)
    assert code == 2 and f"{bad}:3: objects[0].radius: must be greater than 0" in line
    assert not (tmp_path / "out.png").exists()


def test_missing_scene_file(capsys, tmp_path):
    code, _, err = run(capsys, "render", tmp_path / "nope.yaml", "-o", tmp_path / "out.png")
    assert code == 2 and "nope.yaml: no such file" in one_error_line(err)


def test_missing_output_folder_writes_nothing(capsys, tiny, tmp_path):
    before = sorted(os.listdir(tmp_path))
    code, _, err = run(capsys, "render", tiny, "-o", tmp_path / "no" / "such" / "out.png")
    assert code == 2 and "does not exist" in one_error_line(err)
    assert sorted(os.listdir(tmp_path)) == before


def test_unknown_extension(capsys, tiny, tmp_path):
    code, _, err = run(capsys, "render", tiny, "-o", tmp_path / "out.jpeg")
    assert code == 2 and "unsupported extension '.jpeg'" in one_error_line(err)
    assert not (tmp_path / "out.jpeg").exists()


def test_stats_folder_missing(capsys, tiny, tmp_path):
    code, _, err = run(capsys, "render", tiny, "-o", tmp_path / "out.png", "--stats", tmp_path / "no" / "s.json")
    assert code == 2 and "cannot write stats" in one_error_line(err)


def test_unknown_method(capsys, tiny, tmp_path):
    code, _, err = run(capsys, "render", tiny, "-o", tmp_path / "out.png", "--method", "nope")
    assert code == 2 and "render.method: unknown method 'nope'" in one_error_line(err)
    assert not (tmp_path / "out.png").exists()


def test_bad_setting_flag(capsys, tiny, tmp_path):
    code, _, err = run(capsys, "render", tiny, "-o", tmp_path / "out.png", "--spp", "0")
    assert code == 2 and "render.spp: must be at least 1, got 0" in one_error_line(err)


def test_internal_error_exit_1_with_hint(capsys, monkeypatch, tiny, tmp_path):
    def boom(source, **_):
        raise RuntimeError("kaboom")

    monkeypatch.setattr("lumos.scene.loader.load_scene", boom)
    monkeypatch.delenv("LUMOS_DEBUG", raising=False)
    code, _, err = run(capsys, "render", tiny, "-o", tmp_path / "out.png")
    assert code == 1 and "lumos: internal error: RuntimeError: kaboom" in err and "LUMOS_DEBUG=1" in err
    monkeypatch.setenv("LUMOS_DEBUG", "1")
    with pytest.raises(RuntimeError):
        cli.main(["render", str(tiny), "-o", str(tmp_path / "out.png")])


def test_keyboard_interrupt_exit_130(capsys, monkeypatch, tiny, tmp_path):
    def interrupted(source, **_):
        raise KeyboardInterrupt

    monkeypatch.setattr("lumos.scene.loader.load_scene", interrupted)
    code, _, err = run(capsys, "render", tiny, "-o", tmp_path / "out.png")
    assert code == 130 and "Traceback" not in err


def test_subprocess_bad_scene_no_traceback(bad, tmp_path):
    proc = subprocess.run([sys.executable, "-m", "lumos", "render", str(bad), "-o", str(tmp_path / "o.png")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and proc.stderr.count("\n") == 1
    assert f"{bad}:3: objects[0].radius" in proc.stderr


# ------------------------------------------------------------------------------------------- compare


@pytest.fixture
def two_images(tmp_path):
    from lumos.io.image_files import write_image

    a = np.full((4, 5, 3), 0.5, np.float32)
    b = a.copy()
    b[0, 0] = 0.0
    write_image(tmp_path / "a.npy", a)
    write_image(tmp_path / "b.npy", b)
    return tmp_path / "a.npy", tmp_path / "b.npy"


def test_compare_prints_four_figures(capsys, two_images, tmp_path):
    code, out, err = run(capsys, "compare", *two_images, "--diff", tmp_path / "d.png")
    assert code == 0, err
    keys = [line.split()[0] for line in out.splitlines()]
    assert keys == ["rmse", "psnr", "mean_rel_error", "max_abs_error"]
    assert float(out.splitlines()[3].split()[1]) == pytest.approx(0.5)
    assert (tmp_path / "d.png").is_file()


def test_compare_missing_image(capsys, two_images, tmp_path):
    code, _, err = run(capsys, "compare", two_images[0], tmp_path / "nope.npy")
    assert code == 2 and "nope.npy" in one_error_line(err)


def test_compare_diff_bad_extension_reads_nothing(capsys, two_images, tmp_path):
    code, _, err = run(capsys, "compare", *two_images, "--diff", tmp_path / "d.gif")
    assert code == 2 and "d.gif" in one_error_line(err)


# ------------------------------------------------------------------------------ real renders (kernels)


@pytest.mark.slow
def test_render_writes_image_and_stats(capsys, tiny, tmp_path):
    out, stats = tmp_path / "out.png", tmp_path / "stats.json"
    code, _, err = run(capsys, "render", tiny, "-o", out, "--stats", stats, "--aov", "depth", "--width", "16")
    assert code == 0, err
    assert out.is_file() and (tmp_path / "out.depth.png").is_file()
    figures = json.loads(stats.read_text())
    for key in ("load_s", "build_s", "render_s", "total_s", "rays", "mrays_per_s"):
        assert key in figures
    assert figures["width"] == 16 and figures["rays"] >= 16 * 24
    assert "lumos: raycast 16x24, 1 spp" in err and f"-> {out}" in err


@pytest.mark.slow
def test_render_default_output_in_cwd(capsys, monkeypatch, tiny, tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    code, _, err = run(capsys, "render", tiny, "--quiet")
    assert code == 0, err
    assert (work / "tiny.png").is_file() and err == ""


@pytest.mark.slow
def test_info(capsys, tiny):
    code, out, err = run(capsys, "info", tiny)
    assert code == 0, err
    assert "objects" in out and "sphere 1" in out and "lights" in out and "point 1" in out


def test_lumos_error_is_exit_2(capsys, monkeypatch, tiny):
    def refuse(source):
        raise LumosError("nope: bad\ninput")

    monkeypatch.setattr("lumos.scene.loader.load_scene", refuse)
    code, _, err = run(capsys, "info", tiny)
    assert code == 2 and one_error_line(err) == "lumos: error: nope: bad input"


def test_a_scene_with_adaptive_antialiasing_renders_with_another_method(tmp_path, capsys):
    # the scene file asks for whitted's adaptive anti-aliasing; --method raster supersamples instead, and says so
    scene = tmp_path / "s.yaml"
    scene.write_text("render: {method: whitted, antialias: adaptive, width: 16, height: 12}\n"
                     "lights: [{type: directional, direction: [0, 0, -1]}]\n"
                     "objects: [{type: sphere, radius: 1}]\n")
    out = tmp_path / "r.png"
    assert cli.main(["render", str(scene), "--method", "raster", "-o", str(out), "-q", "--aov", "samples"]) == 0
    assert "supersamples at 4 spp" in capsys.readouterr().err
    assert out.exists()
    # given as a flag, adaptive with another method is still refused
    assert cli.main(["render", str(scene), "--method", "raster", "--antialias", "adaptive", "-o", str(out)]) == 2


@pytest.mark.parametrize("method", ["raster", "radiosity"])
@pytest.mark.parametrize("scene", [
    "objects: [{type: sphere, radius: 1.0e-300}]",
    "objects: [{type: sphere, radius: 1}]\n"
    "lights: [{type: area, shape: sphere, center: [0, 3, 0], radius: 1.0e-300}]",
    "objects: [{type: plane, point: [0, 0, 0], normal: [0, 1, 0], transform: {scale: [1.0e-300, 1, 1]}}]",
    "objects: [{type: csg, op: union, left: {type: sphere, radius: 1.0e-300}, right: {type: sphere, radius: 1}}]",
])
def test_shapes_too_small_to_tessellate_are_one_line_errors(tmp_path, capsys, method, scene):
    path = tmp_path / "s.yaml"
    path.write_text(scene + "\n")
    out = tmp_path / "o.png"
    assert cli.main(["render", str(path), "--method", method, "-o", str(out), "-q", "--width", "16",
                     "--height", "12"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("lumos: error: ") and "bug" not in err
    assert not out.exists()
