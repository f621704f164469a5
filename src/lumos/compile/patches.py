"""Meshing a scene into patches: every surface as planar triangles and quads no larger than `patch_size`.

    patches = mesh_scene(scene, patch_size=0.1, segments=48)

- meshes and triangles: their triangles (after the mesh keys' fix-ups), each cut into k² triangles whose
  longest edge is at most √2·`patch_size` (a barycentric grid; a triangle with legs of `patch_size` is half a
  grid cell);
- boxes, rects and planes: quads cut into a grid of cells at most `patch_size` on a side; a plane is clipped
  to the rectangle that covers the rest of the scene's bounds (10% larger), since an infinite floor has no
  finite patches;
- spheres, cylinders, cones and disks: the scan-line renderer's tessellation (`compile.tessellate`) at
  `segments`, then cut like meshes;
- csg objects: the scan-line renderer's boolean mesh (`compile.csg_mesh`: the solids tessellated at `segments`
  and combined by mesh booleans), each solid's faces with its own material, cut like meshes;
- area lights: their emitting shapes, tessellated the same way, emitting their radiance on the lit side.

**Sides.** Light may reach either side of an open surface (a wall, a disk, a triangle, a mesh), so each side of
its polygons is a patch of its own, facing its own way; a closed solid (sphere, box, capped cylinder or cone, a
watertight consistently wound mesh) has its outside, and its inside too only when a light or the camera is
inside it (a room built as a box); when every light and the camera are inside, its outside is no patch (no
light reaches it and no eye sees it: the furnace, the closed room). A side that is not a patch (the inside of a solid, the back of a rect or disk
light that neither emits there nor has a material) still blocks light. The polygons (`polys`) are the geometry, shared by both
sides; `side_patch` maps each polygon's front (the side its normal points to) and back to a patch.

**Materials, read as radiosity reads them.** ρ = kd (scaled down, as the path tracer does, when kd + ks + kr +
kt exceeds 1); ks, kr and kt take no part in the diffuse solution (the display traces mirrors and glass in a
second pass); emission leaves every side that is a patch, except the back of a one-sided emitter (an object with
`two_sided: false`; a rect or disk light unless it is `two_sided`). An area light with a material reflects as ρ. Textures are not looked up per point: a
textured material takes part with its texture's mean colour where it applies (a warning says so).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import LumosError
from ..kernels import layout as L

#: A plane is clipped to the scene's bounds grown by this fraction on each side.
PLANE_MARGIN = 0.1
#: Cosine of the largest angle between face normals that the display still smooths across.
SMOOTH_COS = math.cos(math.radians(35.0))


@dataclass
class Patches:
    """The geometry (polygons, shared by their two sides) and the patches (one per side that receives light)."""

    vertices: np.ndarray  # float64 (nv, 3)
    polys: np.ndarray  # int32 (npoly, 4): corners counter-clockwise about poly_normal; column 3 = -1: a triangle
    poly_normal: np.ndarray  # float64 (npoly, 3) unit, the front side's normal
    side_patch: np.ndarray  # int32 (npoly, 2): patch of the front side and of the back side, -1 where none
    patch_poly: np.ndarray  # int32 (n,): the polygon each patch is a side of
    patch_side: np.ndarray  # int8 (n,): +1 front, -1 back
    area: np.ndarray  # float64 (n,)
    centre: np.ndarray  # float64 (n, 3)
    normal: np.ndarray  # float64 (n, 3): unit, the way the patch faces
    reflectance: np.ndarray  # float64 (n, 3)
    emission: np.ndarray  # float64 (n, 3)
    object_id: np.ndarray  # int32 (n,)
    material: np.ndarray  # int32 (n,)
    smooth_group: np.ndarray  # int32 (n,): patches of one surface the display may smooth across (object, material)
    optics: np.ndarray  # float64 (n, 9): kr (3), kt (3), ior, fresnel (1/0), and 1 for a solid's outside, -1 for
    # its inside, 0 for an open surface: what the two-pass display needs to trace mirrors and glass
    surfaces: np.ndarray  # float64 (m, 3, 3): the surfaces before they were cut into polygons, as triangles
    # (a box face, a rect: two): the same geometry as `polys` in far fewer pieces, what blocks visibility rays
    surface_object: np.ndarray  # int32 (m,): the object (or area light, numbered after them) of each triangle

    @property
    def n(self) -> int:
        return int(len(self.area))

    def corners(self, i: int) -> np.ndarray:
        """float64 (3 or 4, 3): patch i's corners, counter-clockwise about its own normal."""
        idx = self.polys[self.patch_poly[i]]
        idx = idx[idx >= 0]
        return self.vertices[idx if self.patch_side[i] > 0 else idx[::-1]]


