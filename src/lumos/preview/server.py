"""The preview's web server: the page (`static/`) and one WebSocket per open page, over a `Session`.

    server = PreviewServer(Session.from_file("scene.yaml"))      # 127.0.0.1, a free port, a random token
    print(server.url)                                             # http://127.0.0.1:PORT/?token=...
    server.serve()                                                # until Ctrl-C (or server.start(): a thread)

Security: it listens on 127.0.0.1 unless told otherwise; every HTTP request and the WebSocket must carry the
token of the printed URL (`?token=`), else 403; the page may only write a new file in the scene's folder (the
session checks); every message from the page is checked, and a bad one gets an error message back on the
socket, never an exception out of the server or the render thread.

The protocol, JSON text messages (and binary ones for images):
    page -> server   {"type": "camera" | "light" | "material" | "settings" | "display" | "save" | "state"
                      | "explain", "id": n, ...}   (see `Session.handle`, `Session.explain`)
    server -> page   {"type": "state", ...} the controls; {"type": "ack", "id", "generation"} for each change;
                     {"type": "frame", ...} followed by one binary message, the PNG; {"type": "explain", ...};
                     {"type": "saved", "path"}; {"type": "busy", "generation", "method"} when a render starts;
                     {"type": "error", "message", "id"}; {"type": "note", "message"}
"""

from __future__ import annotations

import asyncio
import json
import secrets
import socket
import sys
import threading
import time
from collections import deque
from importlib import resources
from typing import Optional
from urllib.parse import parse_qs

from ..errors import LumosError
from .session import Session

#: The page's files: name -> content type. Nothing else is served.
STATIC = {"index.html": "text/html; charset=utf-8", "app.js": "text/javascript; charset=utf-8",
          "style.css": "text/css; charset=utf-8"}
#: Hosts that only this machine can reach: any other `--host` is warned about.
LOOPBACK = ("127.0.0.1", "localhost", "::1")
#: The largest message the page may send (bytes); the page's are well under 1 KB.
MAX_MESSAGE = 1 << 16
HEADERS = {"Cache-Control": "no-store", "X-Content-Type-Options": "nosniff", "Referrer-Policy": "no-referrer",
           "X-Frame-Options": "DENY",
           "Content-Security-Policy": "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; "
                                      "style-src 'self'; script-src 'self'; frame-ancestors 'none'"}


def build_app(session: Session, token: str):
    """The Starlette app: `/` (the page), `/static/<file>`, `/ws` (the socket), all behind the token."""
    from starlette.applications import Starlette
    from starlette.responses import Response
    from starlette.routing import Route, WebSocketRoute

    def page(request):
        html = _static("index.html").replace("{{TOKEN}}", token)
        return Response(html, media_type=STATIC["index.html"], headers=HEADERS)

    def static(request):
        name = request.path_params["name"]
        if name not in STATIC or name == "index.html":
            return Response("not found", status_code=404, headers=HEADERS)
        return Response(_static(name), media_type=STATIC[name], headers=HEADERS)

    async def ws(websocket):
        await _socket(websocket, session)

    app = Starlette(routes=[Route("/", page), Route("/static/{name}", static), WebSocketRoute("/ws", ws)])
    return _TokenGate(app, token)


class _TokenGate:
    """ASGI middleware: a request or socket without the right `?token=` gets 403 and reaches nothing."""

    def __init__(self, app, token: str):
        self.app, self.token = app, token

    async def __call__(self, scope, receive, send):
        if scope["type"] not in ("http", "websocket"):
            return await self.app(scope, receive, send)
        given = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [""])[0]
        if secrets.compare_digest(given.encode(), self.token.encode()):
            return await self.app(scope, receive, send)
        body = b"forbidden: open the URL lumos printed, with its token\n"
        headers = [(b"content-type", b"text/plain; charset=utf-8"), (b"content-length", str(len(body)).encode())]
        if scope["type"] == "http":
            await send({"type": "http.response.start", "status": 403, "headers": headers})
            await send({"type": "http.response.body", "body": body})
        elif "websocket.http.response" in scope.get("extensions", {}):
            await send({"type": "websocket.http.response.start", "status": 403, "headers": headers})
            await send({"type": "websocket.http.response.body", "body": body})
        else:  # closed before the handshake: the server answers 403
            await send({"type": "websocket.close", "code": 1008})


class _Outbox:
    """What one socket has to send: messages in order, and only the newest frame (an older one not yet sent is
    dropped, so a slow page never slows the render or piles up frames)."""

    def __init__(self):
        self.messages: deque = deque()
        self.frame = None
        self.ready = asyncio.Event()

    def put(self, event) -> None:
        kind, payload = event
        if kind == "frame":
            self.frame = payload
        elif kind in ("state", "busy"):
            self.messages.append(payload)
        elif kind in ("error", "note"):
            self.messages.append({"type": kind, "message": payload})
        else:  # "reply": a dict for this page
            self.messages.append(payload)
        self.ready.set()


