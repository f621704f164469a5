"""The `animation:` block of a scene file and its curves: keyframes, interpolation and easing.

Part of the scene model (`lumos.scene.model` holds a Scene's `animation`); what the tracks animate, and the
scene at a time, are `lumos.scene.animation`'s. Pure Python and NumPy.

A track's keys are (time, value) pairs, in increasing time. Between keys k and k+1 (Δt = t₁ − t₀) the local
parameter s = (t − t₀)/Δt, shaped by the `ease` of key k+1 (the way *into* that key), gives

    step         v₀
    linear       v₀ + s·(v₁ − v₀)
    catmull-rom  the cubic Bézier with control points v₀, v₀ + m₀·Δt/3, v₁ − m₁·Δt/3, v₁, where m_k is the
                 slope at key k, (v_{k+1} − v_{k−1})/(t_{k+1} − t_{k−1}) (one-sided at the first and last key)
    bezier       the same curve with the slopes given per key (`tangent`, or `tangent_in` / `tangent_out`, in
                 value per second); a slope not given is Catmull–Rom's

At a key's time the value is the key's value exactly; before the first key and after the last it holds.
"""

from __future__ import annotations

import bisect
import math
from typing import Annotated, Any, Literal, Optional

import numpy as np
from pydantic import Field, model_validator

from .types import Direction, Finite, Positive, StrictModel, Vec3

INTERPOLATIONS = ("linear", "step", "catmull-rom", "bezier")
EASES = ("linear", "in", "out", "in-out")


class Key(StrictModel):
    """One keyframe: a `time` in seconds or a `frame` (time = frame / fps), one of them, and the `value` there."""

    time: Optional[Finite] = None
    frame: Optional[Finite] = None
    value: Any
    #: the way into this key (the segment from the previous one): linear, in (slow start), out (slow end), in-out
    ease: Literal["linear", "in", "out", "in-out"] = "linear"
    #: bezier: the slope at the key (value per second), both sides; or one side each
    tangent: Optional[Any] = None
    tangent_in: Optional[Any] = None
    tangent_out: Optional[Any] = None

    @model_validator(mode="after")
    def _check(self):
        if (self.time is None) == (self.frame is None):
            raise ValueError("give the key a time (in seconds) or a frame, one of them")
        if self.tangent is not None and (self.tangent_in is not None or self.tangent_out is not None):
            raise ValueError("give tangent (both sides) or tangent_in / tangent_out, not both")
        return self


class Orbit(StrictModel):
    """A 3-vector key (a position) turned about the line through `center` along `axis`: the keys' values are
    angles in degrees (counter-clockwise looking down the axis), the vector as the scene gives it is angle 0."""

    center: Vec3 = (0.0, 0.0, 0.0)
    axis: Direction = (0.0, 1.0, 0.0)


class Track(StrictModel):
    """What one animated key (`target`, a key path into the scene) does over time."""

    target: str
    interpolation: Literal["linear", "step", "catmull-rom", "bezier"] = "linear"
    orbit: Optional[Orbit] = None
    keys: Annotated[list[Key], Field(min_length=1)]


class Animation(StrictModel):
    """`fps`, the length (`frames`, or `duration` in seconds, or up to the last key), and the tracks."""

    fps: Positive = 24.0
    frames: Optional[Annotated[int, Field(ge=1)]] = None
    duration: Optional[Positive] = None
    #: sub-frames over an open shutter: N > 1 renders each frame as the mean of N renders of the scene at times
    #: spread over the shutter (`animate.render_at`), so every track blurs along its curve; 1: the chord of
    #: translate tracks only (`scene.animation.scene_at`)
    motion_samples: Annotated[int, Field(ge=1, le=256)] = 1
    tracks: list[Track] = Field(default_factory=list)

    @model_validator(mode="after")
    def _check(self):
        if self.frames is not None and self.duration is not None:
            raise ValueError("give frames (a count) or duration (seconds), not both")
        return self

    def key_time(self, key: Key) -> float:
        """A key's time in seconds."""
        return float(key.time) if key.time is not None else key.frame / self.fps

    def frame_count(self) -> int:
        """`frames`; else round(duration · fps); else up to and including the frame of the last key."""
        if self.frames is not None:
            return self.frames
        if self.duration is not None:
            return max(1, round(self.duration * self.fps))
        last = max((self.key_time(k) for track in self.tracks for k in track.keys), default=0.0)
        return max(1, math.floor(last * self.fps + 1e-9) + 1)

    def frame_time(self, frame: int) -> float:
        """The time of frame `frame`: frame / fps."""
        return frame / self.fps


