"""pbrt-v4 materials as lumos materials: `conductor`, `dielectric` and `coateddiffuse` as lumos's microfacet
`conductor`, `dielectric` and `plastic`, the others as the classic coefficients (kd, ks + shininess, kr, kt + ior).

    spec = MaterialSpec("coateddiffuse", params, where)
    lumos_material(spec, ctx, named)       # {"kd": ..., "plastic": {...}, "texture": [...]} (scene-format keys)

pbrt-v4's roughness r is the Trowbridge–Reitz α = √r (α = r with `"bool remaproughness" false`). Where lumos has
no microfacet material (a conductor given by its reflectance), a rough surface is a Phong lobe of
the same width: glTF's mapping (`gltf_materials.shininess`, Beckmann α, Walter et al. 2007). One function per
material type (`_diffuse`, `_conductor`…); each stand-in warns once per type. The table is in docs/formats.md
("pbrt-v4 scenes").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from . import pbrt_spectra as spectra
from ..scene.materials import METALS, Dielectric
from .gltf_materials import shininess
from .pbrt_textures import Context, Tex, color, grey, samples, scalar, texture_ref, tidy
from .pbrt_tokens import Params, Where

#: the colour of pbrt's default "diffuse" material (reflectance 0.5)
DEFAULT_MATERIAL = {"kd": 0.5}
_WHITE = (1.0, 1.0, 1.0)
#: wavelength at which a dielectric's η spectrum is read (lumos's ior is one number)
_ETA_NM = 550.0
#: the materials that stand in for what pbrt does, and what the warning says
_STAND_INS = {
    "coateddiffuse": "lumos's plastic (a Lambertian base under a GGX coat, Mitsuba's roughplastic model); pbrt's "
                     "stochastic layers are not simulated",
    "coatedconductor": "the conductor's head-on reflectance under a head-on-Fresnel coat (kr mirror / ks Phong)",
    "thindielectric": "a mirror of the sheet's head-on reflectance and a straight pass-through (kr + kt, ior 1)",
    "diffusetransmission": "kd for its reflectance and a straight pass-through (kt, ior 1) for its transmittance",
    "interface": "a surface that rays pass straight through (kt 1, ior 1); participating media are not read",
    "hair": "a diffuse surface of its colour",
    "measured": "pbrt's default grey diffuse (kd 0.5)",
    "subsurface": "a diffuse surface of its reflectance (0.5 when not given)",
}


@dataclass
class MaterialSpec:
    """A Material or MakeNamedMaterial statement: its type, parameters and place."""

    kind: str
    params: Params
    where: Where


def lumos_material(spec: MaterialSpec, ctx: Context, named: dict, depth: int = 0) -> dict:
    """The lumos material of a pbrt material statement (`named`: name → MaterialSpec, for `mix`)."""
    kind = "interface" if spec.kind in ("", "none") else spec.kind
    ps = spec.params
    convert: Optional[Callable] = _CONVERTERS.get(kind)
    if kind == "mix":
        out = _mix(spec, ctx, named, depth)
    elif convert is None:
        ctx.warn.once(("material", kind), spec.where, f"Material '{kind}' is unknown: pbrt's default grey diffuse "
                      f"(kd 0.5) stands in")
        ps.ignore(*ps.params)
        out = dict(DEFAULT_MATERIAL)
    else:
        if kind in _STAND_INS:
            ctx.warn.once(("material", kind), spec.where, f"Material '{kind}' is not supported: "
                          f"{_STAND_INS[kind]} stands in")
        out = convert(ps, ctx, spec.where)
    _common(ps, out, ctx, spec.where)
    for p in ps.unused():
        ctx.warn.once(("param", "Material", kind, p.name), p.where, f"Material '{kind}': parameter "
                      f"\"{p.type} {p.name}\" is not used")
    return out


def _common(ps: Params, out: dict, ctx: Context, where: Where) -> None:
    """What every material may have: a normal map, or a bump map (pbrt's `displacement`, a height in scene units:
    lumos's `bump: {type: image}` of the same image, `strength` the texture's scale), and the type name of a named
    material."""
    ps.ignore("type")
    normal_map = ps.string("normalmap", None)
    if normal_map:
        if not (ctx.folder / normal_map).is_file():
            raise where.error(f"normalmap: no such file '{normal_map}'")
        out["bump"] = {"type": "normal", "file": normal_map}
    p = ps.get("displacement")
    if p is None or normal_map:
        return
    tex = texture_ref(p, "float", ctx) if p.type == "texture" else None
    if tex is not None and tex.pattern is not None and tex.pattern["type"] == "image" and tex.rgb[0] > 0:
        out["bump"] = {**{k: v for k, v in tex.pattern.items() if k != "type"}, "type": "image",
                       "strength": tex.rgb[0]}
    else:
        ctx.warn.once(("displacement",), where, "\"displacement\" other than an image texture is not read: the "
                      "surface is drawn without it")


# ------------------------------------------------------------------------------------ one function per type


def _apply(out: dict, key: str, tex: Tex, factor=_WHITE) -> None:
    """out[key] = tex × factor; a patterned tex adds a lumos texture that multiplies out[key]."""
    out[key] = [tidy(a * b, 7) for a, b in zip(tex.rgb, factor)]
    if tex.pattern is not None:
        out.setdefault("texture", []).append({**tex.pattern, "apply_to": [key], "mode": "multiply"})


def _alpha(ps: Params, ctx: Context, prefix: str = "") -> float:
    """The Trowbridge–Reitz α of a material's roughness (the mean of u and v for an anisotropic one)."""
    rough = scalar(ps, prefix + "roughness", ctx, 0.0)
    u, v = scalar(ps, prefix + "uroughness", ctx, rough), scalar(ps, prefix + "vroughness", ctx, rough)
    remap = ps.bool("remaproughness", True)
    alphas = [math.sqrt(max(r, 0.0)) if remap else max(r, 0.0) for r in (u, v)]
    return 0.5 * (alphas[0] + alphas[1])


