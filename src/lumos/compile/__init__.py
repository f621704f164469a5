"""Scene model → `SceneArrays`: flatten once, build the BVH, hand the kernels nothing but arrays.

    compiled = compile_scene(scene)
    compiled.arrays        # kernels.layout.SceneArrays
    compiled.bvh_build_s   # seconds spent in the BVH builder

This package knows no rendering method. What a method needs beyond the flattened scene it asks for itself
(`methods.compile_for`): the polygons (`compile_raster`), the path tracer's physical materials and emitter table
(`emitters.attach`), radiosity's patches (`patches.attach`).
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..errors import LumosError
from ..kernels import layout as L
from .bvh import build, pack_nodes, packed_leaves, wide_nodes
from .memory import aligned_zeros
from .meshprep import mesh_triangles
from .raster import RasterMesh, build_raster_mesh
from .shapes import canonical, frame, rect_canonical, world_bounds
from .textures import build_textures


@dataclass
class CompiledScene:
    arrays: L.SceneArrays
    bvh_build_s: float
    bvh_depth: int
    n_triangles: int
    n_shapes: int
    bounds: np.ndarray  # (2, 3): min and max of everything bounded (planes excluded)
    object_names: list = field(default_factory=list)
    raster: Optional["RasterMesh"] = None  # the polygons, for method raster
    emitters: Optional[L.Emitters] = None  # the lights and emissive primitives, for method path
    #: the environment's (pixels, marginal CDF, conditional CDFs, info) (`compile.environment`), or None
    environment: Optional[tuple] = None
    patches: Optional[object] = None  # compile.patches.Patches, for method radiosity (`compile.patches.attach`)
    digest: str = ""  # radiosity: the fingerprint of the geometry and materials a solution depends on
    material_names: list = field(default_factory=list)  # a name for each material row (messages, explain)
    #: int64 (nt,): for each BVH-ordered triangle, its index in the objects' triangles taken in scene order (each
    #: mesh's prepared faces, one object after another): ray queries report a hit's face of its own mesh
    triangle_order: Optional[np.ndarray] = None
    #: int32 (nt,): each BVH-ordered triangle's face index in its own mesh (what a ray query reports as prim_id)
    triangle_faces: Optional[np.ndarray] = None
    #: the BVH as built, with the hash of the primitive bounds it was built over (`compile_scene(reuse=...)`)
    bvh: Optional[tuple] = None


class _Materials:
    """Material rows, deduplicated by identity (a named material used by ten objects is one row)."""

    def __init__(self, environment_lit: bool = False):
        self.rows: list[np.ndarray] = []
        self.index: dict[int, int] = {}
        self.materials: list = []  # the scene's Material of each row added by `add` (emitters have none)
        self.environment_lit = environment_lit  # physical materials' classic reading (`Material.classic`)

    def add(self, material, one_sided: bool = False) -> int:
        """The row of a scene Material (`one_sided`: its emission leaves the front only, `MAT_ONE_SIDED`)."""
        key = (id(material), one_sided)
        if key not in self.index:
            self.index[key] = len(self.rows)
            self.materials.append(material)
            self.rows.append(self._row(material, material.emission, one_sided))
        return self.index[key]

    def emitter(self, radiance, material=None, one_sided: bool = True) -> int:
        """The row of an area light's surface: its radiance, and the coefficients of its material (none: black)."""
        self.rows.append(self._row(material, radiance, one_sided))
        self.materials.append(material)
        return len(self.rows) - 1

    def _row(self, material, emission, one_sided: bool) -> np.ndarray:
        row = np.zeros(L.MAT_SIZE)
        row[L.MAT_SHININESS] = 1.0
        row[L.MAT_IOR] = 1.0
        if material is not None:
            classic = material.classic(self.environment_lit)  # (a physical model's reading, where not given)
            model = material.physical
            if model is not None:
                columns = (_conductor_columns if material.conductor is not None else
                           _plastic_columns if material.plastic is not None else
                           _dielectric_columns if material.dielectric is not None else _principled_columns)
                columns(row, model)
                if material.principled is not None:  # (its textured reading, `kernels.principled_classic`)
                    row[L.MAT_KA_REFLECTS] = 0.0 if self.environment_lit else 1.0
            row[L.MAT_KA : L.MAT_KA + 3] = classic["ka"]
            row[L.MAT_KD : L.MAT_KD + 3] = classic["kd"]
            row[L.MAT_KS : L.MAT_KS + 3] = classic["ks"]
            row[L.MAT_SHININESS] = classic["shininess"]
            row[L.MAT_KR : L.MAT_KR + 3] = classic["kr"]
            row[L.MAT_KT : L.MAT_KT + 3] = classic["kt"]
            row[L.MAT_IOR] = classic["ior"]
            row[L.MAT_FRESNEL] = 1.0 if classic["fresnel"] else 0.0
        row[L.MAT_EMISSION : L.MAT_EMISSION + 3] = emission
        row[L.MAT_TEXTURE] = -1.0  # set by the texture step when the material has one
        row[L.MAT_BUMP] = -1.0
        row[L.MAT_ONE_SIDED] = 1.0 if one_sided else 0.0
        return row

    def array(self) -> np.ndarray:
        return np.array(self.rows, dtype=np.float64).reshape(-1, L.MAT_SIZE)


