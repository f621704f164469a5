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
screen space, the textbook's way, to show its distortion. A polygon with an opacity cut-out writes neither
z-buffer nor G-buffer where its (u, v) falls in a hole (`kernels.raster.fill_polygon`), so what lies behind it is
drawn there.
"""

from __future__ import annotations

import numpy as np

from .. import config
from ..compile.camera import camera_arrays
from ..kernels import raster as R
from ..kernels.environment import mirrored_environment
from ..kernels.illumination import PER_LIGHT_SIZE, ambient_light, illuminate_terms
from ..kernels.jit import njit, njit_inline, njit_serial
from ..kernels.layout import (AMBIENT_ROWS, CAM_HALF_SIZE, CAM_TAN_HALF_FOV, MAT_BUMP, MAT_CUTOUT, MAT_EMISSION,
                              MAT_KA, MAT_KD, MAT_KR, MAT_KS, MAT_ONE_SIDED, MAT_SHININESS, MAT_SIZE, MAT_TEXTURE,
                              Textures)
from ..kernels.rng import rand01
from ..kernels.sampling import stratified_2d
from ..kernels.surface import shading_side
from ..kernels.bump import bump_normal_filtered
from ..kernels.texture import TEX_SIZE, material_coeffs_filtered
from ..kernels.threads import parallel_for
from ..kernels.views import geometry_of, lighting_of, surfaces_of, textures_of
from .common import (TERM_CHANNELS, Film, allocate_aovs, background_image, check_memory, finish, set_threads,
                     start)

FLAT, GOURAUD, PHONG = 0, 1, 2
_SHADING = {"flat": FLAT, "gouraud": GOURAUD, "phong": PHONG}
#: G-buffer channels: world position, interpolated normal, (u, v) when the scene has textures, then (Gouraud)
#: the interpolated diffuse and specular light of the side the vertex normals point to and of the other side.
G_POS, G_NORMAL, G_UV = 0, 3, 6
#: The display of precomputed colours (radiosity): position, normal, colour.
G_COLOUR = 6
_CHUNK = 2048


@njit_inline
def view_depth(cam_vecs, ortho, p):
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


@njit_inline
def _footprint(cam_vecs, ortho, pixel_size, p, fn, frame):
    """(du/dx, dv/dx, du/dy, dv/dy) at point p of a polygon with unit face normal fn: where the rays through the
    neighbouring pixels meet the polygon's plane (ray differentials), carried to (u, v) by the polygon's
    gradients ∇u, ∇v (frame[6:12]). A plane seen edge-on gets an enormous footprint (its texture's mean)."""
    rx, ry, rz = cam_vecs[1, 0], cam_vecs[1, 1], cam_vecs[1, 2]
    ux, uy, uz = cam_vecs[2, 0], cam_vecs[2, 1], cam_vecs[2, 2]
    big = 1e30
    dpx = (big, big, big)
    dpy = (big, big, big)
    if ortho:
        fx, fy, fz = -cam_vecs[3, 0], -cam_vecs[3, 1], -cam_vecs[3, 2]
        nf = fn[0] * fx + fn[1] * fy + fn[2] * fz
        if abs(nf) > 1e-12:
            a = -pixel_size * (fn[0] * rx + fn[1] * ry + fn[2] * rz) / nf
            dpx = (pixel_size * rx + a * fx, pixel_size * ry + a * fy, pixel_size * rz + a * fz)
            b = -pixel_size * (fn[0] * ux + fn[1] * uy + fn[2] * uz) / nf
            dpy = (pixel_size * ux + b * fx, pixel_size * uy + b * fy, pixel_size * uz + b * fz)
    else:
        dx, dy, dz = p[0] - cam_vecs[0, 0], p[1] - cam_vecs[0, 1], p[2] - cam_vecs[0, 2]
        depth = -(dx * cam_vecs[3, 0] + dy * cam_vecs[3, 1] + dz * cam_vecs[3, 2])
        step = depth * pixel_size
        nd = fn[0] * dx + fn[1] * dy + fn[2] * dz
        for axis in range(2):
            ex, ey, ez = (rx, ry, rz) if axis == 0 else (ux, uy, uz)
            qx, qy, qz = dx + step * ex, dy + step * ey, dz + step * ez
            nq = fn[0] * qx + fn[1] * qy + fn[2] * qz
            if nq * nd > 0.0:
                t = nd / nq
                d = (t * qx - dx, t * qy - dy, t * qz - dz)
                if abs(d[0]) + abs(d[1]) + abs(d[2]) < big:
                    if axis == 0:
                        dpx = d
                    else:
                        dpy = d
    gu = (frame[6], frame[7], frame[8])
    gv = (frame[9], frame[10], frame[11])
    return (gu[0] * dpx[0] + gu[1] * dpx[1] + gu[2] * dpx[2], gv[0] * dpx[0] + gv[1] * dpx[1] + gv[2] * dpx[2],
            gu[0] * dpy[0] + gu[1] * dpy[1] + gu[2] * dpy[2], gv[0] * dpy[0] + gv[1] * dpy[1] + gv[2] * dpy[2])


_NO_FOOTPRINT = (0.0, 0.0, 0.0, 0.0)
#: The texture view of a pass without opacity cut-outs (never read: the same types as a scene's, one compilation).
_NO_TEXTURES = Textures(np.zeros((0, TEX_SIZE)), np.zeros((0, 3), np.float32), np.zeros((0, 12), np.float32))
_NO_PIXEL = np.array([-1, -1], np.int64)
#: The pixel stage's buffers in a vertex stage call of `_shade` (never read: the same types as a pass's, one
#: compilation): bg, ids, gbuf, prim_info, prim_normal, accum, depth, normal, albedo, object_id, terms, light_log.
_NO_PIXEL_BUFFERS = (np.zeros((1, 1, 3)), np.full((1, 1), -1, np.int32), np.zeros((1, 1, 1), np.float32),
                     np.zeros((1, 3), np.int32), np.zeros((1, 3)), np.zeros((1, 1, 3), np.float32),
                     *allocate_aovs(1, 1), np.zeros((1, 1, TERM_CHANNELS), np.float32),
                     np.zeros((0, PER_LIGHT_SIZE)))
#: The vertex stage's inputs in a pixel pass (points, normals, uvs, materials_of).
_NO_POINTS = (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 2)), np.zeros(0, np.int32))


