"""OBJ + MTL import (lumos.io.obj, lumos.io.mtl): real files (tinyobjloader's edge cases, McGuire's Cornell boxes,
trimesh's fuze) checked against trimesh's loader as a twin, smoothing groups, indices, texture options, every
illum model's coefficients, sloppy files (warnings) and broken ones (one-line errors with the line number), a
whitted render of an imported box (random corrupted files: io/test_obj_hostile.py)."""

import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage

from conftest import run_cli as run
from helpers import DATA, ROOT, check_pieces

import lumos
from lumos.errors import LumosError
from lumos.io.models import import_model
from lumos.io.obj import import_obj

OBJ = DATA / "obj"
TINY = OBJ / "tinyobjloader"
SHARED = ROOT.parent / "shared" / "data"
FILES = sorted(p for p in OBJ.glob("*/*.obj") if p.name != "test-nan.obj")
SHARED_FILES = sorted(SHARED.glob("obj_mtl/*/*.obj")) + sorted(SHARED.glob("cornell/mcguire/*.obj"))
CAMERA = {"position": [0, 1, 3.4], "look_at": [0, 1, 0], "fov": 40}


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def all_triangles(model) -> int:
    return sum(len(o["faces"]) for o in model.objects)


def bounds(model) -> np.ndarray:
    vertices = np.concatenate([o["vertices"] for o in model.objects])
    return np.array([vertices.min(axis=0), vertices.max(axis=0)])


# ------------------------------------------------------------------------------------------------ real files


