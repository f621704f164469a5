"""Mitsuba 3 BSDFs and textures → lumos materials: one small function per plugin (`BSDFS`).

    material = bsdf_material(node, ctx)       # a lumos material dict, or None for Mitsuba's `null` BSDF
    rgb, texture = color(node, "reflectance", 0.5, ctx, apply_to="kd")   # a colour or a texture parameter

Each BSDF is read as the lumos material that `path` renders closest to it: metals as lumos's `conductor`
(GGX microfacets, the exact Fresnel factor of η + ik), plastics as lumos's `plastic` (a diffuse base under a
GGX or smooth dielectric coat, Mitsuba's own model), glass (smooth or rough) as lumos's `dielectric` (GGX
reflection and refraction, Walter et al. 2007), the others as the classic model's coefficients; the reasons and
the numbers are in docs/formats.md ("Mitsuba 3 scenes").
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Optional

import numpy as np

from ..errors import LumosError, LumosWarning
from ..scene.materials import Dielectric, Principled, phong_exponent  # (phong_exponent: a Phong lobe as wide as GGX)
from .mitsuba_data import CONDUCTORS, IORS, conductor_reflectance, named_ior, spectrum_rgb, uniform_spectrum_rgb
from .mitsuba_xml import Node, Spectrum, Value, Where, find_file

#: image formats a lumos texture reads
_TEXTURE_FORMATS = (".png", ".jpg", ".jpeg")


class Context:
    """What the conversion of one scene file shares: the main file (paths are written relative to its folder),
    the lines of the lumos keys made (`at`), the warnings already given (`warn` says each once) and the named
    materials made from BSDFs with an id."""

    def __init__(self, main: Path, folders: Optional[list] = None):
        self.main = main
        self.folders = list(folders or [])
        self.lines: dict[tuple, int] = {}
        self.materials: dict[str, dict] = {}
        self._material_of: dict[int, Optional[dict]] = {}
        self._warned: set = set()

    def warn(self, key, where: Where, message: str) -> None:
        """One LumosWarning `<file>:<line>: <message>` for each distinct key (a plugin, a stand-in)."""
        if key not in self._warned:
            self._warned.add(key)
            warnings.warn(LumosWarning(f"{where}: {message}"), stacklevel=2)

    def at(self, key_path: tuple, where: Where) -> None:
        self.lines.setdefault(key_path, where.top)

    def file(self, node: Node, key: str = "filename") -> tuple[str, Path]:
        """A file parameter as lumos writes it (relative to the main file's folder when it lies below it) and
        the path itself; an error when the file is not there (looked for as Mitsuba's file resolver does:
        relative to the file the element is in, to the main file's folder, then in the `<path>` folders)."""
        name = node.string(key)
        if name is None:
            raise node.where.error(f"{node.label()} needs <string name=\"{key}\" value=\"...\"/>")
        where = node.where_of(key)
        path = find_file(name, [where.file.parent, self.main.parent] + self.folders)
        if path is None or not path.is_file():
            raise where.error(f"{node.label()}: file '{name}' not found")
        try:
            return str(path.resolve().relative_to(self.main.parent.resolve())), path
        except ValueError:
            return str(path.resolve()), path


# ------------------------------------------------------------------------------------------------ colours


def color(node: Node, name: str, default, ctx: Context, apply_to: str = "kd",
          emitter: bool = False, bounded: bool = True) -> tuple[tuple, Optional[dict]]:
    """A colour parameter as (linear RGB, texture dict or None): a number (grey), `<rgb>`, `<spectrum>` (as
    Mitsuba's RGB variants read it: mitsuba_data) or a texture. A texture comes back with rgb (1, 1, 1) and a
    lumos texture applied to `apply_to` that replaces it (multiply it by a factor for a scaled parameter)."""
    item = node.props.get(name)
    if item is None:
        return _rgb(default), None
    if isinstance(item, Node):
        return texture(item, ctx, apply_to, emitter)
    return value_rgb(item, node, name, emitter, bounded), None


def value_rgb(item: Value, node: Node, name: str, emitter: bool = False, bounded: bool = True) -> tuple:
    if item.kind in ("float", "integer"):
        return _rgb(float(item.value))
    if item.kind == "rgb":
        return tuple(float(c) for c in item.value)
    if item.kind == "spectrum":
        return spectrum_color(item.value, emitter, bounded)
    raise item.where.error(f"{node.label()}: '{name}' must be a colour (<rgb>, <spectrum>, <float> or a "
                           f"<texture>), got <{item.kind}>")


def spectrum_color(spectrum: Spectrum, emitter: bool, bounded: bool = True) -> tuple:
    if not spectrum.wavelengths:
        return uniform_spectrum_rgb(spectrum.values[0], emitter)
    return spectrum_rgb(spectrum.wavelengths, spectrum.values, d65=not emitter, bounded=bounded and not emitter)


def scalar(node: Node, name: str, default: float, ctx: Context) -> float:
    """A float parameter that Mitsuba also takes as a texture (roughness, alpha…): a texture stands in as the
    default, with a warning."""
    item = node.props.get(name)
    if isinstance(item, Node):
        ctx.warn(("textured", node.type, name), item.where, f"{node.type}: a textured '{name}' is not read; "
                 f"{default:g} stands in")
        return default
    return node.float(name, default)


def _rgb(value) -> tuple:
    if isinstance(value, (int, float)):
        return (float(value),) * 3
    return tuple(float(c) for c in value)


def _scaled(rgb, factor) -> list:
    return [round(float(c) * float(f), 9) for c, f in zip(rgb, np.broadcast_to(factor, 3))]


# ------------------------------------------------------------------------------------------------ textures


def texture(node: Node, ctx: Context, apply_to: str, emitter: bool = False) -> tuple[tuple, Optional[dict]]:
    """A `<texture>` (or `<spectrum type=...>`) as (rgb, lumos texture or None)."""
    kind = node.type
    if kind == "bitmap":
        return _bitmap(node, ctx, apply_to)
    if kind == "checkerboard":
        return _checkerboard(node, ctx, apply_to)
    if kind in ("srgb", "d65"):
        return color(node, "color", 1.0, ctx, apply_to, emitter)[0], None
    if kind == "uniform":
        return _rgb(node.float("value", 1.0)), None
    if kind in ("regular", "irregular") and node.value("value", ("spectrum",), "a <spectrum>"):
        return spectrum_color(node.props["value"].value, emitter), None
    ctx.warn(("texture", kind), node.where, f"texture '{kind}' is not supported; a 0.5 grey stands in")
    return (0.5, 0.5, 0.5), None


def _uv_map(node: Node, ctx: Context, factor: float = 1.0) -> dict:
    """`to_uv` (scale and translation only) as lumos's scale and offset, times `factor` (a checkerboard's 2)."""
    m = node.transform("to_uv")
    a, t = m[:2, :2], m[:2, 3]
    out = {}
    if abs(a[0, 1]) > 1e-12 or abs(a[1, 0]) > 1e-12 or a[0, 0] <= 0 or a[1, 1] <= 0:
        ctx.warn(("to_uv", node.type), node.where_of("to_uv"), f"{node.type}: to_uv with a rotation or a mirror "
                 f"is not read (only a positive scale and a translation)")
        return out
    if not np.allclose(np.diag(a), 1.0 / factor):
        out["scale"] = [float(a[0, 0] * factor), float(a[1, 1] * factor)]
    if np.any(t):
        out["offset"] = [float(t[0] * factor), float(t[1] * factor)]
    return out


def _bitmap(node: Node, ctx: Context, apply_to: str) -> tuple[tuple, Optional[dict]]:
    rel, path = ctx.file(node)
    if path.suffix.lower() not in _TEXTURE_FORMATS:
        mean = _mean_image(path)
        ctx.warn(("bitmap format", path.suffix.lower()), node.where, f"bitmap '{path.name}': lumos textures are "
                 f"PNG or JPEG; its mean colour stands in")
        return mean, None
    tex = {"type": "image", "file": rel, "apply_to": [apply_to], **_uv_map(node, ctx)}
    wrap = node.string("wrap_mode", "repeat")
    if wrap == "clamp":
        tex["wrap"] = "clamp"
    elif wrap == "mirror":
        ctx.warn(("wrap", "mirror"), node.where, "bitmap: wrap_mode mirror is read as repeat")
    if node.bool("raw", False) and apply_to != "opacity":
        ctx.warn(("raw",), node.where, "bitmap: raw=true is not read (lumos decodes colour images as sRGB)")
    return (1.0, 1.0, 1.0), tex


def _checkerboard(node: Node, ctx: Context, apply_to: str) -> tuple[tuple, Optional[dict]]:
    """Mitsuba's checkerboard is color0 where both frac(u) and frac(v) are on the same side of 0.5: lumos's
    checker of the uv scaled by 2 (color0 where floor(2u) + floor(2v) is even)."""
    colors = []
    for key, default in (("color0", 0.4), ("color1", 0.2)):
        rgb, tex = color(node, key, default, ctx, apply_to)
        if tex is not None:
            ctx.warn(("checkerboard", "nested"), node.where, "checkerboard: a textured colour is not read")
        colors.append(list(rgb))
    return (1.0, 1.0, 1.0), {"type": "checker", "colors": colors, "apply_to": [apply_to],
                             **{"scale": 2.0, **_uv_map(node, ctx, 2.0)}}


def _mean_image(path: Path) -> tuple:
    """The mean colour of an image file lumos can read (EXR, PFM, NPY, PNG…), else 0.5 grey."""
    from .image_files import read_image

    try:
        return tuple(float(c) for c in read_image(path).reshape(-1, 3).mean(axis=0))
    except (LumosError, OSError, ValueError):
        return (0.5, 0.5, 0.5)


def with_texture(material: dict, tex: Optional[dict], mode: str = "replace") -> dict:
    if tex is not None:
        if mode != "replace":
            tex = {**tex, "mode": mode}
        material["texture"] = material["texture"] + [tex] if "texture" in material else [tex]
    return material


# ------------------------------------------------------------------------------------------------ BSDFs


def bsdf_material(node: Node, ctx: Context) -> Optional[dict]:
    """The lumos material of a `<bsdf>`; None for `null` (nothing there)."""
    if id(node) not in ctx._material_of:
        if node.tag != "bsdf":
            raise node.where.error(f"a <bsdf> is expected here, not <{node.tag} type='{node.type}'>")
        read = BSDFS.get(node.type)
        if read is None:
            ctx.warn(("bsdf", node.type), node.where, f"bsdf '{node.type}' is not supported; a diffuse 0.5 grey "
                     f"(Mitsuba's default BSDF) stands in")
            read = lambda n, c: {"kd": 0.5}  # noqa: E731
        ctx._material_of[id(node)] = read(node, ctx)
    return ctx._material_of[id(node)]


def nested_bsdf(node: Node, ctx: Context) -> Optional[Node]:
    inner = [child for _, child in node.children("bsdf")]
    if not inner:
        raise node.where.error(f"{node.label()} needs a nested <bsdf>")
    return inner[0]


def _alpha(node: Node, ctx: Context) -> float:
    if "alpha_u" in node.props or "alpha_v" in node.props:
        au, av = scalar(node, "alpha_u", 0.1, ctx), scalar(node, "alpha_v", 0.1, ctx)
        if abs(au - av) > 1e-9:
            ctx.warn(("anisotropic", node.type), node.where, f"{node.type}: anisotropic roughness is read as "
                     f"its mean (alpha {0.5 * (au + av):g})")
        return 0.5 * (au + av)
    return scalar(node, "alpha", 0.1, ctx)


def ior(node: Node, default_int: str = "bk7") -> float:
    """int_ior / ext_ior (numbers or Mitsuba's names), or `eta` (the ratio) when given."""
    if "eta" in node.props:
        return node.float("eta")
    return _ior_value(node, "int_ior", default_int) / _ior_value(node, "ext_ior", "air")


def _ior_value(node: Node, name: str, default: str) -> float:
    item = node.props.get(name)
    if item is None:
        return IORS[default]
    if isinstance(item, Value) and item.kind == "string":
        value = named_ior(item.value)
        if value is None:
            raise item.where.error(f"{node.label()}: unknown {name} '{item.value}' (names: {', '.join(IORS)})")
        return value
    value = node.float(name)
    if value <= 0:
        raise item.where.error(f"{node.label()}: {name} must be positive, got {value:g}")
    return value


def fresnel0(eta: float) -> float:
    """The normal-incidence Fresnel reflectance of a dielectric interface of relative IOR eta."""
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def _diffuse(node: Node, ctx: Context) -> dict:
    rgb, tex = color(node, "reflectance", 0.5, ctx, "kd")
    return with_texture({"kd": list(rgb)}, tex)


def _dielectric(node: Node, ctx: Context) -> dict:
    """A smooth dielectric: lumos's `dielectric` with α 0 (int_ior and ext_ior, or `eta` as ior over 1; the
    specular reflectance and transmittance as its two tints)."""
    if "eta" in node.props:
        inside, outside = node.float("eta"), 1.0
    else:
        inside, outside = _ior_value(node, "int_ior", "bk7"), _ior_value(node, "ext_ior", "air")
    if inside == outside:
        raise node.where.error(f"{node.label()}: int_ior and ext_ior are equal (no interface)")
    tint, _ = color(node, "specular_reflectance", 1.0, ctx)
    through, _ = color(node, "specular_transmittance", 1.0, ctx)
    glass = {"ior": inside, "ext_ior": outside}
    if any(c != 1.0 for c in tint):
        glass["tint"] = [min(c, 1.0) for c in tint]
    if any(c != 1.0 for c in through):
        glass["transmit_tint"] = [min(c, 1.0) for c in through]
    return {"dielectric": glass}


def _roughdielectric(node: Node, ctx: Context) -> dict:
    """A rough dielectric: lumos's `dielectric` with Mitsuba's α (or [αu, αv]); GGX, so Mitsuba's default
    Beckmann lobe is read as GGX of the same α (a warning); `sample_visible` is not read (lumos always samples
    the visible normals)."""
    material = _dielectric(node, ctx)
    material["dielectric"]["alpha"] = _ggx_alpha(node, ctx)
    return material


def _thindielectric(node: Node, ctx: Context) -> dict:
    """A thin sheet: light goes straight through; the sheet's two faces reflect R + T²R/(1 − R²) = 2R/(1 + R)
    of it (the interreflection series), read at normal incidence as a mirror, the rest passed on (ior 1)."""
    r = fresnel0(ior(node))
    reflected = 2.0 * r / (1.0 + r)
    ctx.warn(("bsdf", node.type), node.where, f"thindielectric: read as a mirror of {reflected:.3f} (its "
             f"normal-incidence reflectance) and a straight pass-through of the rest")
    return {"kr": reflected, "kt": 1.0 - reflected, "ior": 1.0}


def _conductor_ior(node: Node, ctx: Context) -> dict:
    """The complex IOR of a conductor as lumos's `conductor` keys: η and k of its preset (`material`, the RGB
    values Mitsuba's RGB variants load: mitsuba_data.CONDUCTORS) or given (`eta`, `k`); none for `material`
    "none" (Mitsuba's default: η 0, k 1, a perfect reflector, which is lumos's conductor without η and k)."""
    preset = node.string("material", "none")
    if "eta" in node.props or "k" in node.props:
        if preset != "none":
            raise node.where.error(f"{node.label()}: give either material or eta and k, not both")
        eta, _ = color(node, "eta", 0.0, ctx, bounded=False)
        k, _ = color(node, "k", 1.0, ctx, bounded=False)
    elif preset == "none":
        return {}
    elif preset in CONDUCTORS:
        eta, k = CONDUCTORS[preset]
    else:
        raise node.where_of("material").error(f"{node.label()}: unknown conductor material '{preset}' "
                                              f"(presets: {', '.join(CONDUCTORS)})")
    return {"eta": [float(c) for c in eta], "k": [float(c) for c in k]}


def _conductor(node: Node, ctx: Context) -> dict:
    """A smooth metal: lumos's `conductor` (the exact Fresnel factor of η + ik) with α 0."""
    tint, _ = color(node, "specular_reflectance", 1.0, ctx)
    return {"conductor": {**_conductor_ior(node, ctx), "tint": [min(c, 1.0) for c in tint]}}


def _roughconductor(node: Node, ctx: Context) -> dict:
    """A rough metal: lumos's `conductor` with Mitsuba's α (GGX; Mitsuba's default Beckmann lobe is read as the
    GGX lobe of the same α, a little narrower in its tails)."""
    material = _conductor(node, ctx)
    material["conductor"]["alpha"] = _ggx_alpha(node, ctx)
    return material


def _ggx_alpha(node: Node, ctx: Context):
    """A rough plugin's `alpha` (or `alpha_u`/`alpha_v`, default 0.1) as lumos's: one number or [αu, αv], each
    at most 1; Mitsuba's default Beckmann distribution is read as GGX of the same α (a warning per plugin)."""
    if "alpha_u" in node.props or "alpha_v" in node.props:
        alpha = [scalar(node, "alpha_u", 0.1, ctx), scalar(node, "alpha_v", 0.1, ctx)]
    else:
        alpha = [scalar(node, "alpha", 0.1, ctx)] * 2
    if max(alpha) > 1.0:
        ctx.warn(("alpha > 1", node.type), node.where, f"{node.type}: alpha above 1 is read as 1 (lumos's widest)")
    alpha = [min(a, 1.0) for a in alpha]
    distribution = node.string("distribution", "beckmann")
    if distribution != "ggx":
        ctx.warn(("distribution", node.type), node.where, f"{node.type}: the {distribution} distribution is "
                 f"read as GGX of the same alpha (lumos's microfacet lobe)")
    return alpha[0] if alpha[0] == alpha[1] else alpha


def _plastic(node: Node, ctx: Context) -> dict:
    """Mitsuba's plastic: a diffuse base under a Fresnel-reflecting coat, lumos's `plastic` (smooth): kd the
    base's reflectance, the coat's index and specular tint."""
    rgb, tex = color(node, "diffuse_reflectance", 0.5, ctx, "kd")
    spec, _ = color(node, "specular_reflectance", 1.0, ctx)
    if node.bool("nonlinear", False):
        ctx.warn(("nonlinear", node.type), node.where, f"{node.type}: nonlinear=true is read as false (lumos's "
                 f"plastic divides by the coat's internal reflectance alone)")
    material = {"kd": list(rgb)} if tex is None else with_texture({"kd": [1.0] * 3}, tex, "multiply")
    material["plastic"] = {"ior": ior(node, "polypropylene"), "tint": [min(c, 1.0) for c in spec]}
    return material


def _roughplastic(node: Node, ctx: Context) -> dict:
    """Mitsuba's roughplastic: lumos's `plastic` with Mitsuba's α (its tables are Mitsuba's; the Beckmann
    default is read as GGX of the same α)."""
    material = _plastic(node, ctx)
    alpha = _alpha(node, ctx)
    if alpha > 1.0:
        ctx.warn(("alpha > 1", node.type), node.where, f"{node.type}: alpha above 1 is read as 1 (lumos's widest)")
    material["plastic"]["alpha"] = min(alpha, 1.0)
    distribution = node.string("distribution", "beckmann")
    if distribution != "ggx":
        ctx.warn(("distribution", node.type), node.where, f"{node.type}: the {distribution} distribution is "
                 f"read as GGX of the same alpha (lumos's microfacet lobe)")
    return material


def _principled(node: Node, ctx: Context) -> dict:
    """Disney's principled BSDF (Mitsuba 3's `principled`) as lumos's `principled` material, glTF's
    metallic–roughness BRDF, which shares its base colour, metallic and roughness (GGX α = r² in both), its
    specular (F0 = 0.08·specular, or from eta: read as the index whose F0 that is), spec_trans (smooth glass of
    that index) and a clear coat (Disney's GTR1 width mix(0.1, 0.001, clearcoat_gloss) read as a GGX coat of that
    width). Sheen, anisotropy, spec_tint and flatness are not read (one warning naming those given)."""
    base, tex = color(node, "base_color", 0.5, ctx, "base_color")
    if "eta" in node.props:
        eta = node.float("eta")
    else:
        eta = 2.0 / (1.0 - math.sqrt(0.08 * scalar(node, "specular", 0.5, ctx))) - 1.0
    gloss = scalar(node, "clearcoat_gloss", 0.0, ctx)
    model = {"base_color": list(base), "metallic": scalar(node, "metallic", 0.0, ctx),
             "roughness": scalar(node, "roughness", 0.5, ctx), "ior": max(eta, 1.0),
             "transmission": scalar(node, "spec_trans", 0.0, ctx),
             "clearcoat": scalar(node, "clearcoat", 0.0, ctx),
             "clearcoat_roughness": math.sqrt(0.1 + (0.001 - 0.1) * gloss)}
    unread = [k for k in ("sheen", "sheen_tint", "anisotropic", "spec_tint", "flatness") if k in node.props]
    if unread:
        ctx.warn(("principled", tuple(unread)), node.where, f"principled: {', '.join(unread)} not read (lumos's "
                 "principled material is glTF's metallic-roughness BRDF)")
    material = {"principled": model}
    if tex is not None:  # the base colour's map, and the classic coefficients that carry it (the local methods)
        classic = Principled(**model).classic()
        targets = [k for k in ("ka", "kd", "ks", "kr") if np.any(np.asarray(classic[k]) > 0)]
        tex = {**tex, "apply_to": ["base_color", *targets]}
    return with_texture(material, tex, "multiply")


def _twosided(node: Node, ctx: Context) -> Optional[dict]:
    """lumos's surfaces reflect on both sides: the nested BSDF (the front one, if two are given)."""
    inner = [child for _, child in node.children("bsdf")]
    if len(inner) > 1:
        ctx.warn(("twosided", 2), node.where, "twosided with two BSDFs: the first is used on both sides")
    return bsdf_material(nested_bsdf(node, ctx), ctx)


def _blendbsdf(node: Node, ctx: Context) -> Optional[dict]:
    """(1 − weight)·first + weight·second, coefficient by coefficient (the same lobes mix linearly)."""
    inner = [child for _, child in node.children("bsdf")]
    if len(inner) != 2:
        raise node.where.error(f"{node.label()} needs two nested <bsdf>s, got {len(inner)}")
    w = scalar(node, "weight", 0.5, ctx)
    a, b = (_classic(bsdf_material(child, ctx) or {}) for child in inner)
    if "texture" in a or "texture" in b:
        ctx.warn(("blendbsdf", "texture"), node.where, "blendbsdf: the textures of the blended BSDFs are not read")
    out = {}
    for key in ("kd", "ks", "kr", "kt"):
        mixed = (1 - w) * np.asarray(a.get(key, 0.0)) + w * np.asarray(b.get(key, 0.0))
        if np.any(mixed):
            out[key] = np.broadcast_to(mixed, 3).tolist()
    for key in ("shininess", "ior", "fresnel"):
        if key in a or key in b:
            out[key] = (b if key in b and (w > 0.5 or key not in a) else a)[key]
    return out


def _classic(material: dict) -> dict:
    """A material's classic coefficients: a `conductor` as its head-on reflectance F0, a mirror `kr` (α below
    0.01) or a Phong lobe `ks` as wide as its GGX lobe (as lumos's local methods read one); a `dielectric` as
    `Dielectric.classic`."""
    if "dielectric" in material:  # glass: its classic reading (kt, ior, fresnel, a highlight)
        return {**Dielectric(**material["dielectric"]).classic(), **{k: v for k, v in material.items()
                                                                     if k != "dielectric"}}
    metal = material.get("conductor")
    if metal is None:
        return material
    f0 = conductor_reflectance(metal["eta"], metal["k"]) if "eta" in metal else (1.0, 1.0, 1.0)
    f0 = [f * t for f, t in zip(f0, metal.get("tint", (1.0, 1.0, 1.0)))]
    alpha = float(np.mean(metal.get("alpha", 0.0)))
    return {"kr": f0} if alpha < 0.01 else {"ks": f0, "shininess": phong_exponent(alpha)}


def _mask(node: Node, ctx: Context) -> Optional[dict]:
    material = dict(bsdf_material(nested_bsdf(node, ctx), ctx) or {})
    item = node.props.get("opacity")
    if isinstance(item, Node) and item.type == "bitmap":
        _, tex = _bitmap(item, ctx, "opacity")
        ctx.warn(("mask",), node.where, "mask: the opacity map is read as a cut-out (opaque where it is ≥ 0.5)")
        return with_texture(material, tex)
    ctx.warn(("mask", "constant"), node.where, "mask: a constant opacity is not read (the surface is opaque)")
    return material


def _bumpmap(node: Node, ctx: Context) -> Optional[dict]:
    material = dict(bsdf_material(nested_bsdf(node, ctx), ctx) or {})
    maps = [child for _, child in node.children("texture") if child.type == "bitmap"]
    if maps:
        rel, _ = ctx.file(maps[0])
        material["bump"] = {"type": "image", "file": rel, "strength": node.float("scale", 1.0)}
        ctx.warn(("bumpmap",), node.where, "bumpmap: read as a lumos height map of strength = scale (Mitsuba "
                 "scales the gradient in uv, lumos the height in scene units: the depth differs)")
    return material


def _normalmap(node: Node, ctx: Context) -> Optional[dict]:
    material = dict(bsdf_material(nested_bsdf(node, ctx), ctx) or {})
    item = node.props.get("normalmap")
    if isinstance(item, Node) and item.type == "bitmap":
        material["bump"] = {"type": "normal", "file": ctx.file(item)[0]}
    else:
        ctx.warn(("normalmap",), node.where, "normalmap: only a bitmap normal map is read")
    return material


def _null(node: Node, ctx: Context) -> None:
    return None


#: Mitsuba BSDF plugin → its reading as a lumos material dict (None: nothing there, Mitsuba's `null`)
BSDFS = {
    "diffuse": _diffuse, "dielectric": _dielectric, "roughdielectric": _roughdielectric,
    "thindielectric": _thindielectric, "conductor": _conductor, "roughconductor": _roughconductor,
    "plastic": _plastic, "roughplastic": _roughplastic, "pplastic": _roughplastic, "principled": _principled,
    "twosided": _twosided, "blendbsdf": _blendbsdf, "mask": _mask, "bumpmap": _bumpmap, "normalmap": _normalmap,
    "null": _null,
}