def _conductor_columns(row: np.ndarray, conductor) -> None:
    """The physical model's columns of a metal (MAT_MODEL …, `kernels.layout`)."""
    row[L.MAT_MODEL] = L.MODEL_CONDUCTOR
    row[L.MAT_ALPHA : L.MAT_ALPHA + 2] = conductor.alphas
    index = conductor.index
    if index is not None:  # else η = k = 0: F = 1 (kernels.microfacet.fresnel_conductor)
        row[L.MAT_ETA : L.MAT_ETA + 3] = index[0]
        row[L.MAT_K : L.MAT_K + 3] = index[1]
    row[L.MAT_TINT : L.MAT_TINT + 3] = conductor.tint


def _plastic_columns(row: np.ndarray, plastic) -> None:
    """The physical model's columns of a plastic: its coat's width, index, tint and tables (`compile.plastic`)."""
    from .plastic import coat_tables

    row[L.MAT_MODEL] = L.MODEL_PLASTIC
    row[L.MAT_ALPHA : L.MAT_ALPHA + 2] = plastic.alpha
    row[L.MAT_ETA] = plastic.ior
    row[L.MAT_TINT : L.MAT_TINT + 3] = plastic.tint
    t, fdr = coat_tables(float(plastic.alpha), float(plastic.ior))
    row[L.MAT_FDR] = fdr
    row[L.MAT_COAT : L.MAT_COAT + L.MAT_COAT_SIZE] = t


def _dielectric_columns(row: np.ndarray, glass) -> None:
    """The physical model's columns of glass: its GGX widths, relative index and the two tints."""
    row[L.MAT_MODEL] = L.MODEL_DIELECTRIC
    row[L.MAT_ALPHA : L.MAT_ALPHA + 2] = glass.alphas
    row[L.MAT_ETA] = glass.eta
    row[L.MAT_TINT : L.MAT_TINT + 3] = glass.tint
    row[L.MAT_TINT_T : L.MAT_TINT_T + 3] = glass.transmit_tint