class _Builder:
    def __init__(self):
        self.vertices: list[np.ndarray] = []
        self.polys: list[np.ndarray] = []
        self.count = 0
        self.meta: list[tuple] = []  # per polygon: (front?, back?, reflectance, emission, object, material, group,
        # optics)
        self.optics = np.zeros(8)  # of the object being added (set by mesh_scene)
        self.surfaces: list[np.ndarray] = []  # each surface uncut, as triangles (k, 3, 3)
        self.surface_object: list[np.ndarray] = []

    def add(self, verts: np.ndarray, polys: np.ndarray, front: bool, back: bool, rho, le, object_id: int,
            material: int, group: int, solid: bool = False, emit_back: bool = True) -> None:
        """Polygons (m, 3 or 4) over `verts` (k, 3), counter-clockwise about their front normal; `le` leaves the
        front patches, and the back ones where `emit_back`."""
        if len(polys) == 0:
            return
        polys = np.asarray(polys, np.int64)
        if polys.shape[1] == 3:
            polys = np.concatenate([polys, np.full((len(polys), 1), -1)], axis=1)
        out = np.where(polys >= 0, polys + self.count, -1)
        self.vertices.append(np.asarray(verts, np.float64))
        self.polys.append(out.astype(np.int32))
        self.count += len(verts)
        le = np.asarray(le, np.float64)
        self.meta.append((len(polys), front, back, np.asarray(rho, np.float64), (le, le if emit_back else 0.0 * le),
                          object_id, material, group, self.optics, solid))


def _grid_quads(corner, eu, ev, patch_size):
    """A parallelogram corner + s·eu + t·ev cut into nu × nv cells no larger than patch_size."""
    nu = max(1, int(math.ceil(np.linalg.norm(eu) / patch_size - 1e-9)))
    nv = max(1, int(math.ceil(np.linalg.norm(ev) / patch_size - 1e-9)))
    s = np.linspace(0.0, 1.0, nu + 1)
    t = np.linspace(0.0, 1.0, nv + 1)
    S, T = np.meshgrid(s, t, indexing="ij")
    verts = corner + S.reshape(-1, 1) * eu + T.reshape(-1, 1) * ev
    idx = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    quads = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1).reshape(-1, 4)
    return verts, quads


def _split_triangles(verts, tris, patch_size):
    """Each triangle cut into k² triangles (a barycentric grid, k from its longest edge over √2·patch_size: a
    triangle whose legs are at most patch_size is half of a grid cell, and as large as a patch may be); vertices
    on shared edges are not merged (the patches of neighbouring triangles meet edge to edge all the same)."""
    out_v, out_t = [], []
    base = 0
    tris = np.asarray(tris, np.int64)
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    longest = np.max(np.stack([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                               np.linalg.norm(a - c, axis=1)]), axis=0)
    ks = np.maximum(1, np.ceil(longest / (math.sqrt(2.0) * patch_size) - 1e-9)).astype(np.int64)
    if np.all(ks == 1):
        return verts, tris
    for k in np.unique(ks[ks > 1]):  # (triangles with k = 1 are kept whole below)
        sel = np.nonzero(ks == k)[0]
        # the grid's barycentric points (i, j) with i + j <= k, and its k² small triangles
        pts = [(i, j) for i in range(k + 1) for j in range(k + 1 - i)]
        index = {p: n for n, p in enumerate(pts)}
        small = []
        for i in range(k):
            for j in range(k - i):
                small.append((index[(i, j)], index[(i + 1, j)], index[(i, j + 1)]))
                if i + j < k - 1:
                    small.append((index[(i + 1, j)], index[(i + 1, j + 1)], index[(i, j + 1)]))
        w = np.array(pts, np.float64) / k  # weights of b and c
        small = np.array(small, np.int64)
        for t in sel:
            p = a[t] + w[:, 0:1] * (b[t] - a[t]) + w[:, 1:2] * (c[t] - a[t])
            out_v.append(p)
            out_t.append(small + base)
            base += len(p)
    keep = np.nonzero(ks == 1)[0]
    if len(keep):
        out_v.append(verts[tris[keep]].reshape(-1, 3))
        out_t.append(np.arange(3 * len(keep)).reshape(-1, 3) + base)
    return np.concatenate(out_v), np.concatenate(out_t)


