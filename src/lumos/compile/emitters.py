"""What the path tracer adds to a compiled scene: the materials read physically, and the table of emitters.

    rows = physical_materials(names, material_rows)   # kd + ks + kr + kt <= 1 per channel (a warning otherwise)
    em = build_emitters(arrays, bounds)               # kernels.layout.Emitters

The table has one entry per scene light and one per emissive primitive (a triangle of an emissive mesh, an
emissive sphere, box, cylinder, cone or disk). Next-event estimation picks an entry by the light tree
(`compile.light_tree`: by each emitter's estimated contribution at the shading point), or, with
`light_selection: power`, with probability proportional to its power (a CDF, searched by bisection in
`kernels.emitters.pick_emitter`), then a point on it. Emissive planes (unbounded) and csg objects are not in the
table: their light is found by BSDF sampling alone (with full weight), which is unbiased but noisier.

Power, in the units of DESIGN.md §3 (a point light of intensity I delivers irradiance π·I·cosθ/att(d)), with
the mean of the RGB channels:
    area light, emissive primitive   π·Le·A (A its world area)
    point light                      4π·r²·π·I/att(r) at r = half the radius of the scene's bounds
    spot light                       the same with Ω = ∫ falloff dω in place of 4π (`spot_solid_angle`)
    directional light                π·I·π·R² (R the radius of the scene's bounds)
    environment                      π·L̄·π·R² (L̄ its mean radiance: `compile.environment`)
The last two are estimates (a delta light's power depends on the scene); any positive weights give the same
image in expectation, these only make the noise smaller where lights of different kinds meet.
"""

from __future__ import annotations

import warnings
from typing import Optional

import numpy as np

from ..errors import LumosWarning
from ..kernels import layout as L

#: Canonical area of each part of a canonical shape (layout.SHAPE_*): the part ids of `kernels.intersect`.
_PART_AREAS = {
    L.SHAPE_SPHERE: (4.0 * np.pi,),
    L.SHAPE_BOX: (1.0,) * 6,
    L.SHAPE_CYLINDER: (2.0 * np.pi, np.pi, np.pi),
    L.SHAPE_CONE: (np.pi * np.sqrt(2.0), np.pi),
    L.SHAPE_DISK: (np.pi,),
    L.SHAPE_RECT: (1.0,),
}


def physical_materials(names: list[str], rows: np.ndarray) -> np.ndarray:
    """The material rows as the path tracer reads them: a physical model's (a metal's, a plastic's) lobe set to its
    microfacet one (ks = its tint; kr = its tint when it is a mirror, α = 0; a metal has no kd), and, in the
    classic rows, kd + ks + kr + kt scaled down to at most 1
    in every channel (more would reflect more light than arrives: energy from nothing), warning once per
    material, named by `names[row]`."""
    rows = rows.copy()
    physical = rows[:, L.MAT_MODEL] != L.MODEL_CLASSIC
    if physical.any():  # the lobe is the microfacet one: ks (a mirror's kr when α = 0) carries its tint
        tint = rows[physical, L.MAT_TINT : L.MAT_TINT + 3]
        smooth = (rows[physical, L.MAT_ALPHA] + rows[physical, L.MAT_ALPHA + 1] == 0.0)[:, None]
        rows[physical, L.MAT_KT : L.MAT_KT + 3] = 0.0
        metal = rows[physical, L.MAT_MODEL] == L.MODEL_CONDUCTOR  # (a plastic keeps kd: its base)
        rows[np.flatnonzero(physical)[metal], L.MAT_KD : L.MAT_KD + 3] = 0.0
        rows[physical, L.MAT_KS : L.MAT_KS + 3] = np.where(smooth, 0.0, tint)
        rows[physical, L.MAT_KR : L.MAT_KR + 3] = np.where(smooth, tint, 0.0)
    gltf = rows[:, L.MAT_MODEL] == L.MODEL_PRINCIPLED  # its lobes' weights come per hit (kernels.principled):
    rows[gltf, L.MAT_KR : L.MAT_KR + 3] = 0.0  # no mirror lobe (and no Phong ks, no classic kt, read)
    glass = rows[:, L.MAT_MODEL] == L.MODEL_DIELECTRIC  # one lobe of weight 1; its tints are in its own columns
    if glass.any():  # (kernels.bsdf: a rough one is the glossy lobe, ks; a smooth one the transmission lobe, kt)
        smooth = (rows[glass, L.MAT_ALPHA] + rows[glass, L.MAT_ALPHA + 1] == 0.0)[:, None]
        rows[glass, L.MAT_KD : L.MAT_KD + 3] = 0.0
        rows[glass, L.MAT_KR : L.MAT_KR + 3] = 0.0
        rows[glass, L.MAT_KS : L.MAT_KS + 3] = np.where(smooth, 0.0, 1.0)
        rows[glass, L.MAT_KT : L.MAT_KT + 3] = np.where(smooth, 1.0, 0.0)
    for i, row in enumerate(rows):
        if physical[i]:
            continue  # energy is the model's own: a plastic's kd + its coat's tint may pass 1
        total = sum(row[c : c + 3] for c in (L.MAT_KD, L.MAT_KS, L.MAT_KR, L.MAT_KT))
        worst = float(np.max(total))
        if worst > 1.0 + 1e-9:
            channel = "rgb"[int(np.argmax(total))]
            scale = 1.0 / worst
            warnings.warn(f"material {names[i]}: kd + ks + kr + kt = {worst:.3g} in {channel} would create energy; "
                          f"the path tracer scales its coefficients by {scale:.3g}", LumosWarning, stacklevel=2)
            for c in (L.MAT_KD, L.MAT_KS, L.MAT_KR, L.MAT_KT):
                rows[i, c : c + 3] *= scale
    return rows