def _light_points(sa, points, normals, uvs, frames, materials_of, cam_vecs, ortho, seed, shadows, gouraud, out, rays,
                  c0, c1):
    """The vertex (or polygon) stage of the illumination model, run by the shading kernel (`_shade`, its
    `vertex_stage`: one kernel, one inlined copy of the model and of the texture lookups to compile).

    Flat (`gouraud` False): at each polygon's centroid, with its face normal turned to the viewer and its
    material's coefficients at the centroid's (u, v) (bumped by its bump map), out[i] = (ambient, diffuse,
    specular, Kd), 12 values. Gouraud: at each vertex, the light that reaches it with unit coefficients (Kd = Ks = 1;
    the texture, or the material's own Kd and Ks, multiplies it per pixel), out[i] = (diffuse, specular) light on
    the side the normal points to, then on the other side, 12 values: which side the viewer sees is known per
    pixel, from the polygon's face normal. Chunks c0 … c1−1 of _CHUNK points; rays[c]: the shadow rays of
    chunk c."""
    no = _NO_PIXEL_BUFFERS
    _shade(sa, no[0], no[1], no[2], np.int64(-1), np.int64(0), no[3], no[4], out, frames, cam_vecs, ortho, 0.0,
           np.int64(GOURAUD if gouraud else FLAT), False, seed, np.int64(0), shadows, 0.0, no[5], False, no[6], no[7],
           no[8], no[9], no[10], False, rays, _NO_PIXEL, no[11], np.int64(c0), np.int64(c1),
           np.ascontiguousarray(points, np.float64), np.ascontiguousarray(normals, np.float64),
           np.ascontiguousarray(uvs, np.float64), np.ascontiguousarray(materials_of, np.int32), True)


