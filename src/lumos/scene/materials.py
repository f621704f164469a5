"""Materials: the illumination model's coefficients, and their textures and bump maps.

Part of the scene model (`lumos.scene.model`, which re-exports every public name).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, Optional, Union

from pydantic import Discriminator, Field, PrivateAttr, Tag, field_validator, model_validator

from .types import Color, Finite, NonNegative, Positive, ShareColor, StrictModel


#: Complex indices of refraction (η, k) per RGB channel of named metals: the values Mitsuba 3's RGB variants use
#: (its `conductor` plugin's `material` names, spectra averaged into linear sRGB).
METALS = {
    "Au": ((0.143, 0.3753, 1.442), (3.983, 2.3856, 1.6034)),
    "Ag": ((0.1553, 0.1167, 0.1384), (4.8284, 3.1222, 2.1469)),
    "Cu": ((0.201, 0.9237, 1.1022), (3.9133, 2.453, 2.1421)),
    "Al": ((1.6575, 0.8804, 0.5212), (9.2238, 6.2695, 4.837)),
    "Cr": ((4.3697, 2.9165, 1.6549), (5.2065, 4.2313, 3.7547)),
    "W": ((4.3708, 3.3002, 2.9984), (3.5006, 2.6049, 2.2732)),
    "Hg": ((2.3989, 1.44, 0.9096), (6.3276, 4.3719, 3.4218)),
    "Li": ((0.2658, 0.1956, 0.2209), (3.5402, 2.3111, 1.6686)),
    "K": ((0.064, 0.0464, 0.0382), (2.1042, 1.3489, 0.9131)),
    "Mo": ((4.484, 3.5251, 2.7763), (4.1114, 3.4208, 3.1506)),
    "Ni": ((2.3673, 1.6634, 1.4671), (4.4988, 3.0502, 2.3454)),
    "Rh": ((2.5858, 1.8602, 1.5543), (6.7823, 4.703, 3.9761)),
    "Ir": ((3.0863, 2.0822, 1.6179), (5.5922, 4.0671, 3.2673)),
    "Ta": ((2.0627, 2.3929, 2.6279), (2.4084, 1.7415, 1.947)),
    "Nb": ((3.4201, 2.7901, 2.3956), (3.4414, 2.7377, 2.5797)),
    "TiN": ((1.6484, 1.1505, 1.3798), (3.3683, 1.9435, 1.1021)),
    "Be": ((4.185, 3.185, 2.7841), (3.8355, 3.0101, 2.869)),
}


class _GGXWidths(StrictModel):
    """`alpha`: a GGX width in [0, 1], one number or [αu, αv] for anisotropic roughness (`alphas` gives the pair).
    A subclass's own `model_validator` calls `_check_alpha`."""

    alpha: Union[tuple[NonNegative, NonNegative], NonNegative] = 0.0

    @field_validator("alpha", mode="before")
    @classmethod
    def _alpha_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    def _check_alpha(self) -> None:
        for a in self.alphas:
            if a > 1.0:
                raise ValueError(f"alpha must be at most 1 (a GGX width), got {a:g}")

    @property
    def alphas(self) -> tuple[float, float]:
        return self.alpha if isinstance(self.alpha, tuple) else (self.alpha, self.alpha)