def _box_faces(world_from_canonical):
    """The six faces of the canonical cube [0, 1]³ placed by the matrix: (corner, edge_u, edge_v) each,
    counter-clockwise about the outward normal (flipped under a mirroring matrix)."""
    m = world_from_canonical
    P = lambda x, y, z: m[:3, :3] @ np.array([x, y, z], np.float64) + m[:3, 3]  # noqa: E731
    ex, ey, ez = m[:3, 0], m[:3, 1], m[:3, 2]
    faces = [(P(0, 0, 0), ez, ey), (P(1, 0, 0), ey, ez),  # x = 0 (normal -x), x = 1 (+x)
             (P(0, 0, 0), ex, ez), (P(0, 1, 0), ez, ex),  # y = 0, y = 1
             (P(0, 0, 0), ey, ex), (P(0, 0, 1), ex, ey)]  # z = 0, z = 1
    if np.linalg.det(m[:3, :3]) < 0:
        faces = [(c, v, u) for c, u, v in faces]
    return faces


def _plane_rect(world_from_canonical, lo, hi):
    """The rectangle of the plane that covers the box [lo, hi] seen along the plane's normal: (corner, eu, ev)."""
    m = world_from_canonical
    e1, e2 = m[:3, 0] / np.linalg.norm(m[:3, 0]), m[:3, 1] / np.linalg.norm(m[:3, 1])
    origin = m[:3, 3]
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    a, b = (corners - origin) @ e1, (corners - origin) @ e2
    (a0, a1), (b0, b1) = (a.min(), a.max()), (b.min(), b.max())
    return origin + a0 * e1 + b0 * e2, (a1 - a0) * e1, (b1 - b0) * e2


def _closed_and_outward(verts, tris) -> bool:
    """A mesh that bounds a volume with its faces wound outward (so only its outside needs patches)."""
    try:
        import trimesh

        m = trimesh.Trimesh(verts, tris, process=True)
        return bool(m.is_watertight and m.is_winding_consistent and m.volume > 0)
    except Exception:  # noqa: BLE001  (an odd mesh: treat it as open, both sides)
        return False


def _inside_canonical(kind: int, q: np.ndarray) -> np.ndarray:
    """Which canonical points q (m, 3) are inside the canonical solid `kind`."""
    x, y, z = q[:, 0], q[:, 1], q[:, 2]
    if kind == L.SHAPE_SPHERE:
        return x * x + y * y + z * z < 1.0
    if kind == L.SHAPE_BOX:
        return np.all((q > 0.0) & (q < 1.0), axis=1)
    if kind == L.SHAPE_CYLINDER:
        return (x * x + y * y < 1.0) & (z > 0.0) & (z < 1.0)
    if kind == L.SHAPE_CONE:
        return (x * x + y * y < (1.0 - z) ** 2) & (z > 0.0) & (z < 1.0)
    return np.zeros(len(q), bool)


def _inside_solid(kind, world_from_canonical, points) -> np.ndarray:
    """Which points (m, 3) are inside the solid `kind` placed by `world_from_canonical`."""
    inv = np.linalg.inv(world_from_canonical)
    return _inside_canonical(kind, points @ inv[:3, :3].T + inv[:3, 3])


def _inside_mesh(verts, tris, points) -> np.ndarray | None:
    """Which points (m, 3) are inside the closed mesh; None when trimesh cannot tell."""
    try:
        import trimesh

        return np.asarray(trimesh.Trimesh(verts, tris, process=False).contains(points), bool)
    except Exception:  # noqa: BLE001
        return None


def _sides(inside: np.ndarray | None, clear: bool, scene) -> tuple[bool, bool]:
    """Which sides of a closed solid are patches, (outside, inside), from which of the viewpoints
    (`_viewpoints`) are inside it (None: unknown). The inside is one when a viewpoint is in it (a room built as
    a box) or the solid is transparent; the outside is one unless every viewpoint is inside and no light
    comes from infinitely far (a closed furnace, the camera in a room-box): then no light reaches the outside
    and no eye sees it. When trimesh cannot tell, both."""
    if inside is None:
        return True, True
    everything_inside = (len(inside) > 0 and bool(np.all(inside))
                         and not any(light.type == "directional" for light in scene.lights))
    return clear or not everything_inside, clear or bool(np.any(inside))


