"""csg objects under `method: raster` (`compile.csg_mesh`): the solids tessellated and combined by mesh booleans.

* the boolean mesh is closed and consistently wound wherever the operands are, and bounds the solid the naive
  point-in-solid test describes (its volume, by Monte Carlo);
* a box minus a sphere: the volume and the two surface pieces equal what the tessellated operands give exactly;
  the cut face has the sphere's material and normals pointing to the sphere's centre, the box's faces stay flat;
* the dice: raster and raycast agree on coverage (object id) except within a pixel of edges, and the pips
  show where they do in raycast; `lumos render --method raster` draws the dice and the planets' csg rings;
* an open mesh operand is a one-line error; a moving csg object is drawn where it is at time 0, as other
  moving shapes are.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from helpers import EXAMPLES
from naive import inside_solid
from scipy import ndimage

import lumos
from lumos import cli
from lumos.api import resolve_settings
from lumos.methods import compile_for
from lumos.compile.csg_mesh import csg_pieces
from lumos.compile.tessellate import tessellate_shape
from lumos.kernels import layout as L

WHITTED = EXAMPLES / "whitted"
PAINT = {"kd": 0.03}
IVORY = {"kd": 0.8}


def pieces_of(obj: dict, segments: int = 48):
    scene = lumos.load_scene({"objects": [obj]})
    o = scene.objects[0]
    return csg_pieces(scene, o, None if o.transform is None else o.transform.to_matrix(), segments, "objects[0]")


def joined(pieces) -> trimesh.Trimesh:
    """All pieces as one mesh, vertices merged by position (the pieces' borders share positions exactly)."""
    offsets = np.cumsum([0] + [len(p.vertices) for p in pieces])
    verts = np.concatenate([p.vertices for p in pieces])
    faces = np.concatenate([p.faces + k for p, k in zip(pieces, offsets)])
    return trimesh.Trimesh(verts, faces, process=True)


def area(piece) -> float:
    return float(trimesh.Trimesh(piece.vertices, piece.faces, process=False).area)


def tessellated(kind, world_from_canonical, segments) -> trimesh.Trimesh:
    t = tessellate_shape(kind, world_from_canonical, segments)
    return trimesh.Trimesh(t.vertices, t.faces, process=True)


def icosphere(center, radius, subdivisions=2, inward=False):
    s = trimesh.creation.icosphere(subdivisions=subdivisions)
    faces = s.faces[:, ::-1] if inward else s.faces
    return {"type": "mesh", "vertices": (s.vertices * radius + center).tolist(), "faces": faces.tolist()}


def box_minus_sphere(center, radius=0.5):
    return {"type": "csg", "op": "difference", "material": IVORY,
            "left": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]},
            "right": {"type": "sphere", "center": list(center), "radius": radius, "material": PAINT}}


# ------------------------------------------------------------------------------------- closed, the right solid

TREES = {
    "box minus a bite": box_minus_sphere([0.3, 0.9, 0.2], 0.55),
    "cylinder and cone": {
        "type": "csg", "op": "difference", "transform": {"rotate": [25, 40, 10], "scale": [1.1, 0.9, 1.0]},
        "left": {"type": "csg", "op": "union",
                 "left": {"type": "cylinder", "base": [0, -0.8, 0], "top": [0, 0.4, 0], "radius": 0.6},
                 "right": {"type": "cone", "base": [0, 0.2, 0], "top": [0, 1.2, 0], "radius": 0.8}},
        "right": {"type": "box", "min": [0.1, -1, -1], "max": [1, 1, 1], "transform": {"rotate": [0, 0, 20]}}},
    "mesh, mirrored node": {
        "type": "csg", "op": "intersection", "transform": {"scale": [-1.0, 1.0, 1.2]},
        "left": icosphere([0.2, 0.0, 0.0], 1.0),
        "right": {"type": "box", "min": [-0.6, -0.7, -2], "max": [1.5, 0.7, 0.5]}},
    "mesh wound inward": {
        "type": "csg", "op": "union",
        "left": icosphere([0.0, 0.0, 0.0], 0.8, inward=True),
        "right": {"type": "sphere", "center": [0.7, 0.2, 0.0], "radius": 0.5}},
    "disjoint union, empty intersection": {
        "type": "csg", "op": "union",
        "left": {"type": "sphere", "center": [-0.8, 0, 0], "radius": 0.5},
        "right": {"type": "csg", "op": "intersection",
                  "left": {"type": "sphere", "center": [0.8, 0, 0], "radius": 0.5},
                  "right": {"type": "box", "min": [-1, -1, -1], "max": [-0.9, 1, 1]}}},
}


