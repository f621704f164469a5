"""Where `lumos render ... --preview [TARGET]` shows the render as it refines.

    browser               the preview page on 127.0.0.1, a free port (the default)
    browser:PORT          ... on that port;  browser:HOST:PORT  on that host (warned about unless loopback)
    tev                   a running tev viewer at 127.0.0.1:14158 (`lumos.live.TevSink`)
    tev:HOST:PORT         ... at that address (or tev:HOST, tev::PORT)

A target gets each of path's passes (`on_pass`) and the finished image (`done`); `finish()` is called once the
image is written: the page keeps being served until Ctrl-C (the image stays there to explore: exposure, tone
map, AOVs, explain), tev's connection is closed.
"""

from __future__ import annotations

import sys
import threading
from typing import Optional

from ..errors import LumosError

def parse_target(spec: str) -> tuple[str, Optional[str], Optional[int]]:
    """`--preview` TARGET -> ("browser", host or None, port or None) or ("tev", address or None, None); the tev
    address is read by `lumos.live` (HOST:PORT, HOST, :PORT). A bad one is a one-line `LumosError`."""
    kind, _, rest = spec.partition(":")
    if kind == "tev":
        return "tev", rest or None, None
    if kind == "browser":
        if not rest:
            return "browser", None, None
        host, _, port = rest.rpartition(":")
        if not port.isdigit() or not 0 <= int(port) < 65536:
            raise LumosError(f"--preview {spec}: expected browser, browser:PORT or browser:HOST:PORT")
        return "browser", host or None, int(port)
    raise LumosError(f"--preview {spec}: expected browser (the preview page, the default), browser:PORT, "
                     "browser:HOST:PORT, tev or tev:HOST:PORT (put SCENE before --preview)")


def open_target(spec: str, scene, cfg, name: str, quiet: bool = False):
    """The target `spec` (`parse_target`) for a render of `scene` with settings `cfg`, opened and ready."""
    kind, host, port = parse_target(spec)
    if kind == "tev":
        return TevTarget(host, name)
    return BrowserTarget(scene, cfg, name, host or "127.0.0.1", port or 0, quiet)


class BrowserTarget:
    """The preview page, showing a render made by the caller (a viewer session)."""

    def __init__(self, scene, cfg, name: str, host: str, port: int, quiet: bool):
        from .server import PreviewServer, warn_if_exposed
        from .session import Session

        self.session = Session.viewer(scene, cfg, path=name)
        self.server = PreviewServer(self.session, host, port).start()
        warn_if_exposed(host)
        print(f"lumos: preview at {self.server.url}", file=sys.stderr, flush=True)
        self.quiet = quiet

    def on_pass(self, image) -> None:
        self.session.show(image)

    def done(self, image) -> None:
        self.session.show(image, final=True)

    def finish(self) -> None:
        print(f"lumos: the preview stays at {self.server.url} until Ctrl-C", file=sys.stderr, flush=True)
        try:
            wait_for_ctrl_c()
        except KeyboardInterrupt:
            pass
        finally:
            self.close()
        print("lumos: preview stopped", file=sys.stderr)

    def close(self) -> None:
        self.server.stop()
        self.session.close()


class TevTarget:
    """A running tev, through `lumos.live.TevSink`."""

    def __init__(self, address: Optional[str], name: str):
        from ..live import TevSink

        self.sink = TevSink(name=name) if address is None else TevSink(address, name=name)

    def on_pass(self, image) -> None:
        self.sink.update(image, False)

    def done(self, image) -> None:
        self.sink.update(image, True)

    def finish(self) -> None:
        self.close()

    def close(self) -> None:
        self.sink.close()


def wait_for_ctrl_c() -> None:
    """Block until Ctrl-C (KeyboardInterrupt); the tests replace it."""
    stop = threading.Event()
    while not stop.wait(0.5):
        pass