@pytest.mark.parametrize("path", FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_copied_file_imports(path):
    model = import_model(path)
    assert model.objects and all_triangles(model) > 0
    check_pieces(model)
    assert all("\n" not in w and w.count(":") >= 2 for w in model.warnings)


@pytest.mark.skipif(not SHARED_FILES, reason="../shared/data is not here")
@pytest.mark.parametrize("path", SHARED_FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_shared_file_imports_or_fails_in_one_line(path):
    if path.name == "test-nan.obj":
        with pytest.raises(LumosError, match=r"test-nan.obj:12: v: .* not finite"):
            import_obj(path)
        return
    model = import_obj(path)
    check_pieces(model)


# Where trimesh agrees: with negative indices over several objects (cornell_box_multimaterial, CornellBox-Original)
# its pieces take the wrong vertices (the floor of CornellBox-Original reaches x = 0.13, not 1.0), so those files
# are checked against their own `v` lines instead (every vertex is used).
TWINS = ["tinyobjloader/cube.obj", "tinyobjloader/pbr-mat-ext.obj", "tinyobjloader/issue-162-smoothing-group.obj",
         "tinyobjloader/tr-and-d-issue-43.obj", "mcguire/CornellBox-Sphere.obj", "trimesh/fuze.obj"]


@pytest.mark.parametrize("name", TWINS)
def test_triangle_counts_and_bounds_agree_with_trimesh(name):
    trimesh = pytest.importorskip("trimesh")
    twin = trimesh.load(str(OBJ / name), process=False, force="scene", skip_materials=True)
    twin_faces = sum(len(g.faces) for g in twin.geometry.values())
    model = import_obj(OBJ / name)
    assert all_triangles(model) == twin_faces
    np.testing.assert_allclose(bounds(model), twin.bounds, atol=1e-9)


@pytest.mark.parametrize("name", ["tinyobjloader/cornell_box_multimaterial.obj", "mcguire/CornellBox-Original.obj"])
def test_bounds_of_negative_index_files_are_those_of_their_vertices(name):
    lines = [line.split() for line in (OBJ / name).read_text().splitlines()]
    v = np.array([[float(x) for x in line[1:4]] for line in lines if line[:1] == ["v"]])
    # (the multimaterial box's front wall, whose face is commented out, lies within the other walls' bounds)
    np.testing.assert_array_equal(bounds(import_obj(OBJ / name)), [v.min(axis=0), v.max(axis=0)])


def test_emissive_parts_emit_on_the_side_their_faces_wind_to():
    """A part whose material has Ke emits on its counter-clockwise side only (`two_sided: false`), as Mitsuba and
    pbrt read area lights: McGuire's lamp faces down, into the box, and no light leaks into the gap above it."""
    model = import_obj(OBJ / "mcguire" / "CornellBox-Original.obj")
    sides = {o["name"]: o.get("two_sided", True) for o in model.objects}
    assert sides.pop("light") is False and all(sides.values())
    lamp = next(o for o in model.objects if o["name"] == "light")
    v = lamp["vertices"][lamp["faces"][0]]
    assert np.cross(v[1] - v[0], v[2] - v[0])[1] < 0  # its front is down


def test_cornell_multimaterial_pieces_follow_objects_and_materials():
    model = import_obj(TINY / "cornell_box_multimaterial.obj")
    names = [(o["name"], o["material"]) for o in model.objects]
    assert names[:3] == [("floor", "white"), ("light", "light"), ("ceiling", "white")]
    assert ("front_wall", "blue") not in names       # its face is commented out
    assert model.materials["light"]["ka"] == [20.0, 20.0, 20.0]
    floor = model.objects[0]
    assert len(floor["faces"]) == 6                  # three quads


def test_groups_with_two_words_and_the_material_they_inherit():
    model = import_obj(TINY / "cube.obj")
    assert [(o["name"], o["material"]) for o in model.objects] == [
        ("front cube", "white"), ("back cube", "white"), ("right cube", "red"), ("top cube", "white"),
        ("left cube", "green"), ("bottom cube", "white")]


def test_vertex_colours_are_ignored_silently():
    plain, coloured = import_obj(TINY / "cube.obj"), import_obj(TINY / "cube-vertexcol.obj")
    assert not coloured.warnings
    for a, b in zip(plain.objects, coloured.objects):
        np.testing.assert_array_equal(a["vertices"], b["vertices"])
        np.testing.assert_array_equal(a["faces"], b["faces"])


def test_leading_zero_exponents():
    model = import_obj(TINY / "leading-zero-in-exponent-notation-issue-210.obj")
    v = model.objects[0]["vertices"]
    assert np.isclose(v[:, 0], 0.08).any() and np.isclose(v[:, 1], -70.0).any()


def test_texture_name_with_a_space_is_found():
    model = import_obj(OBJ / "trimesh" / "fuze.obj")
    texture = model.materials["a-super-duper-material"]["texture"]
    assert Path(texture["file"]) == (OBJ / "trimesh" / "fuze uv.jpg").resolve()
    assert texture["mode"] == "multiply" and texture["apply_to"] == ["kd"]
    assert "uvs" in model.objects[0]


def test_faces_that_name_normals_the_file_lacks_are_read_without_them():
    model = import_obj(TINY / "catmark_torus_creases0.obj")
    assert all_triangles(model) == 64 and "normals" not in model.objects[0]
    assert any("refer to normals but the file defines none" in w for w in model.warnings)
    assert any("'t' statements are not supported" in w for w in model.warnings)


# ------------------------------------------------------------------------------------- indices and polygons


CUBE_V = """v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
"""
CUBE_F = ["1 4 3 2", "5 6 7 8", "1 2 6 5", "2 3 7 6", "3 4 8 7", "4 1 5 8"]


def test_negative_indices_equal_positive(tmp_path):
    positive = write(tmp_path, "pos.obj", CUBE_V + "".join(f"f {f}\n" for f in CUBE_F))
    negative = write(tmp_path, "neg.obj", CUBE_V + "".join(
        "f " + " ".join(str(int(i) - 9) for i in f.split()) + "\n" for f in CUBE_F))
    a, b = import_obj(positive).objects[0], import_obj(negative).objects[0]
    for key in ("vertices", "faces"):
        np.testing.assert_array_equal(a[key], b[key])
    assert len(a["faces"]) == 12


def test_negative_indices_count_from_the_face(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf -3 -2 -1\n"
    obj = import_obj(write(tmp_path, "rel.obj", text)).objects[0]
    tris = obj["vertices"][obj["faces"]]
    assert tris[0].max() == 1.0 and tris[1].min() == 5.0


def test_concave_polygon_is_ear_clipped(tmp_path):
    # An L of area 3 (a 2x2 square less a unit square); a fan from corner 0 would cover area outside it.
    text = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n"
    obj = import_obj(write(tmp_path, "l.obj", text)).objects[0]
    p = obj["vertices"][obj["faces"]]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert len(obj["faces"]) == 4 and np.all(cross[:, 2] > 0)
    assert math.isclose(0.5 * np.abs(cross[:, 2]).sum(), 3.0)


def test_uv_seams_split_vertices_only_there(tmp_path):
    text = CUBE_V + "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n" + "".join(
        "f " + " ".join(f"{i}/{k + 1}" for k, i in enumerate(f.split())) + "\n" for f in CUBE_F)
    obj = import_obj(write(tmp_path, "uv.obj", text)).objects[0]
    corners = [(int(i), k) for f in CUBE_F for k, i in enumerate(f.split())]
    assert len(obj["vertices"]) == len(set(corners))
    assert "normals" not in obj        # neither vn nor s: the mesh keys decide the shading


def test_continuation_tabs_comments(tmp_path):
    text = "# a cube\nv\t0 0 0\nv 1 0 \\\n 0\nv 0 1 0  # corner\n\nf 1 \\\n 2 3\n"
    obj = import_obj(write(tmp_path, "cont.obj", text)).objects[0]
    assert len(obj["faces"]) == 1 and obj["vertices"].shape == (3, 3)


# ---------------------------------------------------------------------------------------- smoothing groups


def cube_with_groups(tmp_path, groups: list[str]) -> dict:
    text = CUBE_V + "".join(f"s {g}\nf {f}\n" for g, f in zip(groups, CUBE_F))
    return import_obj(write(tmp_path, "s.obj", text)).objects[0]


def test_one_smoothing_group_shares_normals(tmp_path):
    obj = cube_with_groups(tmp_path, ["1"] * 6)
    assert len(obj["vertices"]) == 8
    centre = obj["vertices"] - 0.5
    np.testing.assert_allclose(obj["normals"], centre / np.linalg.norm(centre, axis=1, keepdims=True), atol=1e-12)


def test_s_off_gives_face_normals(tmp_path):
    for off in ("off", "0"):
        obj = cube_with_groups(tmp_path, [off] * 6)
        assert len(obj["vertices"]) == 24
        assert np.allclose(np.abs(obj["normals"]).max(axis=1), 1.0)     # axis-aligned


def test_faces_in_different_groups_do_not_share_normals(tmp_path):
    obj = cube_with_groups(tmp_path, ["1", "1", "2", "3", "2", "3"])   # opposite faces paired
    assert len(obj["vertices"]) == 24
    assert np.allclose(np.abs(obj["normals"]).max(axis=1), 1.0)        # each face alone in its group at a corner
    mixed = cube_with_groups(tmp_path, ["1", "1", "1", "1", "off", "off"])
    n = mixed["normals"]
    assert (np.abs(n).max(axis=1) < 0.99).any() and np.isclose(np.abs(n).max(axis=1), 1.0).any()


def test_issue_162_file_normals_win_and_groups_stay_apart():
    model = import_obj(TINY / "issue-162-smoothing-group.obj")
    test1, test2 = model.objects
    assert test1["name"] == "test1" and test2["material"] == "test2"
    axes = np.eye(3)
    for obj in model.objects:                                # the file's vn: axis normals, one per face
        assert np.allclose(np.abs(obj["normals"] @ axes.T).max(axis=1), 1.0)
    assert len(test2["vertices"]) == 20                      # 5 faces x 4 corners: no sharing across groups


# ------------------------------------------------------------------------------------------------- MTL


def test_tr_and_d_issue_43_d_wins_in_either_order():
    model = import_obj(TINY / "tr-and-d-issue-43.obj")
    for name in ("Material.001", "Material.002"):
        assert model.materials[name]["kt"] == pytest.approx([0.25] * 3)


def test_tr_alone_and_tr_1(tmp_path):
    write(tmp_path, "m.mtl", "newmtl a\nKd 0.5 0.5 0.5\nTr 0.3\nillum 2\nnewmtl b\nKd 0.5 0.5 0.5\nTr 1\n")
    model = import_obj(write(tmp_path, "m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n"))
    a, b = model.materials["a"], model.materials["b"]
    assert a["kt"] == pytest.approx([0.3] * 3) and a["kd"] == pytest.approx([0.35] * 3) and a["ior"] == 1.0
    assert b["kt"] == [0.0] * 3 and b["kd"] == [0.5] * 3
    assert any("m.mtl:7: Tr 1 would make the material invisible" in w for w in model.warnings)


def test_an_unreadable_texture_is_a_warning_as_in_gltf(tmp_path, capsys):
    """A map file that exists but is no image is a warning and the material goes without it (glTF's importer
    does the same), said once however many map statements name it; the render does not fail."""
    (tmp_path / "broken.png").write_bytes(b"not an image at all")
    write(tmp_path, "m.mtl", "newmtl a\nKd 0.5 0.5 0.5\nmap_Kd broken.png\nnewmtl b\nKd 0.2 0.2 0.2\n"
                              "map_Kd broken.png\n")
    obj = write(tmp_path, "m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl a\nf 1/1 2/1 3/1\n")
    model = import_obj(obj)
    assert "texture" not in model.materials["a"] and model.materials["a"]["kd"] == [0.5] * 3
    unreadable = [w for w in model.warnings_once() if "not a readable image" in w]
    assert len(unreadable) == 1 and "(no image format Pillow knows); map_Kd ignored (2 times; also line 6)" in unreadable[0], model.warnings_once()
    code, _, err = run(capsys, "render", obj, "-o", tmp_path / "o.npy", "--width", "8", "--height", "6", "--quiet")
    assert code == 0 and np.isfinite(np.load(tmp_path / "o.npy")).all(), err


def test_texture_options_issue_85(tmp_path):
    for name in ("m.obj", "m.mtl"):
        shutil.copy(TINY / f"texture-options-issue-85.{name[2:]}", tmp_path / name)
    (tmp_path / "m.obj").write_text((tmp_path / "m.obj").read_text().replace("texture-options-issue-85", "m"))
    for image in ("ambient", "diffuse", "specular", "specular_highlight", "bumpmap", "bumpmap2", "alpha", "bump",
                  "displacement"):
        PILImage.new("RGB", (2, 2), (90, 90, 90)).save(tmp_path / f"{image}.jpg")
    model = import_obj(tmp_path / "m.obj")
    assert not [w for w in model.warnings if "not found" in w]
    textures = {tuple(t["apply_to"]): t for t in model.materials["default"]["texture"]}
    assert textures[("ka",)]["wrap"] == "clamp"
    assert textures[("kd",)]["offset"] == [0.1, 0.0]
    assert textures[("ks",)]["scale"] == [0.1, 0.2]
    assert Path(textures[("kd",)]["file"]).name == "diffuse.jpg"
    assert model.materials["default"]["bump"] == {"type": "image", "file": str((tmp_path / "bumpmap.jpg").resolve()),
                                                  "strength": 3.0}
    bm2 = model.materials["bm2"]
    assert Path(bm2["bump"]["file"]).name == "bumpmap2.jpg" and bm2["bump"]["strength"] == 1.5
    assert [Path(t["file"]).name for t in bm2["texture"]] == ["diffuse.jpg", "specular.jpg"]
    bm3 = model.materials["bm3"]
    opacity = [t for t in bm3["texture"] if t["apply_to"] == ["opacity"]]
    assert Path(opacity[0]["file"]).name == "alpha.jpg" and Path(bm3["bump"]["file"]).name == "bump.jpg"


def test_windows_paths_and_several_libraries_with_spaces(tmp_path):
    (tmp_path / "tex").mkdir()
    PILImage.new("RGB", (2, 2)).save(tmp_path / "tex" / "wood grain.png")
    write(tmp_path, "my lib.mtl", "newmtl wood\nKd 1 1 1\nmap_Kd -s 2 2 tex\\wood grain.png\n")
    write(tmp_path, "b.mtl", "newmtl red\nKd 1 0 0\n")
    write(tmp_path, "c.mtl", "newmtl blue\nKd 0 0 1\n")
    text = "mtllib my lib.mtl\nmtllib b.mtl c.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl wood\nf 1 2 3\n" \
           "usemtl blue\nf 3 2 1\n"
    model = import_obj(write(tmp_path, "m.obj", text))
    assert set(model.materials) == {"wood", "red", "blue"} and not model.warnings
    texture = model.materials["wood"]["texture"]
    assert Path(texture["file"]).name == "wood grain.png" and texture["scale"] == [2.0, 2.0]
    assert [o["material"] for o in model.objects] == ["wood", "blue"]


K = {"Ka": 0.1, "Kd": 0.2, "Ks": 0.1, "Ns": 50, "Ni": 1.5, "Tf": 0.6}
# illum -> expected lumos coefficients for the material K (see docs/formats.md; none needs energy scaling)
ILLUM = {
    0: dict(ka=0, kd=0, ks=0, kr=0, kt=0, emission=0.2, ior=1.5, fresnel=False),
    1: dict(ka=0.1, kd=0.2, ks=0, kr=0, kt=0, emission=0, ior=1.5, fresnel=False),
    2: dict(ka=0.1, kd=0.2, ks=0.1, kr=0, kt=0, emission=0, ior=1.5, fresnel=False),
    3: dict(ka=0.1, kd=0.2, ks=0.1, kr=0.1, kt=0, emission=0, ior=1.5, fresnel=False),
    4: dict(ka=0.04, kd=0.08, ks=0.1, kr=0.1, kt=0.6, emission=0, ior=1.0, fresnel=False),
    5: dict(ka=0.1, kd=0.2, ks=0.1, kr=0.1, kt=0, emission=0, ior=1.5, fresnel=True),
    6: dict(ka=0.1, kd=0.2, ks=0.1, kr=0.1, kt=0.54, emission=0, ior=1.5, fresnel=False),
    7: dict(ka=0.1, kd=0.2, ks=0.1, kr=0.1, kt=0.54, emission=0, ior=1.5, fresnel=True),
    8: dict(ka=0.1, kd=0.2, ks=0.1, kr=0.1, kt=0, emission=0, ior=1.5, fresnel=False),
    9: dict(ka=0.04, kd=0.08, ks=0.1, kr=0.1, kt=0.6, emission=0, ior=1.0, fresnel=False),
    10: dict(ka=0.1, kd=0.2, ks=0, kr=0, kt=0, emission=0, ior=1.5, fresnel=False),
}


def one_material(tmp_path, mtl: str):
    write(tmp_path, "m.mtl", "newmtl m\n" + mtl)
    return import_obj(write(tmp_path, "m.obj", "mtllib m.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"))


@pytest.mark.parametrize("illum", sorted(ILLUM))
def test_illum_model(tmp_path, illum):
    model = one_material(tmp_path, "".join(f"{k} {v}\n" for k, v in K.items()) + f"illum {illum}\n")
    material = model.materials["m"]
    for key, value in ILLUM[illum].items():
        if isinstance(value, bool):
            assert material[key] is value, key
        elif key == "ior":
            assert material[key] == value
        else:
            assert material[key] == pytest.approx([value] * 3), key
    assert material["shininess"] == 50
    assert any("illum 10" in w for w in model.warnings) == (illum == 10)
    total = np.sum([material[k] for k in ("kd", "ks", "kr", "kt")], axis=0)
    assert total.max() <= 1.0 + 1e-12


def test_energy_stays_at_most_one_keeping_the_ray_traced_terms(tmp_path):
    fuze = one_material(tmp_path, "Kd 1 1 1\nKs 1 1 1\nNs 20\nillum 2\n").materials["m"]
    assert fuze["kd"] == pytest.approx([0.5] * 3) and fuze["ks"] == pytest.approx([0.5] * 3)
    mirror = import_obj(OBJ / "mcguire" / "CornellBox-Mirror.obj").materials["tallBox"]
    assert mirror["kr"] == pytest.approx([0.95] * 3) and mirror["fresnel"] is True
    assert sum(mirror[k][0] for k in ("kd", "ks", "kr", "kt")) == pytest.approx(1.0)


def test_dissolve_blends_straight_through(tmp_path):
    material = one_material(tmp_path, "Kd 0.8 0.4 0.2\nKs 0.2 0.2 0.2\nd 0.25\nNi 1.5\nillum 2\n").materials["m"]
    assert material["kd"] == pytest.approx([0.2, 0.1, 0.05]) and material["ks"] == pytest.approx([0.05] * 3)
    assert material["kt"] == pytest.approx([0.75] * 3) and material["ior"] == 1.0


def test_mcguire_illum_5_and_7():
    materials = import_obj(OBJ / "mcguire" / "CornellBox-Sphere.obj").materials
    mirror, glass = materials["leftSphere"], materials["rightSphere"]
    assert mirror["kr"] == pytest.approx([0.95] * 3) and mirror["fresnel"] and mirror["kt"] == [0.0] * 3
    assert glass["fresnel"] and glass["ior"] == 2.5 and glass["kr"] == pytest.approx([0.3] * 3)
    assert glass["kt"] == pytest.approx([0.7 * 0.1] * 3)        # (1 - Ks)·Tf
    assert materials["light"]["emission"] == [10.0] * 3


def test_map_kd_of_illum_0_is_the_emitted_colour_and_map_ks_of_a_mirror_its_reflection(tmp_path):
    PILImage.new("RGB", (2, 2)).save(tmp_path / "t.png")
    flat = one_material(tmp_path, "Kd 1 1 1\nmap_Kd t.png\nillum 0\n").materials["m"]
    assert flat["texture"]["apply_to"] == ["emission"]
    mirror = one_material(tmp_path, "Ks 0.5 0.5 0.5\nmap_Ks t.png\nmap_d t.png\nillum 3\n").materials["m"]
    assert [t["apply_to"] for t in mirror["texture"]] == [["ks", "kr"], ["opacity"]]


# ------------------------------------------------------------------------------------- sloppy and broken


def test_sloppy_files_warn_once_per_problem(tmp_path):
    write(tmp_path, "m.mtl", "newmtl shiny\r\nKs 0.5 0.5 0.5\r\nNs 0\r\nmap_Kd missing.png\r\n")
    text = ("mtllib m.mtl\r\nmtllib nowhere.mtl\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nusemtl shiny\r\nf 1 2 3\r\n"
            "usemtl ghost\r\nf 3 2 1\r\nl 1 2\r\nl 2 3\r\np 1\r\n")
    model = import_obj(write(tmp_path, "m.obj", text))
    text = "\n".join(model.warnings)
    for expected in ("m.obj:1: CRLF", "m.mtl:1: CRLF", "m.mtl:3: Ns 0", "m.mtl:4: texture 'missing.png' not found",
                     "m.obj:2: material library 'nowhere.mtl' not found", "m.obj:8: usemtl 'ghost'",
                     "m.obj:10: 'l' statements", "m.obj:12: 'p' statements"):
        assert expected in text, expected
    assert len(model.warnings) == 8
    assert model.materials["ghost"] == {"ka": 0.8, "kd": 0.8}
    assert model.materials["shiny"]["shininess"] == 1.0


V3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
BROKEN = {
    "index out of range": (V3 + "f 1 2 4\n", r"b.obj:4: f: vertex index 4 is out of range \(the file has 3"),
    "negative too far back": (V3 + "f -1 -2 -4\n", r"b.obj:4: f: vertex index -4 is out of range"),
    "index zero": (V3 + "f 0 1 2\n", r"b.obj:4: f: vertex index 0"),
    "uv out of range": (V3 + "vt 0 0\nf 1/1 2/2 3/1\n", r"b.obj:5: f: texture coordinate index 2"),
    "nan": ("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", r"b.obj:2: v: nan 0 0 is not finite"),
    "inf normal": (V3 + "vn 0 inf 0\nf 1//1 2//1 3//1\n", r"b.obj:4: vn: .* not finite"),
    "garbage number": ("v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n", r"b.obj:2: v: 'zero' is not a number"),
    "garbage index": (V3 + "f 1 2 three\n", r"b.obj:4: f: 'three' is not a vertex reference"),
    "truncated face": (V3 + "f 1 2", r"b.obj:4: a face needs at least 3 vertices, got 2"),
    "truncated vertex": (V3 + "v 1 2\nf 1 2 3\n", r"b.obj:4: v needs 3 numbers, got 2"),
    "bad smoothing group": (V3 + "s maybe\nf 1 2 3\n", r"b.obj:4: s: 'maybe'"),
    "empty": ("", r"b.obj: no faces"),
    "no faces": (V3 + "l 1 2\n", r"b.obj: no faces"),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_files_are_one_line_errors_with_the_line(tmp_path, case):
    text, message = BROKEN[case]
    with pytest.raises(LumosError, match=message) as info:
        import_obj(write(tmp_path, "b.obj", text))
    assert "\n" not in str(info.value)


def test_broken_mtl_numbers_are_errors_with_the_line(tmp_path):
    with pytest.raises(LumosError, match=r"m.mtl:3: Ns: 'shiny' is not a number"):
        one_material(tmp_path, "Kd 1 1 1\nNs shiny\n")
    with pytest.raises(LumosError, match=r"m.mtl:2: Kd: nan is not a finite number"):
        one_material(tmp_path, "Kd nan 1 1\n")


def test_missing_file_and_directory():
    with pytest.raises(LumosError, match="file not found"):
        import_model(OBJ / "nothing.obj")
    with pytest.raises(LumosError, match="cannot read the file"):
        import_obj(OBJ)


@pytest.mark.slow
def test_a_million_lines_take_seconds_not_minutes(tmp_path):
    # Not a timing assertion: a 250k-vertex, 250k-face file must simply finish (a per-line NumPy call would not).
    n = 250_000
    rng = np.random.default_rng(1)
    v = "".join(f"v {x:.4f} {y:.4f} {z:.4f}\n" for x, y, z in rng.random((n, 3)))
    f = "".join(f"f {a} {b} {c}\n" for a, b, c in rng.integers(1, n + 1, (n, 3)))
    model = import_obj(write(tmp_path, "big.obj", v + "s 1\n" + f))
    assert all_triangles(model) == n


# ------------------------------------------------------------------------------------ scenes and rendering


def scene_of(model, **render) -> dict:
    return {"camera": CAMERA, "ambient": 0.05, "lights": [{"type": "point", "position": [0, 1.8, 0.6]}],
            "render": {"width": 48, "height": 48, **render}, "materials": model.materials, "objects": model.objects}


@pytest.mark.parametrize("name", ["mcguire/CornellBox-Original.obj", "mcguire/CornellBox-Sphere.obj",
                                  "tinyobjloader/cornell_box_multimaterial.obj", "tinyobjloader/cube.obj"])
def test_untextured_imports_validate_as_scenes(name):
    scene = lumos.load_scene(scene_of(import_obj(OBJ / name)))
    assert len(scene.objects) == len(import_obj(OBJ / name).objects)


def test_textured_imports_validate_as_scenes(tmp_path):
    lumos.load_scene(scene_of(import_obj(OBJ / "trimesh" / "fuze.obj")))
    (tmp_path / "t.png").write_bytes((OBJ / "trimesh" / "fuze uv.jpg").read_bytes())
    model = one_material(tmp_path, "Kd 1 1 1\nKs 0.5 0.5 0.5\nmap_Kd -o 0.5 0 t.png\nmap_Ks -s 2 2 t.png\n"
                                   "map_d -clamp on t.png\nmap_Ke t.png\nnorm -bm 0.5 t.png\nillum 3\n")
    scene = lumos.load_scene(scene_of(model))
    textures = scene.materials["m"].texture
    assert [t.apply_to for t in textures] == [["kd"], ["ks", "kr"], ["emission"], ["opacity"]]
    assert scene.materials["m"].bump.type == "normal"


def test_whitted_renders_an_imported_mcguire_box():
    model = import_obj(OBJ / "mcguire" / "CornellBox-Sphere.obj")
    with warnings.catch_warnings():
        warnings.simplefilter("error", lumos.errors.LumosWarning)   # no energy warning from the materials
        image = lumos.render(lumos.load_scene(scene_of(model, method="whitted", max_depth=3)))
    assert np.isfinite(image.array).all() and image.array.mean() > 0.01
    left, right = image.array[:, :12].mean(axis=(0, 1)), image.array[:, -12:].mean(axis=(0, 1))
    assert left[0] > left[2] and right[2] > right[0]        # the red wall left, the blue wall right
