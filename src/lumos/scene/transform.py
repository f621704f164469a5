"""Object transforms: translate, rotate, scale, or a matrix, composed in a stated order.

Part of the scene model (`lumos.scene.model`, which re-exports every public name).
"""

from __future__ import annotations

import math
from typing import Optional, Union

import numpy as np
from pydantic import field_validator, model_validator

from .types import Finite, StrictModel, Vec3


Row4 = tuple[Finite, Finite, Finite, Finite]


class Transform(StrictModel):
    """world_from_object = T(translate) · Rz · Ry · Rx · S(scale), or an explicit 4×4 `matrix`."""

    translate: Vec3 = (0.0, 0.0, 0.0)
    rotate: Vec3 = (0.0, 0.0, 0.0)
    scale: Union[Vec3, Finite] = 1.0
    matrix: Optional[tuple[Row4, Row4, Row4, Row4]] = None

    @field_validator("scale", mode="before")
    @classmethod
    def _scale_list(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @field_validator("matrix", mode="before")
    @classmethod
    def _matrix_rows(cls, v):
        if isinstance(v, list):
            return tuple(tuple(r) if isinstance(r, list) else r for r in v)
        return v

    @model_validator(mode="after")
    def _check(self):
        s = self.scale if isinstance(self.scale, tuple) else (self.scale,) * 3
        if any(c == 0 for c in s):
            raise ValueError("scale must not be zero on any axis")
        if any(not 1e-100 <= abs(c) <= 1e100 for c in s):  # beyond, products of three scales leave float64
            raise ValueError(f"scale must be between 1e-100 and 1e100 in size on every axis, got {list(s)}")
        if self.matrix is not None:
            explicit = self.model_fields_set & {"translate", "rotate", "scale"}
            if explicit:
                raise ValueError(f"give either matrix or {'/'.join(sorted(explicit))}, not both")
            m = np.array(self.matrix, dtype=np.float64)
            if not np.allclose(m[3], [0, 0, 0, 1]):
                raise ValueError("matrix: the last row must be [0, 0, 0, 1] (affine transforms only)")
            if abs(np.linalg.det(m[:3, :3])) < 1e-12:
                raise ValueError("matrix is singular")
        return self

    def to_matrix(self) -> np.ndarray:
        """The 4×4 world_from_object matrix (float64)."""
        if self.matrix is not None:
            return np.array(self.matrix, dtype=np.float64)
        s = self.scale if isinstance(self.scale, tuple) else (self.scale,) * 3
        rx, ry, rz = (math.radians(a) for a in self.rotate)
        cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
        Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
        Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
        m = np.eye(4)
        m[:3, :3] = Rz @ Ry @ Rx @ np.diag(s)
        m[:3, 3] = self.translate
        return m
