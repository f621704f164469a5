"""How fast a path tracer written in Numba can be on Mitsuba's Cornell box: the floor under lumos's `path`.

    python benchmarks/floor_path.py [--spp 64] [--rounds 6] [--threads 2] [--no-mitsuba]

lumos's `path` is measured against Mitsuba 3's LLVM variant (`bench_path.py`). This script sizes what stands
between the two. It renders the same box (`examples/path/cornell.yaml`, read with lumos's own scene loader, so the
geometry, reflectances, light and camera are the scene file's) four ways, in one process, each warm, alternating
round by round (each round starts from the other end):

  floor      a kernel written for this scene alone: its rects and boxes tested one by one (no BVH: there are
             seven), Lambertian reflection only, the one rect light sampled by area with MIS against cosine
             BSDF sampling (power heuristic), Russian roulette as lumos's (from the 5th bounce, q = min(max
             throughput, 0.95)), lumos's max_depth, independent random numbers. Everything is inlined into one
             loop; nothing in it is general.
  floor+bvh  the same loop, but every hit found by lumos's own traversal (`traverse.closest_hit`, `any_hit`) and
             described by lumos's `surface.surface_at`, on lumos's compiled scene.
  lumos      `lumos.render(scene, method="path")`, as a user calls it.
  mitsuba    Mitsuba 3 `llvm_ad_rgb` (`peers_path.mitsuba_render`), max_depth = lumos's + 2.

Reported: time min / median / max of each, the median of its per-round ratios to Mitsuba (to lumos without
Mitsuba), and its RMSE against the stored converged reference (`peers_path.reference`), whose value says the two
floor kernels compute the same image as the others: they are Mitsuba's estimator (independent samples), so their
RMSE should be Mitsuba's, where lumos's Sobol points give less.

What it says (BENCHMARKS.md has the figures): the cost of a general renderer's generality, and whether a scalar
float64 Numba kernel can match Mitsuba's LLVM variant at all on this scene.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "examples" / "path" / "cornell.yaml"
sys.path.insert(0, str(ROOT / "benchmarks"))

import lumos  # noqa: E402
from lumos import config  # noqa: E402
from lumos.api import resolve_settings  # noqa: E402
from lumos.methods import compile_for  # noqa: E402
from lumos.kernels.layout import MAT_KD  # noqa: E402
from lumos.kernels.surface import surface_at  # noqa: E402
from lumos.kernels.traverse import any_hit, closest_hit  # noqa: E402
from lumos.kernels.views import geometry_of, lighting_of, surfaces_of  # noqa: E402

RR_DEPTH = 5  # = lumos.methods.path.RR_DEPTH: roulette from the 5th bounce, as Mitsuba's rr_depth 5
EPS = 1e-6  # ray origins are moved EPS·max(1, |p|) off the surface along the normal (lumos: config.RAY_EPSILON)
INV_PI = 1.0 / math.pi


# ------------------------------------------------------------------------------------------------- the scene

def scene_arrays(scene):
    """The scene file's box as flat arrays: rects (N, 13) = corner, edge_u/|edge_u|², edge_v/|edge_v|², unit
    normal, material row; boxes (M, 21) = object_from_world (3×4), world_from_object's linear part (3×3), material
    row (the unit cube [-1, 1]³ transformed); kd (K, 3); the light (corner, edge_u, edge_v, unit normal, area,
    radiance) as (6, 3); the camera (position, u, v, -w, (tan half fov, aspect, 0)) as (5, 3)."""
    names = list(scene.materials)
    kd = np.array([scene.materials[n].kd for n in names], np.float64)
    rects, boxes = [], []
    for obj in scene.objects:
        mat = names.index(obj.material)
        if obj.type == "rect":
            c, eu, ev = (np.array(a, np.float64) for a in (obj.corner, obj.edge_u, obj.edge_v))
            n = np.cross(eu, ev)
            rects.append(np.concatenate([c, eu / eu.dot(eu), ev / ev.dot(ev), n / np.linalg.norm(n), [mat]]))
        elif obj.type == "box":
            if tuple(obj.min) != (-1.0, -1.0, -1.0) or tuple(obj.max) != (1.0, 1.0, 1.0):
                raise ValueError("floor kernel: boxes must be the unit cube [-1, 1]³ with a transform")
            m = np.array(obj.transform.matrix, np.float64)
            inv = np.linalg.inv(m)
            boxes.append(np.concatenate([inv[:3].ravel(), m[:3, :3].ravel(), [mat]]))
        else:
            raise ValueError(f"floor kernel: no {obj.type} (rects and boxes only)")
    (light,) = scene.lights
    c, eu, ev = (np.array(a, np.float64) for a in (light.corner, light.edge_u, light.edge_v))
    n = np.cross(eu, ev)
    area = np.linalg.norm(n)
    light_rows = np.array([c, eu, ev, n / area, [area, 0.0, 0.0], light.radiance], np.float64)
    cam = scene.camera
    pos, at, up = (np.array(a, np.float64) for a in (cam.position, cam.look_at, cam.up))
    w = (pos - at) / np.linalg.norm(pos - at)
    u = np.cross(up, w)
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    camera = np.array([pos, u, v, -w, [math.tan(math.radians(cam.fov) / 2), 1.0, 0.0]], np.float64)
    return np.array(rects), np.array(boxes), kd, light_rows, camera


# ------------------------------------------------------------------------------------------------ shared parts

@numba.njit(inline="always")
def _mix(x):
    x ^= x >> np.uint64(33)
    x *= np.uint64(0xFF51AFD7ED558CCD)
    x ^= x >> np.uint64(33)
    x *= np.uint64(0xC4CEB9FE1A85EC53)
    x ^= x >> np.uint64(33)
    return x


@numba.njit(inline="always")
def _rand(state):
    """A uniform float64 in [0, 1): a 64-bit LCG step, hashed (state is a one-element uint64 array)."""
    state[0] = state[0] * np.uint64(6364136223846793005) + np.uint64(1442695040888963407)
    return float(_mix(state[0]) >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@numba.njit(inline="always")
def _camera_ray(camera, x, y, width, height, state):
    sx = 2.0 * (x + _rand(state)) / width - 1.0
    sy = 1.0 - 2.0 * (y + _rand(state)) / height
    t = camera[4, 0]
    dx = camera[3, 0] + sx * t * camera[1, 0] + sy * t * camera[2, 0]
    dy = camera[3, 1] + sx * t * camera[1, 1] + sy * t * camera[2, 1]
    dz = camera[3, 2] + sx * t * camera[1, 2] + sy * t * camera[2, 2]
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    return camera[0, 0], camera[0, 1], camera[0, 2], dx * inv, dy * inv, dz * inv


@numba.njit(inline="always")
def _light_sample(light, px, py, pz, u1, u2):
    """A point on the light, uniform by area, seen from p: (wi, dist², cos at the light; cos <= 0: unlit)."""
    lx = light[0, 0] + u1 * light[1, 0] + u2 * light[2, 0]
    ly = light[0, 1] + u1 * light[1, 1] + u2 * light[2, 1]
    lz = light[0, 2] + u1 * light[1, 2] + u2 * light[2, 2]
    wx, wy, wz = lx - px, ly - py, lz - pz
    d2 = wx * wx + wy * wy + wz * wz
    inv = 1.0 / math.sqrt(d2)
    wx, wy, wz = wx * inv, wy * inv, wz * inv
    cos_l = -(light[3, 0] * wx + light[3, 1] * wy + light[3, 2] * wz)
    return wx, wy, wz, d2, cos_l, lx, ly, lz


@numba.njit(inline="always")
def _cosine_direction(nx, ny, nz, u1, u2):
    """A cosine-weighted direction about unit n (Duff et al.'s frame) and its pdf."""
    r = math.sqrt(u1)
    phi = 2.0 * math.pi * u2
    a, b, c = r * math.cos(phi), r * math.sin(phi), math.sqrt(max(0.0, 1.0 - u1))
    sgn = math.copysign(1.0, nz)
    k = -1.0 / (sgn + nz)
    m = nx * ny * k
    tx, ty, tz = 1.0 + sgn * nx * nx * k, sgn * m, -sgn * nx
    bx, by, bz = m, sgn + ny * ny * k, -ny
    return a * tx + b * bx + c * nx, a * ty + b * by + c * ny, a * tz + b * bz + c * nz, c * INV_PI


@numba.njit(inline="always")
def _emitted_weight(light, depth, prev_pdf, t, cos_l):
    """The MIS weight of the light met at distance t (cosine cos_l there) by a cosine-sampled ray of pdf prev_pdf
    (power heuristic against light sampling); 1 for the camera ray."""
    if depth == 0:
        return 1.0
    pdf_l = t * t / (cos_l * light[4, 0])
    return prev_pdf * prev_pdf / (prev_pdf * prev_pdf + pdf_l * pdf_l)


@numba.njit(inline="always")
def _nee_factor(light, cos_i, cos_l, d2):
    """What an unblocked light sample adds to a Lambertian surface, per unit kd and radiance: f·cos/pdf_l times the
    power heuristic's weight, (cos/π)·pdf_l / (pdf_l² + pdf_b²)."""
    pdf_l = d2 / (cos_l * light[4, 0])
    pdf_b = cos_i * INV_PI
    return cos_i * INV_PI * pdf_l / (pdf_l * pdf_l + pdf_b * pdf_b)


@numba.njit(inline="always")
def _bounce(nx, ny, nz, k0, k1, k2, b0, b1, b2, depth, state):
    """BSDF sampling and roulette at a Lambertian vertex: (new direction, its pdf, throughput, whether the path goes
    on). The weight f·cos/pdf of a cosine-sampled Lambertian lobe is kd; from the RR_DEPTH-th bounce the path goes on
    with probability q = min(max throughput, 0.95) and is divided by it."""
    dx, dy, dz, pdf = _cosine_direction(nx, ny, nz, _rand(state), _rand(state))
    b0, b1, b2 = b0 * k0, b1 * k1, b2 * k2
    if depth + 1 >= RR_DEPTH:
        q = min(max(b0, b1, b2), 0.95)
        if _rand(state) >= q:
            return dx, dy, dz, pdf, b0, b1, b2, False
        b0, b1, b2 = b0 / q, b1 / q, b2 / q
    return dx, dy, dz, pdf, b0, b1, b2, True


# ------------------------------------------------------------------------------------------- the floor kernel

@numba.njit(inline="always")
def _hit_scene(rects, boxes, ox, oy, oz, dx, dy, dz, t_max, shadow):
    """Nearest hit below t_max among the rects and boxes, one by one: (t, material row, unit normal); t = -1
    for none. shadow: stop at the first hit (t = 1)."""
    best, mat, nx, ny, nz = t_max, -1, 0.0, 0.0, 0.0
    for i in range(rects.shape[0]):
        r = rects[i]
        dn = r[9] * dx + r[10] * dy + r[11] * dz
        if dn == 0.0:
            continue
        t = (r[9] * (r[0] - ox) + r[10] * (r[1] - oy) + r[11] * (r[2] - oz)) / dn
        if t <= 0.0 or t >= best:
            continue
        qx, qy, qz = ox + t * dx - r[0], oy + t * dy - r[1], oz + t * dz - r[2]
        a = qx * r[3] + qy * r[4] + qz * r[5]
        b = qx * r[6] + qy * r[7] + qz * r[8]
        if a < 0.0 or a > 1.0 or b < 0.0 or b > 1.0:
            continue
        if shadow:
            return 1.0, 0, 0.0, 0.0, 0.0
        best, mat, nx, ny, nz = t, np.int64(r[12]), r[9], r[10], r[11]
    for i in range(boxes.shape[0]):
        m = boxes[i]
        lox = m[0] * ox + m[1] * oy + m[2] * oz + m[3]
        loy = m[4] * ox + m[5] * oy + m[6] * oz + m[7]
        loz = m[8] * ox + m[9] * oy + m[10] * oz + m[11]
        ix = 1.0 / (m[0] * dx + m[1] * dy + m[2] * dz)
        iy = 1.0 / (m[4] * dx + m[5] * dy + m[6] * dz)
        iz = 1.0 / (m[8] * dx + m[9] * dy + m[10] * dz)
        ax, bx = (-1.0 - lox) * ix, (1.0 - lox) * ix
        ay, by = (-1.0 - loy) * iy, (1.0 - loy) * iy
        az, bz = (-1.0 - loz) * iz, (1.0 - loz) * iz
        t_near = max(min(ax, bx), min(ay, by), min(az, bz))
        t_far = min(max(ax, bx), max(ay, by), max(az, bz))
        if t_near > t_far or t_far <= 0.0:
            continue
        t = t_near if t_near > 0.0 else t_far
        if t >= best:
            continue
        if shadow:
            return 1.0, 0, 0.0, 0.0, 0.0
        # the face hit: the local axis the hit point is farthest along; its normal to world by the inverse
        # transpose (the rows of object_from_world)
        hx, hy, hz = abs(lox + t / ix), abs(loy + t / iy), abs(loz + t / iz)
        k = 0 if hx >= hy and hx >= hz else (1 if hy >= hz else 2)
        s = math.copysign(1.0, (lox, loy, loz)[k] + t / (ix, iy, iz)[k])
        nx, ny, nz = s * m[4 * k], s * m[4 * k + 1], s * m[4 * k + 2]
        inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
        best, mat, nx, ny, nz = t, np.int64(m[20]), nx * inv, ny * inv, nz * inv
    if best == t_max:
        return -1.0, -1, 0.0, 0.0, 0.0
    return best, mat, nx, ny, nz


@numba.njit(inline="always")
def _hit_light(light, ox, oy, oz, dx, dy, dz):
    """t where the ray meets the light's emitting side, -1 if it does not."""
    dn = light[3, 0] * dx + light[3, 1] * dy + light[3, 2] * dz
    if dn >= 0.0:
        return -1.0
    t = (light[3, 0] * (light[0, 0] - ox) + light[3, 1] * (light[0, 1] - oy) + light[3, 2] * (light[0, 2] - oz)) / dn
    if t <= 0.0:
        return -1.0
    qx, qy, qz = ox + t * dx - light[0, 0], oy + t * dy - light[0, 1], oz + t * dz - light[0, 2]
    uu = light[1, 0] ** 2 + light[1, 1] ** 2 + light[1, 2] ** 2
    vv = light[2, 0] ** 2 + light[2, 1] ** 2 + light[2, 2] ** 2
    a = (qx * light[1, 0] + qy * light[1, 1] + qz * light[1, 2]) / uu
    b = (qx * light[2, 0] + qy * light[2, 1] + qz * light[2, 2]) / vv
    if a < 0.0 or a > 1.0 or b < 0.0 or b > 1.0:
        return -1.0
    return t


@numba.njit(parallel=True, nogil=True, error_model="numpy")
def render_floor(rects, boxes, kd, light, camera, width, height, spp, max_depth, seed, out):
    """The scene-specific kernel: the mean of spp paths per pixel into out (H, W, 3)."""
    for y in numba.prange(height):
        state = np.empty(1, np.uint64)
        for x in range(width):
            acc0 = acc1 = acc2 = 0.0
            for s in range(spp):
                state[0] = _mix(np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15) + np.uint64((y * width + x) * spp + s))
                ox, oy, oz, dx, dy, dz = _camera_ray(camera, x, y, width, height, state)
                b0 = b1 = b2 = 1.0
                L0 = L1 = L2 = 0.0
                prev_pdf = 0.0
                depth = 0
                while True:
                    t, mat, nx, ny, nz = _hit_scene(rects, boxes, ox, oy, oz, dx, dy, dz, 1e30, False)
                    t_l = _hit_light(light, ox, oy, oz, dx, dy, dz)
                    if t_l > 0.0 and (t < 0.0 or t_l < t):  # the light, weighted against light sampling
                        cos_l = -(light[3, 0] * dx + light[3, 1] * dy + light[3, 2] * dz)
                        w = _emitted_weight(light, depth, prev_pdf, t_l, cos_l)
                        L0 += b0 * light[5, 0] * w
                        L1 += b1 * light[5, 1] * w
                        L2 += b2 * light[5, 2] * w
                        break
                    if t < 0.0 or depth > max_depth:
                        break
                    px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
                    if nx * dx + ny * dy + nz * dz > 0.0:
                        nx, ny, nz = -nx, -ny, -nz
                    k0, k1, k2 = kd[mat, 0], kd[mat, 1], kd[mat, 2]
                    eps = EPS * max(1.0, abs(px), abs(py), abs(pz))
                    sx, sy, sz = px + nx * eps, py + ny * eps, pz + nz * eps
                    # next-event estimation
                    wx, wy, wz, d2, cos_l, lx, ly, lz = _light_sample(light, px, py, pz, _rand(state), _rand(state))
                    cos_i = nx * wx + ny * wy + nz * wz
                    if cos_i > 0.0 and cos_l > 0.0:
                        if _hit_scene(rects, boxes, sx, sy, sz, lx - sx, ly - sy, lz - sz, 1.0 - 1e-6, True)[0] < 0.0:
                            f = _nee_factor(light, cos_i, cos_l, d2)
                            L0 += b0 * k0 * light[5, 0] * f
                            L1 += b1 * k1 * light[5, 1] * f
                            L2 += b2 * k2 * light[5, 2] * f
                    dx, dy, dz, prev_pdf, b0, b1, b2, alive = _bounce(nx, ny, nz, k0, k1, k2, b0, b1, b2, depth, state)
                    if not alive:
                        break
                    depth += 1
                    ox, oy, oz = sx, sy, sz
                acc0 += L0
                acc1 += L1
                acc2 += L2
            out[y, x, 0] = acc0 / spp
            out[y, x, 1] = acc1 / spp
            out[y, x, 2] = acc2 / spp


