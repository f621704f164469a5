"""pbrt-v4 textures and spectrum-valued parameters as lumos colours and textures.

    ctx = Context(folder, warnings)
    define_texture(statement, ctx)                  # a Texture directive: ctx.textures["spectrum"][name] = Tex
    tex = color(params, "reflectance", "albedo", ctx, default=Tex((0.5, 0.5, 0.5)))
    tex.rgb, tex.pattern                            # a constant colour, or a lumos texture times that colour

A `Tex` is either a constant linear sRGB colour or a lumos texture pattern (an `image` of a PNG/JPEG file, or a
`checker` of two colours) multiplied by `rgb`; a material applies a pattern with `mode: multiply` to the
coefficient it colours. What lumos cannot draw stands in as a constant, with a warning once per kind:

- `constant`: its `value`. `scale`: the product of `tex` and `scale` (a pattern times the other's colour).
- `imagemap` of a PNG/JPEG: an `image` texture (`uscale`/`vscale` → `scale`, `udelta`/`vdelta` → `offset`, `wrap`
  repeat or clamp, `scale` a factor); of an EXR/PFM: its mean colour (lumos's textures are 8-bit images).
- `checkerboard` (2D, constant `tex1`/`tex2`): `checker` with colours [tex1, tex2] (tex1 where ⌊s⌋ + ⌊t⌋ is even).
- `mix`: (1 − amount)·tex1 + amount·tex2 (of their mean colours for patterns); `bilerp`, `directionmix`, `fbm`,
  `wrinkled`, `windy`, `marble`, `dots`, `ptex`: their mean, or a grey 0.5.

Spectrum-valued parameters: `rgb` as given (a reflectance must lie in [0, 1], as pbrt requires); `blackbody` the
colour of that temperature at luminance 1; `spectrum` (λ, value) pairs, a file of such pairs (relative to the
main file's folder) or one of pbrt's named spectra, converted by `pbrt_spectra` (a reflectance under D65; an
emission spectrum at luminance 1).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from . import pbrt_spectra as spectra
from .pbrt_tokens import Param, Params, Statement, Warnings, Where, number

_GREY = (0.5, 0.5, 0.5)
_PATTERN_FILES = (".png", ".jpg", ".jpeg")
_STAND_IN_CLASSES = ("bilerp", "directionmix", "fbm", "wrinkled", "windy", "marble", "dots", "ptex")


@dataclass(frozen=True)
class Tex:
    """A constant colour, or a lumos texture `pattern` (without apply_to and mode) multiplied by `rgb`."""

    rgb: tuple
    pattern: Optional[dict] = None
    mean_rgb: Optional[tuple] = None  # the pattern's mean colour times rgb (for stand-ins)
    image: Optional[Path] = None  # an image pattern's file, whose mean is read when a stand-in needs it

    @property
    def mean(self) -> tuple:
        if self.pattern is None:
            return self.rgb
        if self.mean_rgb is None and self.image is not None:
            return tuple(a * b for a, b in zip(self.rgb, _image_mean(self.image)))
        return self.mean_rgb or self.rgb

    @property
    def scalar(self) -> float:
        return float(sum(self.mean) / 3.0)

    def times(self, rgb) -> "Tex":
        mul = tuple(a * b for a, b in zip(self.rgb, rgb))
        mean = None if self.mean_rgb is None else tuple(a * b for a, b in zip(self.mean_rgb, rgb))
        return Tex(mul, self.pattern, mean, self.image)


@functools.lru_cache(maxsize=64)
def _image_mean(path: Path) -> tuple:
    """The mean linear colour of an image file (grey 0.5 when it cannot be read)."""
    from .image_files import read_image

    try:
        return tuple(float(c) for c in read_image(path).reshape(-1, 3).mean(axis=0))
    except Exception:  # noqa: BLE001 - any file lumos cannot decode stands in as grey
        return _GREY


@dataclass
class Context:
    """What the mapping of one scene shares: the main file's folder (pbrt's search directory, where relative file
    names start), the warnings said so far and the named textures of each type."""

    folder: Path
    warn: Warnings
    textures: dict = field(default_factory=lambda: {"float": {}, "spectrum": {}})


def grey(value: float) -> tuple:
    return (float(value),) * 3


def tidy(x: float, digits: int = 9) -> float:
    """x to `digits` significant digits: values without the last bits of rounding noise, however small."""
    return float(f"{x:.{digits}g}") + 0.0


# ---------------------------------------------------------------------------------------- parameter values


def color(ps: Params, name: str, kind: str, ctx: Context, default: Optional[Tex] = None) -> Optional[Tex]:
    """A spectrum-valued parameter (`kind`: "albedo", "illuminant" or "unbounded") as a Tex, or `default`."""
    p = ps.get(name)
    if p is None:
        return default
    if p.type == "texture":
        return texture_ref(p, "spectrum", ctx)
    return Tex(spectrum_rgb(p, kind, ctx))


def scalar(ps: Params, name: str, ctx: Context, default: float) -> float:
    """A float-valued parameter that may name a float texture (a pattern stands in as its mean, with a warning)."""
    p = ps.get(name)
    if p is None:
        return default
    if p.type == "texture":
        tex = texture_ref(p, "float", ctx)
        if tex.pattern is not None:
            ctx.warn.once(("float-texture", name), p.where, f"'{name}' from a texture: lumos reads it as one number "
                          f"here, the texture's mean {tex.scalar:.3g}")
        return tex.scalar
    if p.type not in ("float", "integer") or len(p.values) != 1:
        raise p.where.error(f'"{p.type} {name}": expected one float')
    return float(p.values[0])


def texture_ref(p: Param, kind: str, ctx: Context) -> Tex:
    """The texture a `"texture name" "tex"` parameter names (a float texture serves as a grey spectrum one)."""
    if len(p.values) != 1:
        raise p.where.error(f'"texture {p.name}": expected one texture name')
    key = p.values[0]
    found = ctx.textures[kind].get(key)
    if found is None and kind == "spectrum":
        found = ctx.textures["float"].get(key)
    if found is None:
        defined = ", ".join(sorted(ctx.textures[kind])) or "none"
        raise p.where.error(f"unknown {kind} texture '{key}' (defined: {defined})")
    return found


def spectrum_rgb(p: Param, kind: str, ctx: Context) -> tuple:
    """The linear sRGB of an rgb, blackbody, spectrum or float parameter."""
    decl = f'"{p.type} {p.name}"'
    if p.type in ("float", "integer"):
        if len(p.values) != 1:
            raise p.where.error(f"{decl}: expected one value")
        return grey(p.values[0])
    if p.type == "rgb":
        if len(p.values) != 3:
            raise p.where.error(f"{decl}: expected 3 values, got {len(p.values)}")
        if min(p.values) < 0:
            raise p.where.error(f"{decl}: RGB values must not be negative")
        if kind == "albedo" and max(p.values) > 1:
            raise p.where.error(f"{decl}: a reflectance's RGB must not exceed 1 (pbrt refuses it too)")
        return tuple(float(v) for v in p.values)
    if p.type == "blackbody":
        if not p.values or not spectra.kelvin_ok(p.values[0]):
            raise p.where.error(f"{decl}: expected a temperature in kelvin > 0")
        return spectra.blackbody_rgb(p.values[0])
    if p.type == "spectrum":
        if len(p.values) == 1 and isinstance(p.values[0], str):
            return _named_rgb(p, kind, ctx)
        lam, values = samples(p, ctx)
        return spectra.illuminant_rgb(lam, values) if kind == "illuminant" else spectra.reflectance_rgb(lam, values)
    raise p.where.error(f"{decl}: expected rgb, spectrum, blackbody or texture")


def _named_rgb(p: Param, kind: str, ctx: Context) -> tuple:
    name = p.values[0]
    if name in spectra.NAMED_ILLUMINANTS:
        return spectra.NAMED_ILLUMINANTS[name]
    if name in spectra.NAMED_GLASSES:
        return grey(spectra.NAMED_GLASSES[name])
    lam, values = samples(p, ctx)
    return spectra.illuminant_rgb(lam, values) if kind == "illuminant" else spectra.reflectance_rgb(lam, values)


def samples(p: Param, ctx: Context) -> tuple[np.ndarray, np.ndarray]:
    """The (wavelengths, values) of a sampled spectrum: given inline, or read from a file of pairs."""
    if len(p.values) == 1 and isinstance(p.values[0], str):
        path = ctx.folder / p.values[0]
        if not path.is_file():
            raise p.where.error(f'"spectrum {p.name}": \'{p.values[0]}\' is neither one of pbrt\'s named spectra '
                                f"that lumos knows nor a file")
        tokens = [t for line in path.read_text(errors="replace").splitlines()
                  for t in line.split("#", 1)[0].replace(",", " ").split()]
        values = [number(t, Where(str(path), 1)) for t in tokens]
        if len(values) % 2 or not values:
            raise p.where.error(f"spectrum file '{p.values[0]}': expected (wavelength, value) pairs")
    else:
        values = p.values
    lam, val = np.asarray(values[0::2], dtype=np.float64), np.asarray(values[1::2], dtype=np.float64)
    if len(lam) == 0 or np.any(np.diff(lam) <= 0):
        raise p.where.error(f'"spectrum {p.name}": wavelengths must increase')
    return lam, val


# ---------------------------------------------------------------------------------------- Texture directives


def define_texture(st: Statement, ctx: Context, attributes: Optional[dict] = None) -> None:
    """A `Texture "name" "float"|"spectrum" "class" params` statement, stored in ctx.textures."""
    name, kind, cls = st.args
    if kind not in ("float", "spectrum"):
        raise st.where.error(f"Texture '{name}': type '{kind}' unknown (float or spectrum)")
    if name in ctx.textures[kind]:
        raise st.where.error(f"Texture '{name}': a {kind} texture of that name is already defined")
    defaults = attributes or {}
    ps = Params({**defaults, **st.params}, st.where, used=set(defaults) - set(st.params))
    value_kind = "albedo" if kind == "spectrum" else "float"
    ctx.textures[kind][name] = _texture(cls, ps, value_kind, ctx, st.where)
    ps.ignore("filter", "maxanisotropy", "encoding")
    for p in ps.unused():
        ctx.warn.once(("param", "Texture", cls, p.name), p.where, f"Texture '{cls}': parameter \"{p.type} {p.name}\""
                      f" is not used")


def _value(ps: Params, name: str, kind: str, ctx: Context, default: float) -> Tex:
    if kind == "float":
        p = ps.get(name)
        if p is not None and p.type == "texture":
            return texture_ref(p, "float", ctx)
        return Tex(grey(scalar(ps, name, ctx, default)))
    return color(ps, name, "unbounded" if kind == "unbounded" else kind, ctx, Tex(grey(default)))


def _texture(cls: str, ps: Params, kind: str, ctx: Context, where: Where) -> Tex:
    mapping = ps.string("mapping", "uv")
    if mapping != "uv":
        ctx.warn.once(("mapping", mapping), where, f"texture mapping '{mapping}' is not supported: the shapes' (u, v)"
                      f" stand in")
    if cls == "constant":
        return _value(ps, "value", kind, ctx, 1.0)
    if cls == "scale":
        a, b = _value(ps, "tex", kind, ctx, 1.0), _value(ps, "scale", kind, ctx, 1.0)
        if a.pattern is None:
            a, b = b, a
        if b.pattern is not None:
            ctx.warn.once(("scale-two-patterns",), where, "Texture 'scale' of two patterns: the second one's mean "
                          "colour stands in for it")
        return a.times(b.mean)
    if cls in ("mix", "directionmix"):
        a, b = _value(ps, "tex1", kind, ctx, 0.0), _value(ps, "tex2", kind, ctx, 1.0)
        amount = scalar(ps, "amount", ctx, 0.5) if cls == "mix" else 0.5
        if cls == "directionmix" or a.pattern is not None or b.pattern is not None:
            ctx.warn.once(("texture", cls), where, f"Texture '{cls}' is not supported: the blend of its textures' "
                          f"mean colours stands in")
            ps.ignore("dir")
        return Tex(tuple((1 - amount) * x + amount * y for x, y in zip(a.mean, b.mean)))
    if cls == "imagemap":
        return _imagemap(ps, ctx, where)
    if cls == "checkerboard":
        return _checkerboard(ps, kind, ctx, where)
    if cls == "bilerp":
        corners = [_value(ps, n, kind, ctx, d).mean for n, d in (("v00", 0), ("v01", 1), ("v10", 0), ("v11", 1))]
        ctx.warn.once(("texture", cls), where, "Texture 'bilerp' is not supported: the mean of its corners stands in")
        return Tex(tuple(float(np.mean(c)) for c in zip(*corners)))
    known = cls in _STAND_IN_CLASSES
    ctx.warn.once(("texture", cls), where, f"Texture '{cls}' is {'not supported' if known else 'unknown'}: a grey "
                  f"0.5 stands in")
    ps.ignore(*ps.params)
    return Tex(_GREY)


def _uv_map(ps: Params) -> dict:
    su, sv = ps.float("uscale", 1.0), ps.float("vscale", 1.0)
    return {"scale": [abs(su) or 1.0, abs(sv) or 1.0], "offset": [ps.float("udelta", 0.0), ps.float("vdelta", 0.0)]}


def _imagemap(ps: Params, ctx: Context, where: Where) -> Tex:
    filename = ps.string("filename", None)
    if not filename:
        raise where.error("Texture 'imagemap' needs \"string filename\"")
    path = ctx.folder / filename
    if not path.is_file():
        raise where.error(f"Texture 'imagemap': no such file '{filename}'")
    factor = grey(ps.float("scale", 1.0))
    if ps.bool("invert", False):
        ctx.warn.once(("invert",), where, "imagemap \"bool invert\" is not supported: the image as it is stands in")
    wrap = ps.string("wrap", "repeat")
    if wrap not in ("repeat", "clamp"):
        ctx.warn.once(("wrap", wrap), where, f"imagemap wrap '{wrap}' is not supported: clamp stands in")
    if path.suffix.lower() in _PATTERN_FILES:
        encoding = ps.string("encoding", "sRGB")
        if encoding != "sRGB":
            ctx.warn.once(("encoding", encoding), where, f"imagemap encoding '{encoding}': lumos decodes 8-bit "
                          f"images as sRGB")
        pattern = {"type": "image", "file": filename, **_uv_map(ps), "wrap": "repeat" if wrap == "repeat" else "clamp"}
        return Tex(factor, pattern, image=path)
    mean = _image_mean(path)
    stand_in = f"its mean colour ({', '.join(f'{c:.3g}' for c in mean)})"
    ctx.warn.once(("imagemap-format", path.suffix.lower()), where, f"imagemap '{filename}': lumos textures are PNG "
                  f"or JPEG images; {stand_in} stands in")
    return Tex(tuple(m * f for m, f in zip(mean, factor)))


def _checkerboard(ps: Params, kind: str, ctx: Context, where: Where) -> Tex:
    if ps.int("dimension", 2) != 2:
        ctx.warn.once(("checkerboard3d",), where, "Texture 'checkerboard' of dimension 3 is not supported: the 2D "
                      "checkerboard over (u, v) stands in")
    a, b = _value(ps, "tex1", kind, ctx, 1.0), _value(ps, "tex2", kind, ctx, 0.0)
    if a.pattern is not None or b.pattern is not None:
        ctx.warn.once(("checker-of-textures",), where, "Texture 'checkerboard' of textures: their mean colours stand "
                      "in for them")
    colors = [list(a.mean), list(b.mean)]
    mean = tuple((x + y) / 2 for x, y in zip(a.mean, b.mean))
    return Tex((1.0, 1.0, 1.0), {"type": "checker", "colors": colors, **_uv_map(ps)}, mean)