async def _socket(websocket, session: Session) -> None:
    from starlette.concurrency import run_in_threadpool
    from starlette.websockets import WebSocketDisconnect

    await websocket.accept()
    loop = asyncio.get_running_loop()
    outbox = _Outbox()
    outbox.put(("state", session.state()))

    def deliver(event):  # called on the session's threads
        loop.call_soon_threadsafe(outbox.put, event)

    unsubscribe = session.subscribe(deliver)
    sender = asyncio.create_task(_send_loop(websocket, outbox))
    try:
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                break
            text = message.get("text")
            if text is None:
                outbox.put(("error", "binary messages are not understood; send JSON text"))
                continue
            await _handle(text, session, outbox, deliver, run_in_threadpool)
    except WebSocketDisconnect:
        pass
    finally:
        unsubscribe()
        sender.cancel()


async def _handle(text: str, session: Session, outbox: _Outbox, deliver, run_in_threadpool) -> None:
    """One message from the page: its reply, or an error message, goes to the outbox; nothing raises."""
    ident = None
    try:
        try:
            message = json.loads(text)
        except (ValueError, RecursionError) as exc:
            raise LumosError(f"malformed message (not JSON: {str(exc)[:80]})") from None
        if not isinstance(message, dict):
            raise LumosError(f"malformed message: expected a JSON object with a 'type', got {type(message).__name__}")
        ident = message.get("id") if isinstance(message.get("id"), (int, str)) else None
        if message.get("type") == "explain":
            reply = lambda result: deliver(("reply", dict(result, id=ident)))  # noqa: E731
            session.explain(message.get("x"), message.get("y"), reply)
            return
        reply = await run_in_threadpool(session.handle, message)
        if reply is not None:
            outbox.put(("reply", reply))
    except LumosError as exc:
        outbox.put(("reply", {"type": "error", "message": " ".join(str(exc).split()), "id": ident}))
    except Exception as exc:  # a bug, not the page's fault: said on the page, and the server goes on
        outbox.put(("reply", {"type": "error", "id": ident,
                              "message": f"internal error: {type(exc).__name__}: {' '.join(str(exc).split())}"}))


async def _send_loop(websocket, outbox: _Outbox) -> None:
    from starlette.concurrency import run_in_threadpool

    try:
        while True:
            await outbox.ready.wait()
            outbox.ready.clear()
            while outbox.messages:
                await websocket.send_text(json.dumps(outbox.messages.popleft(), default=_plain))
            frame, outbox.frame = outbox.frame, None
            if frame is not None:
                png = await run_in_threadpool(frame.png)  # off the event loop: a few ms a frame
                meta = frame.meta()
                meta["sent_latency_s"] = time.perf_counter() - frame.edited_at
                await websocket.send_text(json.dumps(meta, default=_plain))
                await websocket.send_bytes(png)
    except Exception:  # the page went away
        return


def _plain(value):
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def _static(name: str) -> str:
    return resources.files("lumos.preview").joinpath("static", name).read_text(encoding="utf-8")


class PreviewServer:
    """A `Session` served over HTTP: bound at once (so `url` is known), served by `serve()` (blocking, ends on
    Ctrl-C) or `start()` (a thread; `stop()` ends it)."""

    def __init__(self, session: Session, host: str = "127.0.0.1", port: int = 0, token: Optional[str] = None):
        try:
            import uvicorn  # noqa: F401
            import starlette  # noqa: F401
        except ImportError:
            raise LumosError('the preview needs Starlette and uvicorn: pip install "lumos[preview]"') from None
        self.session = session
        self.host = host
        self.token = token or secrets.token_urlsafe(24)
        self.app = build_app(session, self.token)
        self._socket = _bind(host, port)
        self.port = self._socket.getsockname()[1]
        self._server = None
        self._thread: Optional[threading.Thread] = None

    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("", "0.0.0.0") else self.host
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{self.port}/?token={self.token}"

    def _make_server(self):
        import uvicorn

        config = uvicorn.Config(self.app, log_level="warning", lifespan="off", ws_max_size=MAX_MESSAGE,
                                ws_ping_interval=20.0, access_log=False)
        self._server = uvicorn.Server(config)
        return self._server

    def serve(self) -> None:
        """Serve until Ctrl-C (uvicorn stops on SIGINT and SIGTERM)."""
        self._make_server().run(sockets=[self._socket])

    def start(self, timeout: float = 10.0) -> "PreviewServer":
        """Serve in a daemon thread; returns once the server accepts connections."""
        server = self._make_server()
        self._thread = threading.Thread(target=server.run, kwargs={"sockets": [self._socket]},
                                        name="lumos-preview-server", daemon=True)
        self._thread.start()
        deadline = time.perf_counter() + timeout
        while not server.started:
            if not self._thread.is_alive() or time.perf_counter() > deadline:
                raise LumosError("the preview server did not start")
            time.sleep(0.01)
        return self

    def stop(self) -> None:
        if self._server is not None:
            self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout=10.0)
        self._socket.close()


def _bind(host: str, port: int) -> socket.socket:
    """A listening socket on (host, port); port 0: a free one."""
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise LumosError(f"--port: expected 0 (a free port) to 65535, got {port!r}")
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        sock = socket.socket(family, kind, proto)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(64)
    except OSError as exc:
        raise LumosError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    sock.setblocking(False)
    return sock


def warn_if_exposed(host: str) -> None:
    """Say so when the preview listens where other machines can reach it."""
    if host not in LOOPBACK:
        print(f"lumos: warning: listening on {host}: other machines can reach the preview; the token in the URL is "
              "all that keeps them out (prefer 127.0.0.1 and an SSH tunnel)", file=sys.stderr)