def _principled_columns(row: np.ndarray, principled) -> None:
    """The physical model's columns of glTF's metallic–roughness material: its factors (`kernels.principled`)."""
    from ..kernels.principled import ALPHA_MIN

    row[L.MAT_MODEL] = L.MODEL_PRINCIPLED
    row[L.MAT_BASE : L.MAT_BASE + 3] = principled.base_color
    row[L.MAT_METALLIC] = principled.metallic
    row[L.MAT_ROUGHNESS] = principled.roughness
    row[L.MAT_ALPHA : L.MAT_ALPHA + 2] = principled.roughness**2
    row[L.MAT_TRANSMISSION] = principled.transmission
    row[L.MAT_F0 : L.MAT_F0 + 3] = principled.f0
    row[L.MAT_F90] = principled.specular
    row[L.MAT_CLEARCOAT] = principled.clearcoat
    row[L.MAT_COAT_ALPHA] = max(principled.clearcoat_roughness**2, ALPHA_MIN)


class _Shapes:
    def __init__(self, shutter=(0.0, 0.0)):
        self.xforms, self.infos, self.bounds = [], [], []
        self.shutter = shutter

    def add(self, kind, world_from_canonical, material, object_id, flags=0, light=-1, motion=(0.0, 0.0, 0.0),
            ref=0, count=0, bounds=None, bounded=True) -> int:
        """Add a shape; returns its index. `bounds` overrides the canonical shape's (csg nodes); shapes added
        with `bounded=False` (the solids inside a csg node) stay out of the BVH and the unbounded list."""
        xform = np.zeros((4, 4))
        xform[:3, :4] = np.linalg.inv(world_from_canonical)[:3, :4]
        if any(motion):
            xform[3, :3] = motion
            xform[3, 3] = 1.0
        self.xforms.append(xform)
        self.infos.append((kind, material, object_id, flags, light, ref, count))
        if not bounded:
            self.bounds.append(False)
        elif kind == L.SHAPE_PLANE:
            self.bounds.append(None)
        else:
            box = world_bounds(kind, world_from_canonical) if bounds is None else np.asarray(bounds, np.float64)
            if any(motion):  # swept over the shutter interval
                lo = [box[:3] + tau * np.asarray(motion) for tau in self.shutter]
                hi = [box[3:] + tau * np.asarray(motion) for tau in self.shutter]
                box = np.concatenate([np.minimum(*lo), np.maximum(*hi)])
            self.bounds.append(box)
        return len(self.infos) - 1