class Conductor(_GGXWidths):
    """A metal, read physically: a GGX (Trowbridge–Reitz) microfacet surface of width `alpha` (one number, or
    [αu, αv] for anisotropic roughness; 0: a perfect mirror) whose reflectance is the exact Fresnel factor of
    the complex index of refraction η + ik per channel: a named `metal`, or `eta` and `k` (neither: a perfect
    reflector, F = 1), times `tint`."""

    metal: Optional[Literal[tuple(METALS)]] = None
    eta: Optional[Color] = None
    k: Optional[Color] = None
    tint: ShareColor = (1.0, 1.0, 1.0)

    @model_validator(mode="after")
    def _check(self):
        if self.metal is not None and (self.eta is not None or self.k is not None):
            raise ValueError("give metal or eta and k, not both")
        if (self.eta is None) != (self.k is None):
            raise ValueError("eta and k go together (the complex index of refraction η + ik)")
        self._check_alpha()
        return self

    @property
    def index(self) -> Optional[tuple[tuple, tuple]]:
        """(η, k) per channel, or None for a perfect reflector."""
        if self.metal is not None:
            return METALS[self.metal]
        return None if self.eta is None else (tuple(self.eta), tuple(self.k))

    def normal_reflectance(self) -> tuple[float, float, float]:
        """F0 = ((η − 1)² + k²)/((η + 1)² + k²) per channel, times the tint: the reflectance head-on."""
        index = self.index
        if index is None:
            return tuple(self.tint)
        return tuple(t * ((e - 1.0) ** 2 + k * k) / ((e + 1.0) ** 2 + k * k)
                     for t, e, k in zip(self.tint, *index))

    def classic(self, environment_lit: bool = False) -> dict:
        """The classic coefficients the local methods (raycast, whitted, raster) read for this metal: its head-on
        reflectance F0 as the mirror `kr` (α below 0.01) or as a Phong lobe `ks` whose exponent matches the GGX
        width (`phong_exponent`), and as `ka` (the surroundings it reflects, as ambient light) unless an
        environment lights the model, whose reflection the local methods then show; no diffuse light."""
        f0 = self.normal_reflectance()
        alpha = 0.5 * sum(self.alphas)
        zero = (0.0, 0.0, 0.0)
        ka = zero if environment_lit else f0
        if alpha < 0.01:
            return {"ka": ka, "kd": zero, "ks": zero, "kr": f0, "shininess": 1.0}
        return {"ka": ka, "kd": zero, "ks": f0, "kr": zero, "shininess": phong_exponent(alpha)}


class Plastic(StrictModel):
    """A plastic, read physically: the material's `kd` as a Lambertian base under a dielectric coat of index
    `ior` (inside over outside) whose surface is GGX microfacets of width `alpha` (0: smooth), as Mitsuba 3's
    `roughplastic` (`plastic` when smooth): the coat reflects with its Fresnel factor (times `tint`), and the base
    sees the light the coat lets in and sends out, with the light the coat reflects back down to it."""

    alpha: NonNegative = 0.0
    ior: Positive = 1.49
    tint: ShareColor = (1.0, 1.0, 1.0)

    @model_validator(mode="after")
    def _check(self):
        if self.alpha > 1.0:
            raise ValueError(f"alpha must be at most 1 (a GGX width), got {self.alpha:g}")
        if self.ior == 1.0:
            raise ValueError("ior must differ from 1 (a coat of index 1 is no coat)")
        return self

    def classic(self, environment_lit: bool = False) -> dict:
        """What the local methods read for the coat: its head-on reflectance ((η−1)/(η+1))² as a mirror `kr`
        (α below 0.01) or as a Phong lobe `ks` as wide as the GGX one."""
        f0 = tuple(t * ((self.ior - 1.0) / (self.ior + 1.0)) ** 2 for t in self.tint)
        zero = (0.0, 0.0, 0.0)
        if self.alpha < 0.01:
            return {"ks": zero, "kr": f0, "shininess": 1.0}
        return {"ks": f0, "kr": zero, "shininess": phong_exponent(self.alpha)}


class Dielectric(_GGXWidths):
    """Glass, read physically: an interface between an inside of index `ior` and an outside of index `ext_ior`
    (Mitsuba's int_ior and ext_ior: refraction reads only their ratio) whose surface is GGX microfacets of width
    `alpha` (one number, or [αu, αv]; 0: smooth glass), as Mitsuba 3's `roughdielectric` (`dielectric` when
    smooth): reflection with the dielectric Fresnel factor (times `tint`), refraction with the rest of it (times
    `transmit_tint`), both sampled by the normals visible from the viewer (Walter et al. 2007; Heitz 2018)."""

    ior: Positive = 1.5
    ext_ior: Positive = 1.0
    tint: ShareColor = (1.0, 1.0, 1.0)
    transmit_tint: ShareColor = (1.0, 1.0, 1.0)

    @model_validator(mode="after")
    def _check(self):
        self._check_alpha()
        if self.ior == self.ext_ior:
            raise ValueError("ior must differ from ext_ior (an interface between equal indices is no interface)")
        return self

    @property
    def eta(self) -> float:
        """The relative index inside over outside."""
        return self.ior / self.ext_ior

    def classic(self, environment_lit: bool = False) -> dict:
        """What the local methods read for this glass: `kt` = transmit_tint, `ior` = ior/ext_ior (they assume
        the outside is the medium the ray comes from) with `fresnel: true` (Schlick's reflection and refraction),
        and for a rough one (α at least 0.01) a Phong highlight `ks` of the head-on reflectance ((η−1)/(η+1))²
        as wide as the GGX lobe; the reflected and refracted rays stay sharp."""
        f0 = tuple(t * ((self.eta - 1.0) / (self.eta + 1.0)) ** 2 for t in self.tint)
        zero = (0.0, 0.0, 0.0)
        alpha = 0.5 * sum(self.alphas)
        out = {"ka": zero, "kd": zero, "kr": zero, "kt": tuple(self.transmit_tint), "ior": self.eta,
               "fresnel": True}
        if alpha < 0.01:
            return {**out, "ks": zero, "shininess": 1.0}
        return {**out, "ks": f0, "shininess": phong_exponent(alpha)}


