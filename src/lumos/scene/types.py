"""Field types shared by the scene model: vectors, colours and positive numbers.

Every model is strict (a string is not a number, a bool is not a number), forbids unknown keys (typos are
errors), and rejects NaN and infinities. Lists from YAML/JSON become tuples; a scalar where a colour is expected
means grey.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field


class StrictModel(BaseModel):
    """Base of every scene model: unknown keys, wrong types and NaN/Inf are errors."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=False)


def _list_to_tuple(value):
    return tuple(value) if isinstance(value, list) else value


def _scalar_to_rgb(value):
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return (value, value, value)
    return _list_to_tuple(value)


def _nonzero(vec):
    if math.sqrt(sum(c * c for c in vec)) <= 1e-12:
        raise ValueError("must not be the zero vector")
    return vec


Finite = Annotated[float, Field(allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False)]

Vec2 = Annotated[tuple[Finite, Finite], BeforeValidator(_list_to_tuple)]
Vec3 = Annotated[tuple[Finite, Finite, Finite], BeforeValidator(_list_to_tuple)]
Direction = Annotated[tuple[Finite, Finite, Finite], BeforeValidator(_list_to_tuple), AfterValidator(_nonzero)]
#: Linear RGB, each channel >= 0; a scalar means grey.
#: A colour channel (reflectance, intensity, radiance): at most 1e30, so that sums of lights times coefficients
#: stay inside the float32 film (3.4e38) instead of turning into infinity
Channel = Annotated[float, Field(ge=0, le=1e30, allow_inf_nan=False)]
Color = Annotated[tuple[Channel, Channel, Channel], BeforeValidator(_scalar_to_rgb)]
#: A share of light handed on per RGB channel (a material's kr and kt): in [0, 1]. A larger one is no physical
#: surface, and compounded through a recursion of reflections (1e18 after three bounces of kr = 1e6) it turned
#: pixels into infinity.
Share = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
ShareColor = Annotated[tuple[Share, Share, Share], BeforeValidator(_scalar_to_rgb)]


def norm(v) -> float:
    return math.sqrt(sum(c * c for c in v))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