def spot_solid_angle(cos_outer: float, cos_inner: float) -> float:
    """∫ falloff dω over the sphere of directions of a spot light (`kernels.illumination.spot_falloff`), in
    steradians: 2π·∫ s(c)² dc over c = cosθ, which is 1 on [cos inner, 1] and ((c − cos outer)/(cos inner −
    cos outer))² on [cos outer, cos inner], whose integral is (cos inner − cos outer)/3. A hard edge (equal
    cosines) is the cone's solid angle 2π(1 − cos outer), the same formula's limit."""
    return 2.0 * np.pi * ((1.0 - cos_inner) + max(cos_inner - cos_outer, 0.0) / 3.0)


def _mean(rgb) -> float:
    return float(np.mean(rgb))


def _shape_parts(kind: int, capped: bool, world_from_canonical: np.ndarray) -> np.ndarray:
    """World area of each part of a canonical shape under the affine map, estimated from the Jacobian
    |det M|·|M^-T n| of the area element at points spread over the part (exact for flat parts)."""
    m = world_from_canonical[:3, :3]
    inv_t = np.linalg.inv(m).T
    det = abs(np.linalg.det(m))
    areas = np.zeros(L.EMIT_PARTS)
    phi = (np.arange(64) + 0.5) * (2.0 * np.pi / 64)
    for part, area in enumerate(_PART_AREAS[kind]):
        if kind in (L.SHAPE_CYLINDER, L.SHAPE_CONE) and part > 0 and not capped:
            continue
        if kind == L.SHAPE_SPHERE:  # normals spread over the sphere (a Fibonacci lattice)
            z = 1.0 - (np.arange(256) + 0.5) / 128.0
            a = np.arange(256) * np.pi * (3.0 - np.sqrt(5.0))
            r = np.sqrt(1.0 - z * z)
            normals = np.stack([r * np.cos(a), r * np.sin(a), z], axis=1)
        elif kind == L.SHAPE_BOX:
            normals = np.zeros((1, 3))
            normals[0, part // 2] = 1.0
        elif part == 0 and kind == L.SHAPE_CYLINDER:  # the side: unit normals (cos φ, sin φ, 0)
            normals = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
        elif part == 0:  # the cone's side: unit normals (cos φ, sin φ, 1)/√2
            normals = np.stack([np.cos(phi), np.sin(phi), np.ones_like(phi)], axis=1) / np.sqrt(2.0)
        else:  # caps and disks
            normals = np.array([[0.0, 0.0, 1.0]])
        jac = det * np.linalg.norm(normals @ inv_t.T, axis=1)
        areas[part] = area * float(jac.mean())
    return areas


def _uniform_scale(m: np.ndarray) -> bool:
    """True when the linear part of m is a rotation times one scale (a sphere stays a sphere)."""
    a = m[:3, :3]
    g = a.T @ a
    s = g[0, 0]
    return bool(np.allclose(g, s * np.eye(3), rtol=1e-9, atol=1e-12 * max(s, 1e-300)))


def build_emitters(arrays: L.SceneArrays, bounds: np.ndarray, environment: Optional[tuple] = None) -> L.Emitters:
    """The emitter table of a compiled scene (see the module doc), with the scene's environment (its
    `compile.environment.environment_arrays`, as `CompiledScene.environment` holds them; None: none) as one more
    entry."""
    from .environment import environment_arrays, environment_power

    mats = arrays.materials
    lk, lv, ls = arrays.light_kind, arrays.light_vecs, arrays.light_scalars
    radius = 0.5 * float(np.linalg.norm(bounds[1] - bounds[0])) if len(bounds) else 1.0
    radius = max(radius, 1e-6)
    kinds, refs, powers, areas, slots, parts, geoms = [], [], [], [], [], [], []

    def add(kind, ref, power, area=0.0, part=None, geom=None):
        kinds.append(kind)
        refs.append(ref)
        powers.append(max(power, 0.0))
        areas.append(area)
        slots.append(-1 if geom is None else len(geoms))
        if geom is not None:  # shapes only: their parts and placement
            parts.append(np.zeros(L.EMIT_PARTS) if part is None else part)
            geoms.append(geom)

    light_emit = np.full(len(lk), -1, np.int32)
    for j in range(len(lk)):
        light_emit[j] = len(kinds)
        intensity = _mean(lv[j, L.LV_DIFFUSE] + lv[j, L.LV_SPECULAR]) / 2.0
        if lk[j] == L.LIGHT_POINT or lk[j] == L.LIGHT_SPOT:
            r = 0.5 * radius
            att = ls[j, L.LS_ATT_C] + ls[j, L.LS_ATT_L] * r + ls[j, L.LS_ATT_Q] * r * r
            omega = 4.0 * np.pi if lk[j] == L.LIGHT_POINT else spot_solid_angle(ls[j, L.LS_COS_OUTER],
                                                                               ls[j, L.LS_COS_INNER])
            add(L.EMIT_LIGHT, j, omega * r * r * np.pi * intensity / att)
        elif lk[j] == L.LIGHT_DIRECTIONAL:
            add(L.EMIT_LIGHT, j, np.pi * intensity * np.pi * radius * radius)
        else:
            add(L.EMIT_LIGHT, j, np.pi * _mean(lv[j, L.LV_DIFFUSE]) * ls[j, L.LS_AREA])

    # emissive triangles (not those of csg mesh solids: they are tested inside their csg object), vectorised: a
    # mesh may have millions
    tri_emit = np.full(len(arrays.tri_info), -1, np.int32)
    tris = np.arange(int(np.count_nonzero(arrays.prim_ref >= 0)))  # the BVH's triangles come first, in order
    if len(tris):
        info = arrays.tri_info[tris]
        le = mats[info[:, L.INFO_MATERIAL], L.MAT_EMISSION : L.MAT_EMISSION + 3]
        v = arrays.tri_verts[tris].astype(np.float64).reshape(-1, 3, 3)
        area = 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
        keep = (info[:, L.INFO_LIGHT] < 0) & np.any(le > 0, axis=1) & (area > 0)
        tris, le, area = tris[keep], le[keep], area[keep]
        first = len(kinds)
        tri_emit[tris] = np.arange(first, first + len(tris), dtype=np.int32)
        kinds.extend([L.EMIT_TRIANGLE] * len(tris))
        refs.extend(tris.tolist())
        powers.extend((np.pi * le.mean(axis=1) * area).tolist())
        areas.extend(area.tolist())
        slots.extend([-1] * len(tris))

    # emissive shapes in the BVH (planes are unbounded, csg objects are sampled by BSDF rays only)
    shape_emit = np.full(len(arrays.shape_info), -1, np.int32)
    top_shapes = np.unique(~arrays.prim_ref[arrays.prim_ref < 0])
    for s in top_shapes:
        info = arrays.shape_info[s]
        kind = int(info[L.INFO_KIND])
        le = mats[info[L.INFO_MATERIAL], L.MAT_EMISSION : L.MAT_EMISSION + 3]
        if info[L.INFO_LIGHT] >= 0 or kind not in _PART_AREAS or not np.any(le > 0):
            continue
        object_from_world = np.eye(4)
        object_from_world[:3, :4] = arrays.shape_xform[s, :3, :4]
        world = np.linalg.inv(object_from_world)
        geom = np.zeros((4, 4))
        if kind == L.SHAPE_SPHERE and _uniform_scale(world):
            r = float(np.linalg.norm(world[:3, 0]))
            geom[3] = (*world[:3, 3], r)
            shape_emit[s] = len(kinds)
            add(L.EMIT_SPHERE, int(s), np.pi * _mean(le) * 4.0 * np.pi * r * r, 4.0 * np.pi * r * r, geom=geom)
            continue
        part_areas = _shape_parts(kind, bool(info[L.INFO_FLAGS] & L.FLAG_CAPPED), world)
        area = float(part_areas.sum())
        if area <= 0.0:
            continue
        geom[:3, :4] = world[:3, :4]
        geom[3, 0] = abs(np.linalg.det(world[:3, :3]))
        shape_emit[s] = len(kinds)
        add(L.EMIT_SHAPE, int(s), np.pi * _mean(le) * area, area, part_areas / area, geom)

    env_pixels, env_marginal, env_conditional, env_info = environment or environment_arrays(None)
    env_info = env_info.copy()  # (its entry is the table's; the scene arrays' copy is not written)
    if environment is not None:
        env_power = environment_power(env_pixels, radius)
        if env_power > 0.0:
            env_info[L.ENV_ENTRY] = len(kinds)
            add(L.EMIT_ENV, 0, env_power)

    power = np.asarray(powers, np.float64)
    total = power.sum()
    if len(power) and not total > 0.0:  # lights of zero power: none is worth a sample
        power = np.zeros_like(power)
    pmf = power / total if total > 0.0 else power
    cdf = np.cumsum(pmf)
    if len(cdf) and total > 0.0:
        cdf[-1] = 1.0
        cdf[pmf > 0] = np.minimum(cdf[pmf > 0], 1.0)
    n = len(kinds)
    return L.Emitters(
        emit_kind=np.asarray(kinds, np.int32).reshape(n),
        emit_ref=np.asarray(refs, np.int32).reshape(n),
        emit_cdf=np.ascontiguousarray(cdf, np.float64).reshape(n),
        emit_pmf=np.ascontiguousarray(pmf, np.float64).reshape(n),
        emit_area=np.asarray(areas, np.float64).reshape(n),
        emit_slot=np.asarray(slots, np.int32).reshape(n),
        emit_parts=np.asarray(parts, np.float64).reshape(len(parts), L.EMIT_PARTS),
        emit_geom=np.asarray(geoms, np.float64).reshape(len(geoms), 4, 4),
        tri_emit=tri_emit,
        shape_emit=shape_emit,
        light_emit=light_emit,
        env_pixels=env_pixels,
        env_marginal=env_marginal,
        env_conditional=env_conditional,
        env_info=env_info,
        tree_nodes=np.zeros((0, L.TREE_SIZE)),
        tree_link=np.zeros((0, 3), np.int32),
        emit_node=np.full(n, -1, np.int32),
        emit_unbounded=np.zeros(0, np.int32),
        unbounded_cdf=np.zeros(0),
    )


def attach(compiled, light_selection: str = "tree") -> None:
    """Ready a compiled scene (`compile_scene`) for the path tracer: its material rows read physically
    (`physical_materials`) and its emitter table (`CompiledScene.emitters`), the scene's environment in it, with
    its light tree (`compile.light_tree`) unless `light_selection` is "power" (then picked by power alone)."""
    rows = physical_materials(compiled.material_names, compiled.arrays.materials)
    compiled.arrays = compiled.arrays._replace(materials=rows)
    # emitters whose emission is textured are left to the BSDF rays (light sampling would need the texture at the
    # sampled point): the table is built as if they did not emit
    untextured = rows.copy()
    untextured[_textured_emission(rows, compiled.arrays.tex_info), L.MAT_EMISSION:L.MAT_EMISSION + 3] = 0.0
    untextured_arrays = compiled.arrays._replace(materials=untextured)
    compiled.emitters = build_emitters(untextured_arrays, compiled.bounds, compiled.environment)
    if light_selection == "tree":
        from .light_tree import with_light_tree

        compiled.emitters = with_light_tree(compiled.emitters, untextured_arrays)


def _textured_emission(rows: np.ndarray, tex_info: np.ndarray) -> np.ndarray:
    """bool (n,): which material rows have a texture applied to their emission."""
    from ..kernels.texture import APPLY_EMISSION, TEX_APPLY

    out = np.zeros(len(rows), bool)
    for i, row in enumerate(rows):
        first, count = int(row[L.MAT_TEXTURE]), int(row[L.MAT_TEXTURE_COUNT])
        if first >= 0:
            out[i] = any(int(tex_info[k, TEX_APPLY]) & APPLY_EMISSION for k in range(first, first + count))
    return out