def _lights(scene, materials: _Materials, emitters: list):
    """Light arrays; each area light's emitting shape is appended to `emitters` as (kind, matrix, material, light)."""
    n = len(scene.lights)
    kind = np.zeros(n, np.int32)
    samples = np.ones(n, np.int32)
    vecs = np.zeros((n, 6, 3))
    scalars = np.zeros((n, L.LS_SIZE))
    for i, light in enumerate(scene.lights):
        if light.type in ("point", "spot", "directional"):
            vecs[i, L.LV_DIFFUSE] = light.diffuse_intensity
            vecs[i, L.LV_SPECULAR] = light.specular_intensity
            scalars[i, : 3] = (1.0, 0.0, 0.0)
            if light.type in ("point", "spot"):
                kind[i] = L.LIGHT_POINT
                vecs[i, L.LV_POSITION] = light.position
                scalars[i, :3] = light.attenuation
            if light.type == "spot":
                kind[i] = L.LIGHT_SPOT
                vecs[i, L.LV_DIRECTION] = np.divide(light.direction, np.linalg.norm(light.direction))
                scalars[i, L.LS_COS_OUTER] = spot_cos(light.angle)
                scalars[i, L.LS_COS_INNER] = spot_cos(light.inner_angle)
            elif light.type == "directional":
                kind[i] = L.LIGHT_DIRECTIONAL
                vecs[i, L.LV_DIRECTION] = np.divide(light.direction, np.linalg.norm(light.direction))
            continue
        vecs[i, L.LV_DIFFUSE] = light.radiance
        vecs[i, L.LV_SPECULAR] = light.radiance
        samples[i] = light.samples
        scalars[i, L.LS_TWO_SIDED] = 1.0 if light.two_sided else 0.0
        mat = materials.emitter(light.radiance, scene.material_of(light),
                                one_sided=light.shape != "sphere" and not light.two_sided)
        if light.shape == "rect":
            kind[i] = L.LIGHT_RECT
            m = rect_canonical(light.corner, light.edge_u, light.edge_v)
            vecs[i, L.LV_POSITION] = light.corner
            vecs[i, L.LV_DIRECTION] = m[:3, 2]
            vecs[i, L.LV_EDGE_U] = light.edge_u
            vecs[i, L.LV_EDGE_V] = light.edge_v
            scalars[i, L.LS_AREA] = np.linalg.norm(np.cross(light.edge_u, light.edge_v))
            emitters.append((L.SHAPE_RECT, m, mat, i))
        elif light.shape == "disk":
            kind[i] = L.LIGHT_DISK
            f = frame(light.normal)
            vecs[i, L.LV_POSITION] = light.center
            vecs[i, L.LV_DIRECTION] = f[:, 2]
            vecs[i, L.LV_EDGE_U] = f[:, 0] * light.radius
            vecs[i, L.LV_EDGE_V] = f[:, 1] * light.radius
            scalars[i, L.LS_RADIUS] = light.radius
            scalars[i, L.LS_AREA] = np.pi * light.radius**2
            m = np.eye(4)
            m[:3, :3] = np.column_stack([f[:, 0] * light.radius, f[:, 1] * light.radius, f[:, 2]])
            m[:3, 3] = light.center
            emitters.append((L.SHAPE_DISK, m, mat, i))
        else:
            kind[i] = L.LIGHT_SPHERE
            vecs[i, L.LV_POSITION] = light.center
            scalars[i, L.LS_RADIUS] = light.radius
            scalars[i, L.LS_AREA] = 4.0 * np.pi * light.radius**2
            m = np.eye(4)
            m[:3, :3] *= light.radius
            m[:3, 3] = light.center
            emitters.append((L.SHAPE_SPHERE, m, mat, i))
    return kind, samples, vecs, scalars


def spot_cos(degrees: float) -> float:
    """cos of a spot light's cone half-angle; exactly 0 at 90 degrees (a half-space, as a point light's lit side)."""
    return 0.0 if degrees == 90.0 else float(np.cos(np.radians(degrees)))


def compile_scene(scene, reuse: Optional[CompiledScene] = None, tree: bool = True) -> CompiledScene:
    """Flatten a validated `Scene` into `SceneArrays` (analytic shapes as themselves, meshes as triangles) and
    build its BVH; with `reuse` (an earlier compile) its BVH is taken as it is when the primitives' bounds are
    the same to the bit (an edit of materials or lights only: the live preview), and `bvh_build_s` is 0. With
    `tree` False the BVH is an empty one, and the triangles with it: arrays of the same types that hold nothing
    to hit (what a first run compiles the methods' kernels against while the BVH build's kernels compile
    elsewhere: `api.compile_with_helper`)."""
    materials = _Materials(environment_lights_model(scene))
    shapes = _Shapes(scene.camera.shutter)
    tri_parts = []  # (verts, normals, uvs, material, object)
    names = []
    for object_id, obj in enumerate(scene.objects):
        names.append(obj.name or f"{obj.type}#{object_id}")
        mat = materials.add(scene.material_of(obj), one_sided=not obj.two_sided)
        world_from_object = None if obj.transform is None else obj.transform.to_matrix()
        if obj.type in ("triangle", "mesh"):
            if any(obj.motion):
                raise LumosError(f"objects[{object_id}].motion: {obj.type} objects cannot move (motion blur is "
                                 "for spheres, boxes, cylinders, cones, disks, rects, planes and csg objects)")
            tri_v, tri_n, tri_uv, tri_t = mesh_triangles(obj, world_from_object)
            tri_parts.append((tri_v, tri_n, tri_uv, mat, object_id, tri_t))
            continue
        if obj.type == "csg":
            from .csg import add_csg

            add_csg(obj, object_id, world_from_object, scene, materials, shapes, tri_parts)
            continue
        kind, object_from_canonical = canonical(obj)
        m = object_from_canonical if world_from_object is None else world_from_object @ object_from_canonical
        flags = L.FLAG_CAPPED if getattr(obj, "capped", False) else 0
        shapes.add(kind, m, mat, object_id, flags, motion=obj.motion)
    emitters = []
    lights = _lights(scene, materials, emitters)
    for kind, m, mat, i in emitters:
        shapes.add(kind, m, mat, len(scene.objects) + i, light=i)
    return _assemble(scene, materials, shapes, tri_parts, lights, names, reuse, tree)


