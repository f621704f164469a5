"""Materials: the illumination model's coefficients, and their textures and bump maps.

Part of the scene model (`lumos.scene.model`, which re-exports every public name).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, Optional, Union

from pydantic import Discriminator, Field, PrivateAttr, Tag, field_validator, model_validator

from .types import Color, Finite, NonNegative, Positive, ShareColor, StrictModel


class Material(StrictModel):
    """Coefficients of the classic model, per RGB channel (a scalar means grey). Missing ones are 0."""

    ka: Color = (0.0, 0.0, 0.0)
    kd: Color = (0.0, 0.0, 0.0)
    ks: Color = (0.0, 0.0, 0.0)
    shininess: NonNegative = 1.0
    #: the shares of light reflected and transmitted (whitted's recursion; path's specular lobes): in [0, 1]
    kr: ShareColor = (0.0, 0.0, 0.0)
    kt: ShareColor = (0.0, 0.0, 0.0)
    ior: Positive = 1.0
    emission: Color = (0.0, 0.0, 0.0)
    #: whitted: weight reflection and transmission by Schlick's approximation of the Fresnel factor
    fresnel: bool = False
    #: one texture or a list of them, applied in list order (a later one sees what the earlier ones made)
    texture: Optional[Union["Texture", list["Texture"]]] = None
    bump: Optional["Bump"] = None

    @field_validator("texture", mode="after")
    @classmethod
    def _texture_list(cls, v):
        if isinstance(v, list) and not v:
            return None
        return v

    @property
    def textures(self) -> list["Texture"]:
        """The material's textures as a list, in the order they apply (empty when it has none)."""
        if self.texture is None:
            return []
        return list(self.texture) if isinstance(self.texture, list) else [self.texture]


TEXTURE_TARGETS = ("ka", "kd", "ks", "kr", "emission", "opacity")


class _UVMap(StrictModel):
    """What textures and bump maps share: an image `file` or a procedural pattern, repeated `scale` times across
    the uv square, wrapped or clamped outside it."""

    type: str
    file: Optional[str] = None
    #: repeats across the uv square: (u, v) multipliers (a scalar means both)
    scale: Union[tuple[Positive, Positive], Positive] = 1.0
    wrap: Literal["repeat", "clamp"] = "repeat"
    #: added to the scaled coordinates: the pattern is looked up at (scale_u·u + offset_u, scale_v·v + offset_v)
    offset: tuple[Finite, Finite] = (0.0, 0.0)
    _path: Optional[Path] = PrivateAttr(default=None)
    _noun: ClassVar[str] = "map"  # for error messages
    _file_types: ClassVar[tuple[str, ...]] = ("image",)  # the types read from a file

    @field_validator("scale", "offset", mode="before")
    @classmethod
    def _scale_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check_file(self):
        if (self.type in self._file_types) != (self.file is not None):
            kind = " or ".join(self._file_types)
            raise ValueError(f"an {kind} {self._noun} needs file (and only an {kind} {self._noun} takes one)")
        return self

    @property
    def uv_scale(self) -> tuple[float, float]:
        return self.scale if isinstance(self.scale, tuple) else (self.scale, self.scale)


class Texture(_UVMap):
    """A colour that varies over a surface, looked up at the hit's (u, v), replacing (`mode: replace`) or
    multiplying (`mode: multiply`) the coefficients named in `apply_to`. `image`: a PNG/JPEG file (relative to
    the scene file), bilinearly filtered; `checker`, `stripes` (along u) and `noise` (gradient noise, blending
    `colors`) are procedural. `apply_to: [opacity]` reads the coverage α instead of a colour: an image's alpha
    channel (its luminance when it has none), a pattern's luminance; α < 0.5 is a cut-out hole."""

    type: Literal["image", "checker", "stripes", "noise"]
    colors: tuple[Color, Color] = ((0.9, 0.9, 0.9), (0.1, 0.1, 0.1))
    apply_to: list[Literal["ka", "kd", "ks", "kr", "emission", "opacity"]] = Field(
        default_factory=lambda: ["ka", "kd"])
    mode: Literal["replace", "multiply"] = "replace"
    _noun: ClassVar[str] = "texture"

    @field_validator("colors", mode="before")
    @classmethod
    def _colors_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check(self):
        if not self.apply_to:
            raise ValueError("apply_to must name at least one of ka, kd, ks, kr, emission, opacity")
        if "kr" in self.apply_to and self.type != "image" and max(max(c) for c in self.colors) > 1.0:
            raise ValueError("colors: a texture applied to kr gives a share of light reflected: each channel must "
                             "be in [0, 1]")
        return self


class Bump(_UVMap):
    """Bump mapping: the shading normal tilted by the gradient of a height field over (u, v): an image's
    luminance or gradient noise, times `strength`; or (`type: normal`) replaced by a tangent-space normal map,
    an image whose raw RGB in [0, 1] is the normal's (x, y, z) in [-1, 1] along (tangent, bitangent, normal),
    x and y scaled by `strength`."""

    type: Literal["image", "noise", "normal"]
    strength: Finite = 1.0
    _noun: ClassVar[str] = "bump map"
    _file_types: ClassVar[tuple[str, ...]] = ("image", "normal")


Material.model_rebuild()


#: The material of an object that names none: a matte light grey.
DEFAULT_MATERIAL = Material(ka=0.8, kd=0.8)


def _material_tag(value: Any) -> str:
    return "name" if isinstance(value, str) else "inline"


MaterialRef = Annotated[
    Union[Annotated[str, Tag("name")], Annotated[Material, Tag("inline")]],
    Discriminator(_material_tag),
]
