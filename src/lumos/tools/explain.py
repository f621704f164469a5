"""Explain one pixel: what produced it, with the numbers the renderer computed.

    tree = lumos.explain("examples/whitted/classic.yaml", 412, 300)     # any render settings as keywords
    tree["value"]               # the pixel's linear RGB, as `lumos.render` makes it with the same settings
    tree["samples"][0]["ray"]   # whitted: the first camera ray's tree (hits, per-light terms, children)
    print(format_text(tree))    # what `lumos explain` prints

Every number comes out of the renderer's own kernels: whitted logs its ray tree while it traces the pixel
(`methods.whitted.explain_pixel` runs the same per-pixel code as the render, adaptive anti-aliasing included);
raycast renders the pixel's row with a per-light log at the pixel; raster runs its passes one by one and reads
the G-buffer and the shaded value at the pixel. So the tree adds up to the pixel (a test checks it against the
rendered image), and the textbook's formulas can be checked by hand:

    whitted ray:   I = emitted + Ka·Ia + Σ_lights shadow·(Kd·Id·(N·L) + Ks·Is·(R·V)^n) + w_r·I_r + w_t·I_t
    pixel:         Σ_samples weight · I(camera ray)

Everything returned is dicts, lists, floats, ints, strings and None (`--json` prints it as it is).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LumosError

#: The methods that can explain a pixel.
EXPLAINED = ("raycast", "raster", "whitted")


def explain(scene, x: int, y: int, **settings) -> dict:
    """What produced pixel (x, y) (column, row from the top left) of `scene` rendered with `settings`."""
    from ..api import resolve_settings
    from ..methods import compile_for
    from ..scene.loader import load_scene

    scene = load_scene(scene)
    method = settings.get("method")
    if method is not None and method not in EXPLAINED:  # before the method's own checks of the other settings
        raise LumosError(f"explain: method {method} cannot explain a pixel (choose from {', '.join(EXPLAINED)})")
    cfg = resolve_settings(scene, settings)
    if cfg.method not in EXPLAINED:
        raise LumosError(f"explain: method {cfg.method} cannot explain a pixel (choose from {', '.join(EXPLAINED)})")
    for name, v, size in (("x", x, cfg.width), ("y", y, cfg.height)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or not 0 <= v < size:
            raise LumosError(f"explain: pixel {name} = {v!r} is outside the image (0 to {size - 1})")
    compiled = compile_for(scene, cfg)
    info = {"method": cfg.method, "pixel": [int(x), int(y)], "width": cfg.width, "height": cfg.height,
            "scene": str(scene.source) if getattr(scene, "source", None) is not None else None}
    context = _Context(scene, compiled)
    if cfg.method == "whitted":
        info.update(_whitted(scene, compiled, cfg, int(x), int(y), context))
    elif cfg.method == "raycast":
        info.update(_raycast(scene, compiled, cfg, int(x), int(y), context))
    else:
        info.update(_raster(scene, compiled, cfg, int(x), int(y), context))
    return info


class _Context:
    """Names of objects, materials and lights."""

    def __init__(self, scene, compiled):
        self.objects = list(compiled.object_names)
        self.materials = list(compiled.material_names)
        self.lights = [light.type if light.type != "area" else f"area ({light.shape})" for light in scene.lights]

    def object(self, i: int) -> str | None:
        if i < 0:
            return None
        if i < len(self.objects):
            return self.objects[i]
        return f"light {i - len(self.objects)} ({self.lights[i - len(self.objects)]})"

    def material(self, i: int) -> str | None:
        return self.materials[i] if 0 <= i < len(self.materials) else None


def _v(a) -> list:
    return [float(c) for c in a]


def _per_light(rows, context) -> list:
    from ..kernels.illumination import PL_COS, PL_DIFFUSE, PL_LIT, PL_SHADOW, PL_SPECULAR, PL_SPOT

    out = []
    for j, row in enumerate(rows):
        entry = {"light": j, "type": context.lights[j], "n_dot_l": float(row[PL_COS]),
                 "shadow": _v(row[PL_SHADOW:PL_SHADOW + 3]), "samples_lit": int(row[PL_LIT]),
                 "diffuse": _v(row[PL_DIFFUSE:PL_DIFFUSE + 3]), "specular": _v(row[PL_SPECULAR:PL_SPECULAR + 3])}
        if context.lights[j] == "spot":  # the cone's falloff s² towards the point (1 inside inner_angle)
            entry["spot_falloff"] = float(row[PL_SPOT])
        out.append(entry)
    return out


# ------------------------------------------------------------------------------------------------- whitted


def _whitted(scene, compiled, cfg, x, y, context) -> dict:
    from ..compile.camera import camera_arrays
    from ..methods import whitted as W
    from ..methods import whitted_trace as T

    max_depth = cfg.resolved_max_depth()
    if max_depth is None:
        raise LumosError("render.max_depth: whitted needs a finite number of bounces (-1, unbounded, is for path)")
    mode = W.ANTIALIAS_MODES[cfg.antialias]
    spp = 1 if mode == W.AA_NONE else cfg.spp
    points = (2 ** cfg.adaptive_depth + 1) ** 2 if mode == W.AA_ADAPTIVE else spp
    rows = int(min(max(points * (2 ** (min(max_depth, 12) + 1)), 64), 400_000))
    cam_vecs, cam_params = camera_arrays(scene.camera, cfg.filter)
    value, log, light_log, used, weight = W.explain_pixel(
        compiled.arrays, cam_vecs, cam_params, np.array(scene.camera.shutter, np.float64), np.int64(cfg.width),
        np.int64(cfg.height), np.int64(x), np.int64(y), np.int64(mode), np.int64(spp), np.int64(cfg.seed),
        np.int64(max_depth), float(cfg.adaptive_threshold), np.int64(cfg.adaptive_depth), np.int64(rows),
        bool(cfg.mipmap))
    used = int(used)
    n_lights = len(scene.lights)
    nodes = [_whitted_node(log[r], light_log[r * max(n_lights, 1):r * max(n_lights, 1) + n_lights], context)
             for r in range(used)]
    samples = []
    for r in range(used):
        parent = int(log[r, T.LOG_PARENT])
        if parent >= 0:
            nodes[parent]["children"].append(nodes[r])
    for r in range(used):
        if log[r, T.LOG_DEPTH] == 0 and weight[r] > 0.0:
            _radiance(nodes[r])
            sample = {"weight": float(weight[r]), "value": nodes[r]["radiance"], "ray": nodes[r]}
            if mode == W.AA_ADAPTIVE:
                sample["image_point"] = [float(log[r, T.LOG_FX]), float(log[r, T.LOG_FY])]
            samples.append(sample)
    total = np.zeros(3)
    for s in samples:
        total += s["weight"] * np.array(s["value"])
    return {"antialias": cfg.antialias, "max_depth": max_depth, "value": _v(value), "sum_of_samples": _v(total),
            "samples": samples, "truncated": used >= rows,
            "formula": "I = emitted + ambient + Σ lights (diffuse + specular) + w_r·I_reflected + w_t·I_transmitted; "
                       "pixel = Σ weight · I(camera ray)"}


def _whitted_node(row, lights, context) -> dict:
    from ..methods import whitted_trace as T

    kind = ("camera", "reflected", "transmitted")[int(row[T.LOG_KIND])]
    node = {"kind": kind, "depth": int(row[T.LOG_DEPTH]), "origin": _v(row[T.LOG_ORIGIN:T.LOG_ORIGIN + 3]),
            "direction": _v(row[T.LOG_DIR:T.LOG_DIR + 3]), "path_weight": _v(row[T.LOG_WEIGHT:T.LOG_WEIGHT + 3]),
            "hit": None, "children": []}
    if row[T.LOG_T] < 0.0:
        node["background"] = _v(row[T.LOG_BACKGROUND:T.LOG_BACKGROUND + 3])
        return node
    obj, mat = int(row[T.LOG_OBJECT]), int(row[T.LOG_MATERIAL])
    hit = {"t": float(row[T.LOG_T]), "object": obj, "object_name": context.object(obj), "material": mat,
           "material_name": context.material(mat), "point": _v(row[T.LOG_POINT:T.LOG_POINT + 3]),
           "normal": _v(row[T.LOG_NORMAL:T.LOG_NORMAL + 3]), "geometric_normal": _v(row[T.LOG_NGEO:T.LOG_NGEO + 3]),
           "entering": bool(row[T.LOG_ENTERING]), "uv": _v(row[T.LOG_UV:T.LOG_UV + 2]),
           "ka": _v(row[T.LOG_KA:T.LOG_KA + 3]), "kd": _v(row[T.LOG_KD:T.LOG_KD + 3]),
           "ks": _v(row[T.LOG_KS:T.LOG_KS + 3]),
           "emitted": _v(row[T.LOG_EMITTED:T.LOG_EMITTED + 3]), "ambient": _v(row[T.LOG_AMBIENT:T.LOG_AMBIENT + 3]),
           "diffuse": _v(row[T.LOG_DIFFUSE:T.LOG_DIFFUSE + 3]),
           "specular": _v(row[T.LOG_SPECULAR:T.LOG_SPECULAR + 3]), "lights": _per_light(lights, context),
           "reflected_weight": _v(row[T.LOG_WR:T.LOG_WR + 3]), "transmitted_weight": _v(row[T.LOG_WT:T.LOG_WT + 3]),
           "eta": float(row[T.LOG_ETA]) if row[T.LOG_ETA] > 0.0 else None,
           "fresnel": float(row[T.LOG_FRESNEL]) if row[T.LOG_FRESNEL] >= 0.0 else None,
           "total_internal_reflection": bool(row[T.LOG_TIR])}
    hit["local"] = _v(np.sum([hit[k] for k in ("emitted", "ambient", "diffuse", "specular")], axis=0))
    node["hit"] = hit
    return node


def _radiance(node) -> np.ndarray:
    """I of a logged ray from its children: local + w_r·I_r + w_t·I_t (stored in node['radiance'])."""
    if node["hit"] is None:
        value = np.array(node["background"])
    else:
        hit = node["hit"]
        value = np.array(hit["local"], dtype=np.float64)
        for child in node["children"]:
            w = hit["reflected_weight"] if child["kind"] == "reflected" else hit["transmitted_weight"]
            value = value + np.array(w) * _radiance(child)
    node["radiance"] = _v(value)
    return value


# ------------------------------------------------------------------------------------------------- raycast


def _raycast(scene, compiled, cfg, x, y, context) -> dict:
    from ..kernels.illumination import PER_LIGHT_SIZE
    from ..methods.raycast import render_raycast
    from ..scene.model import TERM_AOVS

    light_log = np.zeros((len(scene.lights), PER_LIGHT_SIZE))
    aov = ["depth", "normal", "albedo", "object_id"] + list(TERM_AOVS)
    film = render_raycast(compiled, scene.camera, cfg.model_copy(update={"aov": aov}), explain=(x, y, light_log))
    spp = 1 if cfg.antialias == "none" else cfg.spp
    a = film.aovs
    obj = int(a["object_id"][y, x])
    terms = {name: _v(a[name][y, x]) for name in TERM_AOVS if name not in ("reflected", "transmitted")}
    out = {"antialias": cfg.antialias, "spp": spp, "value": _v(film.radiance[y, x]), "terms": terms,
           "sum_of_terms": _v(np.sum([terms[k] for k in terms], axis=0)),
           "formula": "I = emitted + ambient + Σ lights (diffuse + specular), no shadow rays; "
                      "pixel = the mean of its samples"}
    if obj < 0:
        out["hit"] = None
        return out
    out["hit"] = {"t": float(a["depth"][y, x]), "object": obj, "object_name": context.object(obj),
                  "normal": _v(a["normal"][y, x]), "kd": _v(a["albedo"][y, x]),
                  "lights": _per_light(light_log, context), "of_sample": 1}
    return out


# -------------------------------------------------------------------------------------------------- raster


def _raster(scene, compiled, cfg, x, y, context) -> dict:
    from ..kernels.illumination import PER_LIGHT_SIZE
    from ..methods.common import TERM_CHANNELS, allocate_aovs
    from ..methods.raster import G_NORMAL, G_POS, G_UV, RasterFrame, view_depth
    from ..scene.model import TERM_AOVS

    frame = RasterFrame(compiled, scene.camera, cfg)
    mesh = frame.mesh
    h, w = cfg.height, cfg.width
    passes = []
    total = np.zeros(3)
    pixel = np.array([x, y], np.int64)
    n = len(frame.offsets)
    for s in range(n):
        radiance = np.zeros((h, w, 3), np.float32)
        terms = np.zeros((h, w, TERM_CHANNELS), np.float32)
        light_log = np.zeros((len(scene.lights), PER_LIGHT_SIZE))
        buffers = allocate_aovs(h, w)
        zbuf, ids, gbuf = frame.shade_pass(s, 1.0, radiance, buffers, terms, True, np.zeros(h, np.int64),
                                           pixel, light_log)
        value = radiance[y, x].astype(np.float64)
        total += value / n
        entry = {"sample_point": [x + frame.offsets[s][0], y + frame.offsets[s][1]], "value": _v(value),
                 "terms": {name: _v(terms[y, x, 3 * k:3 * k + 3]) for k, name in enumerate(TERM_AOVS[:4])}}
        prim = int(ids[y, x])
        if prim < 0:
            entry["polygon"] = None
            passes.append(entry)
            continue
        g = gbuf[y, x]
        p = g[G_POS:G_POS + 3].astype(np.float64)
        verts = mesh.prim_index[mesh.prim_start[prim]:mesh.prim_start[prim + 1]]
        vertices = []
        for v in verts:
            vertex = {"index": int(v), "position": _v(mesh.positions[v]), "normal": _v(mesh.normals[v]),
                      "screen": _v(frame.raster.screen[v, :2]) if frame.raster.clip[v, 3] >= frame.raster.near
                      else None}
            if frame.shading == 1:  # Gouraud: the light at the vertex, both sides (unit Kd and Ks)
                light = frame.attrs[v, frame.light_at:frame.light_at + 12]
                vertex["light_front"] = {"diffuse": _v(light[0:3]), "specular": _v(light[3:6])}
                vertex["light_back"] = {"diffuse": _v(light[6:9]), "specular": _v(light[9:12])}
            vertices.append(vertex)
        info_row = mesh.prim_info[prim]
        entry["polygon"] = {
            "index": prim, "object": int(info_row[1]), "object_name": context.object(int(info_row[1])),
            "material": int(info_row[0]), "material_name": context.material(int(info_row[0])),
            "face_normal": _v(mesh.prim_normal[prim]), "vertices": vertices,
            "depth": float(view_depth(frame.cam_vecs, frame.ortho, tuple(p))),
            "interpolated": {"position": _v(p), "normal": _v(g[G_NORMAL:G_NORMAL + 3])}}
        if frame.uv_at >= 0:
            entry["polygon"]["interpolated"]["uv"] = _v(g[G_UV:G_UV + 2])
        if frame.shading == 0:  # flat: the model at the centroid
            entry["polygon"]["centroid"] = _v(mesh.prim_point[prim])
            if mesh.prim_uv is not None:
                entry["polygon"]["centroid_uv"] = _v(mesh.prim_uv[prim])
        if frame.shading == 2:
            entry["lights"] = _per_light(light_log, context)
        entry["normal_used"] = _v(buffers[1][y, x])
        passes.append(entry)
    covered = [p["polygon"]["index"] for p in passes if p["polygon"] is not None]
    return {"shading": cfg.shading, "antialias": cfg.antialias, "value": _v(total), "passes": passes,
            "coverage": f"{len(covered)} of {n} sample points",
            "polygons": sorted(set(covered)),
            "formula": {"flat": "each polygon's colour: the model at its centroid with its face normal",
                        "gouraud": "the light at the vertices interpolated, times Ka, Kd, Ks at the pixel",
                        "phong": "the model at the pixel with the interpolated normal"}[cfg.shading]
            + "; pixel = the mean of its passes (background where a pass covers nothing)"}


# --------------------------------------------------------------------------------------------------- text


def format_text(tree: dict) -> str:
    """`lumos explain`'s printout of an `explain` result."""
    lines = []
    x, y = tree["pixel"]
    where = f" of {tree['scene']}" if tree.get("scene") else ""
    lines.append(f"pixel ({x}, {y}){where}, method {tree['method']}"
                 + (f", shading {tree['shading']}" if tree["method"] == "raster" else "")
                 + f", antialias {tree.get('antialias')}")
    lines.append(f"value = {_rgb(tree['value'])} (linear RGB)")
    lines.append(f"  {tree['formula']}")
    if tree["method"] == "whitted":
        for i, s in enumerate(tree["samples"]):
            point = f" through image point ({s['image_point'][0]:.4f}, {s['image_point'][1]:.4f})" \
                if "image_point" in s else ""
            lines.append(f"sample {i + 1} of {len(tree['samples'])}, weight {s['weight']:.6g}{point}: "
                         f"I = {_rgb(s['value'])}")
            _text_ray(s["ray"], 1, lines)
        lines.append(f"pixel = Σ weight · I = {_rgb(tree['sum_of_samples'])}")
        if tree.get("truncated"):
            lines.append("(the log filled up: the tree above is cut short)")
    elif tree["method"] == "raycast":
        hit = tree["hit"]
        if hit is None:
            lines.append("the ray hits nothing: the background")
        else:
            lines.append(f"hit {hit['object_name']} at t = {hit['t']:.6g}, normal {_vec(hit['normal'])}, "
                         f"Kd {_rgb(hit['kd'])}")
            for light in hit["lights"]:
                lines.append("  " + _light_text(light))
        for name, v in tree["terms"].items():
            lines.append(f"  {name:9} {_rgb(v)}")
        lines.append(f"  sum       {_rgb(tree['sum_of_terms'])}")
    else:
        lines.append(f"coverage: {tree['coverage']}")
        for i, p in enumerate(tree["passes"]):
            sx, sy = p["sample_point"]
            poly = p["polygon"]
            if poly is None:
                lines.append(f"pass {i + 1}: sample ({sx:.4f}, {sy:.4f}) covered by no polygon: background "
                             f"{_rgb(p['value'])}")
                continue
            lines.append(f"pass {i + 1}: sample ({sx:.4f}, {sy:.4f}) → polygon {poly['index']} of "
                         f"{poly['object_name']} ({poly['material_name']}), depth {poly['depth']:.6g}, "
                         f"{len(poly['vertices'])} vertices")
            for v in poly["vertices"]:
                extra = ""
                if "light_front" in v:
                    extra = (f", light diffuse {_rgb(v['light_front']['diffuse'])} specular "
                             f"{_rgb(v['light_front']['specular'])} (back: diffuse "
                             f"{_rgb(v['light_back']['diffuse'])})")
                screen = _vec(v["screen"], 2) if v["screen"] is not None else "behind the eye (clipped)"
                lines.append(f"    vertex {v['index']}: {_vec(v['position'])} on screen {screen}, normal "
                             f"{_vec(v['normal'])}{extra}")
            lines.append(f"  interpolated: position {_vec(poly['interpolated']['position'])}, normal "
                         f"{_vec(poly['interpolated']['normal'])}"
                         + (f", uv {_vec(poly['interpolated']['uv'], 2)}" if "uv" in poly["interpolated"] else ""))
            if "centroid" in poly:
                lines.append(f"  flat: the model at the centroid {_vec(poly['centroid'])}")
            for light in p.get("lights", []):
                lines.append("  " + _light_text(light))
            for name, v in p["terms"].items():
                lines.append(f"  {name:9} {_rgb(v)}")
            lines.append(f"  value     {_rgb(p['value'])}")
    return "\n".join(lines)