# ------------------------------------------------------------------------------ the same loop, lumos's traversal

@numba.njit(nogil=True)
def _stacks():
    return np.empty(config.BVH_STACK, np.int64), np.empty(config.BVH_STACK)


@numba.njit(parallel=True, nogil=True, error_model="numpy")
def render_floor_bvh(sa, light, camera, width, height, spp, max_depth, seed, out):
    """`render_floor` with every hit found by lumos's `closest_hit` / `any_hit` and read by `surface_at` (the light
    is in lumos's BVH: a hit on it is the emitter)."""
    for y in numba.prange(height):
        geo, surf, lit = geometry_of(sa), surfaces_of(sa), lighting_of(sa)
        stack, stack_t = _stacks()
        state = np.empty(1, np.uint64)
        for x in range(width):
            acc0 = acc1 = acc2 = 0.0
            for s in range(spp):
                state[0] = _mix(np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15) + np.uint64((y * width + x) * spp + s))
                ox, oy, oz, dx, dy, dz = _camera_ray(camera, x, y, width, height, state)
                b0 = b1 = b2 = 1.0
                L0 = L1 = L2 = 0.0
                prev_pdf = 0.0
                depth = 0
                while True:
                    hit = closest_hit(geo, (ox, oy, oz), (dx, dy, dz), 0.0, config.T_FAR, stack, stack_t, 0.0)
                    t = hit[0]
                    if t < 0.0:
                        break
                    p, n, n_sh, u, v, mat, obj, light_id = surface_at(surf, (ox, oy, oz), (dx, dy, dz), t, hit[1],
                                                                      hit[2], hit[3], hit[4], 0.0)
                    if light_id >= 0:
                        cos_l = -(light[3, 0] * dx + light[3, 1] * dy + light[3, 2] * dz)
                        if cos_l > 0.0:
                            w = _emitted_weight(light, depth, prev_pdf, t, cos_l)
                            L0 += b0 * light[5, 0] * w
                            L1 += b1 * light[5, 1] * w
                            L2 += b2 * light[5, 2] * w
                        break
                    if depth > max_depth:
                        break
                    px, py, pz = p
                    nx, ny, nz = n
                    if nx * dx + ny * dy + nz * dz > 0.0:
                        nx, ny, nz = -nx, -ny, -nz
                    row = lit.materials[mat]
                    k0, k1, k2 = row[MAT_KD], row[MAT_KD + 1], row[MAT_KD + 2]
                    eps = EPS * max(1.0, abs(px), abs(py), abs(pz))
                    sx, sy, sz = px + nx * eps, py + ny * eps, pz + nz * eps
                    wx, wy, wz, d2, cos_l, lx, ly, lz = _light_sample(light, px, py, pz, _rand(state), _rand(state))
                    cos_i = nx * wx + ny * wy + nz * wz
                    if cos_i > 0.0 and cos_l > 0.0:
                        if not any_hit(geo, (sx, sy, sz), (lx - sx, ly - sy, lz - sz), 0.0, 1.0 - 1e-6, stack, 0.0):
                            f = _nee_factor(light, cos_i, cos_l, d2)
                            L0 += b0 * k0 * light[5, 0] * f
                            L1 += b1 * k1 * light[5, 1] * f
                            L2 += b2 * k2 * light[5, 2] * f
                    dx, dy, dz, prev_pdf, b0, b1, b2, alive = _bounce(nx, ny, nz, k0, k1, k2, b0, b1, b2, depth, state)
                    if not alive:
                        break
                    depth += 1
                    ox, oy, oz = sx, sy, sz
                acc0 += L0
                acc1 += L1
                acc2 += L2
            out[y, x, 0] = acc0 / spp
            out[y, x, 1] = acc1 / spp
            out[y, x, 2] = acc2 / spp