def _viewpoints(scene, exclude: int) -> np.ndarray:
    """Points from which light or the eye may be inside a solid: the camera, point and spot lights, the centres of area
    lights and of emissive objects (other than object `exclude`)."""
    pts = [np.asarray(scene.camera.position, np.float64)]
    for light in scene.lights:
        if light.type in ("point", "spot"):
            pts.append(np.asarray(light.position, np.float64))
        elif light.type == "area":
            if light.shape == "rect":
                pts.append(np.asarray(light.corner) + 0.5 * np.asarray(light.edge_u) + 0.5 * np.asarray(light.edge_v))
            else:
                pts.append(np.asarray(light.center, np.float64))
    for i, obj in enumerate(scene.objects):
        if i != exclude and any(c > 0 for c in scene.material_of(obj).emission):
            for key in ("center", "base", "point", "corner"):
                if hasattr(obj, key):
                    pts.append(np.asarray(getattr(obj, key), np.float64))
                    break
    return np.array(pts, np.float64).reshape(-1, 3)


def usable_bounds(bounds) -> tuple[np.ndarray, np.ndarray]:
    """The compile step's bounds of everything bounded (planes excluded), or a unit box around the origin for a
    scene of planes alone."""
    lo, hi = (np.asarray(b, np.float64) for b in bounds)
    if not np.all(np.isfinite([lo, hi])) or np.all(hi - lo <= 0):
        lo, hi = np.full(3, -1.0), np.full(3, 1.0)
    return lo, hi


def default_patch_size(lo, hi) -> float:
    """A patch size for a scene that gives no `patch_size`: 1/24 of its bounds' diagonal."""
    return max(float(np.linalg.norm(hi - lo)) / 24.0, 1e-6)


@dataclass
class Surface:
    """One surface of the scene as radiosity meshes it, before it is cut into patches: which object (or area
    light, numbered after the objects) it belongs to, which of its sides are patches, and its geometry: a
    parallelogram (`grid`: corner, edge_u, edge_v; cut into cells) or triangles (`triangles()`, computed when
    asked: a curved shape's tessellation is not needed to know its sides)."""

    object_id: int
    outer: bool  # the front side (the side the polygons' normals face) is a patch
    inner: bool  # the back side is a patch
    group: int  # smoothing group of the display
    material: object = None  # the scene's Material; an area light's (None: it reflects nothing)
    emission: np.ndarray = None  # an area light's radiance (None for an object: its material's emission)
    solid: bool = False
    grid: tuple = None
    triangles: Callable = None  # () -> (vertices (k, 3), triangles (m, 3))


