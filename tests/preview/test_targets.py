"""`lumos render ... --preview [TARGET]` and `lumos serve`: the page serves the render in progress and its final
image, `--preview tev` goes to `lumos.live.TevSink`, bad targets and combinations are refused, and `lumos serve`
prints its address, guards it with the token and stops on Ctrl-C."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request

import pytest
from helpers import ROOT

from lumos.errors import LumosError
from lumos.preview import targets
from lumos.preview.server import warn_if_exposed
from lumos.preview.targets import parse_target


def run_cli(*argv):
    """(exit code, stderr) of `lumos ARGV` run in this process."""
    import contextlib
    import io

    from lumos import cli

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, err.getvalue()


@pytest.mark.parametrize("spec, parsed", [
    ("browser", ("browser", None, None)), ("browser:8123", ("browser", None, 8123)),
    ("browser:0.0.0.0:0", ("browser", "0.0.0.0", 0)), ("tev", ("tev", None, None)),
    ("tev:10.0.0.2:14158", ("tev", "10.0.0.2:14158", None)), ("tev::9000", ("tev", ":9000", None)),
])


def test_targets(spec, parsed):
    assert parse_target(spec) == parsed


@pytest.mark.parametrize("spec", ["chrome", "browser:http", "browser:70000", "scene.yaml"])
def test_bad_targets(spec):
    with pytest.raises(LumosError, match="--preview"):
        parse_target(spec)


def test_render_preview_serves_the_render_then_its_final_image(scene_file, tmp_path, monkeypatch):
    """A path render with --preview: the page gets its passes and final image while the command waits for
    Ctrl-C; the image file is written as without --preview."""
    websockets = pytest.importorskip("websockets.sync.client")
    seen = {}

    def look_at_the_page():
        url = seen["url"]
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(url.split("?")[0], timeout=10)
        assert refused.value.code == 403
        assert b"lumos preview" in urllib.request.urlopen(url, timeout=10).read()
        with websockets.connect(url.replace("http://", "ws://").replace("/?", "/ws?"), open_timeout=10) as ws:
            state = json.loads(ws.recv(timeout=10))
            meta = json.loads(ws.recv(timeout=10))
            png = ws.recv(timeout=10)
            ws.send(json.dumps({"type": "material", "name": "red", "key": "kd", "value": 0.1}))
            seen["refused"] = json.loads(ws.recv(timeout=10))
            ws.send(json.dumps({"type": "display", "exposure": 2.0}))
            seen["ack"] = json.loads(ws.recv(timeout=10))
            ws.send(json.dumps({"type": "explain", "x": 32, "y": 30}))
            while "explain" not in seen:
                message = ws.recv(timeout=30)
                if isinstance(message, str) and json.loads(message)["type"] in ("explain", "error"):
                    seen["explain"] = json.loads(message)
        seen.update(state=state, meta=meta, png=png)

    monkeypatch.setattr(targets, "wait_for_ctrl_c", look_at_the_page)
    real_print = print

    def spy(*args, **kwargs):  # the address, as printed
        text = " ".join(map(str, args))
        if "lumos: preview at " in text:
            seen["url"] = text.split(" at ", 1)[1].strip()
        real_print(*args, **kwargs)

    monkeypatch.setattr(targets, "print", spy, raising=False)
    out = tmp_path / "ball.png"
    code, err = run_cli("render", scene_file, "-o", out, "--method", "path", "--spp", "8", "--preview")
    assert code == 0, err
    assert out.exists() and "lumos: the preview stays at" in err
    assert seen["state"]["editable"] is False and seen["state"]["settings"]["method"] == "path"
    assert seen["meta"]["stage"] == "shown" and seen["meta"]["status"]["spp"] == 8 and seen["png"][:4] == b"\x89PNG"
    assert seen["refused"]["type"] == "error" and "lumos serve" in seen["refused"]["message"]
    assert seen["ack"]["type"] == "ack"
    # path explains no pixel: whitted's account of it, with the render's lights and materials
    assert seen["explain"]["method"] == "whitted" and "path does not explain" in seen["explain"]["note"]
    assert "hits sphere#1 ('red')" in seen["explain"]["text"]


def test_render_preview_tev_streams_to_tev_sink(scene_file, tmp_path, monkeypatch):
    live = pytest.importorskip("lumos.live")
    calls = []

    class FakeTev:
        def __init__(self, address=live.TEV_ADDRESS, name="lumos"):
            calls.append(("open", address, name))

        def update(self, image, final=False):
            calls.append(("update", image.width, final))

        def close(self):
            calls.append(("close",))

    monkeypatch.setattr(live, "TevSink", FakeTev)
    code, err = run_cli("render", scene_file, "-o", tmp_path / "b.png", "--method", "path", "--spp", "4",
                        "--preview", "tev:127.0.0.1:9999", "-q")
    assert code == 0, err
    assert calls[0] == ("open", "127.0.0.1:9999", "ball.yaml")
    assert calls[-2:] == [("update", 64, True), ("close",)]
    calls.clear()
    assert run_cli("render", scene_file, "-o", tmp_path / "c.png", "--preview", "tev", "-q")[0] == 0
    assert calls == [("open", live.TEV_ADDRESS, "ball.yaml"), ("update", 64, True), ("close",)]


@pytest.mark.parametrize("extra, says", [
    (["--preview", "chrome"], "--preview chrome"),
    (["--preview", "--frames", "0:2"], "--frames"),
    (["--preview", "--cluster", "local:1"], "--cluster"),
])


def test_render_preview_refuses(scene_file, tmp_path, extra, says):
    code, err = run_cli("render", scene_file, "-o", tmp_path / "x.png", *extra)
    assert code == 2 and says in err
    assert not (tmp_path / "x.png").exists()


def test_serve_refuses_bad_input(tmp_path, scene_file):
    code, err = run_cli("serve", tmp_path / "missing.yaml")
    assert code == 2 and "no such file" in err
    code, err = run_cli("serve", ROOT / "examples" / "data" / "bunny.ply")
    assert code == 2 and "--preview" in err
    code, err = run_cli("serve", scene_file, "--method", "photon")
    assert code == 2 and "unknown method" in err
    code, err = run_cli("serve", scene_file, "--port", "70000")
    assert code == 2 and "--port" in err


def test_a_host_other_than_loopback_is_warned_about(capsys):
    warn_if_exposed("127.0.0.1")
    assert capsys.readouterr().err == ""
    warn_if_exposed("0.0.0.0")
    assert "warning: listening on 0.0.0.0" in capsys.readouterr().err


def test_serve_prints_its_address_and_stops_on_ctrl_c(scene_file):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "lumos", "serve", str(scene_file), "--port", "0"],
                            stderr=subprocess.PIPE, text=True, env=env)
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stderr.readline, "")), daemon=True)
    reader.start()
    try:
        deadline = time.perf_counter() + 60
        while not any("preview at" in line for line in lines):
            assert proc.poll() is None and time.perf_counter() < deadline, lines
            time.sleep(0.05)
        url = next(line for line in lines if "preview at" in line).split(" at ", 1)[1].strip()
        assert url.startswith("http://127.0.0.1:") and "/?token=" in url
        assert b"lumos preview" in urllib.request.urlopen(url, timeout=10).read()
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(url.replace("token=", "token=x"), timeout=10)
        assert refused.value.code == 403
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
    reader.join(timeout=5)
    assert any("preview stopped" in line for line in lines), lines
