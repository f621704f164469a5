"""Watch a render as it refines: sinks that receive the image after each pass (tev, a Jupyter notebook, your own).

    import lumos
    from lumos.live import TevSink

    img = lumos.render(scene, live=True)                        # in Jupyter: an image that updates in place
    with TevSink("127.0.0.1:14158") as tev:                     # a running tev viewer (pip install 'lumos[tev]')
        img = lumos.render(scene, live=tev)

A sink is any object with `update(image, final)` and `close()`: `render(live=sink)` calls `update` with the image
so far after each of path's passes (`final=False`) and once with the finished image (`final=True`; the other
methods produce only that one). `Sink` is the base class to build on: its `update` throttles to a few updates a
second (and to a small share of the render's time) so that a fast render is not slowed by its viewer, and always
lets the final image through; subclasses implement `show(image, final)`. Objects that are not `Sink`s are wrapped
in the same throttle by `render`.
"""

from __future__ import annotations

import contextlib
import math
import sys
import time
import warnings
from typing import Any

import numpy as np

from . import tonemap
from .errors import LumosError, LumosWarning
from .image import Image

#: Least seconds between two updates that are not final, about four a second: the default of every sink made
#: after it is set (0: every update).
INTERVAL_S = 0.25
#: After an update that took d seconds, the next waits at least this many times d, so a slow viewer costs the
#: render at most 1/(1 + SLACK) of its time (5%).
SLACK = 19.0
#: tev's default address (where `tev` listens unless `tev --host HOST:PORT` says otherwise).
TEV_ADDRESS = "127.0.0.1:14158"


class Sink:
    """Base class of the live views: a throttled `update`, a `show` for subclasses, `close` and `with`."""

    clock = staticmethod(time.monotonic)  # seconds, for the throttle

    def __init__(self, interval: float | None = None):
        self.interval = float(INTERVAL_S if interval is None else interval)
        self._next = -math.inf  # monotonic time before which updates that are not final are dropped

    def update(self, image: Image, final: bool = False) -> bool:
        """Show `image` unless the last update was too recent (a final image always goes through): the next
        waits `interval` seconds and SLACK times as long as this one took to show; `interval=0` shows them all.

        Returns whether it was shown."""
        start = self.clock()
        if not final and start < self._next:
            return False
        self.show(image, final)
        end = self.clock()
        if final or self.interval <= 0:
            self._next = -math.inf
        else:
            self._next = end + max(self.interval, SLACK * (end - start))
        return True

    def show(self, image: Image, final: bool) -> None:
        """Display `image` (the image so far, or the finished one when `final`). Subclasses implement it."""
        raise NotImplementedError

    def close(self) -> None:
        """Let go of the viewer (a connection, a widget). The base class holds nothing."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> bool:
        self.close()
        return False


class Throttled(Sink):
    """A sink of your own (any object with `update(image, final)` and `close()`) behind `Sink`'s throttle."""

    def __init__(self, sink: Any, interval: float | None = None):
        super().__init__(interval)
        self.sink = sink

    def show(self, image: Image, final: bool) -> None:
        self.sink.update(image, final)

    def close(self) -> None:
        self.sink.close()


# ------------------------------------------------------------------------------------------------------- tev

def parse_address(address: str) -> tuple[str, int]:
    """'HOST:PORT', 'HOST' or ':PORT' (or '[v6]:PORT') → (host, port); tev's defaults fill what is missing."""
    default_host, default_port = TEV_ADDRESS.rsplit(":", 1)
    text = str(address).strip()
    if text.startswith("["):  # [::1]:14158
        host, _, rest = text[1:].partition("]")
        port = rest[1:] if rest.startswith(":") else ""
    elif text.count(":") == 1:
        host, port = text.split(":")
    elif ":" in text:  # a bare IPv6 address
        host, port = text, ""
    else:
        host, port = text, ""
    try:
        number = int(port) if port else int(default_port)
    except ValueError:
        raise LumosError(f"tev address {address!r}: the port must be a number (HOST:PORT, e.g. {TEV_ADDRESS})") \
            from None
    if not 0 < number < 65536:
        raise LumosError(f"tev address {address!r}: port {number} is out of range")
    return host or default_host, number