def surfaces(scene, segments: int, plane_lo, plane_hi):
    """The `Surface`s of every object and area light of `scene`, in order (module doc: sides); planes clipped to
    the box plane_lo … plane_hi."""
    from .csg_mesh import csg_pieces
    from .meshprep import prepare_mesh
    from .shapes import canonical, frame
    from .tessellate import tessellate_object

    n_groups = len(scene.objects) + len(scene.lights)  # smoothing groups: objects, area lights, then csg solids
    for object_id, obj in enumerate(scene.objects):
        material = scene.material_of(obj)
        clear = any(c > 0 for c in material.classic()["kt"])  # a transparent solid: rays inside it meet its inside
        world = None if obj.transform is None else obj.transform.to_matrix()
        if obj.type == "csg":  # the scan-line renderer's boolean mesh: closed, one piece per solid that shows
            pieces = csg_pieces(scene, obj, world, segments, f"objects[{object_id}]")
            if not pieces:
                continue
            offsets = np.cumsum([0] + [len(p.vertices) for p in pieces])
            inside = _inside_mesh(np.concatenate([p.vertices for p in pieces]),
                                  np.concatenate([p.faces + k for p, k in zip(pieces, offsets)]),
                                  _viewpoints(scene, object_id))
            for piece in pieces:
                outer, inner = _sides(inside, any(c > 0 for c in piece.material.classic()["kt"]), scene)
                yield Surface(object_id, outer, inner, n_groups, piece.material, solid=True,  # smoothed per solid
                              triangles=lambda piece=piece: (piece.vertices, piece.faces))
                n_groups += 1
            continue
        if obj.type in ("mesh", "triangle"):
            m = prepare_mesh(obj, world)
            tris = np.asarray(m.polygons, np.int64)
            closed = obj.type == "mesh" and _closed_and_outward(m.vertices, tris)
            outer, inner = (_sides(_inside_mesh(m.vertices, tris, _viewpoints(scene, object_id)), clear, scene)
                            if closed else (True, True))
            yield Surface(object_id, outer, inner, object_id, material, solid=closed,
                          triangles=lambda m=m, tris=tris: (m.vertices, tris))
            continue
        kind, object_from_canonical = canonical(obj)
        w = object_from_canonical if world is None else world @ object_from_canonical
        if kind == L.SHAPE_BOX:
            outer, inner = _sides(_inside_solid(kind, w, _viewpoints(scene, object_id)), clear, scene)
            for face in _box_faces(w):
                yield Surface(object_id, outer, inner, object_id, material, solid=True, grid=face)
        elif kind == L.SHAPE_RECT:
            yield Surface(object_id, True, True, object_id, material, grid=(w[:3, 3], w[:3, 0], w[:3, 1]))
        elif kind == L.SHAPE_PLANE:
            corner, eu, ev = _plane_rect(w, plane_lo, plane_hi)
            if np.dot(np.cross(eu, ev), w[:3, 2]) < 0:
                eu, ev = ev, eu
            yield Surface(object_id, True, True, object_id, material, grid=(corner, eu, ev))
        else:
            capped = getattr(obj, "capped", True)
            closed = kind == L.SHAPE_SPHERE or (kind in (L.SHAPE_CYLINDER, L.SHAPE_CONE) and capped)
            where = f"objects[{object_id}]"
            tessellate_object(kind, w, 3, capped, where)  # checks the placement now, cheaply (3 segments)
            outer, inner = (_sides(_inside_solid(kind, w, _viewpoints(scene, object_id)), clear, scene)
                            if closed else (True, True))

            def tessellated(kind=kind, w=w, capped=capped, where=where):
                t = tessellate_object(kind, w, segments, capped, where)
                return t.vertices, t.faces

            yield Surface(object_id, outer, inner, object_id, material, solid=closed, triangles=tessellated)
    # area lights: their emitting shapes, the lit side a patch, and the other one where it emits too or reflects
    # (else the other side of a rect or disk only blocks light)
    n_objects = len(scene.objects)
    for i, light in enumerate(scene.lights):
        if light.type != "area":
            continue
        le = np.asarray(light.radiance, np.float64)
        material = scene.material_of(light)
        back = light.two_sided or material is not None
        if light.shape == "rect":
            yield Surface(n_objects + i, True, back, n_objects + i, material, emission=le,
                          grid=(np.asarray(light.corner, float), np.asarray(light.edge_u, float),
                                np.asarray(light.edge_v, float)))
            continue
        m = np.eye(4)
        if light.shape == "disk":
            f = frame(light.normal)
            m[:3, :3] = np.column_stack([f[:, 0] * light.radius, f[:, 1] * light.radius, f[:, 2]])
            kind = L.SHAPE_DISK
        else:
            m[:3, :3] *= light.radius
            kind = L.SHAPE_SPHERE
        m[:3, 3] = light.center

        def tessellated(kind=kind, m=m, i=i):
            t = tessellate_object(kind, m, segments, True, f"lights[{i}]", "light")
            return t.vertices, t.faces

        yield Surface(n_objects + i, True, back and light.shape == "disk", n_objects + i, material, emission=le,
                      triangles=tessellated)


def _plane_box(scene, bounds) -> tuple[np.ndarray, np.ndarray]:
    """The box planes are clipped to: the compile step's bounds grown by PLANE_MARGIN, and far enough to reach
    under the camera, so the floor in front of it is not cut off in view."""
    lo, hi = usable_bounds(bounds)
    grow = PLANE_MARGIN * np.maximum(hi - lo, 1e-6)
    eye = np.asarray(scene.camera.position, np.float64)
    return np.minimum(lo - grow, eye), np.maximum(hi + grow, eye)


