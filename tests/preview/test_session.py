"""The preview session without the web: an edit renders again with the new value, a stale render is dropped,
the display changes without rendering, the camera moves without compiling, frames are throttled, pixels are
explained, and Save writes only new files in the scene's folder."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
import yaml
from helpers import DATA

import lumos
from lumos.errors import LumosError
from lumos.preview.publish import MAX_FRAMES_PER_S
from lumos.preview.session import Session


class Recorder:
    """Collects a session's events; `wait_for` blocks until one matches."""

    def __init__(self):
        self.events = []
        self.cond = threading.Condition()

    def __call__(self, event):
        with self.cond:
            self.events.append((time.perf_counter(), event))
            self.cond.notify_all()

    def frames(self):
        with self.cond:
            return [e[1] for _, e in self.events if e[0] == "frame"]

    def wait_for(self, match, timeout=30.0):
        """The first event (kind, payload) so far, or to come, for which match(kind, payload) holds."""
        deadline = time.perf_counter() + timeout
        with self.cond:
            while True:
                for _, event in self.events:
                    if match(*event):
                        return event[1]
                left = deadline - time.perf_counter()
                if left <= 0:
                    raise AssertionError(f"no matching event in {timeout} s; got {[e[0] for _, e in self.events]}")
                self.cond.wait(left)

    def final(self, generation, timeout=30.0):
        return self.wait_for(lambda kind, p: kind == "frame" and p.generation == generation and p.final, timeout)

    def clear(self):
        with self.cond:
            self.events.clear()


@pytest.fixture
def open_session(scene_file):
    """open_session(**settings) -> (session, recorder), started; closed after the test."""
    made = []

    def make(**settings):
        session = Session.from_file(scene_file, start=False, **settings)
        recorder = Recorder()
        session.subscribe(recorder)
        session.start()
        made.append(session)
        return session, recorder

    yield make
    for session in made:
        session.close()