def tev_channels(image: Image) -> tuple[list[str], np.ndarray]:
    """The channel names and float32 (H, W, C) pixels tev gets: R, G, B, then each float AOV (albedo.R/G/B,
    normal.R/G/B, depth.Z, variance.R/G/B ...), linear and unclamped as in an EXR. Integer AOVs (object_id,
    samples) are left out."""
    names, planes = ["R", "G", "B"], [image.array]
    for name, value in image.aovs.items():
        if value.dtype.kind != "f":
            continue
        if value.ndim == 2:  # one channel, a layer of its own in tev: depth.Z (the EXR name), others NAME.Y
            names.append(f"{name}.{'Z' if name == 'depth' else 'Y'}")
            planes.append(value[:, :, None])
        else:
            k = value.shape[2]
            names += [f"{name}.{c}" for c in ("RGB" if k == 3 else "RGBA" if k == 4 else map(str, range(k)))]
            planes.append(value)
    if len(planes) == 1:
        return names, image.array
    return names, np.ascontiguousarray(np.concatenate(planes, axis=2), dtype=np.float32)


class TevSink(Sink):
    """Stream the image to a running tev (https://github.com/Tom94/tev) as pbrt-v4's `--display-server` does.

    The image `name` is created in tev on the first update (channels R, G, B and the float AOVs, `tev_channels`)
    and its pixels replaced on each update after; the final image is always sent, and the next render to the same
    sink creates the image again (tev replaces an image of the same name). Connects on construction: a clear
    `LumosError` if `tevclient` is missing or nothing listens at `address`. If tev goes away during a render, a
    warning says so and the render goes on.
    """

    def __init__(self, address: str = TEV_ADDRESS, name: str = "lumos", interval: float | None = None):
        super().__init__(interval)
        self.host, self.port = parse_address(address)
        self.address = f"{self.host}:{self.port}"
        self.name = str(name)
        try:
            import tevclient
        except ImportError:
            raise LumosError("tev: the Python client is not installed: pip install 'lumos[tev]' "
                             "(or pip install tevclient)") from None
        self._ipc = tevclient.TevIpc(self.host, self.port)  # (`Ipc` in tevclient 1.0; the old name stays)
        try:
            self._ipc.__enter__()
        except ConnectionRefusedError:
            self._ipc.__exit__(None, None, None)
            raise LumosError(f"tev: nothing is listening at {self.address} (connection refused): start tev first "
                             f"(`tev &`), or give its address as HOST:PORT") from None
        except OSError as exc:
            self._ipc.__exit__(None, None, None)
            raise LumosError(f"tev: cannot connect to {self.address}: {exc.strerror or exc}") from None
        self._layout = None  # (width, height, channel names) of the image created in tev
        self._open = True

    def show(self, image: Image, final: bool) -> None:
        if not self._open:
            return
        names, pixels = tev_channels(image)
        layout = (image.width, image.height, tuple(names))
        try:
            if layout != self._layout:
                self._ipc.create_image(self.name, image.width, image.height, names)
                self._layout = layout
            self._ipc.update_image(self.name, pixels, names)
        except OSError as exc:
            self.close()
            warnings.warn(LumosWarning(f"tev at {self.address} stopped taking images "
                                       f"({exc.strerror or exc}); the render goes on without it"))
            return
        if final:
            self._layout = None

    def close(self) -> None:
        if self._open:
            self._open = False
            self._ipc.__exit__(None, None, None)


# --------------------------------------------------------------------------------------------------- Jupyter