@pytest.mark.parametrize("name", list(TREES))
def test_boolean_mesh_is_closed_and_bounds_the_solid(name):
    obj = TREES[name]
    mesh = joined(pieces_of(obj, segments=64))
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0.0  # wound outward
    # the volume the naive point-in-solid test gives (Monte Carlo over a box around the mesh)
    rng = np.random.default_rng(3)
    lo, hi = mesh.bounds[0] - 0.05, mesh.bounds[1] + 0.05
    n = 40_000 if "mesh" in name else 200_000  # the twin's parity test costs one ray per point and triangle
    points = rng.uniform(lo, hi, (n, 3))
    frac = inside_solid(obj, points).mean()
    expected = frac * np.prod(hi - lo)
    sigma = math.sqrt(frac * (1 - frac) / len(points)) * np.prod(hi - lo)
    assert abs(mesh.volume - expected) < 4 * sigma + 0.01 * expected, (mesh.volume, expected)


def test_the_dice_are_closed():
    scene = lumos.load_scene(WHITTED / "dice.yaml")
    for i in (1, 2):
        obj = scene.objects[i]
        pieces = csg_pieces(scene, obj, obj.transform.to_matrix(), 48, f"objects[{i}]")
        mesh = joined(pieces)
        assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
        assert len(pieces) == 2 + 21  # the cube, the rounding sphere and every pip show


# ------------------------------------------------------------------------------------------ box minus sphere


@pytest.mark.parametrize("centre", [(0.0, 0.0, 0.0), (0.0, 1.0, 0.0)], ids=["cavity", "bite"])
def test_box_minus_sphere_volume_and_areas_are_the_tessellations(centre):
    segments = 48  # 24 rings: one is the equator, which the bite puts exactly in the box's top face
    m = np.eye(4)
    m[:3, :3] *= 0.5
    m[:3, 3] = centre
    sphere = tessellated(L.SHAPE_SPHERE, m, segments)
    assert sphere.is_watertight
    share = 1.0 if centre[1] == 0.0 else 0.5  # the bite removes the sphere's lower half
    hole = 0.0 if share == 1.0 else 0.5 * segments * 0.25 * math.sin(2 * math.pi / segments)  # a 48-gon, r 0.5
    pieces = pieces_of(box_minus_sphere(centre), segments)
    mesh = joined(pieces)
    assert mesh.volume == pytest.approx(8.0 - share * sphere.volume, rel=1e-9)
    assert mesh.volume == pytest.approx(8.0 - share * 4.0 / 3.0 * math.pi * 0.125, rel=5e-3)  # the exact solid
    by_solid = {p.solid: p for p in pieces}
    assert sorted(by_solid) == ["objects[0].left", "objects[0].right"]
    assert area(by_solid["objects[0].left"]) == pytest.approx(24.0 - hole, rel=1e-9)
    assert area(by_solid["objects[0].right"]) == pytest.approx(share * sphere.area, rel=1e-9)


def test_cut_face_keeps_the_spheres_material_and_faces_its_centre():
    centre = np.array([0.3, 0.9, 0.2])  # a bite across the top face, cut at no tessellation ring
    scene = lumos.load_scene({"objects": [box_minus_sphere(centre, 0.55)], "render": {"method": "raster"}})
    compiled = compile_for(scene, resolve_settings(scene, {}))
    mesh = compiled.raster
    faces, prim = mesh.triangles()
    kd = compiled.arrays.materials[mesh.prim_info[prim, 0], L.MAT_KD]
    on_sphere = np.isclose(kd, PAINT["kd"])
    assert 0 < on_sphere.sum() < len(kd)
    assert np.all(np.isclose(kd[~on_sphere], IVORY["kd"]))  # the box takes the csg node's material
    v = mesh.positions
    # the paint triangles lie on the sphere (to the tessellation's sagitta), the ivory ones on the box's faces
    assert np.all(np.abs(np.linalg.norm(v[faces[on_sphere]] - centre, axis=2) - 0.55) < 2e-3)
    assert np.all(np.any(np.isclose(np.abs(v[faces[~on_sphere]]), 1.0, atol=1e-12), axis=2))
    # the cut face's normals point into the sphere's centre (out of the solid), smoothly: each vertex's
    # normal is the sphere's normal there, to the tessellation's accuracy also at the new vertices
    sphere_verts = np.unique(faces[on_sphere])
    to_centre = centre - v[sphere_verts]
    to_centre /= np.linalg.norm(to_centre, axis=1, keepdims=True)
    n = mesh.normals[sphere_verts]
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert np.all(np.sum(n * to_centre, axis=1) > 0.998)
    # the box's faces stay flat: each normal is an axis, and triangles are wound outward of the solid
    box_verts = np.unique(faces[~on_sphere])
    assert np.allclose(np.sort(np.abs(mesh.normals[box_verts]), axis=1), [0.0, 0.0, 1.0], atol=1e-12)
    geo = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
    shading = mesh.normals[faces].sum(axis=1)
    assert np.all(np.sum(geo * shading, axis=1) > 0.0)