def _specular(out: dict, tex: Tex, alpha: float, factor=_WHITE) -> None:
    """A specular reflection of colour tex × factor: a mirror (kr) when smooth, a Phong lobe (ks) of the same width
    when rough — with glTF's split, the share g = (1 − √α)² that stays a sharp mirror."""
    if alpha <= 1e-4:
        _apply(out, "kr", tex, factor)
        return
    alpha = min(alpha, 1.0)
    g = (1.0 - math.sqrt(alpha)) ** 2
    _apply(out, "ks", tex, tuple(f * (1.0 - g) for f in factor))
    if g > 1e-3:
        _apply(out, "kr", tex, tuple(f * g for f in factor))
    out["shininess"] = tidy(shininess(math.sqrt(alpha)), 6)


def _coat_f0(ps: Params, ctx: Context, name: str = "eta") -> float:
    eta = _eta(ps, ctx, name, 1.5)
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def _eta(ps: Params, ctx: Context, name: str, default: float) -> float:
    """A dielectric's index of refraction: a float, or a spectrum read at 550 nm."""
    p = ps.get(name)
    if p is None:
        return default
    if p.type in ("float", "integer"):
        value = float(p.values[0]) if p.values else default
    elif p.type == "spectrum" and len(p.values) == 1 and p.values[0] in spectra.NAMED_GLASSES:
        value = spectra.NAMED_GLASSES[p.values[0]]
    elif p.type == "spectrum":
        lam, val = samples(p, ctx)
        value = float(np.interp(_ETA_NM, lam, val))
    elif p.type == "rgb":
        value = float(p.values[1])
    else:
        raise p.where.error(f'"{p.type} {name}": expected a float or a spectrum')
    if not value > 0:
        raise p.where.error(f'"{p.type} {name}": an index of refraction must be > 0')
    return value


def _diffuse(ps: Params, ctx: Context, where: Where) -> dict:
    out: dict = {}
    _apply(out, "kd", color(ps, "reflectance", "albedo", ctx, Tex(grey(0.5))))
    return out


def _coateddiffuse(ps: Params, ctx: Context, where: Where) -> dict:
    """lumos's `plastic`: the reflectance as the base under a GGX coat of index eta (Mitsuba's roughplastic model;
    pbrt's stochastic layers, their thickness and albedo, are not read)."""
    out: dict = {}
    _apply(out, "kd", color(ps, "reflectance", "albedo", ctx, Tex(grey(0.5))))
    out["plastic"] = {"alpha": tidy(min(_alpha(ps, ctx), 1.0), 6), "ior": tidy(_eta(ps, ctx, "eta", 1.5), 6)}
    ps.ignore("thickness", "albedo", "g", "maxdepth", "nsamples")
    return out


