"""Ray casting: one ray per pixel (or `spp` stratified jittered rays, box filter), nearest hit, local illumination.

Each camera ray finds its nearest hit through the BVH (past the holes of opacity cut-outs, `kernels.cutout`); the
surface there is shaded by the classic model
(`kernels.illumination.illuminate`) with no shadow rays: a surface that faces a light is lit by it (the
textbook's simplifying assumption of ray casting). A ray that reaches an area light sees its radiance; a ray
that hits nothing returns the background. Textures and bump maps are filtered over each camera ray's cone, one
pixel wide (`kernels.camera.camera_cone`, `kernels.bump.material_in_cone`), unless `mipmap` is false.
"""

from __future__ import annotations

import numpy as np

from .. import config
from ..compile.camera import camera_arrays
from ..kernels.camera import camera_cone, camera_ray
from ..kernels.cutout import closest_visible_hit
from ..kernels.illumination import PER_LIGHT_SIZE, illuminate_terms
from ..kernels.jit import njit, njit_serial
from ..kernels.environment import mirrored_environment, sky_radiance
from ..kernels.layout import MAT_ONE_SIDED
from ..kernels.surface import shading_side, surface_at
from ..kernels.bump import material_in_cone
from ..kernels.views import geometry_of, lighting_of, sky_of, surfaces_of, textures_of
from ..kernels.vec import dot, mul
from .common import Film, finish, kernel_arrays, row_bands, run_bands, start


@njit
def shade_hit(surf, lit, tex, geo, sky, o, d, cone, hit, seed, pixel, sample, shadows, stack, stack_t, per_light,
              log_base):
    """Radiance towards the eye from a primary hit; returns (rgb, n_shading, kd, object_id, shadow rays,
    (ambient, diffuse, specular, emitted, reflected)); each light's share goes to `per_light` from row `log_base`
    (>= 0; `illuminate_terms`). The textures are filtered over the footprint of the ray's cone (`cone`: width at
    o, spread; `kernels.camera.camera_cone`). Where an environment lights the model, `kr` reflects it (`sky`,
    `views.sky_of`; `environment.mirrored_environment`)."""
    t, ref, b1, b2, part = hit
    p, n_geo, n_sh, u, v, mat_id, object_id, light_id = surface_at(surf, o, d, t, ref, b1, b2, part, 0.0)
    mat = lit.materials[mat_id]
    V = mul(d, -1.0)
    # the material's coefficients and the shading normal, textures and bump map filtered over the ray's cone
    ka, kd, ks, kr, ke, shininess, n_sh = material_in_cone(surf, tex, mat, ref, part, b1, b2, p, n_geo, n_sh, u, v, d,
                                                abs(cone[0] + cone[1] * t), 0.0)
    # emitted light: from the front only where the material says so (rect and disk lights, one-sided objects)
    emit = 1.0
    if mat[MAT_ONE_SIDED] != 0.0 and dot(n_geo, V) < 0.0:
        emit = 0.0
    # the shading normal on the viewer's side of the surface (DESIGN.md §3: two-sided surfaces)
    n_sh = shading_side(n_sh, n_geo, V)
    n_g = n_geo if dot(n_geo, V) >= 0.0 else mul(n_geo, -1.0)
    a, dif, spec, rays = illuminate_terms(lit, geo, surf, p, n_sh, n_g, V, ka, kd, ks, shininess, seed,
                                          pixel, sample, shadows, stack, stack_t, 0.0, per_light,
                                          log_base, geo)
    e = (emit * ke[0], emit * ke[1], emit * ke[2])
    m = mirrored_environment(lit.ambient, sky[0], sky[1], n_sh, V, kr)
    rgb = (a[0] + dif[0] + spec[0] + e[0] + m[0], a[1] + dif[1] + spec[1] + e[1] + m[1],
           a[2] + dif[2] + spec[2] + e[2] + m[2])
    return rgb, n_sh, kd, object_id, rays, (a, dif, spec, e, m)


@njit_serial
def _raycast_rows(sa, cam_vecs, cam_params, width, height, y0, y1, spp, seed, mipmap, radiance, depth, normal,
                  albedo, object_id, terms, want_terms, rays_per_row, explain, light_log):
    """Rows y0 … y1−1 (`_raycast_band`), with their traversal stacks."""
    stack = np.empty(config.BVH_STACK, np.int64)
    stack_t = np.empty(config.BVH_STACK)
    _raycast_band(sa, cam_vecs, cam_params, width, height, y0, y1, spp, seed, mipmap, radiance, depth, normal,
                  albedo, object_id, terms, want_terms, rays_per_row, explain, light_log, stack, stack_t)


