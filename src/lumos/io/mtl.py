"""Wavefront MTL material libraries read into lumos materials (docs/formats.md, "OBJ + MTL").

    materials, warnings = read_mtl(path)      # {"name": {...scene-format material...}}, ["file:line: ...", ...]

Each `newmtl` block is collected as the file states it (`Ka Kd Ks Ke Ns Ni d Tr Tf illum` and the texture
maps with their options), then `material_from_mtl` maps it onto lumos's coefficients by its `illum` model
(the table in docs/formats.md gives the reason for each line). Sloppy but readable input (a missing texture,
`Ns 0`, an unknown statement) becomes a one-line warning and a sensible default; a number that is not one is
a LumosError `<file>:<line>: <what>`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import LumosError
from .text import logical_lines

#: The material of a `usemtl` name that no library defines (lumos's default matte grey).
UNDEFINED_MATERIAL = {"ka": 0.8, "kd": 0.8}
#: Illumination model of a material that gives no `illum`: 2, Lambert + highlight (a Ks of 0 makes it 1).
DEFAULT_ILLUM = 2
#: Texture statements: the lumos coefficient each multiplies (map_Ks also maps kr where Ks is a mirror).
COLOR_MAPS = {"map_kd": "kd", "map_ka": "ka", "map_ks": "ks", "map_ke": "emission"}
BUMP_MAPS = {"map_bump": "height", "bump": "height", "norm": "normal"}
#: Texture options lumos reads, and the number of arguments of those it skips (None: up to 3 numbers).
_SKIPPED_OPTIONS = {"-blendu": 1, "-blendv": 1, "-boost": 1, "-mm": 2, "-t": None, "-texres": 1, "-imfchan": 1,
                    "-type": 1, "-cc": 1}
_READ_OPTIONS = ("-s", "-o", "-clamp", "-bm")
#: Statements of the spec and of common extensions that lumos has no use for (ignored silently).
_QUIET = {"sharpness", "map_ns", "map_d_", "disp", "decal", "refl", "map_refl", "pr", "pm", "ps", "pc", "pcr",
          "aniso", "anisor", "map_pr", "map_pm", "map_ps", "kt", "ni_"}


@dataclass
class MtlMaterial:
    """One `newmtl` block as written; colours are (3,) float lists, missing statements None."""

    name: str
    line: int
    ka: list | None = None
    kd: list | None = None
    ks: list | None = None
    ke: list | None = None
    tf: list | None = None
    ns: float | None = None
    ni: float | None = None
    d: float | None = None
    tr: float | None = None
    illum: int | None = None
    maps: dict = field(default_factory=dict)      # statement ('map_kd', 'map_d', 'bump'...) -> option dict
    lines: dict = field(default_factory=dict)     # statement -> the line it was on (for warnings)

    def at(self, key: str, label: str) -> str:
        """`<file>:<line>` of statement `key` (of the newmtl line when it is absent)."""
        return f"{label}:{self.lines.get(key, self.line)}"


def read_mtl(path: Path, label: str) -> tuple[dict[str, dict], list[str]]:
    """Read the MTL file `path` (named `label` in messages) into lumos material dicts and warnings."""
    warnings: list[str] = []
    blocks = parse_mtl(path, label, warnings)
    materials = {}
    for block in blocks:
        if block.name in materials:
            warnings.append(f"{label}:{block.line}: material '{block.name}' is defined again; the later one is used")
        materials[block.name] = material_from_mtl(block, label, warnings)
    return materials, warnings


def parse_mtl(path: Path, label: str, warnings: list[str]) -> list[MtlMaterial]:
    """The `newmtl` blocks of an MTL file, in file order."""
    blocks: list[MtlMaterial] = []
    unknown: set[str] = set()
    lines, crlf = logical_lines(path.read_bytes())
    if crlf:
        warnings.append(f"{label}:1: CRLF (Windows) line ends; read as plain line ends")
    for number, line in lines:
        parts = line.split(None, 1)
        if not parts:
            continue
        key, rest = parts[0].lower(), (parts[1].strip() if len(parts) > 1 else "")
        where = f"{label}:{number}"
        if key == "newmtl":
            name = " ".join(rest.split())
            if not name:
                raise LumosError(f"{where}: newmtl needs a material name")
            blocks.append(MtlMaterial(name, number))
            continue
        if not blocks:
            if key not in _QUIET:
                warnings.append(f"{where}: '{parts[0]}' before any newmtl is ignored")
            continue
        blocks[-1].lines[key] = number
        _statement(blocks[-1], key, parts[0], rest, where, path.parent, warnings, unknown)
    return blocks


def _statement(m: MtlMaterial, key: str, word: str, rest: str, where: str, folder: Path, warnings, unknown):
    if key in ("ka", "kd", "ks", "ke", "tf"):
        if rest.split()[:1] in (["spectral"], ["xyz"]):
            warnings.append(f"{where}: {word} {rest.split()[0]} colours are not supported; ignored")
            return
        setattr(m, key, _color(rest, word, where, warnings))
    elif key in ("ns", "ni", "d", "tr"):
        tokens = rest.split()
        if key == "d" and tokens[:1] == ["-halo"]:
            tokens = tokens[1:]
        setattr(m, key, _number(tokens[:1], word, where))
    elif key == "illum":
        value = _number(rest.split()[:1], word, where)
        if value != int(value) or not 0 <= value <= 10:
            warnings.append(f"{where}: illum {rest} is not a model 0-10; illum {DEFAULT_ILLUM} is used")
            value = DEFAULT_ILLUM
        m.illum = int(value)
    elif key in COLOR_MAPS or key in BUMP_MAPS or key == "map_d":
        option = _texture(rest, word, where, folder, warnings)
        if option is not None:
            m.maps[key] = option
    elif key not in _QUIET and key not in unknown:
        unknown.add(key)
        warnings.append(f"{where}: '{word}' statements are not supported; ignored")


def _number(tokens: list[str], word: str, where: str) -> float:
    if not tokens:
        raise LumosError(f"{where}: {word} needs a number")
    try:
        value = float(tokens[0])
    except ValueError:
        raise LumosError(f"{where}: {word}: '{tokens[0][:40]}' is not a number") from None
    if not math.isfinite(value):
        raise LumosError(f"{where}: {word}: {tokens[0][:40]} is not a finite number")
    return value


def _color(rest: str, word: str, where: str, warnings) -> list:
    tokens = rest.split()
    if not tokens:
        raise LumosError(f"{where}: {word} needs a colour (r g b, or one grey value)")
    values = [_number([t], word, where) for t in tokens[:3]]
    values = values * 3 if len(values) == 1 else values
    if len(values) == 2:
        raise LumosError(f"{where}: {word} needs 3 numbers (r g b) or 1, got 2")
    if any(not 0.0 <= v <= 1e30 for v in values):
        warnings.append(f"{where}: {word} {' '.join(tokens[:3])} is outside [0, 1e30]; clamped")
        values = [min(max(v, 0.0), 1e30) for v in values]
    return values


def _texture(rest: str, word: str, where: str, folder: Path, warnings) -> dict | None:
    """A map statement's options and file: {'file', 'scale', 'offset', 'clamp', 'bm'}; None if unusable."""
    tokens = rest.split()
    opts = {"scale": (1.0, 1.0), "offset": (0.0, 0.0), "clamp": False, "bm": 1.0}
    name_parts, i = [], 0
    while i < len(tokens):
        tok = tokens[i].lower()
        if tok in _READ_OPTIONS or tok in _SKIPPED_OPTIONS:
            count = {"-clamp": 1, "-bm": 1}.get(tok, _SKIPPED_OPTIONS.get(tok))
            args = tokens[i + 1:i + 1 + (count or 3)]
            if count is None or tok in ("-s", "-o"):   # up to 3 numbers
                n = 0
                while n < len(args) and _is_number(args[n]):
                    n += 1
                args = args[:n]
            if not args or (count and len(args) < count):
                raise LumosError(f"{where}: {word} option {tokens[i]} needs {count or 'a number or more'} "
                                 f"argument{'s' if (count or 2) > 1 else ''}")
            _texture_option(opts, tok, args, word, where, warnings)
            i += 1 + len(args)
        else:
            name_parts.append(tokens[i])
            i += 1
    if not name_parts:
        raise LumosError(f"{where}: {word} needs a texture file name")
    file = find_file(folder, " ".join(name_parts))
    if file is None:
        warnings.append(f"{where}: texture '{' '.join(name_parts)}' not found; {word} ignored")
        return None
    problem = unreadable_image(file)
    if problem is not None:  # as glTF's importer does: a warning and no texture, not a failed render
        warnings.append(f"{where}: texture '{' '.join(name_parts)}' is not a readable image ({problem}); "
                        f"{word} ignored")
        return None
    opts["file"] = str(file)
    return opts