def environment_lights_model(scene) -> bool:
    """Whether the scene's environment lights the classic model of the local methods: it has one and gives no
    `ambient` of its own."""
    return getattr(scene, "environment", None) is not None and "ambient" not in getattr(scene, "model_fields_set", ())


def _ambient_and_background(scene, env_pixels: Optional[np.ndarray],
                            rotation: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Ia (`layout.AMBIENT_ROWS` rows, and the environment's glossy reflection after them) and what rays that miss
    see where the environment is not looked up: the scene's `ambient` and `background`; with an environment (its
    `env_pixels`, turned `rotation` degrees), its mean radiance for the background, and where the scene gives no
    `ambient`, for Ia its irradiance over π by the surface's normal (a white diffuse surface, ka 1, under a uniform
    sky L shows L; under a sky with a sun it is brighter on the side that faces the sun: the classic Ka·Ia made
    physical) and for Ks its radiance through the material's Phong lobe (`environment.glossy_levels`)."""
    constant = np.array([scene.ambient], dtype=np.float64)
    background = np.array(scene.background, dtype=np.float64)
    if env_pixels is None:
        return constant, background
    from .environment import glossy_levels, irradiance_sh, mean_radiance

    if not environment_lights_model(scene):
        return constant, mean_radiance(env_pixels)
    ambient = np.zeros((L.AMBIENT_ROWS, 3))
    ambient[1:] = irradiance_sh(env_pixels, rotation)
    return np.concatenate([ambient, glossy_levels(env_pixels, rotation)]), mean_radiance(env_pixels)


def _material_names(scene, materials: _Materials) -> list[str]:
    """A name for each material row, for messages: its key in `materials:` or the object that holds it inline."""
    names = {id(m): repr(name) for name, m in scene.materials.items()}
    for key, things in (("objects", scene.objects), ("lights", scene.lights)):
        for i, thing in enumerate(things):
            material = getattr(thing, "material", None)
            if material is not None and not isinstance(material, str):
                names.setdefault(id(material), f"{key}[{i}].material")
    return [names.get(id(m), "(default)" if m is not None else "(light)") for m in materials.materials]


def compile_raster(scene, tessellation: int, shadows: bool, tree: bool = True) -> CompiledScene:
    """The scene for scan conversion: its objects as polygons (`CompiledScene.raster`, shapes tessellated with
    `tessellation` segments) and, for the optional shadow rays (`shadows`), a BVH over those same polygons
    instead of the analytic shapes (`tree`: as `compile_scene`'s)."""
    materials = _Materials(environment_lights_model(scene))
    names = [obj.name or f"{obj.type}#{i}" for i, obj in enumerate(scene.objects)]
    object_materials = [materials.add(scene.material_of(obj), one_sided=not obj.two_sided) for obj in scene.objects]
    emitters = []
    lights = _lights(scene, materials, emitters)
    mesh = build_raster_mesh(scene, tessellation, object_materials, emitters, material_row=materials.add)
    tri_parts = []
    if shadows:  # shadow rays test the polygons the camera sees (area lights cast no shadows)
        faces, prim = mesh.triangles()
        info = mesh.prim_info[prim]
        solid = info[:, 2] < 0
        faces, info = faces[solid], info[solid]
        verts = mesh.positions[faces].reshape(-1, 9)
        uvs = mesh.uvs[faces].reshape(-1, 6)  # where a shadow ray meets an opacity cut-out, its holes are looked up
        for mat, obj in {(int(a), int(b)) for a, b in info[:, :2]}:
            sel = (info[:, 0] == mat) & (info[:, 1] == obj)
            tri_parts.append((verts[sel], None, uvs[sel], mat, obj))
    compiled = _assemble(scene, materials, _Shapes(), tri_parts, lights, names, tree=tree)
    compiled.raster = mesh
    return compiled