def patch_sides(scene, bounds, segments: int = 48) -> np.ndarray:
    """int64 (2, k): the (object id, side) pairs, side +1 front and −1 back, that are patches, sorted: what a
    solution depends on besides the scene model (`scene_digest`), found without meshing (no tessellation, no
    cutting; a csg object's boolean mesh and a closed mesh's containment test are still needed)."""
    pairs = set()
    for surface in surfaces(scene, segments, *_plane_box(scene, bounds)):
        if surface.outer:
            pairs.add((surface.object_id, 1))
        if surface.inner:
            pairs.add((surface.object_id, -1))
    return np.array(sorted(pairs), np.int64).reshape(-1, 2).T


def mesh_scene(scene, bounds, patch_size=None, segments: int = 48) -> Patches:
    """Patches of every object and area light of a validated `Scene` (see the module doc); `bounds` (2, 3) are
    the compile step's (`CompiledScene.bounds`), to which planes are clipped."""
    import warnings

    from .textures import mean_coefficients
    from ..errors import LumosWarning

    if patch_size is None:
        patch_size = default_patch_size(*usable_bounds(bounds))
    plane_lo, plane_hi = _plane_box(scene, bounds)
    b = _Builder()
    mat_index: dict[int, int] = {}
    textured = set()

    def material_row(mat) -> tuple[int, np.ndarray, np.ndarray]:
        key = id(mat)
        if key not in mat_index:
            mat_index[key] = len(mat_index)
        means = mean_coefficients(mat)  # a patch takes its textures' mean colours where they apply
        kd, ks, kr, emission = means["kd"], means["ks"], means["kr"], means["emission"]
        if mat.textures:
            if key not in textured:
                textured.add(key)
                name = next((repr(k) for k, m in scene.materials.items() if m is mat), "an inline material")
                warnings.warn(f"radiosity does not look textures up per point: material {name} takes part with "
                              "its texture's mean colour", LumosWarning, stacklevel=3)
                if any("opacity" in t.apply_to for t in mat.textures):
                    warnings.warn(f"radiosity ignores opacity maps: the surfaces of material {name} stay whole "
                                  "(no cut-out holes)", LumosWarning, stacklevel=3)
        total = kd + ks + kr + np.asarray(mat.classic()["kt"])
        if total.max() > 1.0:
            kd = kd / total.max()
        return mat_index[key], kd, emission

    def optics(material) -> np.ndarray:
        c = material.classic()
        return np.array([*c["kr"], *c["kt"], c["ior"], 1.0 if c["fresnel"] else 0.0])

    n_objects = len(scene.objects)
    for surface in surfaces(scene, segments, plane_lo, plane_hi):
        if surface.material is None:  # an area light without a material: emits, reflects nothing
            mat, rho, le = -1, np.zeros(3), surface.emission
            b.optics = np.zeros(8)
        else:
            mat, rho, le = material_row(surface.material)
            b.optics = optics(surface.material)
        if surface.object_id < n_objects:  # an object: two-sided emission unless it says otherwise
            emit_back = scene.objects[surface.object_id].two_sided
        else:  # an area light: its radiance, on its back only where two-sided
            le, emit_back = surface.emission, scene.lights[surface.object_id - n_objects].two_sided
        if surface.grid is not None:
            v, polys = _grid_quads(*surface.grid, patch_size)
            corner, eu, ev = (np.asarray(g, np.float64) for g in surface.grid)
            b.surfaces.append(np.array([[corner, corner + eu, corner + eu + ev],
                                        [corner, corner + eu + ev, corner + ev]]))
        else:
            whole_v, whole_t = surface.triangles()
            v, polys = _split_triangles(whole_v, whole_t, patch_size)
            b.surfaces.append(np.asarray(whole_v, np.float64)[np.asarray(whole_t, np.int64)].reshape(-1, 3, 3))
        b.surface_object.append(np.full(len(b.surfaces[-1]), surface.object_id, np.int32))
        b.add(v, polys, surface.outer, surface.inner, rho, le, surface.object_id, mat, surface.group, surface.solid,
              emit_back)
    return _assemble(b)


