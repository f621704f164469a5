"""The path tracer from the command line: progressive stops (--time-limit, Ctrl-C), checkpoints that survive a
killed process, the denoiser's clear error, the help naming every method, and first-run compile messages."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from lumos import api, cli
from lumos.io.image_files import read_image

BOX = """\
camera: {position: [0, 0, 0.9], look_at: [0, 0, 0], fov: 75}
render: {method: path, width: 48, height: 32}
lights:
  - {type: area, shape: rect, corner: [-0.3, 0.99, -0.3], edge_u: [0.6, 0, 0], edge_v: [0, 0, 0.6], radiance: 8}
objects:
  - {type: box, min: [-1, -1, -1], max: [1, 1, 1], material: {kd: 0.7}}
  - {type: sphere, center: [0, -0.6, 0], radius: 0.4, material: {kd: 0.5, ks: 0.3, shininess: 30}}
"""


@pytest.fixture
def box(tmp_path):
    path = tmp_path / "box.yaml"
    path.write_text(BOX)
    return path


def lumos_cmd(*argv):
    return [sys.executable, "-m", "lumos", *map(str, argv)]


def test_render_help_names_every_method(capsys):
    with pytest.raises(SystemExit):
        cli.build_parser().parse_args(["render", "--help"])
    out = capsys.readouterr().out
    for name in api.METHODS:
        assert name in out
    for flag in ("--time-limit", "--checkpoint-every", "--denoise", "--filter", "--sampling"):
        assert flag in out


def test_time_limit_writes_the_samples_so_far(box, tmp_path, capsys):
    out, stats = tmp_path / "out.exr", tmp_path / "stats.json"
    code = cli.main(["render", str(box), "-o", str(out), "--spp", "1000000", "--time-limit", "0.5",
                     "--stats", str(stats)])
    err = capsys.readouterr().err
    assert code == 0, err
    figures = json.loads(stats.read_text())
    assert figures["stopped"] == "time limit" and 1 <= figures["spp"] < 1000000
    assert f"{figures['spp']} spp (stopped by the time limit" in err
    img = read_image(out)
    assert img.shape == (32, 48, 3) and np.all(np.isfinite(img)) and img.mean() > 0


def test_path_flags_are_refused_by_other_methods(box, tmp_path, capsys):
    for flags in (["--time-limit", "1"], ["--checkpoint-every", "1"], ["--denoise"]):
        code = cli.main(["render", str(box), "-o", str(tmp_path / "x.png"), "--method", "raycast", *flags])
        err = capsys.readouterr().err
        assert code == 2 and "path feature" in err and err.count("\n") == 1, (flags, err)
        assert not (tmp_path / "x.png").exists()


def test_denoise_without_pyoidn_names_the_package(box, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyoidn", None)  # import pyoidn now raises ImportError
    code = cli.main(["render", str(box), "-o", str(tmp_path / "x.png"), "--denoise"])
    err = capsys.readouterr().err
    assert code == 2 and "pip install pyoidn" in err and err.count("\n") == 1
    assert not (tmp_path / "x.png").exists()


@pytest.mark.slow
def test_ctrl_c_stops_after_the_current_pass_and_writes_the_image(box, tmp_path):
    out = tmp_path / "out.npy"
    proc = subprocess.Popen(lumos_cmd("render", box, "-o", out, "--spp", "1000000", "--width", "96"),
                            stderr=subprocess.PIPE, text=True)
    time.sleep(_startup_seconds())
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert "interrupted after" in err and "Traceback" not in err
    img = np.load(out)
    assert img.shape == (32, 96, 3) and np.all(np.isfinite(img)) and img.mean() > 0


@pytest.mark.slow
def test_checkpoints_leave_a_valid_image_when_killed(box, tmp_path):
    out = tmp_path / "out.exr"
    proc = subprocess.Popen(lumos_cmd("render", box, "-o", out, "--spp", "1000000", "--width", "96",
                                      "--checkpoint-every", "0.2", "-q"), stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not out.exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)
    time.sleep(0.5)
    proc.kill()  # SIGKILL: no handler runs; what is on disk must be a whole image
    proc.communicate(timeout=60)
    assert out.exists(), "no checkpoint was written"
    img = read_image(out)
    assert img.shape == (32, 96, 3) and np.all(np.isfinite(img)) and img.mean() > 0
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], "a temporary file was left behind"


def _startup_seconds() -> float:
    """Long enough for the process to import, load its cached kernels and start its first passes."""
    return float(os.environ.get("LUMOS_TEST_STARTUP_S", "6"))


def test_first_run_says_it_compiles_and_keeps_it_out_of_the_render_time(box, tmp_path):
    """With a kernel missing from the cache the command says it is compiling, and its render time and ray rate
    leave the compiling out (jit_s holds it). The cache is a copy of this install's with one small top-level
    raster kernel taken out, so only that one compiles (its callees load)."""
    import shutil

    from lumos.kernels.cache import cache_dirs

    cache = tmp_path / "cache"
    source = cache_dirs()[0]
    if source.is_dir():
        shutil.copytree(source, cache)
    for entry in cache.glob("kernels/raster.project_vertices-*"):
        entry.unlink()
    env = dict(os.environ, LUMOS_CACHE_DIR=str(cache))
    stats = tmp_path / "stats.json"
    proc = subprocess.run(lumos_cmd("render", box, "-o", tmp_path / "a.png", "--method", "raster", "--stats", stats),
                          capture_output=True, text=True, timeout=600, env=env)
    assert proc.returncode == 0, proc.stderr
    assert "compiling kernels, once: about" in proc.stderr
    figures = json.loads(stats.read_text())
    assert figures["jit_s"] > 0.0 and figures["render_s"] + figures["build_s"] < figures["total_s"] - 0.5 * figures["jit_s"]
    again = subprocess.run(lumos_cmd("render", box, "-o", tmp_path / "b.png", "--method", "raster"),
                           capture_output=True, text=True, timeout=600, env=env)
    assert again.returncode == 0 and "compiling" not in again.stderr