def _assemble(scene, materials, shapes, tri_parts, lights, names, reuse=None, tree=True) -> CompiledScene:
    light_kind, light_samples, light_vecs, light_scalars = lights
    tri_verts, tri_normals, tri_uvs, tri_info, tri_tangents = _concat_triangles(tri_parts)
    n_tri, n_shape = len(tri_verts), len(shapes.infos)
    shape_info = np.array(shapes.infos, dtype=np.int32).reshape(-1, L.SHAPE_INFO_SIZE)
    shape_xform = np.array(shapes.xforms, dtype=np.float64).reshape(-1, 4, 4)
    # as vec.normalize computes it (the same sum, the same division), so a face normal scaled by it is bit for bit
    # the normalised one (a shape too small to matter overflows its square to inf, and scales by 0 as normalize's
    # 1/inf does)
    rows = shape_xform[:, :3, :3]
    with np.errstate(over="ignore", invalid="ignore"):
        norms = np.sqrt(rows[:, :, 0] * rows[:, :, 0] + rows[:, :, 1] * rows[:, :, 1] + rows[:, :, 2] * rows[:, :, 2])
        shape_nscale = np.divide(1.0, norms, out=np.zeros_like(norms), where=norms > 0.0)
    # the triangles of mesh solids inside csg objects follow the BVH's (kernels.csg tests them, not the BVH)
    solid_tris = _concat_triangles(getattr(shapes, "solid_triangles", []))
    shape_info[shape_info[:, L.INFO_KIND] == L.SHAPE_MESH_SOLID, L.INFO_REF] += n_tri
    bounded = [s for s in range(n_shape) if shapes.bounds[s] is not None and shapes.bounds[s] is not False]
    unbounded = np.array([s for s in range(n_shape) if shapes.bounds[s] is None], dtype=np.int32)

    # one BVH over triangles and bounded shapes
    prim_bounds = np.empty((n_tri + len(bounded), 6))
    if n_tri:
        v = tri_verts.reshape(-1, 3, 3).astype(np.float64)
        prim_bounds[:n_tri, :3] = v.min(axis=1)
        prim_bounds[:n_tri, 3:] = v.max(axis=1)
    for k, s in enumerate(bounded):
        prim_bounds[n_tri + k] = shapes.bounds[s]
    key = hashlib.sha256(prim_bounds.tobytes() + str(n_tri).encode()).hexdigest()
    if not tree:  # an empty tree over nothing: the leaf order below then keeps no triangle either
        node_box, node_link, order, depth = build(prim_bounds[:0])
        build_s = 0.0
    elif reuse is not None and reuse.bvh is not None and reuse.bvh[0] == key:
        node_box, node_link, order, depth = (a.copy() if isinstance(a, np.ndarray) else a for a in reuse.bvh[1])
        build_s = 0.0
    else:
        t0 = time.perf_counter()
        node_box, node_link, order, depth = build(prim_bounds, first_shape=n_tri)
        build_s = time.perf_counter() - t0
    # the builder's output, kept for `reuse` (the packing below writes links into views of the node arrays)
    built = (key, tuple(a.copy() if isinstance(a, np.ndarray) else a for a in (node_box, node_link, order, depth)))
    node_box, node_link = pack_nodes(node_box, node_link)
    wide_box, wide_link = wide_nodes(node_box, node_link)

    # leaf order: triangles are permuted so that leaves read them contiguously
    is_tri = order < n_tri
    tri_order = order[is_tri]
    prim_ref = np.empty(len(order), np.int32)
    prim_ref[is_tri] = np.arange(len(tri_order), dtype=np.int32)
    shape_ids = np.array(bounded, dtype=np.int64)[order[~is_tri] - n_tri] if len(bounded) else np.zeros(0, np.int64)
    prim_ref[~is_tri] = ~shape_ids.astype(np.int32)

    tex_info, tex_pixels = build_textures(materials)  # also fills the rows' MAT_TEXTURE / MAT_BUMP
    from .environment import environment_arrays

    environment = getattr(scene, "environment", None)
    env = environment_arrays(environment)  # read once: the ray methods' misses and path's light sampling use it
    ambient, background = _ambient_and_background(scene, env[0] if environment is not None else None,
                                                  environment.rotation if environment is not None else 0.0)
    material_rows = materials.array()
    if n_shape:
        shape_mats = material_rows[shape_info[:, L.INFO_MATERIAL]]
        reads_uv = (shape_mats[:, L.MAT_TEXTURE] >= 0) | (shape_mats[:, L.MAT_BUMP] >= 0)
        shape_info[reads_uv, L.INFO_FLAGS] |= L.FLAG_READS_UV
    all_tri_verts = _leaf_ordered(tri_verts, tri_order, solid_tris[0])
    all_tri_info = _leaf_ordered(tri_info, tri_order, solid_tris[3])
    tri_face = _triangle_faces(tri_order, all_tri_info[:len(tri_order), L.INFO_OBJECT])
    leaf_tris, leaf_link = packed_leaves(wide_link, prim_ref, all_tri_verts, all_tri_info[:, L.INFO_OBJECT],
                                         np.concatenate([tri_face, np.full(len(solid_tris[0]), -1, np.int32)]),
                                         all_tri_info[:, L.INFO_FLAGS] & L.FLAG_UVS != 0)
    arrays = L.SceneArrays(
        tri_verts=all_tri_verts,
        tri_normals=_leaf_ordered(tri_normals, tri_order, solid_tris[1]),
        tri_uvs=_leaf_ordered(tri_uvs, tri_order, solid_tris[2]),
        tri_info=all_tri_info,
        shape_xform=shape_xform,
        shape_info=shape_info,
        shape_nscale=shape_nscale,
        prim_ref=prim_ref,
        node_box=node_box,
        node_link=node_link,
        wide_nodes=wide_box,
        wide_link=wide_link,
        leaf_tris=leaf_tris,
        leaf_link=leaf_link,
        unbounded=unbounded,
        materials=material_rows,
        light_kind=light_kind,
        light_samples=light_samples,
        light_vecs=light_vecs,
        light_scalars=light_scalars,
        ambient=ambient,
        background=background,
        env_pixels=env[0],
        env_info=env[3],
        csg_nodes=np.asarray(getattr(shapes, "csg_nodes", np.zeros((0, 4), np.int32)), np.int32).reshape(-1, 4),
        tex_info=tex_info,
        tex_pixels=tex_pixels,
        tri_tangents=_tangent_rows(tri_tangents[tri_order], solid_tris[4]),
    )
    if len(prim_bounds):
        bounds = np.array([prim_bounds[:, :3].min(axis=0), prim_bounds[:, 3:].max(axis=0)])
    else:
        bounds = np.zeros((2, 3))
    return CompiledScene(arrays, build_s, depth, n_tri, n_shape, bounds, names,
                         material_names=_material_names(scene, materials), triangle_order=tri_order,
                         triangle_faces=tri_face, environment=env if environment is not None else None,
                         bvh=built)