def _assemble(b: _Builder) -> Patches:
    if not b.polys:
        raise LumosError("radiosity: the scene has no surfaces to mesh into patches")
    vertices = np.concatenate(b.vertices)
    polys = np.concatenate(b.polys)
    p = vertices[np.maximum(polys, 0)]  # (npoly, 4, 3); a triangle repeats corner 0 in slot 3
    tri = polys[:, 3] < 0
    p[tri, 3] = p[tri, 0]
    # area and normal of a planar polygon: half the cross product of its diagonals (exact for triangles and
    # planar quads)
    cross = 0.5 * np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    cross[tri] = 0.5 * np.cross(p[tri, 1] - p[tri, 0], p[tri, 2] - p[tri, 0])
    area = np.linalg.norm(cross, axis=1)
    good = area > 1e-300
    normal = np.divide(cross, np.maximum(area, 1e-300)[:, None])
    centre = np.where(tri[:, None], p[:, :3].mean(axis=1), p.mean(axis=1))
    side_patch = np.full((len(polys), 2), -1, np.int32)
    cols = {k: [] for k in ("poly", "side", "rho", "le", "obj", "mat", "group", "optics")}
    start = 0
    n = 0
    for count, front, back, rho, le, obj, mat, group, opt, solid in b.meta:
        for side, wanted in ((0, front), (1, back)):
            if not wanted:
                continue
            idx = np.arange(start, start + count)
            idx = idx[good[idx]]
            side_patch[idx, side] = np.arange(n, n + len(idx))
            n += len(idx)
            cols["poly"].append(idx)
            cols["side"].append(np.full(len(idx), 1 if side == 0 else -1, np.int8))
            cols["rho"].append(np.broadcast_to(rho, (len(idx), 3)))
            cols["le"].append(np.broadcast_to(le[side], (len(idx), 3)))
            cols["obj"].append(np.full(len(idx), obj, np.int32))
            cols["mat"].append(np.full(len(idx), mat, np.int32))
            cols["group"].append(np.full(len(idx), 2 * group + side, np.int32))
            kind = 0.0 if not solid else (1.0 if side == 0 else -1.0)
            cols["optics"].append(np.broadcast_to(np.append(opt, kind), (len(idx), 9)))
        start += count
    patch_poly = np.concatenate(cols["poly"]).astype(np.int32)
    side = np.concatenate(cols["side"])
    return Patches(
        vertices=vertices, polys=polys, poly_normal=normal, side_patch=side_patch, patch_poly=patch_poly,
        patch_side=side, area=area[patch_poly], centre=centre[patch_poly],
        normal=normal[patch_poly] * side[:, None], reflectance=np.ascontiguousarray(np.concatenate(cols["rho"])),
        emission=np.ascontiguousarray(np.concatenate(cols["le"])), object_id=np.concatenate(cols["obj"]),
        material=np.concatenate(cols["mat"]), smooth_group=np.concatenate(cols["group"]),
        optics=np.ascontiguousarray(np.concatenate(cols["optics"])),
        surfaces=np.concatenate(b.surfaces), surface_object=np.concatenate(b.surface_object))