class Principled(StrictModel):
    """glTF 2.0's metallic–roughness material (its specification's Appendix B, with KHR_materials_ior,
    _specular and _transmission), read exactly by `path`: a base colour b, `metallic` m and perceptual
    `roughness` r (GGX α = r²); a mix by m of a metal (GGX, Schlick's Fresnel from F0 = b) and a dielectric (the
    same GGX lobe with F0 = ((ior − 1)/(ior + 1))²·specular_color·specular, F90 = specular, over a Lambertian
    base b weighted by 1 − max F). `transmission` t turns that share of the dielectric's base into smooth glass
    of index `ior`; `clearcoat` lays KHR_materials_clearcoat's clear coat (Schlick F0 0.04, GGX of width
    clearcoat_roughness²) over it. Textures reach it through `apply_to: [base_color]` (multiplies b) and
    `[metallic_roughness]` (a glTF metallicRoughnessTexture: its blue multiplies m, its green r)."""

    base_color: ShareColor = (1.0, 1.0, 1.0)
    metallic: Annotated[float, Field(ge=0.0, le=1.0)] = 1.0
    roughness: Annotated[float, Field(ge=0.0, le=1.0)] = 1.0
    ior: Annotated[float, Field(ge=1.0, le=1e3)] = 1.5
    specular: Annotated[float, Field(ge=0.0, le=1.0)] = 1.0
    specular_color: Color = (1.0, 1.0, 1.0)
    transmission: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0
    clearcoat: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0
    clearcoat_roughness: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0

    @property
    def f0(self) -> tuple[float, float, float]:
        """The dielectric's reflectance head-on per channel: min(((ior − 1)/(ior + 1))²·specular_color, 1)·specular."""
        base = ((self.ior - 1.0) / (self.ior + 1.0)) ** 2
        return tuple(min(base * c, 1.0) * self.specular for c in self.specular_color)

    def classic(self, environment_lit: bool = False) -> dict:
        """The classic coefficients the local methods read (docs/formats.md#gltf-20), with g = (1 − r)² the share
        of the specular reflection that is a sharp mirror and F0s = F0·(1 − m) + b·m its colour:
        kd = b·(1 − m)·(1 − F0)·(1 − t), kt = b·(1 − m)·(1 − F0)·t, ks = F0s·(1 − g), kr = F0s·g, ka = kd + F0s
        (kd alone where an environment lights the model: the local methods then show its reflection), and the
        Phong exponent of the GGX width r² (`phong_exponent`), so kd + ks + kr + kt <= 1; a clear coat takes
        0.04·c off all of them and adds it to kr (its roughness below 0.5) or ks."""
        import numpy as np

        b, m, t = np.asarray(self.base_color, dtype=float), self.metallic, self.transmission
        f0 = np.asarray(self.f0)
        under = 1.0 - 0.04 * self.clearcoat  # a clear coat takes its head-on reflectance off what lies below
        dielectric = (1.0 - m) * (1.0 - f0) * under
        specular = (f0 * (1.0 - m) + b * m) * under
        g = (1.0 - self.roughness) ** 2
        kd = b * dielectric * (1.0 - t)
        coat = 0.04 * self.clearcoat  # and reflects it: a mirror when smooth (roughness below 0.5), else a highlight
        smooth = self.clearcoat_roughness < 0.5
        out = {"ka": kd if environment_lit else kd + specular + coat, "kd": kd,
               "ks": specular * (1.0 - g) + (0.0 if smooth else coat), "kr": specular * g + (coat if smooth else 0.0),
               "shininess": phong_exponent(self.roughness ** 2)}
        if t > 0.0:
            out.update(kt=b * dielectric * t, ior=self.ior, fresnel=True)
        return {k: tuple(float(x) for x in v) if isinstance(v, np.ndarray) else v for k, v in out.items()}