@njit_serial
def _shade(sa, bg, ids, gbuf, uv_at, light_at, prim_info, prim_normal, prim_terms, frames, cam_vecs, ortho,
           pixel_size, shading, mipmap, seed, sample, shadows, weight, accum, aovs, depth, normal, albedo,
           object_id, terms, want_terms, rays_per_row, explain, light_log, y0, y1, points, normals, uvs,
           materials_of, vertex_stage):
    """One shading pass over the G-buffer: adds weight × each pixel's radiance to `accum` (float32) and, with
    `want_terms`, weight × its ambient, diffuse, specular and emitted terms to terms[..., 0:12]; with `aovs` set
    (the first pass, when any is asked for) it also fills the AOV buffers. At pixel `explain` (x, y; (−1, −1)
    for none) Phong shading records each light's share in `light_log` (`lumos.explain`). `uv_at` is the G-buffer
    channel of (u, v) (−1: the scene has no textures), `light_at` that of Gouraud's interpolated light. Rows
    y0 … y1−1.

    With `vertex_stage`, instead the vertex (Gouraud) or polygon (flat) stage of `_light_points` over chunks
    y0 … y1−1 of `points` (with their `normals`, `uvs`, `frames` and `materials_of`), into `prim_terms` and
    `rays_per_row` (one count per chunk): the same kernel, so that the illumination model, the texture lookup
    and the bump map are each compiled once for raster (one call site each, below)."""
    _shade_band(sa, bg, ids, gbuf, uv_at, light_at, prim_info, prim_normal, prim_terms, frames, cam_vecs, ortho,
                pixel_size, shading, mipmap, seed, sample, shadows, weight, accum, aovs, depth, normal, albedo,
                object_id, terms, want_terms, rays_per_row, explain, light_log, y0, y1, points, normals, uvs,
                materials_of, vertex_stage, np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK))