_READABLE: dict[tuple, str | None] = {}


def unreadable_image(path: Path) -> str | None:
    """Why Pillow cannot read the image at `path` (its header and, for PNG, its chunks' checksums), or None
    when it can; remembered per file, since a library names one image in many map statements."""
    try:
        stat = os.stat(path)
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    if key not in _READABLE:
        from PIL import Image as PILImage

        try:
            with PILImage.open(path) as img:
                img.verify()
            _READABLE[key] = None
        except PILImage.UnidentifiedImageError:
            _READABLE[key] = "no image format Pillow knows"
        except Exception as exc:  # noqa: BLE001 -- Pillow raises many kinds on corrupt images
            _READABLE[key] = " ".join(str(exc).replace(str(path), "").split())[:80] or type(exc).__name__
    return _READABLE[key]


def _texture_option(opts: dict, tok: str, args: list[str], word: str, where: str, warnings) -> None:
    if tok == "-clamp":
        if args[0].lower() not in ("on", "off"):
            raise LumosError(f"{where}: {word} -clamp takes on or off, not '{args[0][:40]}'")
        opts["clamp"] = args[0].lower() == "on"
    elif tok == "-bm":
        opts["bm"] = _number(args, f"{word} -bm", where)
    elif tok in ("-s", "-o"):
        values = [_number([a], f"{word} {tok}", where) for a in args]
        u = values[0]
        v = values[1] if len(values) > 1 else (u if tok == "-s" else 0.0)
        if tok == "-s":
            if u <= 0 or v <= 0 or max(u, v) > 1e12 or min(u, v) < 1e-12:
                warnings.append(f"{where}: {word} -s {' '.join(args)}: scale must be positive; 1 is used")
                u = v = 1.0
            opts["scale"] = (u, v)
        else:
            opts["offset"] = (u, v)