@njit
def _raycast_band(sa, cam_vecs, cam_params, width, height, y0, y1, spp, seed, mipmap, radiance, depth, normal,
                  albedo, object_id, terms, want_terms, rays_per_row, explain, light_log, stack, stack_t):
    """One band of rows: `spp` camera rays per pixel, box-filtered; the first sample's depth, normal, albedo and
    object id in those (H, W) buffers, or nowhere when they are None (Numba compiles that case apart, without
    the stores: even an untaken branch to them costs a tenth of a render of a large mesh); with `want_terms`, the
    mean of the samples' terms (ambient, diffuse, specular, emitted, reflected: the environment's mirror image;
    transmitted stays 0) in terms[y, x, :18]. At pixel `explain` (x, y), the first sample's per-light shares go
    to `light_log` (`lumos.explain`). With `mipmap`, textures are filtered over each camera ray's cone
    (`camera_cone`)."""
    geo, surf, lit, tex = geometry_of(sa), surfaces_of(sa), lighting_of(sa), textures_of(sa)
    cone = camera_cone(cam_params, height, spp, mipmap)
    for y in range(y0, y1):
        rays = 0
        inv = 1.0 / spp
        for x in range(width):
            pixel = y * width + x
            r = g = b = 0.0
            for s in range(spp):
                # stage 1: camera ray; stage 2: nearest hit; stage 3: local illumination
                o, d = camera_ray(cam_vecs, cam_params, width, height, x, y, s, spp, seed, pixel)
                hit = closest_visible_hit(geo, surf, lit, o, d, 0.0, config.T_FAR, stack, stack_t, 0.0)
                rays += 1
                if hit[0] < 0.0:  # the background, or the environment in that direction
                    bg = sky_radiance(sa.env_pixels, sa.env_info, sa.background, d)
                    r += bg[0]
                    g += bg[1]
                    b += bg[2]
                    if want_terms:  # what a ray that misses sees counts as emitted (DESIGN.md: term AOVs)
                        for k in range(3):
                            terms[y, x, 9 + k] += inv * bg[k]
                    continue
                logged = x == explain[0] and y == explain[1] and s == 0
                rgb, n_sh, kd, obj, extra, parts = shade_hit(surf, lit, tex, geo, sky_of(sa), o, d, cone, hit, seed,
                                                             pixel, s, None, stack, stack_t, light_log,
                                                             0 if logged else -1)
                rays += extra
                if want_terms:
                    for j in range(5):
                        for k in range(3):
                            terms[y, x, 3 * j + k] += inv * parts[j][k]
                r += rgb[0]
                g += rgb[1]
                b += rgb[2]
                if depth is not None:  # (a compile-time test: see above)
                    if s == 0:  # AOVs come from the first sample of each pixel
                        depth[y, x] = hit[0]
                        normal[y, x, 0], normal[y, x, 1], normal[y, x, 2] = n_sh
                        albedo[y, x, 0], albedo[y, x, 1], albedo[y, x, 2] = kd
                        object_id[y, x] = obj
            radiance[y, x, 0] = r * inv
            radiance[y, x, 1] = g * inv
            radiance[y, x, 2] = b * inv
        rays_per_row[y] = rays


_NO_PIXEL = np.array([-1, -1], np.int64)


def render_raycast(compiled, camera, settings, progress=None, explain=None, rows=None) -> Film:
    """Ray-cast `compiled` (a `CompiledScene`) through `camera` with `settings` (a `RenderSettings`).

    `progress(fraction)` is called after each band of rows. Returns a `Film`. `explain` = (x, y, light_log):
    only row y is rendered, and pixel (x, y)'s per-light shares go to light_log (`lumos.explain`). `rows` =
    (y0, y1): only those rows are rendered (a cluster's tile; the others stay as allocated).
    """
    width, height = settings.width, settings.height
    # the surface AOV buffers only when one of them is asked for (writing them costs about a fifth of a render of
    # a large mesh: BENCHMARKS.md)
    threads, b = start(settings, aovs_if_asked=True)
    spp = 1 if settings.antialias == "none" else settings.spp
    cam_vecs, cam_params = camera_arrays(camera, settings.filter)
    pixel, light_log, bands = _NO_PIXEL, np.zeros((0, PER_LIGHT_SIZE)), row_bands(height, rows=rows)
    if explain is not None:
        pixel, light_log, bands = np.array(explain[:2], np.int64), explain[2], [(explain[1], explain[1] + 1)]
    sa = kernel_arrays(_raycast_rows, compiled.arrays)  # (compile.features)
    run_bands(lambda r0, r1: _raycast_rows(sa, cam_vecs, cam_params, width, height, r0, r1, spp,
                                           settings.seed, bool(settings.mipmap), b.radiance, b.depth, b.normal,
                                           b.albedo, b.object_id, b.terms, b.want_terms, b.rays_per_row, pixel,
                                           light_log),
              height, progress, bands)
    return finish(settings, b, threads, np.full((height, width), spp, np.int32), int(b.rays_per_row.sum()),
                  primary_rays=width * sum(y1 - y0 for y0, y1 in bands) * spp)