# ------------------------------------------------------------------------------------------------------ main

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--no-mitsuba", action="store_true", help="leave Mitsuba out (ratios are then to lumos)")
    args = ap.parse_args()

    numba.set_num_threads(args.threads)
    scene = lumos.load_scene(SCENE)
    width, height = scene.render.width, scene.render.height
    max_depth = scene.render.max_depth
    rects, boxes, kd, light, camera = scene_arrays(scene)
    compiled = compile_for(scene, resolve_settings(scene, {"method": "path"}))
    out = {name: np.zeros((height, width, 3)) for name in ("floor", "floor+bvh")}

    def run_floor(seed):
        render_floor(rects, boxes, kd, light, camera, width, height, args.spp, max_depth, seed, out["floor"])
        return out["floor"]

    def run_floor_bvh(seed):
        render_floor_bvh(compiled.arrays, light, camera, width, height, args.spp, max_depth, seed, out["floor+bvh"])
        return out["floor+bvh"]

    def run_lumos(seed):
        return np.asarray(lumos.render(scene, spp=args.spp, seed=seed, threads=args.threads).array)[..., :3]

    renderers = {"floor": run_floor, "floor+bvh": run_floor_bvh, "lumos": run_lumos}
    if not args.no_mitsuba:
        import peers_path as peers

        try:
            peers._mitsuba("llvm_ad_rgb")
        except Exception as exc:  # not installed, or no libLLVM for its LLVM variant
            print(f"mitsuba llvm_ad_rgb: {exc}; left out")
        else:
            renderers["mitsuba"] = lambda seed: peers.mitsuba_render("llvm_ad_rgb", args.spp, max_depth + 2, width,
                                                                     height, seed=seed, threads=args.threads)[0]
    base = "mitsuba" if "mitsuba" in renderers else "lumos"

    for name, fn in renderers.items():  # warm: compile (or load from the cache)
        t0 = time.perf_counter()
        fn(0)
        print(f"{name}: warm in {time.perf_counter() - t0:.1f} s", flush=True)

    times = {name: [] for name in renderers}
    images = {}
    names = list(renderers)
    for r in range(args.rounds):
        for name in names if r % 2 == 0 else names[::-1]:
            t0 = time.perf_counter()
            img = renderers[name](1 + r)
            times[name].append(time.perf_counter() - t0)
            images[name] = np.array(img, np.float64)

    ref = None
    try:
        import peers_path as pp

        ref = np.asarray(pp.reference(max_depth=max_depth + 2, width=width, height=height), np.float64)
    except Exception as exc:  # no stored reference and no Mitsuba to make one
        print(f"no reference image ({exc}); RMSE left out")

    from common import machine

    print(f"\nmachine: {machine()}")
    print(f"{SCENE.name}, {width}x{height}, {args.spp} spp, max_depth {max_depth}, {args.threads} threads, "
          f"{args.rounds} rounds")
    print(f"{'':10s} {'min':>7s} {'median':>7s} {'max':>7s}   {'/ ' + base:>10s}   {'RMSE':>8s}   mean RGB")
    for name in names:
        t = times[name]
        ratio = statistics.median(a / b for a, b in zip(t, times[base]))
        err = f"{np.sqrt(np.mean((images[name] - ref) ** 2)):.5f}" if ref is not None else "-"
        mean = ", ".join(f"{m:.4f}" for m in images[name].mean(axis=(0, 1)))
        spread = f"{min(t):7.3f} {statistics.median(t):7.3f} {max(t):7.3f}"
        print(f"{name:10s} {spread}   {ratio:10.3f}   {err:>8s}   {mean}")


if __name__ == "__main__":
    main()