def _is_number(token: str) -> bool:
    try:
        float(token)
        return True
    except ValueError:
        return False


def find_file(folder: Path, name: str) -> Path | None:
    """The file `name` refers to, relative to `folder`: as written, with Windows backslashes read as `/`, or
    (the usual slip of exporters that write their own absolute paths) by its bare name in `folder`."""
    candidates = [name, name.replace("\\", "/")]
    candidates.append(candidates[-1].rsplit("/", 1)[-1])
    for candidate in candidates:
        if not candidate:
            continue
        path = folder / candidate
        try:
            if path.is_file():
                return path.resolve()
        except (OSError, ValueError):   # a name the file system cannot hold
            continue
    return None


# ------------------------------------------------------------------------------------- illum -> lumos terms


def material_from_mtl(m: MtlMaterial, label: str, warnings: list[str]) -> dict:
    """The lumos material of one MTL block, by its illumination model (docs/formats.md gives each reason);
    `label` names the MTL file in warnings."""
    illum = DEFAULT_ILLUM if m.illum is None else m.illum
    black = np.zeros(3)
    Ka, Kd, Ks, Ke = (np.array(c if c is not None else black, dtype=np.float64) for c in (m.ka, m.kd, m.ks, m.ke))
    shininess = 1.0 if m.ns is None else m.ns
    if m.ns is not None and m.ns <= 0.0:
        warnings.append(f"{m.at('ns', label)}: Ns {m.ns:g} makes the highlight cover the hemisphere; shininess 1 is used")
        shininess = 1.0
    ior = 1.0 if m.ni is None else m.ni
    if m.ni is not None and not 1e-3 <= m.ni <= 100:
        warnings.append(f"{m.at('ni', label)}: Ni {m.ni:g} is not an index of refraction; 1 is used")
        ior = 1.0
    d = _dissolve(m, m.at("tr", label), warnings)
    transmit = _transmission(m, d)                         # (3,) what a glass mode lets through

    ka, kd, ks, kr, kt, emission = Ka.copy(), Kd.copy(), black.copy(), black.copy(), black.copy(), Ke.copy()
    fresnel, mirror = False, False
    if illum == 0:                  # colour on, ambient off: Kd as it is, lit by nothing
        ka, kd, emission = black, black, Kd + Ke
    elif illum == 10:               # shadow matte: no shadow catcher in lumos, so the matte surface itself
        warnings.append(f"{m.at('illum', label)}: illum 10 (shadow matte) is read as illum 1: lumos has no shadow catcher")
    if illum in (2, 3, 4, 5, 6, 7, 8, 9):
        ks = Ks.copy()
    if illum in (3, 4, 5, 6, 7, 8, 9):
        kr, mirror = Ks.copy(), True
    if illum in (5, 7):
        fresnel = True
    if illum in (4, 9):             # glass: transparency that keeps its reflection and highlight
        kt = transmit
        ka, kd = ka * (1.0 - transmit), kd * (1.0 - transmit)
    elif illum in (6, 7):           # refraction: (1 - Ks)·Tf·I_t through a surface of index Ni
        kt = (1.0 - np.minimum(Ks, 1.0)) * transmit
    elif d < 1.0:                   # dissolve: d·surface + (1 - d)·what lies behind, straight through
        ka, kd, ks, kr, emission = ka * d, kd * d, ks * d, kr * d, emission * d
        kt = np.full(3, 1.0 - d)
        ior = 1.0
    if illum in (4, 9) or (illum not in (6, 7) and d < 1.0):
        ior = 1.0

    kd, ks, kr, kt = _energy(kd, ks, kr, kt)
    material = {"ka": _c(ka), "kd": _c(kd), "ks": _c(ks), "shininess": float(shininess), "kr": _c(kr),
                "kt": _c(kt), "ior": float(ior), "emission": _c(emission), "fresnel": fresnel}
    _maps(material, m, illum, mirror)
    return material


