"""The camera: a pinhole or thin lens, perspective or orthographic, with its shutter (DESIGN.md's basis).

Part of the scene model (`lumos.scene.model`, which re-exports every public name).
"""

from __future__ import annotations

from typing import Annotated, Literal, Optional

import numpy as np
from pydantic import Field, field_validator, model_validator

from .types import Finite, NonNegative, Positive, StrictModel, Vec3, cross, norm, sub


class Camera(StrictModel):
    """Pinhole or thin-lens perspective camera (vertical `fov` in degrees), or orthographic (`size` tall)."""

    type: Literal["perspective", "orthographic"] = "perspective"
    position: Vec3 = (0.0, 0.0, 5.0)
    look_at: Vec3 = (0.0, 0.0, 0.0)
    up: Vec3 = (0.0, 1.0, 0.0)
    fov: Annotated[float, Field(gt=0, lt=180)] = 45.0
    size: Positive = 2.0
    aperture: NonNegative = 0.0
    focus_distance: Optional[Positive] = None
    #: [open, close] times of the shutter; objects with a `motion` move during it (motion blur)
    shutter: tuple[Finite, Finite] = (0.0, 0.0)

    @field_validator("shutter", mode="before")
    @classmethod
    def _shutter_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check_basis(self):
        if self.shutter[1] < self.shutter[0]:
            raise ValueError("shutter: [open, close] must not close before it opens")
        view = sub(self.position, self.look_at)
        if norm(view) <= 1e-12:
            raise ValueError("position and look_at must differ")
        if norm(self.up) <= 1e-12:
            raise ValueError("up must not be the zero vector")
        c = cross(self.up, view)
        if norm(c) <= 1e-9 * norm(self.up) * norm(view):
            raise ValueError("up is parallel to the view direction (position - look_at); choose another up")
        return self

    def basis(self):
        """(u, v, w) as in DESIGN.md: w = normalize(position − look_at), u = normalize(up × w), v = w × u."""
        w = np.subtract(self.position, self.look_at)
        w = w / np.linalg.norm(w)
        u = np.cross(self.up, w)
        u = u / np.linalg.norm(u)
        v = np.cross(w, u)
        return u, v, w

    def resolved_focus_distance(self) -> float:
        if self.focus_distance is not None:
            return self.focus_distance
        return float(np.linalg.norm(np.subtract(self.position, self.look_at)))
