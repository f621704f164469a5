"""Lights: point, spot and directional lights, and area lights (rect, disk, sphere).

Part of the scene model (`lumos.scene.model`, which re-exports every public name).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional, Union

from pydantic import Discriminator, Field, PrivateAttr, Tag, field_validator, model_validator

from .materials import MaterialRef
from .types import Color, Direction, NonNegative, Positive, StrictModel, Vec3, cross, norm


class _LocalLight(StrictModel):
    """Id and Is of the classic model: `intensity` sets both; `diffuse` / `specular` override one."""

    #: a name, to animate the light by (`lights[<name>].intensity`)
    name: Optional[str] = None
    intensity: Color = (1.0, 1.0, 1.0)
    diffuse: Optional[Color] = None
    specular: Optional[Color] = None

    @property
    def diffuse_intensity(self):
        return self.diffuse if self.diffuse is not None else self.intensity

    @property
    def specular_intensity(self):
        return self.specular if self.specular is not None else self.intensity


class _PositionedLight(_LocalLight):
    """A light at a point, dimmed by distance: `att(d) = c + l·d + q·d²` from `attenuation: [c, l, q]`."""

    position: Vec3
    attenuation: tuple[NonNegative, NonNegative, NonNegative] = (1.0, 0.0, 0.0)

    @field_validator("attenuation", mode="before")
    @classmethod
    def _att_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check(self):
        if sum(self.attenuation) <= 0:
            raise ValueError("attenuation [c, l, q] must not be all zero")
        return self


class PointLight(_PositionedLight):
    """Shines equally in every direction."""

    type: Literal["point"]


class SpotLight(_PositionedLight):
    """A point light limited to a cone about `direction`: full intensity within `inner_angle` of the axis, none
    beyond `angle`, and between them the factor s² with s = (cosθ − cos angle)/(cos inner_angle − cos angle)
    (glTF KHR_lights_punctual's recommended falloff; angles are half-angles in degrees)."""

    type: Literal["spot"]
    direction: Direction
    angle: Annotated[float, Field(gt=0, le=90, allow_inf_nan=False)] = 45.0
    inner_angle: Annotated[float, Field(ge=0, le=90, allow_inf_nan=False)] = 0.0

    @model_validator(mode="after")
    def _check_cone(self):
        if self.inner_angle > self.angle:
            raise ValueError(f"inner_angle ({self.inner_angle:g}) must not exceed angle ({self.angle:g})")
        return self


class DirectionalLight(_LocalLight):
    """A parallel light travelling along `direction` (so L = −direction)."""

    type: Literal["directional"]
    direction: Direction


class _AreaLight(StrictModel):
    """A light that is also a surface: `radiance` leaves it (on one side for rect and disk lights, unless
    `two_sided`), and, given a `material`, it reflects like any object (its material's own emission must be 0: the
    light's is `radiance`). Without one it reflects nothing."""

    type: Literal["area"]
    #: a name, to animate the light by (`lights[<name>].radiance`)
    name: Optional[str] = None
    radiance: Color = (1.0, 1.0, 1.0)
    samples: Annotated[int, Field(ge=1, le=4096)] = 16
    two_sided: bool = False
    material: Optional[MaterialRef] = None


class RectLight(_AreaLight):
    """Emits on the side of cross(edge_u, edge_v) only (on both with `two_sided`)."""

    shape: Literal["rect"]
    corner: Vec3
    edge_u: Vec3
    edge_v: Vec3

    @model_validator(mode="after")
    def _check(self):
        if norm(cross(self.edge_u, self.edge_v)) <= 1e-18:
            raise ValueError("edge_u and edge_v must be non-zero and not parallel")
        return self


class DiskLight(_AreaLight):
    """Emits on the side of `normal` only (on both with `two_sided`)."""

    shape: Literal["disk"]
    center: Vec3
    normal: Direction
    radius: Positive


class SphereLight(_AreaLight):
    """Emits outward from its whole surface."""

    shape: Literal["sphere"]
    center: Vec3
    radius: Positive

    @model_validator(mode="after")
    def _check_sides(self):
        if self.two_sided:
            raise ValueError("two_sided is for rect and disk lights: a sphere light emits outward from its whole "
                             "surface")
        return self


def _light_tag(value: Any) -> Optional[str]:
    if not isinstance(value, dict):
        return None
    kind = value.get("type")
    if kind == "area":
        shape = value.get("shape")
        return f"area.{shape}" if shape in ("rect", "disk", "sphere") else "area.?"
    return kind if isinstance(kind, str) else None


Light = Annotated[
    Union[
        Annotated[PointLight, Tag("point")],
        Annotated[SpotLight, Tag("spot")],
        Annotated[DirectionalLight, Tag("directional")],
        Annotated[RectLight, Tag("area.rect")],
        Annotated[DiskLight, Tag("area.disk")],
        Annotated[SphereLight, Tag("area.sphere")],
    ],
    Discriminator(
        _light_tag,
        custom_error_type="light_type",
        custom_error_message=(
            "lights need type: point, spot, directional or area (area needs shape: rect, disk or sphere)"
        ),
    ),
]
LIGHT_TYPES = ("point", "spot", "directional", "area")


class Sky(StrictModel):
    """A daylight sky (Preetham's model, `compile.sky`): the sun at `elevation` degrees above the horizon and
    `azimuth` degrees from −z towards +x (or towards `direction`), the haze `turbidity` (2 clear, 10 hazy), the
    sun's disk drawn or not, a diffuse ground of albedo `ground` below the horizon, tabulated `resolution` pixels
    wide. Scaled so that a white horizontal plane in the open shows radiance 1; the environment's `scale`
    multiplies it."""

    elevation: Annotated[float, Field(ge=0, le=90, allow_inf_nan=False)] = 45.0
    azimuth: Annotated[float, Field(allow_inf_nan=False)] = 0.0
    direction: Optional[Direction] = None
    turbidity: Annotated[float, Field(ge=1.7, le=10, allow_inf_nan=False)] = 3.0
    sun: bool = True
    ground: Color = (0.2, 0.2, 0.2)
    resolution: Annotated[int, Field(ge=16, le=16384)] = 1024

    @model_validator(mode="after")
    def _check(self):
        if self.direction is not None:
            if {"elevation", "azimuth"} & self.model_fields_set:
                raise ValueError("give the sun a direction or an elevation and azimuth, not both")
            if self.direction[1] < 0:
                raise ValueError("the sun's direction points below the horizon (y < 0): Preetham's model describes "
                                 "the sky by day only")
        if self.resolution % 2:
            raise ValueError("resolution must be even (the image is resolution × resolution/2)")
        return self


class Environment(StrictModel):
    """Light from every direction at infinity: a lat-long (equirectangular) image `file` (EXR, PFM, NPY: linear
    radiance; PNG, JPEG: sRGB, decoded) or a constant `color`, times `scale`, turned `rotation` degrees about +y
    (counter-clockwise seen from above). The image's top row is straight up (+y), its bottom row straight down;
    its middle column looks along −z, the column a quarter further right along +x (u = 1/2 + atan2(x, −z)/2π,
    v = acos(y)/π)."""

    file: Optional[str] = None
    color: Optional[Color] = None
    sky: Optional[Sky] = None
    scale: Color = (1.0, 1.0, 1.0)
    rotation: Annotated[float, Field(allow_inf_nan=False)] = 0.0
    _path: Any = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _check(self):
        if (self.file is not None) + (self.color is not None) + (self.sky is not None) != 1:
            raise ValueError("give the environment one of a file (a lat-long image), a color or a sky")
        return self