# --------------------------------------------------------------------------------------------------- curves


def ease(kind: str, s: float) -> float:
    """The easing curves, each from 0 at s = 0 to 1 at s = 1: linear s; in s²; out s(2 − s); in-out s²(3 − 2s)."""
    if kind == "in":
        return s * s
    if kind == "out":
        return s * (2.0 - s)
    if kind == "in-out":
        return s * s * (3.0 - 2.0 * s)
    return s


def catmull_rom_slopes(times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(n, d) slopes (value per second) at the keys: central differences over the neighbouring keys, one-sided
    at the ends; 0 for a single key."""
    n = len(times)
    slopes = np.zeros_like(values)
    if n < 2:
        return slopes
    slopes[0] = (values[1] - values[0]) / (times[1] - times[0])
    slopes[-1] = (values[-1] - values[-2]) / (times[-1] - times[-2])
    if n > 2:
        slopes[1:-1] = (values[2:] - values[:-2]) / (times[2:] - times[:-2])[:, None]
    return slopes


class Curve:
    """A track's keys made ready to evaluate: times (n,) increasing, values (n, d), eases (n,), and for the
    cubic interpolations the slopes into (`slope_in`) and out of (`slope_out`) each key."""

    def __init__(self, times, values, interpolation: str = "linear", eases=None, slope_in=None, slope_out=None):
        self.times = np.asarray(times, dtype=np.float64)
        self.values = np.asarray(values, dtype=np.float64).reshape(len(self.times), -1)
        self.interpolation = interpolation
        self.eases = list(eases) if eases is not None else ["linear"] * len(self.times)
        if interpolation in ("catmull-rom", "bezier"):
            auto = catmull_rom_slopes(self.times, self.values)
            self.slope_in = auto if slope_in is None else _filled(slope_in, auto)
            self.slope_out = auto if slope_out is None else _filled(slope_out, auto)
        self._t = self.times.tolist()

    def __call__(self, t: float) -> np.ndarray:
        """The value (d,) at time `t` (a copy of a key's value at its time, bit for bit)."""
        times, values = self._t, self.values
        if t <= times[0]:
            return values[0].copy()
        if t >= times[-1]:
            return values[-1].copy()
        k = bisect.bisect_right(times, t) - 1
        if t == times[k]:
            return values[k].copy()
        t0, t1 = times[k], times[k + 1]
        s = ease(self.eases[k + 1], (t - t0) / (t1 - t0))
        v0, v1 = values[k], values[k + 1]
        if self.interpolation == "step":
            return v0.copy()
        if self.interpolation == "linear":
            return v0 + s * (v1 - v0)
        dt = t1 - t0
        p1 = v0 + self.slope_out[k] * (dt / 3.0)
        p2 = v1 - self.slope_in[k + 1] * (dt / 3.0)
        r = 1.0 - s
        return (r * r * r) * v0 + (3.0 * r * r * s) * p1 + (3.0 * r * s * s) * p2 + (s * s * s) * v1


def _filled(given: list, auto: np.ndarray) -> np.ndarray:
    """Per-key slopes: the given ones (None where a key gives none) over the automatic ones."""
    out = auto.copy()
    for k, slope in enumerate(given):
        if slope is not None:
            out[k] = np.asarray(slope, dtype=np.float64).reshape(-1)
    return out


def rotate_about(point: np.ndarray, center, axis, degrees: float) -> np.ndarray:
    """`point` turned `degrees` about the line through `center` along `axis` (right-handed: counter-clockwise
    looking down the axis towards its origin); the point itself, bit for bit, at 0 degrees."""
    point = np.asarray(point, dtype=np.float64)
    if degrees == 0.0:
        return point.copy()
    c = np.asarray(center, dtype=np.float64)
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    v = point - c
    a = math.radians(degrees)
    cos, sin = math.cos(a), math.sin(a)
    return c + v * cos + np.cross(k, v) * sin + k * (np.dot(k, v) * (1.0 - cos))
