"""Ray queries from Python: `lumos.RayCaster`, built once from a scene, NumPy arrays in and out.

    rc = lumos.RayCaster("scene.yaml")        # a Scene, a dict, a scene file or a bare mesh file
    h = rc.closest(origins, directions)       # Hits: t, object_id, prim_id, point, normal, uv
    rc.occluded(origins, directions, t_max)   # (n,) bool
    rc.all_hits(origins, directions)          # Crossings, sorted by (ray, t)
    rc.contains(points)                       # (n,) id of the first solid holding each point, or -1
    rc.path_length(origins, directions, t_max, density={...})
    rc.interference("pipe", "duct")           # Interference: intersects, volume, points, ...

Rays are (n, 3) float arrays (a single (3,) origin or direction is broadcast against the other); `t` is the
parameter along the given direction (world distance when it is unit length). Objects are addressed by their
index in the scene's `objects:` list or by their `name`. Analytic shapes and csg objects are intersected
exactly, as every ray method sees them, not tessellated. See docs/queries.md.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import NamedTuple, Union

import numpy as np

from ..errors import LumosError
from .interference import Interference, measure_interference

_SCENE_FILES = (".yaml", ".yml", ".json")
#: objects whose inside is defined (closed solids)
_SOLID_TYPES = ("sphere", "box", "csg")
_BATCH = 1 << 16  # rays per call of the crossings kernel (its output is batch × max_hits)
#: the directions of the three parity rays of `contains` (not along an axis or a diagonal, not coplanar)
_PROBES = np.array([[0.5377, 0.3127, 0.7831], [-0.8012, 0.5521, 0.2307], [0.1433, -0.9120, 0.3844]])
_PROBES /= np.linalg.norm(_PROBES, axis=1, keepdims=True)


class Hits(NamedTuple):
    """Nearest hits of n rays. Misses have t = inf, object_id = prim_id = -1 and NaN point, normal and uv."""

    t: np.ndarray  # float64 (n,)
    object_id: np.ndarray  # int64 (n,): index in the scene's objects
    prim_id: np.ndarray  # int64 (n,): mesh face, csg solid number, or analytic part (docs/queries.md)
    point: np.ndarray  # float64 (n, 3): o + t·d
    normal: np.ndarray  # float64 (n, 3): unit geometric normal, outward (not turned towards the ray)
    uv: np.ndarray  # float64 (n, 2): surface uv (a mesh's uvs, else the barycentrics of v1 and v2)


class Crossings(NamedTuple):
    """Every crossing of n rays with a surface, sorted by ray and then t (k crossings in all)."""

    ray: np.ndarray  # int64 (k,): the ray's index
    t: np.ndarray  # float64 (k,)
    object_id: np.ndarray  # int64 (k,)
    prim_id: np.ndarray  # int64 (k,)
    entering: np.ndarray  # bool (k,): the crossing enters a solid (open surfaces: dot(d, normal) < 0)
    count: np.ndarray  # int64 (n,): crossings returned per ray
    truncated: np.ndarray  # bool (n,): the ray had more than max_hits crossings in range


class Segments(NamedTuple):
    """The pieces of n rays inside closed solids, within [t_min, t_max] (k pieces, sorted by ray and object)."""

    ray: np.ndarray  # int64 (k,)
    object_id: np.ndarray  # int64 (k,)
    t_in: np.ndarray  # float64 (k,)
    t_out: np.ndarray  # float64 (k,)


def _load(scene):
    """A validated `Scene` from a Scene, a dict, a scene file or a bare mesh file."""
    from ..scene import Scene, load_scene

    if isinstance(scene, Scene):
        return load_scene(scene)  # completes a Scene built in Python (mesh files, includes)
    if isinstance(scene, (str, os.PathLike)):
        path = Path(scene)
        ext = path.suffix.lower()
        if ext not in _SCENE_FILES:
            from ..io.models import MODEL_FORMATS, import_model

            if ext not in MODEL_FORMATS:
                raise LumosError(f"{scene}: not a scene ({', '.join(_SCENE_FILES)}) or model file "
                                 f"({', '.join(MODEL_FORMATS)})")
            model = import_model(path)
            return load_scene({"materials": model.materials, "objects": model.objects})
    return load_scene(scene)


class RayCaster:
    """Ray queries against one scene, compiled once (BVH included). Lights are not geometry here: an area
    light's emitting shape is not hit; only the scene's `objects` are. Queries see geometry, not materials: the
    holes of opacity cut-outs, which the renderers look through, are hit here."""

    def __init__(self, scene):
        from ..compile import compile_scene
        from ..kernels import layout as L

        self.scene = _load(scene)
        self._compiled = compile_scene(self.scene.model_copy(update={"lights": []}))
        sa = self._compiled.arrays
        # every analytic shape computes its (u, v) for the caller (the renderer skips it where no texture reads it)
        info = sa.shape_info.copy()
        info[:, L.INFO_FLAGS] |= L.FLAG_READS_UV
        self._arrays = sa._replace(shape_info=info)
        self.names = [o.name or f"{o.type}#{i}" for i, o in enumerate(self.scene.objects)]
        n_obj = len(self.scene.objects)
        faces = self._compiled.triangle_faces  # each BVH-ordered triangle's face in its mesh; csg mesh solids: -1
        self._tri_prim = np.concatenate([faces, np.full(len(sa.tri_verts) - len(faces), -1, np.int32)])
        self._object_bounds = _object_bounds(sa, n_obj)
        self._closed = None  # (solid (n_obj,) bool, closed mesh (n_obj,) int8, open edges (n_obj,)): on first use
        b = self._compiled.bounds
        pad = 1e-6 * max(float(np.abs(b).max()), 1.0)
        self._bounds = np.array([b[0] - pad, b[1] + pad], np.float64)

    def _closedness(self):
        """Which objects are closed solids; a mesh is one when every edge borders an even number of faces
        (checked on first use: a second or two for a million triangles)."""
        if self._closed is None:
            n_obj = len(self.names)
            solid, closed, open_edges = np.zeros(n_obj, bool), np.zeros(n_obj, np.int8), np.zeros(n_obj, np.int64)
            for i, obj in enumerate(self.scene.objects):
                if obj.type in _SOLID_TYPES or (obj.type in ("cylinder", "cone") and obj.capped):
                    solid[i] = True
                elif obj.type == "mesh":
                    open_edges[i] = _open_edges(obj)
                    solid[i] = closed[i] = open_edges[i] == 0
            self._closed = (solid, closed, open_edges)
        return self._closed

    @property
    def _solid(self) -> np.ndarray:
        return self._closedness()[0]

    @property
    def _mesh_closed(self) -> np.ndarray:
        return self._closedness()[1]

    @property
    def _open_edges(self) -> np.ndarray:
        return self._closedness()[2]

    # --------------------------------------------------------------------------------------- addressing

    def object_id(self, obj: Union[int, str]) -> int:
        """The index of an object given by index or name; LumosError if there is none."""
        n = len(self.names)
        if isinstance(obj, (int, np.integer)) and not isinstance(obj, bool):
            if not 0 <= obj < n:
                raise LumosError(f"object {obj}: no such object (the scene has {n}: 0..{n - 1})")
            return int(obj)
        if isinstance(obj, str):
            names = [o.name for o in self.scene.objects]
            if obj in names:
                return names.index(obj)
            known = ", ".join(repr(x) for x in names if x) or "none has a name"
            raise LumosError(f"object '{obj}': no object has that name (named: {known})")
        raise LumosError(f"object {obj!r}: give an object's index or name")

    def _solid_id(self, obj, what: str) -> int:
        i = self.object_id(obj)
        if not self._solid[i]:
            kind = self.scene.objects[i].type
            if kind == "mesh":
                why = f"{self._open_edges[i]} of its edges border an odd number of faces (an open mesh)"
            elif kind in ("cylinder", "cone"):
                why = f"an uncapped {kind} has no inside (set capped: true)"
            else:
                why = f"a {kind} has no inside"
            raise LumosError(f"{what}: object {i} ('{self.names[i]}') is not a closed solid: {why}")
        return i

    # --------------------------------------------------------------------------------------- queries

    def closest(self, origins, directions, t_max=np.inf) -> Hits:
        """Nearest hit with 0 < t < t_max of each ray (t_max a number or (n,))."""
        from ..kernels.queries import closest_kernel

        o, d = _rays(origins, directions)
        t_max = _t_max(t_max, len(o))
        n = len(o)
        out = Hits(np.empty(n), np.empty(n, np.int64), np.empty(n, np.int64), np.empty((n, 3)),
                   np.empty((n, 3)), np.empty((n, 2)))
        closest_kernel(self._arrays, self._tri_prim, o, d, np.minimum(t_max, 1e300), *out)
        return out

    def occluded(self, origins, directions, t_max=np.inf) -> np.ndarray:
        """(n,) bool: does anything lie on ray i with 0 < t < t_max[i] (shadow and visibility tests)."""
        from ..kernels.batch import trace_any

        o, d = _rays(origins, directions)
        t_max = _t_max(t_max, len(o))
        hit = np.zeros(len(o), bool)
        trace_any(self._arrays, o, d, np.minimum(t_max, 1e300), hit)
        return hit

    def all_hits(self, origins, directions, max_hits: int = 64, t_min=0.0, t_max=np.inf) -> Crossings:
        """Every crossing with t_min < t < t_max of each ray with any surface, sorted by t; at most `max_hits` per
        ray (the nearest; `truncated` marks rays that had more)."""
        o, d = _rays(origins, directions)
        if not isinstance(max_hits, (int, np.integer)) or isinstance(max_hits, bool) or max_hits < 1:
            raise LumosError(f"max_hits: must be a whole number >= 1, got {max_hits!r}")
        return self._crossings(o, d, _t_min(t_min, len(o)), _t_max(t_max, len(o)), int(max_hits))

    def _crossings(self, o, d, t_min, t_max, max_hits) -> Crossings:
        from ..kernels.queries import crossings

        n = len(o)
        parts, counts, truncated = [], np.zeros(n, np.int64), np.zeros(n, bool)
        for s in range(0, n, _BATCH):
            e = min(n, s + _BATCH)
            idx = np.arange(s, e)
            cap = max(64, 2 * max_hits)
            while len(idx):
                m = len(idx)
                t = np.empty((m, max_hits))
                obj, prim = np.empty((m, max_hits), np.int32), np.empty((m, max_hits), np.int32)
                ent, cnt, tot = np.empty((m, max_hits), bool), np.empty(m, np.int64), np.empty(m, np.int64)
                crossings(self._arrays, self._tri_prim, self._mesh_closed, self._bounds, o[idx], d[idx],
                          t_min[idx], t_max[idx], cap, max_hits, t, obj, prim, ent, cnt, tot)
                done = tot >= 0
                keep = np.arange(max_hits)[None, :] < cnt[done, None]
                rows = np.broadcast_to(idx[done, None], keep.shape)[keep]
                parts.append((rows, t[done][keep], obj[done][keep], prim[done][keep], ent[done][keep]))
                counts[idx[done]] = cnt[done]
                truncated[idx[done]] = tot[done] > max_hits
                idx = idx[~done]  # more boundaries on the line than the buffers held: again, with room
                cap *= 8
        if not parts:
            parts = [(np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int32), np.zeros(0, np.int32),
                      np.zeros(0, bool))]
        ray, t, obj, prim, ent = (np.concatenate([p[k] for p in parts]) for k in range(5))
        order = np.argsort(ray, kind="stable")  # retried rays come last; each ray's crossings are in t order
        return Crossings(ray[order].astype(np.int64), t[order], obj[order].astype(np.int64),
                         prim[order].astype(np.int64), ent[order], counts, truncated)

    def segments(self, origins, directions, t_min=0.0, t_max=np.inf, object=None) -> Segments:
        """The pieces of each ray inside closed solids (or only inside `object`), clipped to [t_min, t_max]."""
        o, d = _rays(origins, directions)
        return self._segments(o, d, _t_min(t_min, len(o)), _t_max(t_max, len(o)),
                              self._selection(object, "segments"))

    def _selection(self, obj, what) -> np.ndarray:
        if obj is None:
            return self._solid.copy()
        sel = np.zeros(len(self.names), bool)
        sel[self._solid_id(obj, f"{what}(object=...)")] = True
        return sel

    def _segments(self, o, d, t_min, t_max, selected) -> Segments:
        n = len(o)
        c = self._crossings(o, d, np.full(n, -np.inf), np.full(n, np.inf), 64)
        while c.truncated.any():  # rare: a line through more than 64 boundaries; again with room for all
            c = self._crossings(o, d, np.full(n, -np.inf), np.full(n, np.inf), 8 * int(c.count.max()))
        keep = selected[c.object_id] if len(c.t) else np.zeros(0, bool)
        ray, obj, t, ent = c.ray[keep], c.object_id[keep], c.t[keep], c.entering[keep]
        order = np.lexsort((obj, ray))  # stable: each (ray, object) keeps its crossings in t order
        ray, obj, t, ent = ray[order], obj[order], t[order], ent[order]
        # a piece: an entering crossing followed by a leaving one of the same solid on the same ray
        nxt = np.arange(1, len(t) + 1).clip(max=max(len(t) - 1, 0))
        pair = ent & ~ent[nxt] & (ray[nxt] == ray) & (obj[nxt] == obj) & (np.arange(len(t)) < len(t) - 1)
        ray, obj, t0, t1 = ray[pair], obj[pair], t[pair], t[nxt][pair]
        t0 = np.maximum(t0, t_min[ray])
        t1 = np.minimum(t1, t_max[ray])
        live = t1 > t0
        return Segments(ray[live], obj[live], t0[live], t1[live])

    def contains(self, points, object=None) -> np.ndarray:
        """object=None: (n,) int64, the first (lowest-index) closed solid that holds each point, -1 for none;
        with `object`: (n,) bool. Points on a boundary may go either way."""
        inside = self.containing(points, None if object is None else [object])
        if object is not None:
            return inside[:, 0]
        first = np.where(inside.any(axis=1), inside.argmax(axis=1), -1)
        return first.astype(np.int64)

    def containing(self, points, objects=None) -> np.ndarray:
        """(n, k) bool: which of `objects` (default: every object; non-solids are never True) holds each point.
        A point is inside a solid when at least two of three lines through it, in fixed directions, have it
        inside one of their pieces (the Jordan parity along each line, robust to a line grazing an edge)."""
        p = _points(points)
        ids = (list(range(len(self.names))) if objects is None
               else [self._solid_id(x, "contains(object=...)") for x in objects])
        sel = np.zeros(len(self.names), bool)
        sel[[i for i in ids if self._solid[i]]] = True
        from ..kernels.queries import containing_kernel

        n = len(p)
        col = np.full(len(self.names), -1)
        col[ids] = np.arange(len(ids))
        votes = np.zeros((n, len(ids)), np.int8)
        overflow = np.zeros(n, bool)
        containing_kernel(self._arrays, self._tri_prim, self._mesh_closed, self._bounds, p, _PROBES, sel, col,
                          256, votes, overflow)
        redo = np.flatnonzero(overflow)  # lines through more than 256 boundaries: the general path
        if len(redo):
            q, m = np.ascontiguousarray(p[redo]), len(redo)
            votes[redo] = 0
            for probe in _PROBES:
                d = np.ascontiguousarray(np.broadcast_to(probe, q.shape))
                seg = self._segments(q, d, np.full(m, -np.inf), np.full(m, np.inf), sel)
                holds = (seg.t_in < 0.0) & (seg.t_out > 0.0)
                hit = np.zeros((m, len(ids)), bool)
                hit[seg.ray[holds], col[seg.object_id[holds]]] = True
                votes[redo] += hit
        return votes >= 2

    def path_length(self, origins, directions, t_max=np.inf, object=None, density=None, t_min=0.0,
                    quadrature: int = 8) -> np.ndarray:
        """(n,) float64: the length of each ray's piece [t_min, t_max] inside closed solids (or only inside
        `object`), in world units (t·|d|), summed over the solids (a piece inside two overlapping solids counts
        in each). `density`: {object: value} weighs each solid's length by its constant density (solids not
        named count 0); a callable f(points (k, 3)) -> (k,) is integrated along each piece by `quadrature`-point
        Gauss–Legendre."""
        o, d = _rays(origins, directions)
        n = len(o)
        selected = self._selection(object, "path_length")
        weight = np.ones(len(self.names))
        if isinstance(density, dict):
            weight[:] = 0.0
            for key, value in density.items():
                i = self._solid_id(key, "path_length(density=...)")
                value = float(value)
                if not np.isfinite(value):
                    raise LumosError(f"path_length: density of object {key!r} is not finite ({value})")
                weight[i] = value
        elif density is not None and not callable(density):
            raise LumosError("path_length: density must be None, a dict {object: density} or a callable "
                             f"f(points (k, 3)) -> (k,), got {type(density).__name__}")
        seg = self._segments(o, d, _t_min(t_min, n), _t_max(t_max, n), selected)
        speed = np.linalg.norm(d, axis=1)[seg.ray]
        if callable(density) and not isinstance(density, dict):
            values = _integrate(density, o[seg.ray], d[seg.ray], seg.t_in, seg.t_out, quadrature) * speed
        else:
            values = (seg.t_out - seg.t_in) * speed * weight[seg.object_id]
        return np.bincount(seg.ray, weights=values, minlength=n)

    def interference(self, a, b, tolerance: float = 0.0, resolution: int = 64, seed: int = 0) -> Interference:
        """Do solids a and b (closed: shapes, meshes, csg) intersect, where, and by how much? Casts a
        jittered grid of resolution × resolution parallel rays along each of x, y and z over the overlap of the
        two solids' boxes and intersects the pieces of each ray inside a and inside b (docs/queries.md)."""
        ia, ib = self._solid_id(a, "interference"), self._solid_id(b, "interference")
        tolerance = float(tolerance)
        if not (tolerance >= 0.0 and np.isfinite(tolerance)):
            raise LumosError(f"interference: tolerance must be a finite number >= 0, got {tolerance}")
        if not isinstance(resolution, (int, np.integer)) or resolution < 2:
            raise LumosError(f"interference: resolution must be a whole number >= 2, got {resolution!r}")
        sel = np.zeros(len(self.names), bool)
        sel[[ia, ib]] = True
        return measure_interference(
            lambda o, d: self._segments(o, d, np.full(len(o), -np.inf), np.full(len(o), np.inf), sel),
            self._object_bounds[ia], self._object_bounds[ib], ia, ib, tolerance, int(resolution), seed)

    def camera_rays(self, x, y, width=None, height=None):
        """(origins, directions) float64 (n, 3) of the camera rays through pixel centres (x, y) (numbers or
        arrays; row 0 at the top) of a width × height image (default: the scene's render size), as the
        renderers cast them (DESIGN.md §3; a thin lens' ray through the lens centre)."""
        from ..compile.camera import camera_arrays
        from ..kernels.queries import camera_rays_kernel

        width = self.scene.render.width if width is None else int(width)
        height = self.scene.render.height if height is None else int(height)
        if width < 1 or height < 1:
            raise LumosError(f"camera_rays: width and height must be >= 1, got {width}x{height}")
        fx = np.atleast_1d(np.asarray(x, np.float64)).ravel() + 0.5
        fy = np.atleast_1d(np.asarray(y, np.float64)).ravel() + 0.5
        if fx.shape != fy.shape or not (np.isfinite(fx).all() and np.isfinite(fy).all()):
            raise LumosError("camera_rays: x and y must be finite numbers or arrays of the same length")
        vecs, params = camera_arrays(self.scene.camera)
        o, d = np.empty((len(fx), 3)), np.empty((len(fx), 3))
        camera_rays_kernel(vecs, params, width, height, fx, fy, o, d)
        return o, d


