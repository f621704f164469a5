"""A Mitsuba 3 scene's nodes → lumos's scene dict: sensor, film, sampler, integrator, emitters and shapes.

    data = SceneBuilder(ctx).build(root)       # root: mitsuba_xml.parse_scene's <scene> Node

The mapping, with the unit conversions (docs/formats.md, "Mitsuba 3 scenes", has the table):
- `perspective` / `thinlens` / `orthographic` sensors → lumos's camera: position = to_world·(0, 0, 0), looking
  along to_world's +z with its +y up (Mitsuba's image x runs against the camera's x, as lumos's u = up × w
  does), Mitsuba's fov on its `fov_axis` → lumos's vertical fov; `hdrfilm` size, `rfilter` and `sampler` →
  `render:`; the `path` integrator's max_depth D → lumos's D − 2 (Mitsuba counts the camera segment and the one
  that reaches the light); `render.method` is `path`.
- `point` (intensity I in W/sr) → a point light of intensity I/π with attenuation [0, 0, 1] (lumos's point
  light of intensity I′ delivers π·I′·cosθ/d²); `spot` likewise, its cone angles as lumos's; `directional`
  (irradiance E) → intensity E/π; `constant` → `background`; area emitters on rectangles, disks and spheres →
  lumos area lights, on other shapes → emissive objects with `two_sided: false`.
- shapes: `rectangle` → rect, `disk`, `sphere`, `cube` → box, `cylinder` (uncapped), `obj`/`ply` → mesh files,
  `serialized` → inline meshes, `shapegroup`/`instance` expanded.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .mitsuba_bsdfs import Context, bsdf_material, color
from .mitsuba_shapes import GEOMETRY
from .mitsuba_xml import Node

#: Mitsuba's defaults: hdrfilm 768×576, the independent sampler's 4 samples, the path integrator's unbounded depth
FILM_SIZE, SAMPLE_COUNT = (768, 576), 4
_INTEGRATORS_AS_PATH = ("volpath", "volpathmis", "prb", "prbvolpath", "prb_basic", "direct_projective",
                        "prb_projective", "ptracer")


def _vec(v) -> list:
    return [float(c) for c in v]


class SceneBuilder:
    """Builds the lumos scene dict from the root node, recording each key's line in ctx.lines."""

    def __init__(self, ctx: Context):
        self.ctx = ctx
        self.render: dict = {"method": "path"}  # max_depth absent: path's own default, unbounded
        self.data: dict = {"render": self.render}
        self.lights: list = []
        self.objects: list = []
        self.background = np.zeros(3)
        self.envmap: Optional[dict] = None  # the environment of an envmap emitter

    def build(self, root: Node) -> dict:
        ctx = self.ctx
        handlers = {"sensor": self.sensor, "integrator": self.integrator, "emitter": self.emitter}
        for name, node in root.objects:
            if node.tag == "shape":
                self.shape(node, name=name)
            elif node.tag in handlers:
                handlers[node.tag](node)
            elif node.tag in ("medium", "phase", "volume"):
                ctx.warn(("participating media",), node.where, f"{node.tag} '{node.type}': participating media "
                         f"are not supported; left out")
            elif node.tag in ("film", "sampler", "rfilter"):
                ctx.warn(("top-level", node.tag), node.where, f"a <{node.tag}> outside a <sensor> is not read")
        if "spp" not in self.render:
            self.render["spp"] = SAMPLE_COUNT
        if self.lights:
            self.data["lights"] = self.lights
        if self.objects:
            self.data["objects"] = self.objects
        if ctx.materials:
            self.data["materials"] = ctx.materials
        if self.envmap is not None:
            if np.any(self.background):
                ctx.warn(("constant and envmap",), root.where, "a constant emitter beside an envmap is left out (lumos "
                         "has one environment)")
            self.data["environment"] = self.envmap
        elif np.any(self.background):
            self.data["environment"] = {"color": _vec(self.background)}  # path samples it as a light
        return self.data

    # ------------------------------------------------------------------------------------------- sensor

    def sensor(self, node: Node) -> None:
        ctx = self.ctx
        if "camera" in self.data:
            ctx.warn(("sensors",), node.where, "more than one <sensor>: the first is used")
            return
        if node.type == "batch":
            inner = node.children("sensor")
            ctx.warn(("sensor", "batch"), node.where, "sensor 'batch': its first sensor is used")
            if inner:
                film = node.children("film")
                node = inner[0][1]
                if film and not node.children("film"):
                    node.objects.append(film[0])
        width, height = self.film(node)
        self.sampler(node)
        ctx.at(("camera",), node.where)
        m = node.transform("to_world")
        r, position = m[:3, :3], m[:3, 3]
        forward, up = r @ (0.0, 0.0, 1.0), r @ (0.0, 1.0, 0.0)
        if np.linalg.norm(forward) < 1e-12 or np.linalg.norm(up) < 1e-12:
            raise node.where_of("to_world").error("the sensor's to_world is singular")
        camera = {"position": _vec(position), "look_at": _vec(position + forward / np.linalg.norm(forward)),
                  "up": _vec(up / np.linalg.norm(up))}
        if np.linalg.det(r) < 0:
            ctx.warn(("mirrored camera",), node.where_of("to_world"), "the sensor's to_world mirrors the image; "
                     "lumos's camera cannot, so the image comes out mirrored left to right")
        aspect = width / height
        if node.type in ("perspective", "thinlens"):
            fov_x = _fov_x(node, aspect)
            camera["fov"] = math.degrees(2.0 * math.atan(math.tan(math.radians(fov_x) / 2.0) / aspect))
            if node.type == "thinlens":
                camera["aperture"] = node.float("aperture_radius", 0.0)
                camera["focus_distance"] = node.float("focus_distance", node.float("far_clip", 1e4))
            if node.float("principal_point_offset_x", 0.0) or node.float("principal_point_offset_y", 0.0):
                ctx.warn(("principal point",), node.where, "the sensor's principal point offset is not read")
        elif node.type == "orthographic":
            sx, sy = np.linalg.norm(r[:, 0]), np.linalg.norm(r[:, 1])
            if abs(sx - sy) > 1e-6 * sy:
                ctx.warn(("orthographic scale",), node.where, "orthographic: different x and y scales are read "
                         "as the y scale")
            camera.update(type="orthographic", size=float(2.0 * sy / aspect))
        else:
            ctx.warn(("sensor", node.type), node.where, f"sensor '{node.type}' is not supported; a perspective "
                     f"camera (fov 45) stands in")
        self.data["camera"] = camera

    def film(self, sensor: Node) -> tuple[int, int]:
        ctx, render = self.ctx, self.render
        films = sensor.children("film")
        film = films[0][1] if films else None
        width, height = FILM_SIZE
        render["filter"] = "gaussian"  # Mitsuba's default reconstruction filter
        if film is None:
            render.update(width=width, height=height)
            return width, height
        if film.type not in ("hdrfilm", "specfilm"):
            ctx.warn(("film", film.type), film.where, f"film '{film.type}' is read for its size only")
        width, height = film.int("width", width), film.int("height", height)
        for key, value in (("width", width), ("height", height)):
            render[key] = value
            ctx.at(("render", key), film.where_of(key))
        if any(k in film.props for k in ("crop_width", "crop_height", "crop_offset_x", "crop_offset_y")):
            ctx.warn(("crop",), film.where, "hdrfilm: the crop window is not read (the whole image is rendered)")
        filters = film.children("rfilter")
        if filters:
            rfilter = filters[0][1]
            ctx.at(("render", "filter"), rfilter.where)
            if rfilter.type == "box":
                render["filter"] = "box"
            elif rfilter.type != "gaussian" or abs(rfilter.float("stddev", 0.5) - 0.5) > 1e-9:
                ctx.warn(("rfilter", rfilter.type), rfilter.where, f"rfilter '{rfilter.type}': lumos's Gaussian "
                         f"filter (standard deviation 0.5 pixel, radius 2) stands in")
        return width, height

    def sampler(self, sensor: Node) -> None:
        samplers = sensor.children("sampler")
        if not samplers:
            return
        sampler = samplers[0][1]
        count = sampler.int("sample_count", SAMPLE_COUNT)
        self.render["spp"] = count
        self.ctx.at(("render", "spp"), sampler.where_of("sample_count"))
        # the sampler's type is not read: lumos's own (Sobol) points have less error at equal spp
        seed = sampler.int("seed", 0)
        if seed > 0:
            self.render["seed"] = seed

    # ------------------------------------------------------------------------------------------- integrator

    def integrator(self, node: Node) -> None:
        ctx = self.ctx
        while node.type in ("aov", "moment"):
            inner = node.children("integrator")
            if not inner:
                return  # an aov integrator alone renders no image Mitsuba's path integrator would not
            node = inner[0][1]
        ctx.at(("render", "max_depth"), node.where_of("max_depth"))
        if node.type == "direct":
            self.render["max_depth"] = 0
            return
        if node.type != "path":
            known = node.type in _INTEGRATORS_AS_PATH
            ctx.warn(("integrator", node.type), node.where, f"integrator '{node.type}'"
                     f"{' is read as path' if known else ' is not supported; path stands in'}")
        depth = node.int("max_depth", -1)
        if depth in (0, 1):
            ctx.warn(("max_depth", depth), node.where_of("max_depth"), f"{node.type}: max_depth {depth} (no light, "
                     f"or only emitters seen directly) has no lumos equal; max_depth 2 (direct light) stands in")
        if depth >= 0:  # -1 (unbounded) is path's default: left unset, so that whitted takes its own
            self.render["max_depth"] = max(depth - 2, 0)
        if node.bool("hide_emitters", False):
            ctx.warn(("hide_emitters",), node.where, "path: hide_emitters is not read (emitters stay visible)")

    # ------------------------------------------------------------------------------------------- emitters

    def emitter(self, node: Node) -> None:
        ctx = self.ctx
        m = node.transform("to_world")
        light: Optional[dict] = None
        if node.type == "point":
            position = node.vector("position", m[:3, 3])
            light = {"type": "point", "position": _vec(position), **self._intensity(node, "intensity")}
        elif node.type == "spot":
            cutoff = node.float("cutoff_angle", 20.0)
            beam = node.float("beam_width", 0.75 * cutoff)
            if cutoff > 90.0:
                ctx.warn(("spot", "wide"), node.where, f"spot: cutoff_angle {cutoff:g} is read as 90 (lumos's "
                         f"widest spot)")
            angle = min(cutoff, 90.0)
            if "texture" in node.props:
                ctx.warn(("spot", "texture"), node.where, "spot: the projected texture is not read")
            light = {"type": "spot", "position": _vec(m[:3, 3]), "direction": _vec(m[:3, :3] @ (0, 0, 1.0)),
                     "angle": angle, "inner_angle": min(beam, angle), **self._intensity(node, "intensity")}
        elif node.type == "directional":
            direction = node.vector("direction", m[:3, :3] @ (0.0, 0.0, 1.0))
            rgb = self._emitted(node, "irradiance")
            light = {"type": "directional", "direction": _vec(direction), "intensity": _vec(np.divide(rgb, np.pi))}
            ctx.at(("lights", len(self.lights), "intensity"), node.where_of("irradiance"))
        elif node.type == "constant":
            self._add_background(self._emitted(node, "radiance"), node)
        elif node.type == "envmap":
            self._envmap(node)
        else:
            what = "must be attached to a <shape>" if node.type == "area" else "is not supported"
            ctx.warn(("emitter", node.type), node.where, f"emitter '{node.type}' {what}; left out")
        if light is not None:
            ctx.at(("lights", len(self.lights)), node.where)
            self.lights.append(light)

    def _intensity(self, node: Node, key: str) -> dict:
        """A point or spot light's intensity I (W/sr) as lumos's I/π, falling off as 1/d²."""
        rgb = self._emitted(node, key)
        self.ctx.at(("lights", len(self.lights), "intensity"), node.where_of(key))
        return {"intensity": _vec(np.divide(rgb, np.pi)), "attenuation": [0.0, 0.0, 1.0]}

    def _emitted(self, node: Node, key: str) -> tuple:
        """An emitter's colour (an emitter's spectrum, as Mitsuba reads one); a texture stands in as white."""
        rgb, tex = color(node, key, 1.0, self.ctx, emitter=True)
        if tex is not None:
            self.ctx.warn(("textured", node.type, key), node.where_of(key), f"{node.type}: a textured {key} is not "
                          f"read; white stands in")
        return rgb

    def _add_background(self, rgb, node: Node) -> None:
        self.ctx.at(("environment",), node.where)
        self.background = self.background + np.asarray(rgb, np.float64)
        self.ctx.warn(("background",), node.where, f"{node.type}: the environment lights the scene in path "
                      f"(rays that escape see it); raycast, whitted and raster read it as unshadowed ambient light and "
                      f"reflect it")

    def _envmap(self, node: Node) -> None:
        """An envmap as lumos's image environment. Mitsuba's latitude–longitude map looks along −z at its left
        edge (u = atan2(x, −z)/2π), lumos's at its middle column: the image is rolled by half its width (into a
        .npy in the importers' cache folder). A `to_world` turning about +y is the environment's rotation (the
        same sense in both)."""
        from .gltf_materials import cache_folder
        from .image_files import read_image

        ctx = self.ctx
        if self.envmap is not None:
            ctx.warn(("two envmaps",), node.where, "envmap: only the first environment map is read")
            return
        name, path = ctx.file(node)
        try:
            image = read_image(path)
        except Exception as exc:  # noqa: BLE001 - a map that cannot be read is bad input, said in one line
            raise node.where.error(f"envmap: {exc}") from None
        m = node.transform("to_world")[:3, :3]
        rotation = float(np.degrees(np.arctan2(m[0, 2], m[0, 0])))
        turn = np.array([[np.cos(np.radians(rotation)), 0, np.sin(np.radians(rotation))], [0, 1, 0],
                         [-np.sin(np.radians(rotation)), 0, np.cos(np.radians(rotation))]])
        if not np.allclose(m, turn, atol=1e-6):
            ctx.warn(("envmap", "to_world"), node.where, "envmap: only a to_world turning about +y is read (the "
                     "rest of it is left out)")
        out = cache_folder() / f"envmap-{len(list(cache_folder().glob('envmap-*')))}.npy"
        np.save(out, np.ascontiguousarray(np.roll(image, image.shape[1] // 2, axis=1)))
        ctx.at(("environment",), node.where)
        scale = node.float("scale", 1.0)
        self.envmap = {"file": str(out), "scale": scale, "rotation": rotation}

    # ------------------------------------------------------------------------------------------- shapes

    def shape(self, node: Node, outer: Optional[np.ndarray] = None, name: Optional[str] = None) -> None:
        """One shape (an instance: the shapes of its group) as a lumos object, or as an area light."""
        ctx = self.ctx
        if node.type == "shapegroup":
            return  # drawn where an instance places it
        if node.type == "instance":
            groups = [child for _, child in node.children("shape") if child.type == "shapegroup"]
            if not groups:
                raise node.where.error("instance needs a <ref> to a shapegroup")
            for _, child in groups[0].children("shape"):
                self.shape(child, node.transform() if outer is None else outer @ node.transform())
            return
        geometry = GEOMETRY.get(node.type)
        if geometry is None:
            ctx.warn(("shape", node.type), node.where, f"shape '{node.type}' is not supported; left out")
            return
        bsdfs = node.children("bsdf")
        bsdf = bsdfs[0][1] if bsdfs else None
        emitters = [e for _, e in node.children("emitter")]
        radiance = self._radiance(emitters[0]) if emitters else None
        # Mitsuba gives a shape without a BSDF a diffuse 0.5 grey, and an emitting one a black diffuse
        material = bsdf_material(bsdf, ctx) if bsdf is not None else None if emitters else {"kd": 0.5}
        if material is None and radiance is None:
            if bsdf is not None:
                ctx.warn(("bsdf", "null"), bsdf.where, "bsdf 'null': a shape with only a null BSDF is invisible; "
                         "left out")
            return
        matrix = node.transform() if outer is None else outer @ node.transform()
        textured = material is not None and any(t.get("type") == "image" for t in material.get("texture", []))
        obj, area = geometry(node, matrix, ctx, textured, radiance is not None)
        if area is not None and radiance is not None:
            self._area_light(node, area, bsdf, material, radiance, emitters[0])
            return
        self._object(node, obj, bsdf, material, radiance, node.id or name)

    def _radiance(self, emitter: Node) -> Optional[list]:
        if emitter.type != "area":
            self.ctx.warn(("shape emitter", emitter.type), emitter.where, f"emitter '{emitter.type}' on a shape: "
                          f"only area emitters are read; left out")
            return None
        return _vec(self._emitted(emitter, "radiance"))

    def _material_key(self, bsdf: Optional[Node], material: Optional[dict]):
        """A named material for a BSDF with an id (added to `materials:`), else the inline dict."""
        if bsdf is not None and bsdf.id is not None and material is not None:
            if bsdf.id not in self.ctx.materials:
                self.ctx.materials[bsdf.id] = material
                self.ctx.at(("materials", bsdf.id), bsdf.where)
            return bsdf.id
        return None if material is None else dict(material)

    def _area_light(self, node: Node, area: dict, bsdf, material, radiance, emitter: Node) -> None:
        index = len(self.lights)
        light = {"type": "area", **area, "radiance": radiance}
        if material is not None and _reflects(material):
            light["material"] = self._material_key(bsdf, material)
            self.ctx.at(("lights", index, "material"), bsdf.where if bsdf is not None else node.where)
        self.ctx.at(("lights", index), node.where)
        self.ctx.at(("lights", index, "radiance"), emitter.where_of("radiance"))
        self.lights.append(light)

    def _object(self, node: Node, obj: dict, bsdf, material, radiance, name: Optional[str]) -> None:
        index = len(self.objects)
        if name:
            obj = {"name": name, **obj}
        if radiance is not None:
            obj["material"] = {**(material or {}), "emission": radiance}
            obj["two_sided"] = False
        else:
            obj["material"] = self._material_key(bsdf, material)
        self.ctx.at(("objects", index), node.where)
        if bsdf is not None:
            self.ctx.at(("objects", index, "material"), bsdf.where)
        if "transform" in obj:
            self.ctx.at(("objects", index, "transform"), node.where_of("to_world"))
        if "file" in obj:
            self.ctx.at(("objects", index, "file"), node.where_of("filename"))
        self.objects.append(obj)


def _reflects(material: dict) -> bool:
    return any(np.any(np.asarray(material.get(k, 0.0)) > 0) for k in ("kd", "ks", "kr", "kt")) or "texture" in material


def _fov_x(node: Node, aspect: float) -> float:
    """Mitsuba's parse_fov: the horizontal field of view in degrees from fov + fov_axis, or from focal_length
    (35 mm film equivalent, on the diagonal; default 50mm)."""
    if "fov" in node.props and "focal_length" in node.props:
        raise node.where.error(f"{node.label()}: give fov or focal_length, not both")
    if "fov" in node.props:
        fov = node.float("fov")
        axis = node.string("fov_axis", "x").lower()
        if axis == "smaller":
            axis = "y" if aspect > 1 else "x"
        elif axis == "larger":
            axis = "x" if aspect > 1 else "y"
    else:
        text = node.string("focal_length", "50mm")
        try:
            focal = float(text[:-2] if text.endswith("mm") else text)
        except ValueError:
            raise node.where_of("focal_length").error(f"focal_length '{text}' is not of the form <x>mm") from None
        fov, axis = 2.0 * math.degrees(math.atan(math.hypot(36.0, 24.0) / (2.0 * focal))), "diagonal"
    half = math.tan(math.radians(fov) / 2.0)
    if axis == "x":
        result = fov
    elif axis == "y":
        result = math.degrees(2.0 * math.atan(half * aspect))
    elif axis == "diagonal":
        result = math.degrees(2.0 * math.atan(half / math.sqrt(1.0 + 1.0 / (aspect * aspect))))
    else:
        raise node.where_of("fov_axis").error(f"fov_axis '{axis}' is none of x, y, diagonal, smaller, larger")
    if not 0.0 < result < 180.0:
        raise node.where.error(f"{node.label()}: the horizontal field of view must be in (0, 180), got {result:g}")
    return result