def _leaf_ordered(rows: np.ndarray, order: np.ndarray, tail: np.ndarray) -> np.ndarray:
    """rows[order] followed by tail, in one aligned array (huge pages when large: shading reads a hit's rows)."""
    out = aligned_zeros((len(order) + len(tail),) + rows.shape[1:], rows.dtype)
    np.take(rows, order, axis=0, out=out[:len(order)])
    out[len(order):] = tail
    return out


def _triangle_faces(order: np.ndarray, objects: np.ndarray) -> np.ndarray:
    """int32 (nt,): each BVH-ordered triangle's face index in its own mesh, from `order` (its index among all the
    triangles, taken object after object) and its object id."""
    faces = np.full(len(order), -1, np.int32)
    if len(order):
        obj_of_concat = np.empty(len(order), np.int64)
        obj_of_concat[order] = objects
        first = np.searchsorted(obj_of_concat, np.arange(obj_of_concat.max() + 1))  # objects come in order
        faces[:] = order - first[objects]
    return faces


def triangle_arrays(tri_verts: np.ndarray, tri_ids: np.ndarray) -> CompiledScene:
    """A compiled "scene" of bare triangles, for ray queries against geometry that is not a scene (radiosity's
    patches): tri_verts float (m, 9) world-space corners, tri_ids int (m,) stored as each triangle's object id
    (`tri_info[:, INFO_OBJECT]`, in the BVH's triangle order); no lights, one black material."""
    from types import SimpleNamespace

    materials = _Materials()
    materials.emitter((0.0, 0.0, 0.0))
    lights = (np.zeros(0, np.int32), np.zeros(0, np.int32), np.zeros((0, 6, 3)), np.zeros((0, 5)))
    stand_in = SimpleNamespace(ambient=(0.0, 0.0, 0.0), background=(0.0, 0.0, 0.0), materials={}, objects=[],
                               lights=[])
    parts = [(np.asarray(tri_verts, np.float64), None, None, 0, np.asarray(tri_ids, np.int32))]
    return _assemble(stand_in, materials, _Shapes(), parts, lights, [])