# ------------------------------------------------------------------------------------------- helpers


def _float_array(value, what):
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise LumosError(f"{what}: must be an array of numbers") from None
    return arr


def _rays(origins, directions):
    """(o, d) float64 C-contiguous (n, 3); a (3,) or (1, 3) side is broadcast against the other."""
    o = _float_array(origins, "origins")
    d = _float_array(directions, "directions")
    for arr, what in ((o, "origins"), (d, "directions")):
        if not (arr.ndim in (1, 2) and arr.shape[-1] == 3):
            raise LumosError(f"{what}: must have shape (n, 3) or (3,), got {arr.shape}")
    o, d = np.atleast_2d(o), np.atleast_2d(d)
    if len(o) != len(d) and 1 not in (len(o), len(d)):
        raise LumosError(f"origins and directions: {len(o)} origins but {len(d)} directions")
    o, d = (np.ascontiguousarray(a) for a in np.broadcast_arrays(o, d))
    from ..kernels.queries import bad_rays

    bad_o, bad_d, zero = bad_rays(o, d)
    for bad, arr, what in ((bad_o, o, "origins"), (bad_d, d, "directions")):
        if bad >= 0:
            raise LumosError(f"{what}[{bad}]: not finite (NaN or Inf): {arr[bad]}")
    if zero >= 0:
        raise LumosError(f"directions[{zero}]: a zero vector has no direction")
    return o, d


