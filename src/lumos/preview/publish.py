"""Frames and their delivery: what a session sends its subscribers, at most `MAX_FRAMES_PER_S` a second.

A `Frame` is one float image with how far its render got and how to show it; `Publisher` hands frames and
messages to the subscribers from a thread of its own. While a render refines, a frame that comes less than
1/MAX_FRAMES_PER_S after the last one sent waits, and a newer frame replaces it; an `urgent` frame (the first
after a change, the last of a render, a change of display) goes at once. So a fast render is never slowed by the
page, and the page never waits on the throttle to see what a change did.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

from .display import Display, encode_png, view_array

#: Frames a second sent while a render refines (urgent frames are not held back).
MAX_FRAMES_PER_S = 4.0


@dataclass
class Frame:
    """One image sent to the page: the float image, which render it belongs to and how far it got, and how to
    show it. `png()` encodes it (once, on the caller's thread: the server's, not the render's)."""

    image: object  # lumos.Image
    generation: int
    stage: str  # "quick" (a quarter of the size), "pass" (path: the samples so far), "final", "shown" (viewer)
    status: dict
    display: Display
    edited_at: float  # time.perf_counter() of the change that started this render
    seq: int = 0
    _png: Optional[bytes] = field(default=None, repr=False)

    @property
    def final(self) -> bool:
        return self.stage in ("final", "shown")

    def png(self) -> bytes:
        if self._png is None:
            self._png = encode_png(view_array(self.image, self.display))
        return self._png

    def meta(self) -> dict:
        """What the page reads beside the PNG."""
        return {"type": "frame", "seq": self.seq, "generation": self.generation, "stage": self.stage,
                "width": self.image.width, "height": self.image.height, "view": self.display.view,
                "status": self.status}


class Publisher:
    """The subscribers of a session and the thread that delivers frames to them."""

    def __init__(self):
        self._cond = threading.Condition()
        self._subscribers: list[Callable] = []
        self._pending: Optional[Frame] = None
        self._urgent = False
        self._next_send = 0.0
        self._closed = False
        self.last: Optional[Frame] = None  # the newest frame published (sent or waiting)
        self._thread = threading.Thread(target=self._loop, name="lumos-preview-publish", daemon=True)

    def start(self) -> None:
        if not self._thread.is_alive() and not self._closed:
            self._thread.start()

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=10.0)

    def subscribe(self, callback: Callable) -> Callable[[], None]:
        """Add `callback(event)`; it gets the last frame at once. Returns the unsubscribe function."""
        with self._cond:
            self._subscribers.append(callback)
            last = self.last
        if last is not None:
            callback(("frame", last))
        return lambda: self._unsubscribe(callback)

    def publish(self, frame: Frame, urgent: bool = False) -> None:
        """Send `frame` (replacing one still waiting, unless that one belongs to a newer render)."""
        with self._cond:
            if self._pending is not None and self._pending.generation > frame.generation:
                return
            self._pending, self.last = frame, frame
            self._urgent = urgent
            self._cond.notify_all()

    def broadcast(self, event) -> None:
        """Give `event` to every subscriber now (on the caller's thread); one that raises is dropped."""
        with self._cond:
            subscribers = list(self._subscribers)
        for callback in subscribers:
            try:
                callback(event)
            except Exception:
                self._unsubscribe(callback)

    def _unsubscribe(self, callback) -> None:
        with self._cond:
            if callback in self._subscribers:
                self._subscribers.remove(callback)

    def _loop(self) -> None:
        interval = 1.0 / MAX_FRAMES_PER_S
        while True:
            with self._cond:
                while not self._closed and self._pending is None:
                    self._cond.wait()
                if self._closed:
                    return
                wait = self._next_send - time.perf_counter()
                if wait > 0.0 and not self._urgent:
                    self._cond.wait(wait)  # a newer frame may replace it meanwhile
                    continue
                frame, self._pending = self._pending, None
                self._next_send = time.perf_counter() + interval
            self.broadcast(("frame", frame))