def _dissolve(m: MtlMaterial, where: str, warnings) -> float:
    """d, from `d` or `Tr` (= 1 − d); d wins when both are given, whichever comes first (tinyobjloader #43)."""
    if m.d is not None:
        d = m.d
    elif m.tr is not None:
        d = 1.0 - m.tr
        if d <= 0.0:   # Meshlab, trimesh and others write "Tr 1" meaning opaque: invisible is never meant
            warnings.append(f"{where}: Tr {m.tr:g} would make the material invisible; read as opaque "
                            "(exporters that write Tr for d)")
            d = 1.0
    else:
        d = 1.0
    return min(max(d, 0.0), 1.0)


def _transmission(m: MtlMaterial, d: float) -> np.ndarray:
    """What glass lets through: Tf·(1 − d), where a missing Tf counts as white and a missing d (and Tr) as
    fully dissolved when Tf is given; neither given lets nothing through."""
    if m.tf is None and m.d is None and m.tr is None:
        return np.zeros(3)
    tf = np.ones(3) if m.tf is None else np.minimum(np.array(m.tf, dtype=np.float64), 1.0)
    through = 1.0 if (m.d is None and m.tr is None) else 1.0 - d
    return tf * through


def _energy(kd, ks, kr, kt):
    """Keep kd + ks + kr + kt ≤ 1 per channel (more would reflect more light than arrives; the path tracer
    warns): the ray-traced kr and kt the illum mode asks for stay, and kd and ks share what is left."""
    ray = kr + kt
    over = ray.max()
    if over > 1.0:
        kr, kt, ray = kr / over, kt / over, ray / over
    local = kd + ks
    room = np.maximum(1.0 - ray, 0.0)
    scale = np.where(local > room, room / np.maximum(local, 1e-300), 1.0).min()
    return kd * scale, ks * scale, kr, kt


def _c(rgb) -> list:
    return [float(min(max(c, 0.0), 1e30)) for c in rgb]


def _maps(material: dict, m: MtlMaterial, illum: int, mirror: bool) -> None:
    """Textures (in the agreed "material maps" format) and the bump map of an MTL block."""
    textures = []
    for key, target in COLOR_MAPS.items():
        if key not in m.maps:
            continue
        targets = [target]
        if illum == 0 and target == "kd":
            targets = ["emission"]
        elif illum == 0 and target == "ka":
            continue
        elif target == "ks" and mirror:
            targets = ["ks", "kr"]
        textures.append(_texture_dict(m.maps[key], targets, "multiply"))
    if "map_d" in m.maps:
        textures.append(_texture_dict(m.maps["map_d"], ["opacity"], "replace"))
    if textures:
        material["texture"] = textures[0] if len(textures) == 1 else textures
    for key, kind in BUMP_MAPS.items():
        if key in m.maps and "bump" not in material:
            opt = m.maps[key]
            bump = {"type": "image" if kind == "height" else "normal", "file": opt["file"], "strength": opt["bm"]}
            bump.update({k: v for k, v in _uv_keys(opt).items() if k != "offset"})   # bump maps have no offset
            material["bump"] = bump


def _texture_dict(opt: dict, targets: list[str], mode: str) -> dict:
    texture = {"type": "image", "file": opt["file"], "apply_to": targets, "mode": mode}
    texture.update(_uv_keys(opt))
    return texture


def _uv_keys(opt: dict) -> dict:
    keys = {}
    if opt["scale"] != (1.0, 1.0):
        keys["scale"] = list(opt["scale"])
    if opt["offset"] != (0.0, 0.0):
        keys["offset"] = list(opt["offset"])
    if opt["clamp"]:
        keys["wrap"] = "clamp"
    return keys