def sphere_red(frame):
    """The mean red of the middle of the image (the sphere)."""
    a = frame.image.array
    h, w = a.shape[:2]
    return float(a[h // 3:2 * h // 3, w // 3:2 * w // 3, 0].mean())


def test_the_first_image_comes_quick_then_full(open_session):
    session, rec = open_session()
    final = rec.final(0)
    frames = [f for f in rec.frames() if f.generation == 0]
    assert frames[-1].stage == "final" and (final.image.width, final.image.height) == (64, 48)
    # the quick pass goes out first, unless the full image was ready before the publisher sent it (the latest
    # frame wins)
    quick = [f for f in frames if f.stage == "quick"]
    assert all(f is frames[0] and (f.image.width, f.image.height) == (16, 12) for f in quick)
    assert final.status["method"] == "raycast" and final.status["done"]
    assert final.png()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_edit_renders_again_with_the_new_value(open_session, scene_file):
    session, rec = open_session()
    before = sphere_red(rec.final(0))
    reply = session.handle({"type": "material", "name": "red", "key": "kd", "value": 0.15})
    assert reply == {"type": "ack", "generation": 1, "id": None}
    after = sphere_red(rec.final(1))
    assert after < 0.6 * before
    # the hue is kept: the slider set the largest channel
    assert session.state()["scene_edit"]["materials"][0]["values"]["kd"] == pytest.approx(0.15)
    kd = yaml.safe_load(session.save("ball2.yaml").read_text())["materials"]["red"]["kd"]
    assert kd == pytest.approx([0.15, 0.025, 0.025])
    # the same as lumos.render of the edited scene at the preview's size
    direct = lumos.render(scene_file.with_name("ball2.yaml"), width=64, height=48)
    np.testing.assert_allclose(rec.final(1).image.array, direct.array, atol=1e-6)


def test_a_light_edit_moves_the_light_and_scales_its_colour(open_session):
    session, rec = open_session()
    before = rec.final(0).image.array.mean()
    session.handle({"type": "light", "index": 0, "key": "strength", "value": 2.0})
    assert rec.final(1).image.array.mean() > 1.3 * before
    light = session.state()["scene_edit"]["lights"][0]
    assert light["strength"] == pytest.approx(2.0)
    session.handle({"type": "light", "index": 0, "key": "position", "value": [-2.0, 4.0, 3.0]})
    moved = rec.final(2).image.array
    assert session.state()["scene_edit"]["lights"][0]["vectors"]["position"] == [-2.0, 4.0, 3.0]
    w = moved.shape[1]
    assert moved[:, : w // 2].mean() > moved[:, w // 2:].mean()  # lit from the left now


def test_a_stale_render_is_dropped(open_session):
    """A path render that would take minutes is left at its next band when an edit comes."""
    session, rec = open_session(method="path", spp=1 << 16, width=48, height=36)
    rec.wait_for(lambda kind, f: kind == "frame" and f.generation == 0 and f.stage != "quick")
    session.handle({"type": "camera", "yaw": 20.0})
    rec.wait_for(lambda kind, f: kind == "frame" and f.generation == 1)
    time.sleep(1.6)  # path's passes after the first take about a second each
    frames = [f for _, (kind, f) in rec.events if kind == "frame"]
    first_new = next(k for k, f in enumerate(frames) if f.generation == 1)
    assert all(f.generation == 1 for f in frames[first_new:])  # once the new render shows, the old one is gone
    assert not any(f.final for f in rec.frames() if f.generation == 0)
    assert session.renders == 2


def test_exposure_and_tone_map_re_encode_without_rendering(open_session):
    session, rec = open_session()
    first = rec.final(0)
    renders, compiles = session.renders, session.renderer.compiles
    rec.clear()
    session.set_display(exposure=4.0)
    again = rec.wait_for(lambda kind, f: kind == "frame")
    assert again.generation == 0 and again.image is first.image and again.display.exposure == 4.0
    assert again.png() != first.png()
    rec.clear()
    session.set_display(tonemap="filmic")
    filmic = rec.wait_for(lambda kind, f: kind == "frame")
    assert filmic.display.tonemap == "filmic" and filmic.png() != again.png()
    assert (session.renders, session.renderer.compiles) == (renders, compiles)


def test_an_aov_view_renders_once_then_shows_from_the_image(open_session):
    session, rec = open_session()
    rec.final(0)
    generation = session.handle({"type": "display", "view": "diffuse"})["generation"]
    assert generation == 1  # the image has no diffuse term yet: rendered with it
    frame = rec.final(1)
    assert "diffuse" in frame.image.aovs and frame.display.view == "diffuse"
    with pytest.raises(LumosError, match="not a view of method raycast"):
        session.set_display(view="variance")


def test_a_camera_edit_recompiles_nothing(open_session):
    session, rec = open_session()
    first = rec.final(0)
    compiles = session.renderer.compiles
    session.handle({"type": "camera", "yaw": 30.0, "pitch": 10.0})
    turned = rec.final(1)
    assert session.renderer.compiles == compiles
    assert np.abs(turned.image.array - first.image.array).mean() > 0.01
    session.handle({"type": "camera", "reset": True})
    np.testing.assert_array_equal(rec.final(2).image.array, first.image.array)


def test_switching_method_and_shading(open_session):
    session, rec = open_session()
    rec.final(0)
    session.handle({"type": "settings", "method": "raster", "shading": "flat"})
    frame = rec.final(1)
    assert frame.status["method"] == "raster" and frame.status["shading"] == "flat"
    state = session.state()
    assert state["settings"]["method"] == "raster" and "specular" in state["views"]
    session.handle({"type": "settings", "method": "path"})
    assert session.state()["settings"]["spp"] >= 256  # the scene's 1 spp is for the classic methods
    assert "variance" in session.state()["views"]


@pytest.mark.parametrize("message, says", [
    ({"type": "material", "name": "red", "key": "kd", "value": 7}, "out of range"),
    ({"type": "material", "name": "red", "key": "kd", "value": "a lot"}, "expected a number"),
    ({"type": "material", "name": "red", "key": "kd", "value": float("nan")}, "finite"),
    ({"type": "material", "name": "gold", "key": "kd", "value": 0.5}, "no named material 'gold'"),
    ({"type": "material", "name": "red", "key": "texture", "value": 0.5}, "not an editable"),
    ({"type": "light", "index": 5, "key": "strength", "value": 1}, "no light 5"),
    ({"type": "light", "index": 0, "key": "direction", "value": [0, 1, 0]}, "has no 'direction'"),
    ({"type": "light", "index": 0, "key": "position", "value": [0, 1]}, "expected \\[x, y, z\\]"),
    ({"type": "camera", "dolly": -1}, "positive"),
    ({"type": "settings", "method": "photon-mapping"}, "unknown method"),
    ({"type": "settings", "spp": 0}, "whole number"),
    ({"type": "display", "exposure": -1}, "out of range"),
    ({"type": "display", "tonemap": "hable"}, "unknown tone map"),
    ({"type": "teleport"}, "unknown message type"),
    (["not", "a", "dict"], "JSON object"),
])


def test_bad_messages_are_refused_and_change_nothing(open_session, message, says):
    session, rec = open_session()
    rec.final(0)
    with pytest.raises(LumosError, match=says):
        session.handle(message)
    assert session.generation == 0
    session.handle({"type": "material", "name": "red", "key": "ks", "value": 0.5})  # and it goes on
    rec.final(1)


def test_save_writes_a_new_file_in_the_scene_folder_only(open_session, scene_file, tmp_path):
    session, rec = open_session()
    session.handle({"type": "material", "name": "floor", "key": "kd", "value": 0.25})
    saved = session.save("edited")
    assert saved == scene_file.with_name("edited.yaml").resolve()
    data = yaml.safe_load(saved.read_text())
    assert data["materials"]["floor"]["kd"] == 0.25 and data["objects"] == yaml.safe_load(scene_file.read_text())[
        "objects"]
    lumos.load_scene(saved)
    assert session.save("edited.json").suffix == ".json"
    for name, says in [("edited.yaml", "exists"), ("ball.yaml", "exists"), ("../outside.yaml", "not a file in"),
                       (str(tmp_path / "abs.yaml"), "not a file in"), ("sub/x.yaml", "not a file in"),
                       ("", "give a file name"), (None, "give a file name")]:
        with pytest.raises(LumosError, match=says):
            session.save(name)
    assert not (tmp_path / "outside.yaml").exists() and not (tmp_path / "abs.yaml").exists()
    assert scene_file.read_text() == (DATA / "preview" / "ball.yaml").read_text()  # the scene itself untouched


def test_explain_a_pixel(open_session):
    session, rec = open_session()
    rec.final(0)
    replies = []
    session.explain(32, 24, replies.append)
    deadline = time.perf_counter() + 30
    while not replies and time.perf_counter() < deadline:
        time.sleep(0.02)
    reply = replies[0]
    assert reply["type"] == "explain" and reply["method"] == "raycast" and reply["note"] is None
    assert "hit sphere#1" in reply["text"] and "light 0 (point)" in reply["text"]
    np.testing.assert_allclose(reply["value"], rec.final(0).image.array[24, 32], atol=1e-5)
    session.handle({"type": "settings", "method": "path", "spp": 4})
    replies.clear()
    session.explain(32, 24, replies.append)
    session.explain(640, 24, replies.append)  # outside the image: an error reply, not a dead thread
    while len(replies) < 2 and time.perf_counter() < deadline:
        time.sleep(0.02)
    assert replies[0]["method"] == "whitted" and "path does not explain" in replies[0]["note"]
    assert replies[1]["type"] == "error" and "outside the image" in replies[1]["message"]
    with pytest.raises(LumosError, match="whole number"):
        session.explain("32", 24, replies.append)


def test_frames_are_throttled_but_the_last_goes_at_once():
    """A viewer shown 40 passes in 0.4 s sends about 4 a second; the final image is not held back."""
    scene = lumos.load_scene({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]}, "objects": []})
    cfg = scene.render.model_copy(update={"method": "path", "width": 8, "height": 6})
    session = Session.viewer(scene, cfg)
    got = []
    session.subscribe(lambda event: got.append((time.perf_counter(), event)))
    try:
        t0 = time.perf_counter()
        for k in range(40):
            session.show(lumos.Image(np.full((6, 8, 3), k / 40, np.float32), stats={"spp": k + 1}))
            time.sleep(0.01)
        t_final = time.perf_counter()
        session.show(lumos.Image(np.ones((6, 8, 3), np.float32), stats={"spp": 64}), final=True)
        time.sleep(0.3)
    finally:
        session.close()
    frames = [(t, e[1]) for t, e in got if e[0] == "frame"]
    # the final image goes out before the throttle would have let the next pass through
    assert frames[-1][1].final and frames[-1][0] - t_final < 1.0 / MAX_FRAMES_PER_S
    passes = [t for t, f in frames if not f.final]
    assert 1 <= len(passes) <= (t_final - t0) * MAX_FRAMES_PER_S + 1
    with pytest.raises(LumosError, match="lumos serve"):
        session.handle({"type": "camera", "yaw": 1})
