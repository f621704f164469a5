"""The values of Mitsuba 3's scene XML: numbers, vectors, and the transform operations, as Mitsuba builds them.

    m = transform_op("rotate", {"y": "1", "angle": "30"}, where)      # a 4×4 float64 matrix
    look_at(origin, target, up)                                        # Mitsuba's Transform::look_at

Errors are LumosErrors `<file>:<line>: <what>` made by `Where.error`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from ..errors import LumosError

TRANSFORM_OPS = {"translate", "rotate", "scale", "matrix", "lookat"}
#: a number as Mitsuba's parser takes it (no NaN, no infinity, no digit separators)
NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
#: the separators of lists of numbers: commas and white space
SPLIT = re.compile(r"[,\s]+")


@dataclass(frozen=True)
class Where:
    """Where an element is: its file and line, and `top`, the line in the main file (that of the `<include>`
    an element of an included file came through), which is what lumos's own messages point at."""

    file: Path
    line: int
    top: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"

    def error(self, what: str) -> LumosError:
        return LumosError(f"{self}: {what}")


def required(attrs: dict, key: str, tag: str, where: Where) -> str:
    if key not in attrs:
        raise where.error(f"<{tag}> needs a {key} attribute")
    return attrs[key]


def number(text: str, where: Where) -> float:
    text = text.strip()
    if not NUMBER.fullmatch(text):
        raise where.error(f"'{text[:40]}' is not a number")
    value = float(text)
    if not math.isfinite(value):
        raise where.error(f"'{text[:40]}' is too large a number")
    return value


def numbers(text: str, where: Where, what: str) -> list[float]:
    tokens = [t for t in SPLIT.split(text.strip()) if t]
    if not tokens:
        raise where.error(f"{what}: no numbers in '{text}'")
    return [number(t, where) for t in tokens]


def xyz(attrs: dict, where: Where, default: float, tag: str) -> np.ndarray:
    """x/y/z attributes (missing ones `default`), or `value` with one number (all three) or three."""
    if "value" in attrs:
        if any(k in attrs for k in "xyz"):
            raise where.error(f"<{tag}>: give value or x/y/z, not both")
        values = numbers(attrs["value"], where, f"<{tag}>")
        if len(values) not in (1, 3):
            raise where.error(f"<{tag}>: value takes one or three numbers, got {len(values)}")
        return np.array(values * 3 if len(values) == 1 else values, np.float64)
    return np.array([number(attrs[k], where) if k in attrs else default for k in "xyz"], np.float64)


def transform_op(tag: str, attrs: dict, where: Where) -> np.ndarray:
    """The 4×4 matrix of one transform operation, as Mitsuba's Transform builds it (angles in degrees)."""
    m = np.eye(4)
    if tag == "translate":
        m[:3, 3] = xyz(attrs, where, 0.0, tag)
    elif tag == "scale":
        m[:3, :3] = np.diag(xyz(attrs, where, 1.0, tag))
    elif tag == "rotate":
        axis = xyz(attrs, where, 0.0, tag)
        if not np.any(axis):
            raise where.error("<rotate>: the axis (x, y, z) must not be zero")
        m[:3, :3] = rotation(axis, number(required(attrs, "angle", tag, where), where))
    elif tag == "matrix":
        values = numbers(required(attrs, "value", tag, where), where, "<matrix>")
        if len(values) not in (9, 16):
            raise where.error(f"<matrix> takes 16 numbers (or 9), got {len(values)}")
        n = 4 if len(values) == 16 else 3
        m[:n, :n] = np.array(values).reshape(n, n)
    else:
        m = look_at(*(_vec3(attrs.get(k), where, k) for k in ("origin", "target", "up")), where=where)
    return m


def _vec3(text: Optional[str], where: Where, key: str) -> Optional[np.ndarray]:
    if text is None:
        if key == "up":
            return None
        raise where.error(f"<lookat> needs {key}")
    values = numbers(text, where, f"<lookat> {key}")
    if len(values) != 3:
        raise where.error(f"<lookat> {key} takes three numbers, got {len(values)}")
    return np.array(values, np.float64)


def rotation(axis, degrees: float) -> np.ndarray:
    """Mitsuba's Transform::rotate (Dr.Jit's rotate): c·I + s·[a]× + (1 − c)·a·aᵀ, a right-handed rotation by
    `degrees` about a unit axis. Like Mitsuba, the axis is not normalised (a longer one also scales)."""
    a = np.asarray(axis, np.float64)
    s, c = math.sin(math.radians(degrees)), math.cos(math.radians(degrees))
    cross = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return c * np.eye(3) + s * cross + (1 - c) * np.outer(a, a)


def look_at(origin, target, up, where: Optional[Where] = None) -> np.ndarray:
    """Mitsuba's Transform::look_at: columns left = normalize(up × dir), up' = dir × left, dir, origin, where
    dir = normalize(target − origin); an absent or zero up is made up as Mitsuba's coordinate_system does."""
    d = np.asarray(target, np.float64) - origin
    if np.linalg.norm(d) == 0:
        raise (where or Where(Path("?"), 0, 0)).error("<lookat>: origin and target must differ")
    d = d / np.linalg.norm(d)
    if up is None or not np.any(up):
        up = _coordinate_system(d)
    left = np.cross(up, d)
    if np.linalg.norm(left) <= 1e-12 * np.linalg.norm(up):
        raise (where or Where(Path("?"), 0, 0)).error("<lookat>: up is parallel to the view direction")
    left /= np.linalg.norm(left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, np.cross(d, left), d, origin
    return m


def _coordinate_system(n: np.ndarray) -> np.ndarray:
    """The first tangent of Mitsuba's coordinate_system(n) (Duff et al. 2017)."""
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    return np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