def in_notebook() -> bool:
    """Whether this process is a Jupyter kernel (a notebook, JupyterLab, VS Code), not a terminal IPython."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    shell = ipython.get_ipython()
    return shell is not None and getattr(shell, "kernel", None) is not None


def caption(image: Image, final: bool, seconds: float) -> str:
    """The line under the notebook image: size, method, samples so far and time."""
    parts = [f"{image.width}×{image.height}"]
    if "method" in image.stats:
        parts.append(str(image.stats["method"]))
    if "spp" in image.stats:
        parts.append(f"{image.stats['spp']} spp")
    if not final and "passes" in image.stats:
        parts.append(f"pass {image.stats['passes']}")
    parts.append(f"{image.stats.get('total_s', seconds):.1f} s")
    return ("done · " if final else "rendering · ") + " · ".join(parts)


def png_bytes(image: Image, final: bool) -> bytes:
    """The PNG the notebook shows: the final image as `Image.to_png_bytes` writes it; those on the way with the
    fastest deflate (about 7 ms instead of 12–22 at 256×256, for a file 10% larger)."""
    if final:
        return image.to_png_bytes()
    import io

    from PIL import Image as PILImage

    buffer = io.BytesIO()
    PILImage.fromarray(tonemap.to_png8(image.array, image.exposure), mode="RGB").save(buffer, format="PNG",
                                                                                      compress_level=1)
    return buffer.getvalue()


class NotebookSink(Sink):
    """An image in the notebook's output that updates in place: an ipywidgets `Image` (PNG, after the image's
    exposure) with a caption line under it; without ipywidgets (or with `widget=False`), IPython display handles
    (`display_id`) updated the same way. Shown on the first update; the same view takes the next renders."""

    def __init__(self, interval: float | None = None, widget: bool | None = None):
        super().__init__(interval)
        if widget is None:
            import importlib.util

            widget = importlib.util.find_spec("ipywidgets") is not None
        self.widget = bool(widget)
        self._view = None  # (image widget, label widget) or (image handle, caption handle)
        self._started = None

    def show(self, image: Image, final: bool) -> None:
        from IPython.display import HTML, display
        from IPython.display import Image as PNG

        now = time.monotonic()
        if self._started is None:
            self._started = now
        png, text = png_bytes(image, final), caption(image, final, now - self._started)
        if final:
            self._started = None
        if self.widget:
            import ipywidgets

            if self._view is None:
                self._view = (ipywidgets.Image(value=png, format="png"), ipywidgets.Label(value=text))
                display(ipywidgets.VBox(list(self._view)))
            else:
                self._view[0].value = png
                self._view[1].value = text
        else:
            if self._view is None:
                self._view = (display(PNG(data=png), display_id=True),
                              display(HTML(f"<small>{text}</small>"), display_id=True))
            else:
                self._view[0].update(PNG(data=png))
                self._view[1].update(HTML(f"<small>{text}</small>"))


# ------------------------------------------------------------------------------------------------ render()

def open_sink(live: Any) -> tuple[Sink | None, bool]:
    """`render(live=...)`'s argument → (the sink to update, whether `render` made it and so closes it).

    True: a `NotebookSink` in Jupyter; elsewhere a warning and no sink. 'tev' or 'tev:HOST:PORT': a `TevSink`.
    A `Sink` as it is; any other object with `update` and `close` behind the throttle (`Throttled`). None or
    False: no sink."""
    if live is None or live is False:
        return None, False
    if live is True:
        if in_notebook():
            return NotebookSink(), True
        warnings.warn(LumosWarning("render(live=True): a live view needs Jupyter; rendering without one "
                                   "(live=lumos.live.TevSink() streams to tev)"), stacklevel=3)
        return None, False
    if isinstance(live, str):
        kind, _, address = live.partition(":")
        if kind == "tev":
            return TevSink(address or TEV_ADDRESS), True
        raise LumosError(f"render(live={live!r}): expected True, 'tev' or 'tev:HOST:PORT', or a sink object")
    if isinstance(live, Sink):
        return live, False
    if callable(getattr(live, "update", None)) and callable(getattr(live, "close", None)):
        return Throttled(live), False
    raise LumosError(f"render(live=...): expected True, 'tev[:HOST:PORT]' or an object with update(image, final) "
                     f"and close(), got {type(live).__name__}")


@contextlib.contextmanager
def close_on_error(sink: Sink | None, owned: bool):
    """Close `sink` if the block raises and `render` made it (`open_sink`); otherwise leave it open."""
    try:
        yield
    except BaseException:
        if owned and sink is not None:
            sink.close()
        raise