def _text_ray(node, indent, lines):
    pad = "  " * indent
    w = node["path_weight"]
    head = f"{pad}{node['kind']} ray (depth {node['depth']}, path weight {_rgb(w)}) from {_vec(node['origin'])} " \
           f"along {_vec(node['direction'])}"
    hit = node["hit"]
    if hit is None:
        lines.append(f"{head}: misses, background {_rgb(node['background'])}")
        return
    side = "entering" if hit["entering"] else "leaving"
    lines.append(f"{head}")
    lines.append(f"{pad}  hits {hit['object_name']} ({hit['material_name']}) at t = {hit['t']:.6g}, point "
                 f"{_vec(hit['point'])}, normal {_vec(hit['normal'])}, {side}")
    lines.append(f"{pad}  Ka {_rgb(hit['ka'])}  Kd {_rgb(hit['kd'])}  Ks {_rgb(hit['ks'])}  uv {_vec(hit['uv'], 2)}")
    lines.append(f"{pad}  emitted  {_rgb(hit['emitted'])}")
    lines.append(f"{pad}  ambient  {_rgb(hit['ambient'])}")
    for light in hit["lights"]:
        lines.append(f"{pad}  {_light_text(light)}")
    lines.append(f"{pad}  local    {_rgb(hit['local'])} (emitted + ambient + the lights' diffuse and specular)")
    optics = []
    if hit["eta"] is not None:
        optics.append(f"η = n1/n2 = {hit['eta']:.6g}")
    if hit["fresnel"] is not None:
        optics.append(f"Fresnel F = {hit['fresnel']:.6g}")
    if hit["total_internal_reflection"]:
        optics.append("total internal reflection")
    lines.append(f"{pad}  w_r {_rgb(hit['reflected_weight'])}  w_t {_rgb(hit['transmitted_weight'])}"
                 + (f"  ({', '.join(optics)})" if optics else ""))
    for child in node["children"]:
        _text_ray(child, indent + 2, lines)
    if any(hit["reflected_weight"]) and not any(c["kind"] == "reflected" for c in node["children"]):
        lines.append(f"{pad}    (no reflected ray: max_depth reached or its weight below the cutoff)")
    lines.append(f"{pad}  I = local + w_r·I_r + w_t·I_t = {_rgb(node['radiance'])}")


def _light_text(light) -> str:
    head = f"light {light['light']} ({light['type']}): "
    if light.get("spot_falloff", 1.0) == 0.0:
        return head + "outside its cone (spot falloff 0), nothing"
    if light["samples_lit"] == 0 and light["n_dot_l"] <= 0.0 and not any(light["shadow"]):
        return head + "behind the surface (N·L <= 0), nothing"
    return (head + f"N·L {light['n_dot_l']:.4f}, shadow {_rgb(light['shadow'])}, "
            + (f"spot falloff {light['spot_falloff']:.4f}, " if "spot_falloff" in light else "")
            + f"diffuse {_rgb(light['diffuse'])}, specular {_rgb(light['specular'])}"
            + (f", {light['samples_lit']} samples lit" if light["type"].startswith("area") else ""))


def _rgb(v) -> str:
    return "(" + ", ".join(_num(c) for c in v) + ")"


def _vec(v, n=3) -> str:
    return "(" + ", ".join(f"{c:.4g}" for c in list(v)[:n]) + ")"


def _num(c: float) -> str:
    if c == 0.0:
        return "0"
    if not math.isfinite(c):
        return str(c)
    return f"{c:.6f}" if abs(c) >= 1e-3 else f"{c:.3e}"
