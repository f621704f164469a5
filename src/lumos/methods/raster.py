"""Scan-line polygon rendering with a z-buffer and flat, Gouraud or Phong shading.

The scene's polygons (`compile.raster`) are projected with the ray methods' camera, clipped against the near
plane and scan-converted (`kernels.raster`) into a z-buffer and a G-buffer holding, per pixel, the nearest
polygon and its interpolated world position and normal (and, for Gouraud, the interpolated intensity).
Shading then reads the G-buffer, one pixel at a time, through the one illumination model every method uses:

- flat:    one intensity per polygon, the model evaluated at its centroid with its face normal;
- Gouraud: the model evaluated at each vertex with its vertex normal, intensities interpolated;
- Phong:   normals interpolated and renormalised, the model evaluated at each pixel.

Surfaces are two-sided, as in the ray methods: the shading normal is taken on the side of the polygon the
viewer sees (Gouraud keeps an intensity for each side of every vertex). With `spp` > 1 the image is
rendered `spp` times with the sample point moved within the pixel (stratified, the same offset for every pixel,
as an accumulation buffer does) and averaged. `shadows: true` adds shadow rays against a BVH of the same
polygons; `cull_backfaces: true` skips polygons facing away; `perspective_correct: false` interpolates in
screen space, the textbook's way, to show its distortion.
"""

from __future__ import annotations

import numpy as np

from .. import config
from ..errors import LumosError
from ..compile.camera import camera_arrays
from ..kernels import raster as R
from ..kernels.illumination import illuminate
from ..kernels.jit import njit, njit_inline, njit_parallel, prange
from ..kernels.layout import LIGHT_SPHERE, MAT_EMISSION, MAT_KD
from ..kernels.rng import rand01
from ..kernels.sampling import stratified_2d
from ..kernels.surface import shading_side
from ..kernels.views import geometry_of, lighting_of, surfaces_of
from .common import Film, allocate_aovs, check_memory, set_threads

FLAT, GOURAUD, PHONG = 0, 1, 2
_SHADING = {"flat": FLAT, "gouraud": GOURAUD, "phong": PHONG}
#: G-buffer channels: world position, interpolated normal, and (Gouraud) the interpolated intensities of the
#: side the vertex normals point to and of the other side.
G_POS, G_NORMAL, G_COLOUR = 0, 3, 6
_CHUNK = 2048


@njit_inline
def _view_depth(cam_vecs, ortho, p):
    """The depth AOV of point p: its distance from the eye, or along the view direction for an orthographic
    camera (DESIGN.md's AOV convention, as the ray methods write it)."""
    if ortho:
        return ((cam_vecs[0, 0] - p[0]) * cam_vecs[3, 0] + (cam_vecs[0, 1] - p[1]) * cam_vecs[3, 1]
                + (cam_vecs[0, 2] - p[2]) * cam_vecs[3, 2])
    dx, dy, dz = cam_vecs[0, 0] - p[0], cam_vecs[0, 1] - p[1], cam_vecs[0, 2] - p[2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)


@njit
def _toward_eye(p, cam_vecs, ortho):
    """Unit V from p to the eye (the camera's −w direction reversed for orthographic views)."""
    if ortho:
        return cam_vecs[3, 0], cam_vecs[3, 1], cam_vecs[3, 2]
    dx = cam_vecs[0, 0] - p[0]
    dy = cam_vecs[0, 1] - p[1]
    dz = cam_vecs[0, 2] - p[2]
    inv = 1.0 / max(np.sqrt(dx * dx + dy * dy + dz * dz), 1e-300)
    return dx * inv, dy * inv, dz * inv


@njit
def _facing(n, V):
    """n normalised and turned to face V (two-sided surfaces); a zero n stays zero."""
    ln = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    if ln == 0.0:
        return 0.0, 0.0, 0.0
    s = 1.0 / ln if n[0] * V[0] + n[1] * V[1] + n[2] * V[2] >= 0.0 else -1.0 / ln
    return n[0] * s, n[1] * s, n[2] * s


