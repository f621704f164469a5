"""TevSink against a small fake tev: a TCP server on a free port that reads tev's IPC packets as tevclient sends
them (a little-endian uint32 length that counts the whole packet, then a type byte) and records the images
created and the tiles of pixels that arrive."""

from __future__ import annotations

import socket
import struct
import threading
import time

import numpy as np
import pytest
import yaml
from helpers import TINY

import lumos
from lumos.errors import LumosError, LumosWarning
from lumos.live import TevSink, parse_address, tev_channels

pytest.importorskip("tevclient")

#: tev's IpcPacket::EType, the ones tevclient sends (tevclient/packet.py IpcPacketType).
CREATE_IMAGE, UPDATE_IMAGE, CLOSE_IMAGE = 4, 6, 2


class Reader:
    """Fields of one packet's body, in order."""

    def __init__(self, body: bytes):
        self.body, self.at = body, 0

    def take(self, fmt):
        values = struct.unpack_from(fmt, self.body, self.at)
        self.at += struct.calcsize(fmt)
        return values[0] if len(values) == 1 else values

    def string(self):
        end = self.body.index(b"\0", self.at)
        text = self.body[self.at:end].decode()
        self.at = end + 1
        return text


class FakeTev:
    """A fake tev listening on 127.0.0.1:<free port>. `created`: (name, width, height, channels) per CreateImage;
    `tiles`: (name, channels, x, y, tile float32 (h, w, c)) per UpdateImage; `images[name]`: the pixels so far."""

    def __init__(self):
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.address = f"127.0.0.1:{self.port}"
        self.created, self.tiles, self.images, self.packets, self.errors = [], [], {}, 0, []
        self.lock = threading.Lock()
        self.connections = []
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self):
        while True:
            try:
                conn, _ = self.server.accept()
            except OSError:  # closed
                return
            threading.Thread(target=self.read, args=(conn,), daemon=True).start()

    def drop(self):
        """Close the connections, as tev does when it quits."""
        for conn in self.connections:
            conn.shutdown(socket.SHUT_RDWR)
            conn.close()

    def read(self, conn):
        self.connections.append(conn)
        with conn:
            buffer = b""
            while True:
                try:
                    chunk = conn.recv(1 << 16)
                except OSError:  # dropped
                    return
                if not chunk:
                    return
                buffer += chunk
                while len(buffer) >= 4:
                    (length,) = struct.unpack_from("<I", buffer)
                    if len(buffer) < length:
                        break
                    self.packet(buffer[4:length])
                    buffer = buffer[length:]

    def packet(self, body):
        try:
            self.parse(body)
        except Exception as exc:  # seen by wait_for, in the test's thread
            self.errors.append(exc)

    def parse(self, body):
        r = Reader(body)
        kind = r.take("<b")
        with self.lock:
            self.packets += 1
            if kind == CREATE_IMAGE:
                r.take("<b")  # grab focus
                name = r.string()
                width, height, n = r.take("<i"), r.take("<i"), r.take("<i")
                channels = [r.string() for _ in range(n)]
                self.created.append((name, width, height, channels))
                self.images[name] = np.full((height, width, n), np.nan, np.float32)
            elif kind == UPDATE_IMAGE:
                r.take("<b")
                name = r.string()
                n = r.take("<i")
                channels = [r.string() for _ in range(n)]
                x, y, w, h = (r.take("<i") for _ in range(4))
                offsets = [r.take("<q") for _ in range(n)]
                strides = [r.take("<q") for _ in range(n)]
                assert offsets == list(range(n)) and strides == [n] * n  # interleaved, as tevclient sends
                tile = np.frombuffer(body, "<f4", count=w * h * n, offset=r.at).reshape(h, w, n)
                assert r.at + tile.nbytes == len(body)
                self.tiles.append((name, channels, x, y, tile))
                order = [self.created[-1][3].index(c) for c in channels]
                self.images[name][y:y + h, x:x + w, order] = tile
            else:
                raise AssertionError(f"unexpected packet type {kind}")

    def wait_for(self, packets, timeout=10.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.errors:
                raise self.errors[0]
            with self.lock:
                if self.packets >= packets:
                    return
            time.sleep(0.01)
        raise AssertionError(f"fake tev: {self.packets} packets, expected {packets}")

    def close(self):
        self.server.close()


@pytest.fixture
def tev():
    fake = FakeTev()
    yield fake
    fake.close()


def tiny(**render):
    scene = yaml.safe_load(TINY)
    scene["render"].update(render)
    return scene


def tiles_per_update(width, height):
    return -(-width // 128) * -(-height // 128)


def test_the_image_and_its_float_aovs_stream_to_tev(tev, monkeypatch):
    from lumos.methods import path as path_method

    monkeypatch.setattr(path_method, "PASS_SECONDS", 1e-9)  # a pass per sample
    with TevSink(tev.address, name="tiny", interval=0.0) as sink:
        img = lumos.render(tiny(method="path", spp=4, seed=2), live=sink,
                           aov=["albedo", "normal", "depth", "object_id"])
        updates = 4  # passes 1, 2, 3 and the final image
        tev.wait_for(1 + updates * tiles_per_update(32, 24))
    channels = ["R", "G", "B", "albedo.R", "albedo.G", "albedo.B", "normal.R", "normal.G", "normal.B", "depth.Z"]
    assert tev.created == [("tiny", 32, 24, channels)]  # object_id (int32) is not sent
    assert [t[0] for t in tev.tiles] == ["tiny"] * updates
    assert all(t[1] == channels and t[4].shape == (24, 32, 10) for t in tev.tiles)
    last = tev.images["tiny"]
    np.testing.assert_array_equal(last[:, :, :3], img.array)  # the final update is the returned image's radiance
    np.testing.assert_array_equal(last[:, :, 3:6], img.aovs["albedo"])
    np.testing.assert_array_equal(last[:, :, 9], img.aovs["depth"])
    assert not np.array_equal(tev.tiles[0][4][:, :, :3], img.array)  # the first pass was an image of 1 spp


def test_a_large_image_arrives_in_tiles_and_a_second_render_creates_it_again(tev):
    sink = TevSink(tev.address)
    first = lumos.render(tiny(method="raycast", width=200, height=150), live=sink)
    second = lumos.render(tiny(method="raycast", width=40, height=30), live=sink)
    sink.close()
    tev.wait_for(1 + 4 + 1 + 1)  # 200×150 goes as four 128×128 tiles or parts of them
    assert tev.created == [("lumos", 200, 150, ["R", "G", "B"]), ("lumos", 40, 30, ["R", "G", "B"])]
    assert [(x, y, t.shape[:2]) for _, _, x, y, t in tev.tiles[:4]] == [
        (0, 0, (128, 128)), (128, 0, (128, 72)), (0, 128, (22, 128)), (128, 128, (22, 72))]
    np.testing.assert_array_equal(tev.images["lumos"], second.array)
    assert first.array.shape == (150, 200, 3)


def test_live_tev_string_connects_and_closes(tev):
    img = lumos.render(tiny(method="raycast"), live=f"tev:{tev.address}")
    tev.wait_for(2)
    np.testing.assert_array_equal(tev.images["lumos"], img.array)


def test_nothing_listening_is_a_one_line_error_naming_the_address():
    with socket.create_server(("127.0.0.1", 0)) as s:
        port = s.getsockname()[1]  # free once closed
    with pytest.raises(LumosError, match=rf"nothing is listening at 127\.0\.0\.1:{port} \(connection refused\)") as e:
        TevSink(f"127.0.0.1:{port}")
    assert "\n" not in str(e.value)


def test_tevclient_missing_says_what_to_install(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "tevclient", None)
    with pytest.raises(LumosError, match=r"pip install 'lumos\[tev\]'"):
        TevSink()


def test_tev_going_away_warns_and_the_render_goes_on(tev):
    sink = TevSink(tev.address, interval=0.0)
    sink.update(lumos.Image(np.zeros((8, 8, 3), np.float32)))
    tev.wait_for(2)
    tev.drop()  # tev quits: the sends after fail (the first may still reach the socket's buffer)
    with pytest.warns(LumosWarning, match=rf"tev at {tev.address} stopped taking images.*render goes on") as record:
        for _ in range(20):
            sink.update(lumos.Image(np.ones((8, 8, 3), np.float32)), final=True)
            time.sleep(0.01)
    assert len(record) == 1  # said once; the updates after are dropped quietly
    sink.close()


@pytest.mark.parametrize("text, expected", [
    ("127.0.0.1:14158", ("127.0.0.1", 14158)), ("localhost", ("localhost", 14158)), (":9000", ("127.0.0.1", 9000)),
    ("", ("127.0.0.1", 14158)), ("[::1]:7000", ("::1", 7000)), ("example.org:1", ("example.org", 1)),
])
def test_addresses(text, expected):
    assert parse_address(text) == expected


@pytest.mark.parametrize("text", ["host:port", "host:0", "host:70000"])
def test_bad_addresses(text):
    with pytest.raises(LumosError, match="tev address"):
        parse_address(text)


def test_channels_follow_the_aovs_layout():
    img = lumos.Image(np.zeros((2, 3, 3), np.float32), aovs={
        "variance": np.ones((2, 3, 3), np.float32), "samples": np.ones((2, 3), np.int32),
        "depth": np.full((2, 3), np.inf, np.float32)})
    names, pixels = tev_channels(img)
    assert names == ["R", "G", "B", "variance.R", "variance.G", "variance.B", "depth.Z"]
    assert pixels.shape == (2, 3, 7) and pixels.dtype == np.float32 and np.isinf(pixels[:, :, 6]).all()