def refine(p: Patches, split_poly: np.ndarray) -> tuple[Patches, np.ndarray]:
    """`p` with the polygons flagged in `split_poly` (bool (npoly,)) cut in four (a quad through its edge
    midpoints and centre, a triangle through its edge midpoints), each side's patch into the four patches of the
    same side; returns (the refined patches, the index in `p` of each refined patch's parent)."""
    polys = p.polys
    keep = ~split_poly
    quads = split_poly & (polys[:, 3] >= 0)
    tris = split_poly & (polys[:, 3] < 0)
    v = p.vertices
    new_v = [v]
    new_polys = [polys[keep]]
    origin = [np.nonzero(keep)[0]]  # the old polygon of each new one
    base = len(v)
    if quads.any():
        q = polys[quads]
        c = v[q]  # (m, 4, 3)
        mids = 0.5 * (c + np.roll(c, -1, axis=1))  # edge midpoints m01, m12, m23, m30
        centre = c.mean(axis=1)
        m = len(q)
        pts = np.concatenate([mids.reshape(-1, 3), centre])  # 4m midpoints, then m centres
        mid = base + np.arange(4 * m).reshape(m, 4)
        cen = base + 4 * m + np.arange(m)
        new_v.append(pts)
        base += len(pts)
        sub = np.stack([np.stack([q[:, 0], mid[:, 0], cen, mid[:, 3]], 1),
                        np.stack([mid[:, 0], q[:, 1], mid[:, 1], cen], 1),
                        np.stack([cen, mid[:, 1], q[:, 2], mid[:, 2]], 1),
                        np.stack([mid[:, 3], cen, mid[:, 2], q[:, 3]], 1)], axis=1).reshape(-1, 4)
        new_polys.append(sub)
        origin.append(np.repeat(np.nonzero(quads)[0], 4))
    if tris.any():
        t = polys[tris][:, :3]
        c = v[t]
        mids = 0.5 * (c + np.roll(c, -1, axis=1))  # m01, m12, m20
        m = len(t)
        mid = base + np.arange(3 * m).reshape(m, 3)
        new_v.append(mids.reshape(-1, 3))
        base += 3 * m
        minus = np.full(m, -1)
        sub = np.stack([np.stack([t[:, 0], mid[:, 0], mid[:, 2], minus], 1),
                        np.stack([mid[:, 0], t[:, 1], mid[:, 1], minus], 1),
                        np.stack([mid[:, 2], mid[:, 1], t[:, 2], minus], 1),
                        np.stack([mid[:, 0], mid[:, 1], mid[:, 2], minus], 1)], axis=1).reshape(-1, 4)
        new_polys.append(sub)
        origin.append(np.repeat(np.nonzero(tris)[0], 4))
    vertices = np.concatenate(new_v)
    polys2 = np.concatenate(new_polys).astype(np.int32)
    origin = np.concatenate(origin)
    # each side of each new polygon inherits its old polygon's side
    sides = p.side_patch[origin]  # (npoly2, 2): the parent patch of each side, or -1
    pp, ss, parent = [], [], []
    side_patch = np.full((len(polys2), 2), -1, np.int32)
    n = 0
    for side in (0, 1):
        has = np.nonzero(sides[:, side] >= 0)[0]
        side_patch[has, side] = np.arange(n, n + len(has))
        n += len(has)
        pp.append(has)
        ss.append(np.full(len(has), 1 if side == 0 else -1, np.int8))
        parent.append(sides[has, side])
    patch_poly = np.concatenate(pp).astype(np.int32)
    patch_side = np.concatenate(ss)
    parent = np.concatenate(parent).astype(np.int64)
    corners = vertices[np.maximum(polys2, 0)]
    tri = polys2[:, 3] < 0
    corners[tri, 3] = corners[tri, 0]
    cross = 0.5 * np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    cross[tri] = 0.5 * np.cross(corners[tri, 1] - corners[tri, 0], corners[tri, 2] - corners[tri, 0])
    area = np.linalg.norm(cross, axis=1)
    centre = np.where(tri[:, None], corners[:, :3].mean(axis=1), corners.mean(axis=1))
    return Patches(
        vertices=vertices, polys=polys2, poly_normal=p.poly_normal[origin], side_patch=side_patch,
        patch_poly=patch_poly, patch_side=patch_side, area=area[patch_poly], centre=centre[patch_poly],
        normal=p.normal[parent], reflectance=p.reflectance[parent], emission=p.emission[parent],
        object_id=p.object_id[parent], material=p.material[parent], smooth_group=p.smooth_group[parent],
        optics=p.optics[parent], surfaces=p.surfaces, surface_object=p.surface_object), parent


def attach(compiled, scene, settings) -> None:
    """Ready a compiled scene (`compile_scene`) for radiosity: its patches (`CompiledScene.patches`, meshed at
    `settings.radiosity.patch_size`, or a size from the scene's bounds, with `settings.tessellation` segments on
    curved shapes) and the digest of what a solution of it depends on (`scene.digest`)."""
    from ..scene.digest import scene_digest

    rs = settings.radiosity
    size = rs.patch_size if rs.patch_size is not None else default_patch_size(*usable_bounds(compiled.bounds))
    compiled.patches = mesh_scene(scene, compiled.bounds, size, settings.tessellation)
    compiled.digest = scene_digest(scene, patch_sides(scene, compiled.bounds, settings.tessellation))


def attach_digest(compiled, scene, settings) -> None:
    """Only the digest of a compiled scene (`attach` without the patches): enough to match a saved solution,
    which brings its own mesh, to the scene."""
    from ..scene.digest import scene_digest

    compiled.digest = scene_digest(scene, patch_sides(scene, compiled.bounds, settings.tessellation))