def test_nearest_csg_nodes_material():
    scene = lumos.load_scene(WHITTED / "dice.yaml")
    obj = scene.objects[1]
    for p in csg_pieces(scene, obj, obj.transform.to_matrix(), 24, "objects[1]"):
        want = "paint" if p.solid.startswith("objects[1].right") else "ivory"
        assert p.material is scene.materials[want], p.solid


# ------------------------------------------------------------------------------------------------ the dice


def dice(method, **settings):
    return lumos.render(WHITTED / "dice.yaml", method=method, width=160, height=120, antialias="none",
                        aov=["object_id", "albedo"], **settings)


def test_dice_raster_agrees_with_raycast_on_coverage_and_shows_the_pips():
    ray = dice("raycast")
    ids = ray.aovs["object_id"]
    paint = np.all(np.isclose(ray.aovs["albedo"], PAINT["kd"], atol=1e-6), axis=2)
    # edges: where the object, or paint against the body, changes between neighbouring pixels
    label = ids * 2 + paint
    edge = np.zeros(ids.shape, bool)
    edge[:, 1:] |= label[:, 1:] != label[:, :-1]
    edge[1:, :] |= label[1:, :] != label[:-1, :]
    near_edge = ndimage.binary_dilation(edge, iterations=1)
    assert paint.sum() > 100  # the pips are in view
    for shading in ("phong", "flat"):
        ras = dice("raster", shading=shading)  # the default tessellation, 48
        r_ids = ras.aovs["object_id"]
        assert set(np.unique(r_ids)) == set(np.unique(ids))
        wrong = (r_ids != ids) & ~near_edge
        assert wrong.sum() == 0, f"{shading}: {wrong.sum()} pixels away from edges differ in coverage"
        r_paint = np.all(np.isclose(ras.aovs["albedo"], PAINT["kd"], atol=1e-6), axis=2)
        wrong_paint = (r_paint != paint) & ~near_edge
        assert wrong_paint.sum() == 0, f"{shading}: {wrong_paint.sum()} pixels show the pips differently"
        core = ndimage.binary_erosion(paint, iterations=1)
        assert r_paint[core].all()


def test_cli_renders_the_dice_and_the_planets_rings_with_raster(tmp_path, capsys):
    for name in ("dice", "planets"):
        out = tmp_path / f"{name}.png"
        # (both scenes ask for whitted's adaptive anti-aliasing, which `lumos render` refuses for raster)
        code = cli.main(["render", str(WHITTED / f"{name}.yaml"), "--method", "raster", "--antialias", "none",
                         "--width", "160", "--height", "120", "-o", str(out), "-q"])
        assert code == 0, capsys.readouterr().err
        assert out.stat().st_size > 0


# -------------------------------------------------------------------------------------- errors, motion


def test_open_mesh_operand_is_a_one_line_error():
    s = icosphere([0, 0, 0], 1.0, 1)
    s["faces"] = s["faces"][1:]
    scene = {"objects": [{"type": "csg", "op": "difference", "left": {"type": "box"}, "right": s}]}
    with pytest.raises(lumos.LumosError) as err:
        lumos.render(scene, method="raster", width=16, height=12)
    message = str(err.value)
    assert message.startswith("objects[0].right:") and "closed" in message and "\n" not in message


def test_moving_csg_is_drawn_at_time_zero_like_other_moving_shapes():
    def raster_positions(motion):
        obj = dict(box_minus_sphere([0.3, 0.9, 0.2], 0.55), motion=motion)
        sphere = {"type": "sphere", "center": [3, 0, 0], "motion": motion}
        scene = lumos.load_scene({"camera": {"shutter": [0.0, 1.0]}, "objects": [obj, sphere],
                                  "render": {"method": "raster"}})
        return compile_for(scene, resolve_settings(scene, {})).raster.positions

    assert np.array_equal(raster_positions([0.5, 0.0, 0.0]), raster_positions([0.0, 0.0, 0.0]))