def conductor_f0(ps: Params, ctx: Context, prefix: str = "") -> Tex:
    """The head-on reflectance of pbrt's conductor: its `reflectance`, else the Fresnel factor of η + ik (pbrt's
    default is copper): a named metal from the table, sampled spectra per wavelength, RGB per channel."""
    given = color(ps, prefix + "reflectance", "albedo", ctx)
    if given is not None:
        return given
    eta_p, k_p = ps.get(prefix + "eta"), ps.get(prefix + "k")
    named = [p.values[0] for p in (eta_p, k_p) if p is not None and p.type == "spectrum" and len(p.values) == 1
             and isinstance(p.values[0], str)]
    metals = {n[len("metal-"):].rsplit("-", 1)[0] for n in named if n.startswith("metal-")}
    if eta_p is None and k_p is None:
        metals = {"Cu"}
    if len(metals) == 1 and len(named) == sum(p is not None for p in (eta_p, k_p)):
        metal = metals.pop()
        if metal in spectra.NAMED_METALS:
            return Tex(tuple(spectra.NAMED_METALS[metal]))
    if all(p is None or p.type != "spectrum" for p in (eta_p, k_p)):  # RGB or constant: channel by channel
        eta = color(ps, prefix + "eta", "unbounded", ctx, Tex(grey(1.0))).mean
        k = color(ps, prefix + "k", "unbounded", ctx, Tex(grey(0.0))).mean
        return Tex(tuple(float(min(c, 1.0)) for c in spectra.fresnel_f0(eta, k)))
    grid = np.arange(380.0, 780.5, 1.0)

    def curve(p, default):
        if p is None:
            return np.full(len(grid), default)
        if p.type == "spectrum":
            lam, val = samples(p, ctx)
            return np.interp(grid, lam, val)
        rgb = color(Params({p.name: p}, p.where), p.name, "unbounded", ctx).mean
        return np.where(grid < 490.0, rgb[2], np.where(grid < 590.0, rgb[1], rgb[0]))  # RGB as bands

    f0 = spectra.fresnel_f0(curve(eta_p, 1.0), curve(k_p, 0.0))
    return Tex(tuple(min(c, 1.0) for c in spectra.reflectance_rgb(grid, f0)))


def _conductor_index(ps: Params, ctx: Context) -> Optional[dict]:
    """lumos's `conductor` index for pbrt's eta/k: a named metal lumos has (pbrt's default is copper), or RGB
    values; None for a `reflectance` or sampled spectra (the head-on stand-in reads those)."""
    if ps.get("reflectance") is not None:
        return None
    eta_p, k_p = ps.get("eta"), ps.get("k")
    if eta_p is None and k_p is None:
        return {"metal": "Cu"}
    named = [p.values[0] for p in (eta_p, k_p) if p is not None and p.type == "spectrum" and len(p.values) == 1
             and isinstance(p.values[0], str)]
    metals = {n[len("metal-"):].rsplit("-", 1)[0] for n in named if n.startswith("metal-")}
    if len(metals) == 1 and len(named) == 2 and next(iter(metals)) in METALS:
        return {"metal": metals.pop()}
    if all(p is not None and p.type == "rgb" for p in (eta_p, k_p)):
        eta = color(ps, "eta", "unbounded", ctx).mean
        k = color(ps, "k", "unbounded", ctx).mean
        return {"eta": [tidy(c, 6) for c in eta], "k": [tidy(c, 6) for c in k]}
    return None


def _alphas(ps: Params, ctx: Context) -> tuple[float, float]:
    """The Trowbridge–Reitz (αu, αv) of a material's roughness, each at most 1 (lumos's widest)."""
    rough = scalar(ps, "roughness", ctx, 0.0)
    u, v = scalar(ps, "uroughness", ctx, rough), scalar(ps, "vroughness", ctx, rough)
    remap = ps.bool("remaproughness", True)
    au, av = (min(math.sqrt(max(r, 0.0)) if remap else max(r, 0.0), 1.0) for r in (u, v))
    return au, av


def _alpha_key(au: float, av: float):
    """A lumos `alpha`: one number, or [αu, αv] when they differ."""
    return tidy(au, 6) if au == av else [tidy(au, 6), tidy(av, 6)]


def _conductor(ps: Params, ctx: Context, where: Where) -> dict:
    """lumos's `conductor` (GGX, the exact Fresnel factor of η + ik) where its index can be given; else the
    head-on reflectance as a mirror or a Phong lobe."""
    au, av = _alphas(ps, ctx)
    index = _conductor_index(ps, ctx)
    if index is not None:
        return {"conductor": {**index, "alpha": _alpha_key(au, av)}}
    out: dict = {}
    if max(au, av) > 1e-4:
        ctx.warn.once(("material", "conductor", "rough"), where, "Material 'conductor' with roughness and a "
                      "reflectance or sampled spectra: a Phong lobe of the same width (ks, shininess) stands in")
    _specular(out, conductor_f0(ps, ctx), 0.5 * (au + av))
    return out


def _coatedconductor(ps: Params, ctx: Context, where: Where) -> dict:
    out: dict = {}
    f0_coat = _coat_f0(ps, ctx, "interface.eta")
    metal = conductor_f0(ps, ctx, "conductor.")
    _specular(out, metal, _alpha(ps, ctx, "conductor."), grey(1.0 - f0_coat))
    coat: dict = {}
    _specular(coat, Tex(grey(f0_coat)), _alpha(ps, ctx, "interface."))
    for key in ("kr", "ks"):
        if key in coat:
            out[key] = [a + b for a, b in zip(out.get(key, [0.0, 0.0, 0.0]), coat[key])]
    out.setdefault("shininess", coat.get("shininess", 1.0))
    ps.ignore("thickness", "albedo", "g", "maxdepth", "nsamples")
    return out