@njit
def _shade_band(sa, bg, ids, gbuf, uv_at, light_at, prim_info, prim_normal, prim_terms, frames, cam_vecs, ortho,
                pixel_size, shading, mipmap, seed, sample, shadows, weight, accum, aovs, depth, normal, albedo,
                object_id, terms, want_terms, rays_per_row, explain, light_log, y0, y1, points, normals, uvs,
                materials_of, vertex_stage, stack, stack_t):
    width = ids.shape[1]
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    env_pixels, env_info = sa.env_pixels, sa.env_info
    env_lit = lit.ambient.shape[0] > AMBIENT_ROWS  # (an environment lights the model: `mirrored_environment`)
    amb = lit.ambient
    gouraud = shading == GOURAUD
    one = (1.0, 1.0, 1.0)
    zero = (0.0, 0.0, 0.0)
    for y in range(y0, y1):  # rows of pixels; in the vertex stage, chunks of _CHUNK points
        rays = 0
        i0, i1 = (y * _CHUNK, min(points.shape[0], (y + 1) * _CHUNK)) if vertex_stage else (0, width)
        for x in range(i0, i1):
            # the shading point: a vertex (or centroid), or the pixel's nearest polygon in the G-buffer
            prim = -1
            u = v = 0.0
            fp = _NO_FOOTPRINT
            if vertex_stage:
                p = (points[x, 0], points[x, 1], points[x, 2])
                V = _toward_eye(p, cam_vecs, ortho)
                n_raw = (normals[x, 0], normals[x, 1], normals[x, 2])
                fn = n_raw
                mat = lit.materials[materials_of[x]]
                frame = frames[x if x < frames.shape[0] else 0]  # one row of zeros when the scene has no textures
                u, v = uvs[x, 0], uvs[x, 1]
                textured = True  # (read the material's textures and bump map wherever it has them)
                n_in = n_raw
            else:
                prim = ids[y, x]
                if prim < 0:
                    for k in range(3):
                        accum[y, x, k] += weight * bg[y, x, k]
                        if want_terms:
                            terms[y, x, 9 + k] += weight * bg[y, x, k]
                    continue
                mat = lit.materials[prim_info[prim, 0]]
                p = (np.float64(gbuf[y, x, G_POS]), np.float64(gbuf[y, x, G_POS + 1]),
                     np.float64(gbuf[y, x, G_POS + 2]))
                V = _toward_eye(p, cam_vecs, ortho)
                fn = (prim_normal[prim, 0], prim_normal[prim, 1], prim_normal[prim, 2])
                n_raw = fn
                frame = frames[prim if prim < frames.shape[0] else 0]
                textured = uv_at >= 0 and (mat[MAT_TEXTURE] >= 0.0 or mat[MAT_BUMP] >= 0.0)
                if textured:
                    if mipmap:
                        fp = _footprint(cam_vecs, ortho, pixel_size, p, fn, frame)
                    u = np.float64(gbuf[y, x, uv_at])
                    v = np.float64(gbuf[y, x, uv_at + 1])
                n_in = fn
                if shading != FLAT:
                    n_in = _facing((np.float64(gbuf[y, x, G_NORMAL]), np.float64(gbuf[y, x, G_NORMAL + 1]),
                                    np.float64(gbuf[y, x, G_NORMAL + 2])), fn)  # unit, on the face normal's side
                    if n_in[0] == 0.0 and n_in[1] == 0.0 and n_in[2] == 0.0:
                        n_in = fn
            # the material there (one texture lookup, inlined once, whatever the stage and shading) and its bump
            ka = (mat[MAT_KA], mat[MAT_KA + 1], mat[MAT_KA + 2])
            kd = (mat[MAT_KD], mat[MAT_KD + 1], mat[MAT_KD + 2])
            ks = (mat[MAT_KS], mat[MAT_KS + 1], mat[MAT_KS + 2])
            kr = (mat[MAT_KR], mat[MAT_KR + 1], mat[MAT_KR + 2])
            ke = (mat[MAT_EMISSION], mat[MAT_EMISSION + 1], mat[MAT_EMISSION + 2])
            shininess = mat[MAT_SHININESS]
            if textured:
                ka, kd, ks, kr, ke, shininess = material_coeffs_filtered(tex, mat, u, v, p, fp[0], fp[1], fp[2],
                                                                         fp[3])
                # bump maps tilt the normal at the vertices (Gouraud, flat's centroid) or per pixel (Phong)
                if mat[MAT_BUMP] >= 0.0 and (vertex_stage or shading == PHONG):
                    n_in = bump_normal_filtered(tex, mat, u, v, p, n_in, (frame[0], frame[1], frame[2]),
                                                (frame[3], frame[4], frame[5]), fp[0], fp[1], fp[2], fp[3])
            n_sh = _facing(fn, V) if shading == FLAT and not vertex_stage else shading_side(n_in, fn, V)
            # the illumination model: at each side of a vertex (Gouraud, unit coefficients), at a centroid
            # (flat), or at a pixel (Phong); one call of it, inlined once
            a = d = sp = zero
            sides = (2 if gouraud else 1) if vertex_stage else (1 if shading == PHONG else 0)
            for side in range(sides):
                if vertex_stage:
                    if gouraud:
                        sgn = 1.0 if side == 0 else -1.0
                        n_s = (sgn * n_in[0], sgn * n_in[1], sgn * n_in[2])
                        n_g = (sgn * n_raw[0], sgn * n_raw[1], sgn * n_raw[2])
                        ca, cd, cs = zero, one, one
                    else:
                        n_g = _facing(n_raw, V)
                        n_s, ca, cd, cs = _facing(n_in, n_g), ka, kd, ks
                    key, smp, log, log_row = np.int64(x), np.int64(side), prim_terms, -1
                else:
                    n_s, n_g, ca, cd, cs = n_sh, _facing(fn, V), ka, kd, ks
                    key, smp, log = y * width + x, sample, light_log
                    log_row = 0 if x == explain[0] and y == explain[1] else -1
                a, d, sp, extra = illuminate_terms(lit, geo, surf, p, n_s, n_g, V, ca, cd, cs, shininess, seed, key,
                                                   smp, shadows, stack, stack_t, 0.0, log, log_row, None)
                rays += extra
                if vertex_stage:
                    for k in range(3):
                        if gouraud:
                            prim_terms[x, 6 * side + k] = d[k]
                            prim_terms[x, 6 * side + 3 + k] = sp[k]
                        else:
                            prim_terms[x, k] = a[k]
                            prim_terms[x, 3 + k] = d[k]
                            prim_terms[x, 6 + k] = sp[k]
                            prim_terms[x, 9 + k] = kd[k]
            if vertex_stage:
                continue
            if shading == FLAT:
                a = (prim_terms[prim, 0], prim_terms[prim, 1], prim_terms[prim, 2])
                d = (prim_terms[prim, 3], prim_terms[prim, 4], prim_terms[prim, 5])
                sp = (prim_terms[prim, 6], prim_terms[prim, 7], prim_terms[prim, 8])
                kd = (prim_terms[prim, 9], prim_terms[prim, 10], prim_terms[prim, 11])  # at the centroid
            elif gouraud:
                # the light on the side the viewer sees: the vertex normals' own side or the other one
                raw = (gbuf[y, x, G_NORMAL] * fn[0] + gbuf[y, x, G_NORMAL + 1] * fn[1]
                       + gbuf[y, x, G_NORMAL + 2] * fn[2])
                back = (fn[0] * V[0] + fn[1] * V[1] + fn[2] * V[2] < 0.0) != (raw < 0.0)
                c = light_at + 6 if back else light_at
                ia = ambient_light(amb, n_sh)
                a = (ka[0] * ia[0], ka[1] * ia[1], ka[2] * ia[2])
                d = (kd[0] * np.float64(gbuf[y, x, c]), kd[1] * np.float64(gbuf[y, x, c + 1]),
                     kd[2] * np.float64(gbuf[y, x, c + 2]))
                sp = (ks[0] * np.float64(gbuf[y, x, c + 3]), ks[1] * np.float64(gbuf[y, x, c + 4]),
                      ks[2] * np.float64(gbuf[y, x, c + 5]))
            # emitted light (flat shading too takes it per pixel): one-sided emitters (rect and disk lights,
            # one-sided objects) on their front only
            e = (0.0, 0.0, 0.0)
            if mat[MAT_ONE_SIDED] == 0.0 or fn[0] * V[0] + fn[1] * V[1] + fn[2] * V[2] >= 0.0:
                e = ke
            for k in range(3):
                accum[y, x, k] += weight * (a[k] + d[k] + sp[k] + e[k])
            if want_terms:
                for k in range(3):
                    terms[y, x, k] += weight * a[k]
                    terms[y, x, 3 + k] += weight * d[k]
                    terms[y, x, 6 + k] += weight * sp[k]
                    terms[y, x, 9 + k] += weight * e[k]
            if env_lit:  # kr's mirror image of the environment, by the pixel's normal whatever the shading
                m = mirrored_environment(amb, env_pixels, env_info, n_sh, V, kr)
                for k in range(3):
                    accum[y, x, k] += weight * m[k]
                    if want_terms:
                        terms[y, x, 12 + k] += weight * m[k]
            if aovs:
                depth[y, x] = view_depth(cam_vecs, ortho, p)
                normal[y, x, 0], normal[y, x, 1], normal[y, x, 2] = n_sh
                albedo[y, x, 0], albedo[y, x, 1], albedo[y, x, 2] = kd
                object_id[y, x] = prim_info[prim, 1]
        rays_per_row[y] += rays


