"""The preview server through Starlette's TestClient: the token guards the page, its files and the socket; a
malformed or out-of-range message gets an error back and the server goes on with the next one."""

from __future__ import annotations

import json
import time
import warnings

import pytest

pytest.importorskip("starlette")
pytest.importorskip("httpx")

with warnings.catch_warnings():  # Starlette >= 1.10 asks for httpx2 and still takes httpx
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient, WebSocketDenialResponse
from starlette.websockets import WebSocketDisconnect  # noqa: E402

from lumos.preview.server import build_app  # noqa: E402
from lumos.preview.session import Session  # noqa: E402


TOKEN = "test-token-0123456789"


@pytest.fixture
def client(scene_file):
    session = Session.from_file(scene_file)
    with TestClient(build_app(session, TOKEN)) as client:
        client.session = session
        yield client
    session.close()


def receive(ws, kind, timeout=30.0):
    """The next JSON message of type `kind` (others, and the PNGs after frames, skipped); for a frame, (meta,
    png)."""
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        message = ws.receive()
        if message.get("text") is None:
            continue
        data = json.loads(message["text"])
        if data["type"] == kind:
            if kind == "frame":
                return data, ws.receive()["bytes"]
            return data
    raise AssertionError(f"no {kind} message")


def test_the_page_and_its_files_need_the_token(client):
    for url in ("/", "/?token=wrong", "/static/app.js", "/static/style.css?token=nope", "/ws", "/nothing"):
        response = client.get(url)
        assert response.status_code == 403, url
        assert TOKEN not in response.text
    page = client.get(f"/?token={TOKEN}")
    assert page.status_code == 200 and f"static/app.js?token={TOKEN}" in page.text
    assert page.headers["cache-control"] == "no-store" and "default-src 'self'" in page.headers[
        "content-security-policy"]
    assert "connect(" in client.get(f"/static/app.js?token={TOKEN}").text
    assert client.get(f"/static/session.py?token={TOKEN}").status_code == 404
    assert client.get(f"/static/..%2Fsession.py?token={TOKEN}").status_code == 404


def test_the_socket_needs_the_token(client):
    for url in ("/ws", "/ws?token=wrong", f"/ws?token={TOKEN}x"):
        with pytest.raises((WebSocketDenialResponse, WebSocketDisconnect)) as caught:
            with client.websocket_connect(url):
                pass
        if isinstance(caught.value, WebSocketDenialResponse):
            assert caught.value.status_code == 403


def test_state_then_frames(client):
    with client.websocket_connect(f"/ws?token={TOKEN}") as ws:
        state = receive(ws, "state")
        assert state["scene"] == "ball.yaml" and state["editable"]
        assert [m["name"] for m in state["scene_edit"]["materials"]] == ["red", "floor"]
        meta, png = receive(ws, "frame")
        assert png[:4] == b"\x89PNG" and meta["status"]["method"] == "raycast"


def test_bad_messages_get_an_error_and_the_server_goes_on(client):
    with client.websocket_connect(f"/ws?token={TOKEN}") as ws:
        receive(ws, "state")
        ws.send_text("{not json")
        assert "malformed message" in receive(ws, "error")["message"]
        ws.send_text("[1, 2, 3]")
        assert "JSON object" in receive(ws, "error")["message"]
        ws.send_bytes(b"\x00\x01")
        assert "binary" in receive(ws, "error")["message"]
        ws.send_text(json.dumps({"type": "material", "name": "red", "key": "kd", "value": 1e9, "id": 7}))
        error = receive(ws, "error")
        assert error["id"] == 7 and "out of range" in error["message"]
        ws.send_text(json.dumps({"type": "material", "name": "red", "key": "shininess", "value": {"$gt": 1}}))
        assert "expected a number" in receive(ws, "error")["message"]
        ws.send_text("[" * 100_000 + "]" * 100_000)  # deeper than the JSON parser goes
        assert "malformed" in receive(ws, "error")["message"]
        ws.send_text(json.dumps({"type": "save", "name": "../../escape.yaml"}))
        assert "not a file in" in receive(ws, "error")["message"]
        # and the next valid message is served
        ws.send_text(json.dumps({"type": "material", "name": "red", "key": "kd", "value": 0.2, "id": 8}))
        ack = receive(ws, "ack")
        assert ack["id"] == 8
        meta, png = receive(ws, "frame")
        while meta["generation"] < ack["generation"] or meta["stage"] != "final":
            meta, png = receive(ws, "frame")
        assert png[:4] == b"\x89PNG"


def test_explain_and_save_over_the_socket(client, scene_file):
    with client.websocket_connect(f"/ws?token={TOKEN}") as ws:
        receive(ws, "state")
        ws.send_text(json.dumps({"type": "explain", "x": 32, "y": 30, "id": 3}))
        reply = receive(ws, "explain")
        assert reply["id"] == 3 and reply["x"] == 32 and "hit" in reply["text"]
        ws.send_text(json.dumps({"type": "explain", "x": 32}))
        assert "whole number" in receive(ws, "error")["message"]
        ws.send_text(json.dumps({"type": "save", "name": "saved-here"}))
        assert receive(ws, "saved")["path"] == str(scene_file.with_name("saved-here.yaml").resolve())
        assert scene_file.with_name("saved-here.yaml").exists()
