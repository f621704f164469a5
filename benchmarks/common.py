"""Shared helpers for the benchmarks: test meshes, primary rays, timing, machine description."""

from __future__ import annotations

import os
import platform
import time

import numpy as np


def machine() -> str:
    cpu = platform.processor() or "cpu"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def icosphere(subdivisions: int = 8):
    """trimesh's icosphere: subdivisions=8 gives 1,310,720 triangles (PEERS.md)."""
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)


def primary_rays(position, look_at, fov_deg: float, width: int, height: int):
    """Pinhole rays through pixel centres, DESIGN.md's convention; origins/directions float64 (W·H, 3)."""
    pos = np.asarray(position, float)
    w = pos - np.asarray(look_at, float)
    w /= np.linalg.norm(w)
    u = np.cross([0.0, 1.0, 0.0], w)
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    t = np.tan(np.radians(fov_deg) / 2)
    ys, xs = np.mgrid[0:height, 0:width]
    sx = (2 * (xs + 0.5) / width - 1) * (width / height) * t
    sy = (1 - 2 * (ys + 0.5) / height) * t
    d = sx[..., None] * u + sy[..., None] * v - w
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    d = d.reshape(-1, 3)
    o = np.broadcast_to(pos, d.shape).copy()
    return o, d


def best_of(fn, repeats: int = 3) -> float:
    """Least wall time of `repeats` calls (seconds)."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def frame_times(fn, repeats: int = 5, warmup: int = 0) -> list[float]:
    """Wall time (seconds) of each of `repeats` calls of `fn`, after `warmup` untimed calls."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times


def gl_look_at(position, look_at, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """OpenGL view matrix (4×4 float64, row-major: transpose before handing it to GL) from DESIGN.md's basis:
    w = normalize(position − look_at), u = normalize(cross(up, w)), v = cross(w, u); camera looks down −w."""
    pos = np.asarray(position, float)
    w = pos - np.asarray(look_at, float)
    w /= np.linalg.norm(w)
    u = np.cross(np.asarray(up, float), w)
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = u, v, w
    m[:3, 3] = -m[:3, :3] @ pos
    return m


def gl_perspective(fov_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL projection (gluPerspective; 4×4 float64, row-major) with vertical `fov_deg` and aspect W/H.

    With gl_look_at it maps the direction sx·a·t·u + sy·t·v − w to NDC (sx, sy), so GL pixel (x, y_gl) (y_gl = 0
    at the bottom) is DESIGN.md's pixel (x, H − 1 − y_gl): flip the rows of a glReadPixels image."""
    f = 1.0 / np.tan(np.radians(fov_deg) / 2)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2 * far * near / (near - far)
    m[3, 2] = -1.0
    return m