@njit_parallel
def _light_points(sa, points, normals, materials_of, cam_vecs, ortho, seed, shadows, out, rays):
    """The model at each point (flat: polygon centroids, their normals turned to the viewer) → out[:, 0:3];
    with out (n, 6) (Gouraud vertices) the normal is used as given for out[:, 0:3] and reversed for
    out[:, 3:6], the intensities of the side the normal points to and of the other side: which side the
    viewer sees is known per pixel, from the polygon's face normal."""
    n_points = points.shape[0]
    for c in prange((n_points + _CHUNK - 1) // _CHUNK):
        geo, surf, lit = geometry_of(sa), surfaces_of(sa), lighting_of(sa)
        stack = np.empty(config.BVH_STACK, np.int64)
        stack_t = np.empty(config.BVH_STACK)
        count = 0
        for i in range(c * _CHUNK, min(n_points, (c + 1) * _CHUNK)):
            p = (points[i, 0], points[i, 1], points[i, 2])
            V = _toward_eye(p, cam_vecs, ortho)
            n = (normals[i, 0], normals[i, 1], normals[i, 2])
            if out.shape[1] == 3:
                n = _facing(n, V)
            (r, g, b), extra = illuminate(lit, geo, surf, p, n, n, V, materials_of[i], seed, i, 0, shadows, stack,
                                          stack_t, 0.0)
            out[i, 0] = r
            out[i, 1] = g
            out[i, 2] = b
            count += extra
            if out.shape[1] == 6:
                back = (-n[0], -n[1], -n[2])
                (r, g, b), extra = illuminate(lit, geo, surf, p, back, back, V, materials_of[i], seed, i, 1, shadows,
                                              stack, stack_t, 0.0)
                out[i, 3] = r
                out[i, 4] = g
                out[i, 5] = b
                count += extra
        rays[c] = count


@njit_parallel
def _shade(sa, ids, gbuf, prim_info, prim_normal, prim_colour, cam_vecs, ortho, shading, seed, sample, shadows,
           weight, accum, aovs, depth, normal, albedo, object_id, rays_per_row):
    """One shading pass over the G-buffer: adds weight × each pixel's radiance to `accum` (float32); with
    `aovs` set (the first pass, when any is asked for) it also fills the AOV buffers."""
    height, width = ids.shape
    for y in prange(height):
        geo, surf, lit = geometry_of(sa), surfaces_of(sa), lighting_of(sa)
        stack = np.empty(config.BVH_STACK, np.int64)
        stack_t = np.empty(config.BVH_STACK)
        rays = 0
        for x in range(width):
            prim = ids[y, x]
            if prim < 0:
                accum[y, x, 0] += weight * sa.background[0]
                accum[y, x, 1] += weight * sa.background[1]
                accum[y, x, 2] += weight * sa.background[2]
                continue
            mat_id = prim_info[prim, 0]
            light = prim_info[prim, 2]
            mat = lit.materials[mat_id]
            p = (np.float64(gbuf[y, x, G_POS]), np.float64(gbuf[y, x, G_POS + 1]), np.float64(gbuf[y, x, G_POS + 2]))
            V = _toward_eye(p, cam_vecs, ortho)
            fn = (prim_normal[prim, 0], prim_normal[prim, 1], prim_normal[prim, 2])
            if shading == FLAT:
                n_sh = _facing(fn, V)
                r, g, b = prim_colour[prim, 0], prim_colour[prim, 1], prim_colour[prim, 2]
            else:
                n_in = _facing((np.float64(gbuf[y, x, G_NORMAL]), np.float64(gbuf[y, x, G_NORMAL + 1]),
                                np.float64(gbuf[y, x, G_NORMAL + 2])), fn)  # unit, on the face normal's side
                if n_in[0] == 0.0 and n_in[1] == 0.0 and n_in[2] == 0.0:
                    n_in = fn
                n_sh = shading_side(n_in, fn, V)
                if shading == GOURAUD:
                    # the intensity of the side the viewer sees: the vertex normals' own side or the other one
                    raw = (gbuf[y, x, G_NORMAL] * fn[0] + gbuf[y, x, G_NORMAL + 1] * fn[1]
                           + gbuf[y, x, G_NORMAL + 2] * fn[2])
                    back = (fn[0] * V[0] + fn[1] * V[1] + fn[2] * V[2] < 0.0) != (raw < 0.0)
                    c = G_COLOUR + 3 if back else G_COLOUR
                    r = np.float64(gbuf[y, x, c])
                    g = np.float64(gbuf[y, x, c + 1])
                    b = np.float64(gbuf[y, x, c + 2])
                else:
                    (r, g, b), extra = illuminate(lit, geo, surf, p, n_sh, _facing(fn, V), V, mat_id, seed,
                                                  y * width + x, sample, shadows, stack, stack_t, 0.0)
                    rays += extra
            # emitted light: one-sided for rect and disk area lights (their winding faces the lit side)
            if light < 0 or lit.light_kind[light] == LIGHT_SPHERE or fn[0] * V[0] + fn[1] * V[1] + fn[2] * V[2] >= 0.0:
                r += mat[MAT_EMISSION]
                g += mat[MAT_EMISSION + 1]
                b += mat[MAT_EMISSION + 2]
            accum[y, x, 0] += weight * r
            accum[y, x, 1] += weight * g
            accum[y, x, 2] += weight * b
            if aovs:
                depth[y, x] = _view_depth(cam_vecs, ortho, p)
                normal[y, x, 0], normal[y, x, 1], normal[y, x, 2] = n_sh
                albedo[y, x, 0], albedo[y, x, 1], albedo[y, x, 2] = mat[MAT_KD], mat[MAT_KD + 1], mat[MAT_KD + 2]
                object_id[y, x] = prim_info[prim, 1]
        rays_per_row[y] += rays


def sample_offsets(spp: int, seed: int) -> list[tuple[float, float]]:
    """Where each pass samples its pixels: the centre for one pass, else stratified jittered points."""
    if spp == 1:
        return [(0.5, 0.5)]
    return [stratified_2d(s, spp, rand01(seed, 0, s, 0), rand01(seed, 0, s, 1)) for s in range(spp)]


class Rasterizer:
    """The projected scene and its buffers; `draw(jx, jy)` runs one scan-conversion pass.

    Kept separate from shading so tests and tools can use the z-buffer and coverage directly.
    """

    def __init__(self, mesh, attrs, camera, width, height, cull=False, persp=True):
        self.mesh = mesh
        self.width, self.height = width, height
        self.cam_vecs, self.cam_params = camera_arrays(camera)
        self.ortho = bool(camera.type == "orthographic")
        self.cull, self.persp = bool(cull), bool(persp) and not self.ortho
        self.attrs = np.ascontiguousarray(attrs, dtype=np.float64)
        nv = len(mesh.positions)
        far = float(np.abs(mesh.positions - self.cam_vecs[0]).max()) if nv else 1.0
        self.near = 1e-6 * max(far, 1e-3)
        self.clip = np.empty((nv, 4))
        self.screen = np.empty((nv, 4))
        R.project_vertices(mesh.positions, self.cam_vecs, self.cam_params, np.int64(width), np.int64(height),
                           self.near, self.clip, self.screen)
        self.n_bands = -(-height // R.BAND)

    def _bin(self, jy):
        n = self.mesh.n_prims
        row_lo = np.zeros(n, np.int32)
        row_hi = np.zeros(n, np.int32)
        R.bin_prims(self.mesh.prim_start, self.mesh.prim_index, self.clip, self.screen, self.near,
                    self.ortho, self.cull, np.int64(self.width), np.int64(self.height), float(jy), row_lo, row_hi)
        bins, prims = R.fill_bins(row_lo, row_hi, np.int64(self.n_bands))
        return row_lo, row_hi, bins, prims

    def draw(self, jx=0.5, jy=0.5):
        """(zbuf float64 (H, W): depth key, −inf where empty; ids int32 (H, W): polygon or −1; G-buffer)."""
        h, w = self.height, self.width
        zbuf = np.empty((h, w))  # cleared by the raster pass
        ids = np.empty((h, w), np.int32)
        gbuf = np.empty((h, w, self.attrs.shape[1]), np.float32)  # meaningful where ids >= 0
        self._run(jx, jy, R.MODE_DEPTH, zbuf, ids, gbuf, np.zeros((1, 1), np.int32))
        return zbuf, ids, gbuf

    def coverage(self, jx=0.5, jy=0.5):
        """How many polygons cover each pixel's sample point (no depth test): int32 (H, W)."""
        count = np.zeros((self.height, self.width), np.int32)
        dummy = np.zeros((1, 1))
        self._run(jx, jy, R.MODE_COUNT, dummy, np.zeros((1, 1), np.int32), np.zeros((1, 1, 1), np.float32), count)
        return count

    def _run(self, jx, jy, mode, zbuf, ids, gbuf, count):
        row_lo, row_hi, bins, prims = self._bin(jy)
        R.raster_bands(bins, prims, self.mesh.prim_start, self.mesh.prim_index, self.clip, self.screen,
                       self.attrs, self.near, self.ortho, self.persp, np.int64(self.width), np.int64(self.height),
                       float(jx), float(jy), row_lo, row_hi, np.int64(mode), zbuf, ids, gbuf, count)


def render_raster(compiled, camera, settings, progress=None) -> Film:
    """Scan-line render `compiled` (a `CompiledScene` compiled for method raster) with `settings`."""
    width, height = settings.width, settings.height
    if settings.antialias == "adaptive":
        raise LumosError("render.antialias: adaptive anti-aliasing is a whitted feature; raster takes none or "
                         "supersample (spp passes)")
    check_memory(width, height, bytes_per_pixel=96)
    threads = set_threads(settings.threads)
    mesh = compiled.raster
    sa = compiled.arrays
    shading = _SHADING[settings.shading]
    shadows = bool(settings.shadows)
    cam_vecs, _ = camera_arrays(camera)
    ortho = camera.type == "orthographic"
    seed = np.int64(settings.seed)
    rays = 0

    # vertex stage: the attributes the rasterizer interpolates (and, for Gouraud, the intensity at each vertex)
    nv = len(mesh.positions)
    k = 12 if shading == GOURAUD else 6
    attrs = np.empty((nv, k))
    attrs[:, G_POS:G_POS + 3] = mesh.positions
    attrs[:, G_NORMAL:G_NORMAL + 3] = mesh.normals
    prim_colour = np.zeros((1, 3))
    if shading == GOURAUD and nv:
        vert_material = np.zeros(nv, np.int32)
        vert_material[mesh.prim_index] = np.repeat(mesh.prim_info[:, 0], np.diff(mesh.prim_start))
        colour = np.zeros((nv, 6))
        counts = np.zeros(-(-nv // _CHUNK), np.int64)
        _light_points(sa, mesh.positions, mesh.normals, vert_material, cam_vecs, ortho, seed, shadows, colour, counts)
        attrs[:, G_COLOUR:G_COLOUR + 6] = colour
        rays += int(counts.sum())
    if shading == FLAT and mesh.n_prims:
        prim_colour = np.zeros((mesh.n_prims, 3))
        counts = np.zeros(-(-mesh.n_prims // _CHUNK), np.int64)
        _light_points(sa, mesh.prim_point, mesh.prim_normal, np.ascontiguousarray(mesh.prim_info[:, 0]),
                      cam_vecs, ortho, seed, shadows, prim_colour, counts)
        rays += int(counts.sum())

    raster = Rasterizer(mesh, attrs, camera, width, height, settings.cull_backfaces, settings.perspective_correct)
    radiance = np.zeros((height, width, 3), np.float32)
    want_aovs = bool(settings.aov)
    depth, normal, albedo, object_id = allocate_aovs(height, width) if want_aovs else allocate_aovs(1, 1)
    rays_per_row = np.zeros(height, np.int64)
    offsets = sample_offsets(1 if settings.antialias == "none" else settings.spp, settings.seed)
    for s, (jx, jy) in enumerate(offsets):
        zbuf, ids, gbuf = raster.draw(jx, jy)
        _shade(sa, ids, gbuf, mesh.prim_info, mesh.prim_normal, prim_colour, cam_vecs, ortho, np.int64(shading),
               seed, np.int64(s), shadows, 1.0 / len(offsets), radiance, want_aovs and s == 0,
               depth, normal, albedo, object_id, rays_per_row)
        if progress is not None:
            progress((s + 1) / len(offsets))
    all_aovs = {"depth": depth, "normal": normal, "albedo": albedo, "object_id": object_id,
                "samples": np.full((height, width), len(offsets), np.int32)}
    aovs = {name: all_aovs[name] for name in settings.aov}
    return Film(radiance, aovs, rays + int(rays_per_row.sum()), threads)


# -------------------------------------------------------------------- drawing precomputed colours (radiosity)


@njit_parallel
def _shade_colours(ids, gbuf, prim_colour, shading, background, weight, accum, aovs, cam_vecs, ortho, depth,
                   normal, albedo, object_id, prim_albedo, prim_object):
    """One pass over the G-buffer (position, normal, colour): adds weight × the interpolated colour (Gouraud) or
    the polygon's colour (flat) to `accum`; with `aovs`, fills the AOV buffers."""
    height, width = ids.shape
    for y in prange(height):
        for x in range(width):
            prim = ids[y, x]
            if prim < 0:
                for c in range(3):
                    accum[y, x, c] += weight * background[c]
                continue
            for c in range(3):
                v = prim_colour[prim, c] if shading == FLAT else np.float64(gbuf[y, x, G_COLOUR + c])
                accum[y, x, c] += weight * v
            if aovs:
                p = (np.float64(gbuf[y, x, 0]), np.float64(gbuf[y, x, 1]), np.float64(gbuf[y, x, 2]))
                depth[y, x] = _view_depth(cam_vecs, ortho, p)
                for c in range(3):
                    normal[y, x, c] = gbuf[y, x, G_NORMAL + c]
                    albedo[y, x, c] = prim_albedo[prim, c]
                object_id[y, x] = prim_object[prim]


def draw_colours(positions, normals, faces, vertex_colour, face_colour, face_albedo, face_object, camera, settings,
                 background, progress=None) -> Film:
    """Scan-convert one-sided triangles that carry their own colours (a radiosity solution's display mesh):
    Gouraud interpolates `vertex_colour` (nv, 3), flat shows `face_colour` (nf, 3) per triangle; back faces are
    culled (each side of a surface that is seen has its own triangles). Anti-aliasing as `render_raster`."""
    width, height = settings.width, settings.height
    check_memory(width, height, bytes_per_pixel=96)
    threads = set_threads(settings.threads)
    nf = len(faces)
    centroid = positions[faces].mean(axis=1) if nf else np.zeros((0, 3))
    e1 = positions[faces[:, 1]] - positions[faces[:, 0]] if nf else np.zeros((0, 3))
    e2 = positions[faces[:, 2]] - positions[faces[:, 0]] if nf else np.zeros((0, 3))
    fn = np.cross(e1, e2)
    fn /= np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300)
    from ..compile.raster import RasterMesh

    mesh = RasterMesh(positions=positions, normals=normals, uvs=np.zeros((len(positions), 2)),
                      prim_start=np.arange(0, 3 * nf + 1, 3, dtype=np.int64),
                      prim_index=np.ascontiguousarray(faces.ravel(), np.int32),
                      prim_info=np.zeros((nf, 3), np.int32), prim_point=centroid, prim_normal=fn)
    attrs = np.empty((len(positions), 9))
    attrs[:, G_POS:G_POS + 3] = positions
    attrs[:, G_NORMAL:G_NORMAL + 3] = normals
    attrs[:, G_COLOUR:G_COLOUR + 3] = vertex_colour
    raster = Rasterizer(mesh, attrs, camera, width, height, cull=True, persp=settings.perspective_correct)
    cam_vecs, _ = camera_arrays(camera)
    radiance = np.zeros((height, width, 3), np.float32)
    want_aovs = bool(settings.aov)
    depth, normal, albedo, object_id = allocate_aovs(height, width) if want_aovs else allocate_aovs(1, 1)
    offsets = sample_offsets(1 if settings.antialias == "none" else settings.spp, settings.seed)
    shading = FLAT if settings.radiosity.display == "flat" else GOURAUD
    for s, (jx, jy) in enumerate(offsets):
        zbuf, ids, gbuf = raster.draw(jx, jy)
        _shade_colours(ids, gbuf, np.ascontiguousarray(face_colour, np.float64), np.int64(shading),
                       np.asarray(background, np.float64), 1.0 / len(offsets), radiance, want_aovs and s == 0,
                       cam_vecs, camera.type == "orthographic", depth, normal, albedo, object_id,
                       np.ascontiguousarray(face_albedo, np.float64), np.ascontiguousarray(face_object, np.int32))
        if progress is not None:
            progress((s + 1) / len(offsets))
    all_aovs = {"depth": depth, "normal": normal, "albedo": albedo, "object_id": object_id,
                "samples": np.full((height, width), len(offsets), np.int32)}
    return Film(radiance, {name: all_aovs[name] for name in settings.aov if name in all_aovs}, 0, threads)