def _points(points):
    p = _float_array(points, "points")
    if not (p.ndim in (1, 2) and p.shape[-1] == 3):
        raise LumosError(f"points: must have shape (n, 3) or (3,), got {p.shape}")
    p = np.atleast_2d(p)
    bad = ~np.isfinite(p).all(axis=1)
    if bad.any():
        raise LumosError(f"points[{int(np.argmax(bad))}]: not finite (NaN or Inf): {p[np.argmax(bad)]}")
    return np.ascontiguousarray(p)


def _per_ray(value, n, what):
    arr = _float_array(value, what)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    elif arr.shape != (n,):
        raise LumosError(f"{what}: must be a number or an array of shape ({n},), got {arr.shape}")
    if np.isnan(arr).any():
        raise LumosError(f"{what}[{int(np.argmax(np.isnan(arr)))}]: NaN")
    return np.ascontiguousarray(arr)


def _t_max(value, n):
    arr = _per_ray(value, n, "t_max")
    if (arr < 0.0).any():
        raise LumosError(f"t_max[{int(np.argmax(arr < 0.0))}]: negative ({arr[np.argmax(arr < 0.0)]})")
    return arr


def _t_min(value, n):
    arr = _per_ray(value, n, "t_min")
    if (arr == np.inf).any():
        raise LumosError("t_min: must be less than infinity")
    return arr


