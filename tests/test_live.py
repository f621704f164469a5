"""lumos.live: the sink interface, its throttle, and `render(live=...)` wired onto path's passes (tev:
test_live_tev.py; Jupyter: test_live_notebook.py)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from helpers import TINY

import lumos
from lumos.errors import LumosError, LumosWarning
from lumos.live import NotebookSink, Sink, Throttled, caption, close_on_error, open_sink


class Recorder(Sink):
    """A sink that keeps what it was shown: (image, final) pairs."""

    def __init__(self, interval=0.0):
        super().__init__(interval)
        self.shown = []
        self.closed = False

    def show(self, image, final):
        self.shown.append((image, final))

    def close(self):
        self.closed = True


class Plain:
    """A sink that is not a `Sink`: just update and close."""

    def __init__(self):
        self.updates, self.closed = [], False

    def update(self, image, final):
        self.updates.append(final)

    def close(self):
        self.closed = True


def tiny(**render):
    scene = yaml.safe_load(TINY)
    scene["render"].update(render)
    return scene


@pytest.fixture
def many_passes(monkeypatch):
    from lumos.methods import path as path_method

    monkeypatch.setattr(path_method, "PASS_SECONDS", 1e-9)  # one sample per pass


def image(value=0.5):
    return lumos.Image(np.full((4, 6, 3), value, np.float32))


def test_updates_are_throttled_and_the_final_one_always_goes_through():
    sink = Recorder(interval=60.0)
    assert sink.update(image(0.1)) is True  # the first goes through
    assert [sink.update(image(0.2)), sink.update(image(0.3))] == [False, False]
    assert sink.update(image(0.4), final=True) is True
    assert [final for _, final in sink.shown] == [False, True]
    assert sink.shown[-1][0].array[0, 0, 0] == np.float32(0.4)
    assert sink.update(image(0.5)) is True  # after a final image, the next render's first one goes through


def test_a_slow_sink_is_updated_less_often():
    """After an update that took d seconds the next waits SLACK·d, so the sink costs the render at most ~5%."""
    clock = iter([0.0, 2.0, 2.5, 30.0, 41.0, 42.0])
    sink = Recorder(interval=0.25)
    sink.clock = lambda: next(clock)
    assert sink.update(image()) is True  # 0 → 2: two seconds to show; the next one not before 2 + 19·2 = 40
    assert sink.update(image()) is False  # at 2.5
    assert sink.update(image()) is False  # at 30
    assert sink.update(image()) is True  # at 41 (ends at 42)


def test_render_sends_each_pass_and_the_final_image(many_passes):
    sink = Recorder()
    seen = []
    img = lumos.render(tiny(method="path", spp=5, seed=1), live=sink, on_pass=lambda im: seen.append(im.stats["spp"]))
    finals = [final for _, final in sink.shown]
    assert finals == [False] * 4 + [True]  # passes 1..4 (the fifth is the final image), then the final one
    assert [im.stats["spp"] for im, _ in sink.shown] == [1, 2, 3, 4, 5]
    assert seen == [1, 2, 3, 4]  # the caller's own on_pass still runs
    assert sink.shown[-1][0] is img
    assert not sink.closed  # a sink given by the caller stays open


def test_other_methods_send_only_the_final_image():
    sink = Recorder()
    img = lumos.render(tiny(method="raycast"), live=sink)
    assert len(sink.shown) == 1 and sink.shown[0] == (img, True)


def test_a_sink_that_is_not_a_sink_subclass_is_throttled_and_left_open(many_passes):
    plain = Plain()
    lumos.render(tiny(method="path", spp=4), live=plain)
    assert plain.updates[0] is False and plain.updates[-1] is True
    assert len(plain.updates) <= 4 and not plain.closed
    wrapped, owned = open_sink(plain)
    assert isinstance(wrapped, Throttled) and wrapped.sink is plain and not owned


def test_live_true_outside_a_notebook_warns_once_and_renders():
    with pytest.warns(LumosWarning, match="needs Jupyter") as record:
        img = lumos.render(tiny(method="raycast"), live=True)
    assert len(record) == 1 and img.array.shape == (24, 32, 3)
    assert open_sink(None) == (None, False) and open_sink(False) == (None, False)


@pytest.mark.parametrize("live, message", [("browser", "expected True, 'tev'"), (42, "got int")])
def test_a_bad_live_argument_is_a_clear_error(live, message):
    with pytest.raises(LumosError, match=message):
        lumos.render(tiny(method="raycast"), live=live)


def test_a_sink_render_made_is_closed_when_the_render_fails():
    mine, given = Recorder(), Recorder()
    for sink, owned in ((mine, True), (given, False)):
        with pytest.raises(RuntimeError):
            with close_on_error(sink, owned):
                raise RuntimeError("boom")
    assert mine.closed and not given.closed


def test_the_notebook_caption_says_where_the_render_is():
    running = lumos.Image(np.zeros((24, 32, 3), np.float32), stats={"spp": 3, "passes": 3})
    done = lumos.Image(np.zeros((24, 32, 3), np.float32), stats={"method": "path", "spp": 8, "total_s": 1.25})
    assert caption(running, False, 0.5) == "rendering · 32×24 · 3 spp · pass 3 · 0.5 s"
    assert caption(done, True, 9.0) == "done · 32×24 · path · 8 spp · 1.2 s"


def test_notebook_sink_falls_back_to_display_handles(monkeypatch):
    """Without ipywidgets (widget=False) the image goes through IPython display handles, updated in place."""
    pytest.importorskip("IPython")
    import IPython.display

    calls = []

    class Handle:
        def update(self, obj):
            calls.append(("update", type(obj).__name__))

    def display(obj, display_id=None):
        calls.append(("display", type(obj).__name__))
        return Handle()

    monkeypatch.setattr(IPython.display, "display", display)
    sink = NotebookSink(interval=0.0, widget=False)
    sink.update(image(0.2))
    sink.update(image(0.3), final=True)
    assert calls == [("display", "Image"), ("display", "HTML"), ("update", "Image"), ("update", "HTML")]


def test_a_render_in_pieces_sends_only_the_final_image(tmp_path, many_passes):
    """With a checkpoint folder (or a cluster) the passes happen in pieces, not here: the sink gets the final image."""
    sink = Recorder()
    img = lumos.render(tiny(method="path", spp=3), live=sink, checkpoint=str(tmp_path / "pieces"))
    assert len(sink.shown) == 1 and sink.shown[0] == (img, True)