def sample_offsets(spp: int, seed: int, pixel_filter: str = "box") -> list[tuple[float, float]]:
    """Where each pass samples its pixels: the centre for one pass, else stratified jittered points, uniform in
    the pixel (box) or drawn from the Gaussian filter about its centre (as `kernels.camera.filter_offset`)."""
    if spp == 1:
        return [(0.5, 0.5)]
    points = [stratified_2d(s, spp, rand01(seed, 0, s, 0), rand01(seed, 0, s, 1)) for s in range(spp)]
    if pixel_filter != "gaussian":
        return points
    from ..kernels.camera import GAUSSIAN_RADIUS, GAUSSIAN_SIGMA
    from ..kernels.sampling import truncated_gaussian

    return [(0.5 + truncated_gaussian(jx, GAUSSIAN_SIGMA, GAUSSIAN_RADIUS),
             0.5 + truncated_gaussian(jy, GAUSSIAN_SIGMA, GAUSSIAN_RADIUS)) for jx, jy in points]


class Rasterizer:
    """The projected scene and its buffers; `draw(jx, jy)` runs one scan-conversion pass.

    Kept separate from shading so tests and tools can use the z-buffer and coverage directly.
    """

    def __init__(self, mesh, attrs, camera, width, height, cull=False, persp=True, cutouts=None):
        """`cutouts`: None, or (scene arrays, uv_at) to discard the samples of polygons whose material has an
        opacity cut-out where their (u, v), attributes uv_at and uv_at + 1, fall in a hole; False for a mesh that
        never has any (a radiosity solution's display), whose scan conversion is compiled without the test (the
        texture lookups behind it: a second of a first radiosity render's compile)."""
        self.mesh = mesh
        if cutouts is False:
            self.cutouts = (None, np.zeros((1, MAT_SIZE)), np.zeros(1, np.int32), np.int64(-1))
        elif cutouts is None:
            self.cutouts = (_NO_TEXTURES, np.zeros((1, MAT_SIZE)), np.zeros(1, np.int32), np.int64(-1))
        else:
            sa, uv_at = cutouts
            self.cutouts = (Textures(sa.tex_info, sa.tex_pixels, sa.tri_tangents), sa.materials,
                            np.ascontiguousarray(mesh.prim_info[:, 0], np.int32), np.int64(uv_at))
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
        parallel_for(lambda c0, c1: R.bin_prims(self.mesh.prim_start, self.mesh.prim_index, self.clip, self.screen,
                                                self.near, self.ortho, self.cull, np.int64(self.width),
                                                np.int64(self.height), float(jy), row_lo, row_hi, np.int64(c0),
                                                np.int64(c1)), 0, -(-n // R.BIN_CHUNK))
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
        parallel_for(lambda b0, b1: R.raster_bands(bins, prims, self.mesh.prim_start, self.mesh.prim_index,
                                                   self.clip, self.screen, self.attrs, self.near, self.ortho,
                                                   self.persp, np.int64(self.width), np.int64(self.height), float(jx),
                                                   float(jy), row_lo, row_hi, np.int64(mode), zbuf, ids, gbuf, count,
                                                   *self.cutouts, np.int64(b0), np.int64(b1)),
                     0, len(bins) - 1)


class RasterFrame:
    """Everything one raster image needs before its passes: the vertex stage done (Gouraud's light at the
    vertices, flat's terms per polygon), the rasterizer set up; `shade_pass` runs one scan-conversion and
    shading pass. `render_raster` runs them all; `lumos.explain` runs them one by one at one pixel."""

    def __init__(self, compiled, camera, settings):
        width, height = settings.width, settings.height
        self.settings = settings
        self.mesh = mesh = compiled.raster
        self.sa = sa = compiled.arrays
        self.shading = _SHADING[settings.shading]
        self.shadows = bool(settings.shadows)
        self.cam_vecs, cam_params = camera_arrays(camera)
        self.ortho = camera.type == "orthographic"
        self.background = background_image(compiled.environment, sa.background, camera, width, height)
        half = cam_params[CAM_HALF_SIZE] if self.ortho else cam_params[CAM_TAN_HALF_FOV]
        self.pixel_size = 2.0 * half / height  # one pixel's step in the image plane at unit depth (or world units)
        self.seed = np.int64(settings.seed)
        self.rays = 0
        # vertex stage: the attributes the rasterizer interpolates (and, for Gouraud, the light at each vertex)
        nv = len(mesh.positions)
        textured = sa.tex_info.shape[0] > 0
        self.frames = mesh.uv_frames() if textured else np.zeros((1, 12))  # read only where a material is textured
        self.uv_at = G_UV if textured else -1
        self.light_at = G_UV + 2 if textured else G_UV
        k = self.light_at + (12 if self.shading == GOURAUD else 0)
        attrs = np.empty((nv, k))
        attrs[:, G_POS:G_POS + 3] = mesh.positions
        attrs[:, G_NORMAL:G_NORMAL + 3] = mesh.normals
        if textured:
            attrs[:, G_UV:G_UV + 2] = mesh.uvs
        self.prim_terms = np.zeros((1, 12))
        if self.shading == GOURAUD and nv:
            vert_material = np.zeros(nv, np.int32)
            vert_material[mesh.prim_index] = np.repeat(mesh.prim_info[:, 0], np.diff(mesh.prim_start))
            light = np.zeros((nv, 12))
            counts = np.zeros(-(-nv // _CHUNK), np.int64)
            frames = _vertex_frames(mesh, self.frames) if textured else self.frames
            parallel_for(lambda c0, c1: _light_points(sa, mesh.positions, mesh.normals, mesh.uvs, frames,
                                                      vert_material, self.cam_vecs, self.ortho, self.seed,
                                                      self.shadows, True, light, counts, c0, c1), 0, len(counts))
            attrs[:, self.light_at:self.light_at + 12] = light
            self.rays += int(counts.sum())
        if self.shading == FLAT and mesh.n_prims:
            self.prim_terms = np.zeros((mesh.n_prims, 12))
            counts = np.zeros(-(-mesh.n_prims // _CHUNK), np.int64)
            materials_of = np.ascontiguousarray(mesh.prim_info[:, 0])
            parallel_for(lambda c0, c1: _light_points(sa, mesh.prim_point, mesh.prim_normal, mesh.prim_uv,
                                                      self.frames, materials_of, self.cam_vecs, self.ortho, self.seed,
                                                      self.shadows, False, self.prim_terms, counts, c0, c1),
                         0, len(counts))
            self.rays += int(counts.sum())
        self.attrs = attrs
        cutouts = textured and bool((sa.materials[:, MAT_CUTOUT] != 0.0).any())
        self.raster = Rasterizer(mesh, attrs, camera, width, height, settings.cull_backfaces,
                                 settings.perspective_correct, (sa, self.uv_at) if cutouts else None)
        self.offsets = sample_offsets(1 if settings.antialias == "none" else settings.spp, settings.seed,
                                      settings.filter)

    def shade_pass(self, s, weight, radiance, aov_buffers, terms, want_terms, rays_per_row, explain=_NO_PIXEL,
                   light_log=None):
        """Pass s (at its sample offset): scan-convert, then add weight × the shaded pixels to `radiance` (and
        the terms); fills the AOV buffers when `aov_buffers` is given. Returns (zbuf, ids, gbuf) of the pass."""
        jx, jy = self.offsets[s]
        zbuf, ids, gbuf = self.raster.draw(jx, jy)
        want_aovs = aov_buffers is not None
        depth, normal, albedo, object_id = aov_buffers if want_aovs else allocate_aovs(1, 1)
        log = light_log if light_log is not None else np.zeros((0, PER_LIGHT_SIZE))
        parallel_for(lambda y0, y1: _shade(self.sa, self.background, ids, gbuf, np.int64(self.uv_at),
                                           np.int64(self.light_at),
                                           self.mesh.prim_info, self.mesh.prim_normal, self.prim_terms, self.frames,
                                           self.cam_vecs, self.ortho, self.pixel_size, np.int64(self.shading),
                                           bool(self.settings.mipmap), self.seed, np.int64(s), self.shadows, weight,
                                           radiance, want_aovs, depth, normal, albedo, object_id, terms, want_terms,
                                           rays_per_row, explain, log, np.int64(y0), np.int64(y1), *_NO_POINTS,
                                           False),
                     0, ids.shape[0])
        return zbuf, ids, gbuf


def render_raster(compiled, camera, settings, progress=None) -> Film:
    """Scan-line render `compiled` (a `CompiledScene` compiled for method raster) with `settings`."""
    width, height = settings.width, settings.height
    threads, b = start(settings, bytes_per_pixel=96, aovs_if_asked=True)
    frame = RasterFrame(compiled, camera, settings)
    surface = (b.depth, b.normal, b.albedo, b.object_id) if b.depth is not None else None
    n = len(frame.offsets)
    for s in range(n):
        frame.shade_pass(s, 1.0 / n, b.radiance, surface if s == 0 else None, b.terms, b.want_terms, b.rays_per_row)
        if progress is not None:
            progress((s + 1) / n)
    return finish(settings, b, threads, np.full((height, width), n, np.int32), frame.rays + int(b.rays_per_row.sum()))


def _vertex_frames(mesh, frames):
    """Per vertex, ∂p/∂u and ∂p/∂v for bump maps at the vertices (Gouraud): the sums of the frames of the
    polygons around it (columns 6:12, the gradients, are not needed there and stay zero)."""
    out = np.zeros((len(mesh.positions), 12))
    counts = np.diff(mesh.prim_start)
    owner = np.repeat(np.arange(mesh.n_prims), counts)
    np.add.at(out[:, :6], mesh.prim_index, frames[owner, :6])
    return out


# -------------------------------------------------------------------- drawing precomputed colours (radiosity)


@njit_serial
def _shade_colours(ids, gbuf, prim_colour, shading, background, weight, accum, aovs, cam_vecs, ortho, depth,
                   normal, albedo, object_id, prim_albedo, prim_object, y0, y1):
    """One pass over the G-buffer (position, normal, colour): adds weight × the interpolated colour (Gouraud) or
    the polygon's colour (flat) to `accum`; with `aovs`, fills the AOV buffers. Rows y0 … y1−1."""
    width = ids.shape[1]
    for y in range(y0, y1):
        for x in range(width):
            prim = ids[y, x]
            if prim < 0:
                for c in range(3):
                    accum[y, x, c] += weight * background[y, x, c]
                continue
            for c in range(3):
                v = prim_colour[prim, c] if shading == FLAT else np.float64(gbuf[y, x, G_COLOUR + c])
                accum[y, x, c] += weight * v
            if aovs:
                p = (np.float64(gbuf[y, x, 0]), np.float64(gbuf[y, x, 1]), np.float64(gbuf[y, x, 2]))
                depth[y, x] = view_depth(cam_vecs, ortho, p)
                for c in range(3):
                    normal[y, x, c] = gbuf[y, x, G_NORMAL + c]
                    albedo[y, x, c] = prim_albedo[prim, c]
                object_id[y, x] = prim_object[prim]


def draw_colours(positions, normals, faces, vertex_colour, face_colour, face_albedo, face_object, camera, settings,
                 background, progress=None) -> Film:
    """Scan-convert one-sided triangles that carry their own colours (a radiosity solution's display mesh):
    Gouraud interpolates `vertex_colour` (nv, 3), flat shows `face_colour` (nf, 3) per triangle; back faces are
    culled (each side of a surface that is seen has its own triangles); pixels that nothing covers show
    `background`, one colour (3,) or an image (H, W, 3). Anti-aliasing as `render_raster`."""
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
    raster = Rasterizer(mesh, attrs, camera, width, height, cull=True, persp=settings.perspective_correct,
                        cutouts=False)
    cam_vecs, _ = camera_arrays(camera)
    radiance = np.zeros((height, width, 3), np.float32)
    want_aovs = bool(settings.aov)
    depth, normal, albedo, object_id = allocate_aovs(height, width) if want_aovs else allocate_aovs(1, 1)
    offsets = sample_offsets(1 if settings.antialias == "none" else settings.spp, settings.seed, settings.filter)
    shading = FLAT if settings.radiosity.display == "flat" else GOURAUD
    colours, bg = np.ascontiguousarray(face_colour, np.float64), np.asarray(background, np.float64)
    if bg.ndim == 1:  # one colour: every pixel's
        bg = np.ascontiguousarray(np.broadcast_to(bg, (height, width, 3)))
    albedos, objects = np.ascontiguousarray(face_albedo, np.float64), np.ascontiguousarray(face_object, np.int32)
    ortho = camera.type == "orthographic"
    for s, (jx, jy) in enumerate(offsets):
        zbuf, ids, gbuf = raster.draw(jx, jy)
        parallel_for(lambda y0, y1: _shade_colours(ids, gbuf, colours, np.int64(shading), bg, 1.0 / len(offsets),
                                                   radiance, want_aovs and s == 0, cam_vecs, ortho, depth, normal,
                                                   albedo, object_id, albedos, objects, np.int64(y0), np.int64(y1)),
                     0, height)
        if progress is not None:
            progress((s + 1) / len(offsets))
    all_aovs = {"depth": depth, "normal": normal, "albedo": albedo, "object_id": object_id,
                "samples": np.full((height, width), len(offsets), np.int32)}
    return Film(radiance, {name: all_aovs[name] for name in settings.aov if name in all_aovs}, 0, threads)