def _dielectric(ps: Params, ctx: Context, where: Where) -> dict:
    """lumos's `dielectric` (GGX reflection and refraction, Walter et al. 2007; smooth below pbrt's α of 10⁻³, as
    its EffectivelySmooth); η = 1, pbrt's index-matched interface, passes light straight through."""
    eta = _eta(ps, ctx, "eta", 1.5)
    if eta == 1.0:
        return {"kt": 1.0, "ior": 1.0}
    au, av = _alphas(ps, ctx)
    if max(au, av) < 1e-3:
        au = av = 0.0
    return {"dielectric": {"ior": tidy(eta, 6), "alpha": _alpha_key(au, av)}}


def _thindielectric(ps: Params, ctx: Context, where: Where) -> dict:
    r = _coat_f0(ps, ctx)
    kr = 2.0 * r / (1.0 + r)  # the sheet's two surfaces and the light between them, at normal incidence
    return {"kr": tidy(kr, 7), "kt": tidy(1.0 - kr, 7), "ior": 1.0}


def _diffusetransmission(ps: Params, ctx: Context, where: Where) -> dict:
    out: dict = {}
    scale = grey(ps.float("scale", 1.0))
    _apply(out, "kd", color(ps, "reflectance", "albedo", ctx, Tex(grey(0.25))), scale)
    out["kt"] = [min(c * s, 1.0) for c, s in zip(color(ps, "transmittance", "albedo", ctx, Tex(grey(0.25))).mean,
                                                 scale)]
    out["ior"] = 1.0
    return out


def _interface(ps: Params, ctx: Context, where: Where) -> dict:
    return {"kt": 1.0, "ior": 1.0}


def _stand_in_diffuse(ps: Params, ctx: Context, where: Where) -> dict:
    out: dict = {}
    tex = color(ps, "reflectance", "albedo", ctx) or color(ps, "color", "albedo", ctx) or Tex(grey(0.5))
    _apply(out, "kd", tex)
    ps.ignore(*ps.params)
    return out


def _mix(spec: MaterialSpec, ctx: Context, named: dict, depth: int) -> dict:
    """pbrt's mix picks materials[1] with probability `amount` at each point: the blend of the two, coefficient by
    coefficient (textures of the first, a shininess and ior from the one that has the lobe)."""
    ps = spec.params
    p = ps.get("materials", "string")
    if p is None or len(p.values) != 2:
        raise spec.where.error("Material 'mix' needs \"string materials\" with two named materials")
    if depth > 16:
        raise spec.where.error("Material 'mix': materials mixed into themselves")
    amount = scalar(ps, "amount", ctx, 0.5)
    parts = []
    for name in p.values:
        if name not in named:
            raise p.where.error(f"Material 'mix': unknown named material '{name}' (defined: "
                                f"{', '.join(sorted(named)) or 'none'})")
        part = lumos_material(named[name], ctx, named, depth + 1)
        if "dielectric" in part:  # its classic reading (kt, ior, a highlight), which mixes coefficient-wise
            part = {**Dielectric(**part.pop("dielectric")).classic(), **part}
        parts.append(part)
    weights = (1.0 - amount, amount)
    out: dict = {}
    for key in ("kd", "ks", "kr", "kt", "emission"):
        total = [0.0, 0.0, 0.0]
        for w, part in zip(weights, parts):
            value = part.get(key, 0.0)
            rgb = value if isinstance(value, (list, tuple)) else [value] * 3
            total = [t + w * float(c) for t, c in zip(total, rgb)]
        if any(total):
            out[key] = [tidy(t, 7) for t in total]
    for key, lobe in (("shininess", "ks"), ("ior", "kt")):
        having = [part for part in parts if key in part and part.get(lobe)]
        if having:
            out[key] = having[0][key]
    textures = [t for part in parts for t in part.get("texture", [])]
    if textures:
        out["texture"] = textures[:1]
        if len(textures) > 1:
            ctx.warn.once(("mix-textures",), spec.where, "Material 'mix' of textured materials: only the first "
                          "texture is kept")
    return out


_CONVERTERS = {
    "diffuse": _diffuse, "coateddiffuse": _coateddiffuse, "conductor": _conductor,
    "coatedconductor": _coatedconductor, "dielectric": _dielectric, "thindielectric": _thindielectric,
    "diffusetransmission": _diffusetransmission, "interface": _interface, "hair": _stand_in_diffuse,
    "measured": _stand_in_diffuse, "subsurface": _stand_in_diffuse,
}