def _open_edges(obj) -> int:
    """How many edges of a mesh object (its vertices merged by position) border an odd number of faces: 0 for a
    closed mesh."""
    faces = np.asarray(obj.faces, np.int64).reshape(-1, 3)
    if not len(faces):
        return 0
    v = np.ascontiguousarray(np.asarray(obj.vertices, np.float64)) + 0.0  # -0.0 and 0.0: one position
    # merge by position: one sort of the vertices (not of every face corner)
    _, index = np.unique(v.view(np.dtype((np.void, 24))).ravel(), return_inverse=True)
    tri = index.ravel()[faces]
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    edges = edges[edges[:, 0] != edges[:, 1]]
    _, counts = np.unique(edges[:, 0] * (int(index.max()) + 1) + edges[:, 1], return_counts=True)
    return int((counts % 2 == 1).sum())


def _object_bounds(sa, n_obj) -> np.ndarray:
    """float64 (n_obj, 2, 3): world bounds of each object (its triangles and canonical shapes; a csg object's
    solids' union), +-inf where it has none (planes)."""
    from ..compile.shapes import world_bounds
    from ..kernels import layout as L

    lo = np.full((n_obj, 3), np.inf)
    hi = np.full((n_obj, 3), -np.inf)
    if len(sa.tri_verts):
        v = sa.tri_verts.reshape(-1, 3, 3).astype(np.float64)
        obj = sa.tri_info[:, 2]
        for k in range(3):
            np.minimum.at(lo[:, k], obj, v[:, :, k].min(axis=1))
            np.maximum.at(hi[:, k], obj, v[:, :, k].max(axis=1))
    for s, info in enumerate(sa.shape_info):
        kind, obj = info[L.INFO_KIND], info[L.INFO_OBJECT]
        if kind in (L.SHAPE_CSG, L.SHAPE_MESH_SOLID, L.SHAPE_PLANE) or obj >= n_obj:
            continue
        m = np.eye(4)
        m[:3, :4] = sa.shape_xform[s, :3, :4]
        box = world_bounds(kind, np.linalg.inv(m))
        lo[obj] = np.minimum(lo[obj], box[:3])
        hi[obj] = np.maximum(hi[obj], box[3:])
    return np.stack([lo, hi], axis=1)


def _integrate(f, o, d, t0, t1, k):
    """∫ f(o + t·d) dt over [t0, t1] for each piece, by k-point Gauss–Legendre (float64 (m,))."""
    if not isinstance(k, (int, np.integer)) or k < 1:
        raise LumosError(f"path_length: quadrature must be a whole number >= 1, got {k!r}")
    if not len(t0):
        return np.zeros(0)
    x, w = np.polynomial.legendre.leggauss(int(k))
    half, mid = 0.5 * (t1 - t0), 0.5 * (t1 + t0)
    t = mid[:, None] + half[:, None] * x[None, :]  # (m, k)
    pts = o[:, None, :] + t[..., None] * d[:, None, :]
    values = np.asarray(f(pts.reshape(-1, 3)), dtype=np.float64)
    if values.shape != (len(pts) * k,):
        raise LumosError(f"path_length: density(points) must return shape ({len(pts) * k},), got {values.shape}")
    if not np.isfinite(values).all():
        raise LumosError("path_length: density(points) returned a value that is not finite")
    return (values.reshape(-1, k) * w[None, :]).sum(axis=1) * half
