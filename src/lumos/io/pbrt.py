"""pbrt-v4 scene files (`.pbrt`) read into lumos's scene format, so that `lumos render scene.pbrt` works.

    data, lines = read_pbrt(Path("killeroo-simple.pbrt"))   # a scene dict as a YAML file would give it, and
                                                             # {key path: line} for the loader's messages

The statements (`pbrt_tokens`) drive pbrt's graphics state as pbrt-v4's BasicSceneBuilder does (src/pbrt/
scene.cpp): the current transform (CTM) is multiplied on the right by each transform directive; AttributeBegin/
End save and restore the whole state (CTM, material, area light, ReverseOrientation, Attribute defaults);
ObjectBegin/End record shapes that each ObjectInstance places again (CTM at the instance × CTM at the shape);
Include reads a file in place, Import reads one whose graphics state does not leak out; named materials may be
used before they are defined (pbrt creates materials after parsing). At the end the recorded camera, lights,
materials and shapes are mapped onto lumos's (`pbrt_options`, `pbrt_lights`, `pbrt_materials`, `pbrt_shapes`):
docs/formats.md ("pbrt-v4 scenes") has every mapping and unit conversion.

Bad input is a LumosError `<file>:<line>: <what>` (one line); what lumos reads differently from pbrt or leaves
out is a LumosWarning once per kind, naming what stands in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Optional

import numpy as np

from ..errors import LumosError
from .pbrt_lights import EnvironmentMap, lat_long_environment, light_items
from .pbrt_materials import DEFAULT_MATERIAL, MaterialSpec, lumos_material
from .pbrt_options import Option, Options, camera_dict, render_dict, resolution, world_mirror
from .pbrt_shapes import Emission, ShapeRecord, shape_items
from .pbrt_textures import Context, Tex, color, define_texture
from .pbrt_tokens import Params, Statement, Statements, Warnings, Where

#: the directives that set scene-wide options: only before WorldBegin
_OPTIONS = ("Camera", "Film", "Sampler", "Integrator", "PixelFilter", "Accelerator")
#: the directives that describe the world: only after WorldBegin
_WORLD = ("AttributeBegin", "AttributeEnd", "TransformBegin", "TransformEnd", "Shape", "Material",
          "MakeNamedMaterial", "NamedMaterial", "Texture", "LightSource", "AreaLightSource", "ObjectBegin",
          "ObjectEnd", "ObjectInstance", "ReverseOrientation", "Import")
_ATTRIBUTE_TARGETS = ("shape", "light", "material", "medium", "texture")
_DEFAULT_NAME = "pbrt-default"


def read_pbrt(path: Path) -> tuple[dict, dict]:
    """Read a pbrt-v4 scene file: (scene dict in lumos's format, {key path tuple: line in the file})."""
    return _Reader(Path(path)).read()


@dataclass
class _State:
    """pbrt's graphics state: what AttributeBegin saves and AttributeEnd restores."""

    ctm: np.ndarray
    reverse: bool = False
    material: tuple = ("default",)
    emission: Optional[Emission] = None
    attributes: dict = field(default_factory=lambda: {t: {} for t in _ATTRIBUTE_TARGETS})
    active: str = "All"  # ActiveTransform: All, StartTime or EndTime


class _Reader:
    def __init__(self, path: Path):
        self.path = path
        self.ctx = Context(path.parent, Warnings())
        self.options = Options()
        self.state = _State(np.eye(4))
        self.stack: list[tuple[str, _State, Where]] = []
        self.in_world = False
        self.coords: dict[str, np.ndarray] = {}
        self.anonymous: list[tuple[MaterialSpec, int]] = []
        self.named: dict[str, tuple[MaterialSpec, int]] = {}
        self.shapes: list[tuple[ShapeRecord, int]] = []
        self.instances: dict[str, list[ShapeRecord]] = {}
        self.defining: Optional[str] = None
        self.uses: list[tuple[str, np.ndarray, Where, int]] = []
        self.lights: list[tuple[str, Params, np.ndarray, Where, int]] = []
        self.lines: dict = {}

    # ------------------------------------------------------------------------------------------- statements

    def read(self) -> tuple[dict, dict]:
        self.stream = Statements(self.path)
        for st in self.stream:
            if st.directive in _OPTIONS and self.in_world:
                raise st.where.error(f"{st.directive} sets an option: it must come before WorldBegin")
            if st.directive in _WORLD and not self.in_world:
                raise st.where.error(f"{st.directive} describes the world: it must come after WorldBegin")
            getattr(self, f"_{st.directive}", self._ignored)(st)
        if self.stack:
            kind, _, where = self.stack[-1]
            opened = {"a": "AttributeBegin", "o": "ObjectBegin"}[kind]
            raise where.error(f"{opened} without {opened.replace('Begin', 'End')} (the file ends first)")
        if not self.in_world:
            raise LumosError(f"{self.path}: the file ends before WorldBegin (a pbrt scene describes its world after "
                             f"WorldBegin)")
        return self._assemble()

    # ---- transforms

    def _transform(self, st: Statement, m: np.ndarray, replace: bool = False) -> None:
        if self.state.active != "All":
            self.ctx.warn.once(("motion",), st.where, "animated transforms (ActiveTransform) are not supported: the "
                               "start-time transform stands in")
            if self.state.active == "EndTime":
                return
        self.state.ctm = m.copy() if replace else self.state.ctm @ m

    def _Identity(self, st):
        self._transform(st, np.eye(4), replace=True)

    def _Translate(self, st):
        m = np.eye(4)
        m[:3, 3] = st.args
        self._transform(st, m)

    def _Scale(self, st):
        self._transform(st, np.diag([*st.args, 1.0]))

    def _Rotate(self, st):
        angle, axis = st.args[0], np.asarray(st.args[1:], dtype=np.float64)
        if not np.any(axis):
            raise st.where.error("Rotate: the axis is the zero vector")
        self._transform(st, rotation(angle, axis))

    def _LookAt(self, st):
        eye, at, up = (np.asarray(st.args[i:i + 3], dtype=np.float64) for i in (0, 3, 6))
        view = at - eye
        if not np.any(view) or np.linalg.norm(np.cross(up, view)) < 1e-12 * np.linalg.norm(up) * np.linalg.norm(view):
            raise st.where.error("LookAt: the eye and the point looked at coincide, or up is parallel to the view")
        self._transform(st, look_at(eye, at, up))

    def _Transform(self, st):
        self._transform(st, np.asarray(st.args, dtype=np.float64).reshape(4, 4).T, replace=True)

    def _ConcatTransform(self, st):
        self._transform(st, np.asarray(st.args, dtype=np.float64).reshape(4, 4).T)

    def _CoordinateSystem(self, st):
        self.coords[st.args[0]] = self.state.ctm.copy()

    def _CoordSysTransform(self, st):
        if st.args[0] not in self.coords:
            self.ctx.warn.once(("coordsys", st.args[0]), st.where, f"CoordSysTransform: no coordinate system "
                               f"'{st.args[0]}' (the transform is kept)")
            return
        self.state.ctm = self.coords[st.args[0]].copy()

    def _ActiveTransform(self, st):
        if st.args[0] not in ("All", "StartTime", "EndTime"):
            raise st.where.error(f"ActiveTransform: expected All, StartTime or EndTime, got '{st.args[0]}'")
        self.state.active = st.args[0]

    def _TransformTimes(self, st):
        self.ctx.warn.once(("motion",), st.where, "TransformTimes: motion blur is not read (the start-time transform "
                           "stands in)")

    # ---- options and blocks

    def _Camera(self, st):
        self.options.camera = Option(st.args[0], Params(st.params, st.where), st.where, self.state.ctm.copy())
        self.coords["camera"] = np.linalg.inv(self.state.ctm) if np.linalg.det(self.state.ctm) else np.eye(4)
        self.lines[("camera",)] = st.main_line

    def _option(self, st):
        self.options.others[st.directive] = Option(st.args[0], Params(st.params, st.where), st.where)
        self.lines.setdefault(("render",), st.main_line)

    _Film = _Sampler = _Integrator = _PixelFilter = _option

    def _Accelerator(self, st):
        pass  # lumos builds its own BVH

    def _WorldBegin(self, st):
        if self.in_world:
            raise st.where.error("WorldBegin a second time")
        self.in_world = True
        self.state.ctm = np.eye(4)
        self.state.active = "All"
        self.coords["world"] = np.eye(4)

    def _saved(self) -> _State:
        """A copy of the graphics state to restore later (the CTM and the Params are never changed in place)."""
        return replace(self.state, attributes=dict(self.state.attributes))

    def _AttributeBegin(self, st):
        self.stack.append(("a", self._saved(), st.where))

    def _AttributeEnd(self, st):
        if not self.stack:
            raise st.where.error(f"{st.directive} without AttributeBegin")
        kind, state, where = self.stack[-1]
        if kind != "a":
            raise st.where.error(f"{st.directive} while the ObjectBegin of {where} is open")
        self.stack.pop()
        self.state = state

    _TransformBegin, _TransformEnd = _AttributeBegin, _AttributeEnd

    def _ReverseOrientation(self, st):
        self.state.reverse = not self.state.reverse

    def _Attribute(self, st):
        target = st.args[0]
        if target not in _ATTRIBUTE_TARGETS:
            raise st.where.error(f"Attribute: unknown target '{target}' ({', '.join(_ATTRIBUTE_TARGETS)})")
        self.state.attributes[target] = {**self.state.attributes[target], **st.params}

    def _Include(self, st):
        self.stream.include(st)

    def _Import(self, st):
        depth = len(self.stack)
        self.stack.append(("a", self._saved(), st.where))

        def restore():  # an imported file's graphics state does not leak out (pbrt's CopyForImport)
            if len(self.stack) != depth + 1:
                raise st.where.error(f"Import '{st.args[0]}': the file leaves an AttributeBegin or ObjectBegin open")
            self.state = self.stack.pop()[1]

        self.stream.include(st, restore)

    def _WorldEnd(self, st):
        self.ctx.warn.once(("WorldEnd",), st.where, "WorldEnd is pbrt-v3's: ignored")

    def _ColorSpace(self, st):
        if st.args[0].lower() != "srgb":
            self.ctx.warn.once(("colorspace", st.args[0]), st.where, f"ColorSpace '{st.args[0]}' is not supported: "
                               f"RGB values are read as linear sRGB")

    def _params(self, st: Statement, target: str) -> Params:
        """The statement's parameters over the Attribute defaults for `target` (which, as in pbrt, may go unused)."""
        defaults = self.state.attributes[target]
        return Params({**defaults, **st.params}, st.where, used=set(defaults) - set(st.params))

    def _ignored(self, st):
        what = {"MakeNamedMedium": "participating media are not supported",
                "MediumInterface": "participating media are not supported",
                "Option": "rendering options are not read"}.get(st.directive, "not supported")
        self.ctx.warn.once(("directive", st.directive), st.where, f"{st.directive}: {what}; ignored")

    # ---- materials, textures, lights, shapes

    def _Material(self, st):
        spec = MaterialSpec(st.args[0], self._params(st, "material"), st.where)
        self.anonymous.append((spec, st.main_line))
        self.state.material = ("anonymous", len(self.anonymous) - 1)

    def _MakeNamedMaterial(self, st):
        name = st.args[0]
        if name in self.named:
            raise st.where.error(f"MakeNamedMaterial '{name}': a material of that name is already defined "
                                 f"({self.named[name][0].where})")
        ps = self._params(st, "material")
        kind = ps.string("type", None)
        if kind is None:
            raise st.where.error(f"MakeNamedMaterial '{name}' needs \"string type\"")
        self.named[name] = (MaterialSpec(kind, ps, st.where), st.main_line)

    def _NamedMaterial(self, st):
        self.state.material = ("named", st.args[0], st.where)

    def _Texture(self, st):
        define_texture(st, self.ctx, self.state.attributes["texture"])

    def _AreaLightSource(self, st):
        ps = self._params(st, "light")
        if st.args[0] != "diffuse":
            self.ctx.warn.once(("arealight", st.args[0]), st.where, f"AreaLightSource '{st.args[0]}' is unknown: a "
                               f"diffuse area light stands in")
        rgb = color(ps, "L", "illuminant", self.ctx, Tex((1.0, 1.0, 1.0))).mean
        if ps.string("filename", None):
            self.ctx.warn.once(("arealight-image",), st.where, "AreaLightSource with an image: textured emission is "
                               "not read; L (white) stands in")
        scale = ps.float("scale", 1.0)
        emission = Emission(tuple(c * scale for c in rgb), ps.bool("twosided", False), ps.float("power", -1.0),
                            st.where)
        for p in ps.unused():
            self.ctx.warn.once(("param", "AreaLightSource", p.name), p.where, f"AreaLightSource: parameter "
                               f"\"{p.type} {p.name}\" is not used")
        self.state.emission = emission

    def _LightSource(self, st):
        ps = self._params(st, "light")
        self.lights.append((st.args[0], ps, self.state.ctm.copy(), st.where, st.main_line))

    def _Shape(self, st):
        rec = ShapeRecord(st.args[0], self._params(st, "shape"),
                          self.state.ctm.copy(), self.state.reverse, self.state.material, self.state.emission,
                          st.where)
        if self.defining is None:
            self.shapes.append((rec, st.main_line))
            return
        if rec.emission is not None:
            self.ctx.warn.once(("instance-light",), st.where, "area lights inside ObjectBegin/End are not supported "
                               "(pbrt ignores them too): the shape does not emit")
            rec.emission = None
        self.instances[self.defining].append(rec)

    def _ObjectBegin(self, st):
        name = st.args[0]
        if self.defining is not None:
            raise st.where.error(f"ObjectBegin '{name}' inside the definition of '{self.defining}'")
        if name in self.instances:
            raise st.where.error(f"ObjectBegin '{name}': an object of that name is already defined")
        self.stack.append(("o", self._saved(), st.where))
        self.defining, self.instances[name] = name, []

    def _ObjectEnd(self, st):
        if self.defining is None:
            raise st.where.error("ObjectEnd without ObjectBegin")
        kind, state, where = self.stack[-1]
        if kind != "o":
            raise st.where.error(f"ObjectEnd while the AttributeBegin of {where} is open")
        self.stack.pop()
        self.state, self.defining = state, None

    def _ObjectInstance(self, st):
        if self.defining is not None:
            raise st.where.error(f"ObjectInstance inside the definition of '{self.defining}'")
        self.uses.append((st.args[0], self.state.ctm.copy(), st.where, st.main_line))

    # ------------------------------------------------------------------------------------------- assembly

    def _assemble(self) -> tuple[dict, dict]:
        ctx, lines = self.ctx, self.lines
        width, height = resolution(self.options)
        mirror = world_mirror(self.options.camera)
        data: dict = {"camera": camera_dict(self.options, mirror, width, height, ctx),
                      "render": render_dict(self.options, ctx)}
        materials = self._materials()
        lights, background, maps = [], np.zeros(3), []
        for kind, ps, ctm, where, line in self.lights:
            items, sky = light_items(kind, ps, mirror @ ctm, ctx, where)
            for light in items:
                lines[("lights", len(lights))] = line
                lights.append(light)
            if isinstance(sky, EnvironmentMap):
                maps.append(sky)
                lines[("environment",)] = line
            elif sky is not None:
                background += sky
                lines[("environment",)] = line
        if maps:  # the maps (and any constant sky) as one lat-long image, in the importers' cache folder
            from .gltf_materials import cache_folder

            out = cache_folder() / f"pbrt-infinite-{len(list(cache_folder().glob('pbrt-infinite-*')))}.npy"
            np.save(out, lat_long_environment(maps, background))
            data["environment"] = {"file": str(out)}
        elif background.any():
            data["environment"] = {"color": [float(c) for c in background]}  # path samples it as a light
        objects: list = []
        variants = _Variants(materials)
        placed = [(rec, mirror @ rec.ctm, line) for rec, line in self.shapes]
        for name, ctm, where, line in self.uses:
            if name not in self.instances:
                raise where.error(f"ObjectInstance: no object '{name}' (defined: "
                                  f"{', '.join(sorted(self.instances)) or 'none'})")
            placed += [(rec, mirror @ ctm @ rec.ctm, line) for rec in self.instances[name]]
        for rec, world, line in placed:
            for kind, item in shape_items(rec, world, self._material_name(rec.material, materials), variants, ctx):
                target = lights if kind == "light" else objects
                lines[("lights" if kind == "light" else "objects", len(target))] = line
                target.append(item)
        data.update(lights=lights, materials=materials, objects=objects)
        return data, lines

    def _materials(self) -> dict:
        """Every material statement as a named lumos material (anonymous ones as `<type>@<line>`)."""
        named = {name: spec for name, (spec, _) in self.named.items()}
        out: dict = {}
        for name, (spec, line) in self.named.items():
            out[name] = lumos_material(spec, self.ctx, named)
            self.lines[("materials", name)] = line
        self._anonymous_names = []
        for spec, line in self.anonymous:
            in_main = spec.where.file == str(self.path)
            shown = f"{spec.kind}@{spec.where.line if in_main else spec.where}"
            while shown in out:
                shown += "'"
            self._anonymous_names.append(shown)
            out[shown] = lumos_material(spec, self.ctx, named)
            self.lines[("materials", shown)] = line
        return out

    def _material_name(self, ref: tuple, materials: dict) -> str:
        if ref[0] == "anonymous":
            return self._anonymous_names[ref[1]]
        if ref[0] == "named":
            if ref[1] not in self.named:
                raise ref[2].error(f"NamedMaterial: unknown material '{ref[1]}' (defined: "
                                   f"{', '.join(sorted(self.named)) or 'none'})")
            return ref[1]
        materials.setdefault(_DEFAULT_NAME, dict(DEFAULT_MATERIAL))
        return _DEFAULT_NAME


class _Variants:
    """Materials derived from a shape's: lumos's emission and opacity are material keys, pbrt's are the shape's.
    An emitting variant is `<material>+L<n>`, a cut-out one `<material>+alpha<n>`."""

    def __init__(self, materials: dict):
        self.materials, self.names = materials, {}

    def _variant(self, material: str, key, suffix: str, change) -> str:
        if (material, key) not in self.names:
            name = f"{material}+{suffix}{len(self.names) + 1}"
            self.materials[name] = change(dict(self.materials[material]))
            self.names[(material, key)] = name
        return self.names[(material, key)]

    def emissive(self, material: str, rgb: tuple) -> str:
        return self._variant(material, ("L", rgb), "L", lambda m: {**m, "emission": list(rgb)})

    def cut_out(self, material: str, pattern: dict) -> str:
        def change(m):
            textures = m.get("texture", [])
            textures = textures if isinstance(textures, list) else [textures]
            return {**m, "texture": [*textures, {**pattern, "apply_to": ["opacity"], "mode": "replace"}]}

        return self._variant(material, ("alpha", repr(sorted(pattern.items()))), "alpha", change)


def rotation(angle: float, axis: np.ndarray) -> np.ndarray:
    """pbrt's Rotate: `angle` degrees about `axis`, counter-clockwise looking down the axis (Rodrigues)."""
    a = axis / np.linalg.norm(axis)
    s, c = math.sin(math.radians(angle)), math.cos(math.radians(angle))
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    m = np.eye(4)
    m[:3, :3] = c * np.eye(3) + s * k + (1 - c) * np.outer(a, a)
    return m


def look_at(eye: np.ndarray, at: np.ndarray, up: np.ndarray) -> np.ndarray:
    """pbrt's LookAt: camera_from_world, with camera x = normalize(cross(up, view)), y = cross(view, x), z = view."""
    view = (at - eye) / np.linalg.norm(at - eye)
    right = np.cross(up / np.linalg.norm(up), view)
    right /= np.linalg.norm(right)
    world_from_camera = np.eye(4)
    world_from_camera[:3, 0], world_from_camera[:3, 1], world_from_camera[:3, 2] = right, np.cross(view, right), view
    world_from_camera[:3, 3] = eye
    return np.linalg.inv(world_from_camera)