def _concat_triangles(parts):
    """parts: (verts, normals, uvs, material, object[, tangents]) → tri_verts, tri_normals, tri_uvs, tri_info and
    the tangents float32 (m, 12) (zeros where a part has none)."""
    if not parts:
        return (np.zeros((0, 9), np.float32), np.zeros((0, 9), np.float32), np.zeros((0, 6), np.float32),
                np.zeros((0, 5), np.int32), np.zeros((0, 12), np.float32))
    verts, normals, uvs, infos, tangents = [], [], [], [], []
    for v, n, uv, mat, obj, *rest in parts:
        t = rest[0] if rest else None
        m = len(v)
        verts.append(v.astype(np.float32))
        normals.append(np.zeros((m, 9), np.float32) if n is None else n.astype(np.float32))
        uvs.append(np.zeros((m, 6), np.float32) if uv is None else uv.astype(np.float32))
        tangents.append(np.zeros((m, 12), np.float32) if t is None else t.astype(np.float32))
        flags = ((L.FLAG_NORMALS if n is not None else 0) | (L.FLAG_UVS if uv is not None else 0)
                 | (L.FLAG_TANGENTS if t is not None else 0))
        info = np.empty((m, 5), np.int32)
        info[:] = (0, mat, 0, flags, -1)
        info[:, L.INFO_OBJECT] = obj  # one object id, or one per triangle
        infos.append(info)
    return (np.concatenate(verts), np.concatenate(normals), np.concatenate(uvs), np.concatenate(infos),
            np.concatenate(tangents))


def _tangent_rows(*parts) -> np.ndarray:
    """tri_tangents: the parts' rows concatenated, or (0, 12) when no triangle has tangents (no memory spent on
    meshes without them)."""
    rows = np.concatenate(parts)
    if not np.any(rows):
        return np.zeros((0, 12), np.float32)
    return np.ascontiguousarray(rows, dtype=np.float32)