def phong_exponent(alpha: float) -> float:
    """The Phong exponent whose lobe is about as wide as a GGX (or Beckmann) lobe of width α: Blinn-Phong
    n_B = 2/α² − 2 and a Phong lobe about the mirror direction of 4× narrower angle, n = n_B/4; in [1, 10⁴]."""
    if alpha < 0.0025:
        return 1e4
    return float(min(max(0.5 * (alpha ** -2 - 1.0), 1.0), 1e4))


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
    #: a metal read physically by `path` (GGX microfacets, complex Fresnel); the local methods read the classic
    #: coefficients it implies unless they are given (`conductor_classic`)
    conductor: Optional[Conductor] = None
    #: a plastic (kd under a clear coat) read physically by `path`; the local methods read kd and the coat's
    #: classic reading (`Plastic.classic`) unless given
    plastic: Optional[Plastic] = None
    #: glass (smooth or rough) read physically by `path`; the local methods read the kt/ior glass it implies
    #: (`Dielectric.classic`) unless given
    dielectric: Optional[Dielectric] = None
    #: glTF's metallic–roughness material read exactly by `path`; the local methods read its classic reading
    #: (`Principled.classic`) unless given
    principled: Optional[Principled] = None

    @model_validator(mode="after")
    def _one_model(self):
        given = [name for name in PHYSICAL_MODELS if getattr(self, name) is not None]
        if len(given) > 1:
            raise ValueError(f"give one of {', '.join(PHYSICAL_MODELS)}, not {' and '.join(given)}")
        for tex in self.textures:
            reads = {"base_color", "metallic_roughness"} & set(tex.apply_to)
            if reads and self.principled is None:
                raise ValueError(f"a texture applied to {' and '.join(sorted(reads))} needs a principled material")
        return self

    def classic(self, environment_lit: bool = False) -> dict:
        """The classic coefficients the local methods (and radiosity) read: ka, kd, ks, shininess, kr, kt, ior
        and fresnel as given, and where not given the physical model's classic reading (its `classic()`;
        `environment_lit`: an environment lights the local model, `compile.environment_lights_model`)."""
        out = {k: getattr(self, k) for k in ("ka", "kd", "ks", "shininess", "kr", "kt", "ior", "fresnel")}
        if self.physical is not None:
            out.update({k: v for k, v in self.physical.classic(environment_lit).items()
                        if k not in self.model_fields_set})
        return out

    @property
    def physical(self):
        """The physical model the path tracer reads (a Conductor, Plastic, Dielectric or Principled), or None."""
        return self.conductor or self.plastic or self.dielectric or self.principled

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


#: the material's physical models: one at most
PHYSICAL_MODELS = ("conductor", "plastic", "dielectric", "principled")
TEXTURE_TARGETS = ("ka", "kd", "ks", "kr", "emission", "opacity", "base_color", "metallic_roughness", "occlusion")
#: targets whose texels are data, not colour: read raw (not decoded from sRGB), and alone in their texture
DATA_TARGETS = ("metallic_roughness", "occlusion")


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
    channel (its luminance when it has none), a pattern's luminance; α < 0.5 is a cut-out hole.

    A principled material's textures: `base_color` multiplies (or replaces) its base colour, `metallic_roughness`
    is a glTF metallicRoughnessTexture (raw values: blue multiplies metallic, green roughness), `occlusion` a glTF
    occlusionTexture (its raw red multiplies ka: the ambient light a crevice lets in, for the local methods)."""

    type: Literal["image", "checker", "stripes", "noise"]
    colors: tuple[Color, Color] = ((0.9, 0.9, 0.9), (0.1, 0.1, 0.1))
    apply_to: list[Literal[TEXTURE_TARGETS]] = Field(default_factory=lambda: ["ka", "kd"])
    mode: Literal["replace", "multiply"] = "replace"
    _noun: ClassVar[str] = "texture"

    @field_validator("colors", mode="before")
    @classmethod
    def _colors_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check(self):
        if not self.apply_to:
            raise ValueError(f"apply_to must name at least one of {', '.join(TEXTURE_TARGETS)}")
        data = [t for t in self.apply_to if t in DATA_TARGETS]
        if data and len(set(self.apply_to)) > 1:
            raise ValueError(f"a texture applied to {data[0]} holds data, not colour: apply it to nothing else")
        if data and self.type != "image":
            raise ValueError(f"a texture applied to {data[0]} is an image (a glTF map)")
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
