"""Models without a scene file (`lumos render bunny.ply`) and model files included in scenes (`type: model`).

OBJ and glTF files are read by importers that live on their own (lumos.io.obj, lumos.io.gltf); the logic here
is tested with a fabricated importer (`fake_importer`) that returns an ImportedModel with materials, cameras and
lights, exactly as the real ones do, and with the real PLY reader.
"""

import json
import math
import sys
import textwrap
import types
from pathlib import Path

import numpy as np
import pytest

import lumos
from conftest import run_cli as run
from helpers import DATA, EXAMPLES
from lumos.errors import LumosError
from lumos.io.models import ImportedModel
from lumos.scene import from_model

BUNNY = DATA / "bunny_res4.ply"

CUBE_V = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
CUBE_F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.int64)


def cube_model(path, *, cameras=(), lights=(), emission=False, own_translate=None) -> ImportedModel:
    """A two-material model: a cube 'body' (material Metal) and a small 'lid' cube (material Paint)."""
    lid = {"type": "mesh", "name": "lid", "material": "Paint", "vertices": CUBE_V * 0.25, "faces": CUBE_F}
    if own_translate is not None:
        lid["transform"] = {"matrix": [[1, 0, 0, own_translate[0]], [0, 1, 0, own_translate[1]],
                                       [0, 0, 1, own_translate[2]], [0, 0, 0, 1]]}
    return ImportedModel(
        source=Path(path).resolve(),
        materials={"Metal": {"kd": 0.5, "ks": 0.3, "shininess": 20.0},
                   "Paint": {"kd": [0.2, 0.4, 0.6], "emission": 4.0 if emission else 0.0}},
        objects=[{"type": "mesh", "name": "body", "material": "Metal", "vertices": CUBE_V, "faces": CUBE_F}, lid],
        cameras=[dict(c) for c in cameras],
        lights=[dict(light) for light in lights],
    )


@pytest.fixture
def fake_importer(monkeypatch):
    """Install fake lumos.io.obj / lumos.io.gltf importers; returns a dict file name -> ImportedModel factory
    (default: `cube_model`). Every call is recorded in `calls`."""
    makers, calls = {}, []

    def fake(path):
        calls.append(Path(path))
        return makers.get(Path(path).name, cube_model)(path)

    for module, func in (("lumos.io.obj", "import_obj"), ("lumos.io.gltf", "import_gltf")):
        mod = types.ModuleType(module)
        setattr(mod, func, fake)
        monkeypatch.setitem(sys.modules, module, mod)
    makers["calls"] = calls
    return makers


def touch(folder: Path, name: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("# a stand-in: the fake importer does not read it\n")
    return path


def write(folder: Path, text: str, name: str = "scene.yaml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


def one_error_line(err: str) -> str:
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("lumos: warning")]
    assert len(lines) == 1 and lines[0].startswith("lumos: error: "), err
    assert "Traceback" not in err
    return lines[0]


def error_of(source) -> str:
    with pytest.raises(LumosError) as info:
        lumos.load_scene(source)
    message = str(info.value)
    assert "\n" not in message
    return message


# ------------------------------------------------------------------------------------ a model on its own


def test_bunny_scene_is_framed_three_quarter_from_its_front():
    """A closed model: the front (+z on a tie), swung SWING degrees to its left and raised RAISE degrees, y up,
    framed about the bounds' centre, lit by three point lights about the view."""
    scene = lumos.load_scene(BUNNY)
    cam = scene.camera
    assert cam.type == "perspective" and cam.fov == 40 and tuple(cam.up) == (0, 1, 0)
    lo, hi = from_model.model_bounds([{"type": "mesh", "vertices": scene.objects[0].vertices}])
    assert np.allclose(cam.look_at, (lo + hi) / 2)
    d = np.subtract(cam.position, cam.look_at)
    d /= np.linalg.norm(d)
    assert math.degrees(math.asin(d[1])) == pytest.approx(from_model.RAISE)
    front = from_model.front_direction([{"type": "mesh", "vertices": scene.objects[0].vertices,
                                         "faces": scene.objects[0].faces}])
    horizontal = np.array([d[0], 0.0, d[2]]) / math.hypot(d[0], d[2])
    assert math.degrees(math.acos(horizontal @ front)) == pytest.approx(from_model.SWING)
    assert [light.type for light in scene.lights] == ["point"] * 3
    keys = [light.intensity[0] for light in scene.lights]
    assert keys[0] > keys[2] > keys[1] > 0  # key > rim > fill
    # the key light is up-left of the view: left of the camera's right vector, above the model
    right = np.cross(cam.up, d)
    key = np.subtract(scene.lights[0].position, cam.look_at)
    assert key @ right < 0 and key[1] > 0 and key @ d > 0
    assert scene.render.method == "whitted" and scene.objects[0].material is None  # the default white-grey
    assert scene.source == BUNNY and scene.made_for_model


def _quad(corners):
    return {"type": "mesh", "vertices": np.asarray(corners, float), "faces": np.array([[0, 1, 2], [0, 2, 3]])}


def test_one_sided_models_are_seen_from_the_side_their_faces_show():
    """A floor is not framed edge-on, a wall facing -z not from behind; a closed surface is not one-sided (None:
    the three-quarter view); the direction is a unit vector and the floor's camera looks down at TILT degrees."""
    floor = _quad([[-1, 0, 1], [1, 0, 1], [1, 0, -1], [-1, 0, -1]])  # counter-clockwise seen from above: +y
    ceiling = _quad([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]])
    back = _quad([[-1, -1, 0], [-1, 1, 0], [1, 1, 0], [1, -1, 0]])  # faces -z
    side = _quad([[0, -1, -1], [0, -1, 1], [0, 1, 1], [0, 1, -1]])  # faces -x
    c = math.cos(math.radians(from_model.TILT))
    s = math.sin(math.radians(from_model.TILT))
    np.testing.assert_allclose(from_model.view_direction([floor]), [0, s, c], atol=1e-12)
    np.testing.assert_allclose(from_model.view_direction([ceiling]), [0, -s, c], atol=1e-12)
    np.testing.assert_allclose(from_model.view_direction([back]), [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(from_model.view_direction([side]), [-s, 0, c], atol=1e-12)
    assert from_model.view_direction([back, _quad([[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]])]) is None
    bunny = lumos.load_scene(BUNNY)  # nearly closed: not one-sided
    assert from_model.view_direction([{"type": "mesh", "vertices": bunny.objects[0].vertices,
                                       "faces": bunny.objects[0].faces}]) is None
    # what `lumos render floor.ply` gets: a camera above the floor's plane looking down at it
    cam = from_model.scene_from_model(ImportedModel(source=Path("floor.obj"), objects=[floor]))[0]["camera"]
    assert cam["position"][1] > 0 and cam["position"][2] > 0


def _box_mesh(lo, hi, inward=False, per_face=False):
    """A box as a mesh wound outward (or inward), optionally with a vertex per face corner."""
    v = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], float)
    f = CUBE_F[:, ::-1] if inward else CUBE_F
    if per_face:
        v, f = v[f].reshape(-1, 3), np.arange(3 * len(f)).reshape(-1, 3)
    return {"type": "mesh", "vertices": v, "faces": f}


def test_up_axis_front_and_inside():
    """The up axis: z for a model much taller along z than along y (not for glTF); the front: the side the most
    faces face; a box seen from inside (wound inward, open on one side) is looked into straight from its open
    side, with its lights near the view's axis so that they shine in."""
    tall = _box_mesh((0, 0, 0), (1, 1, 2))
    assert from_model.up_axis([tall]) == "z" and from_model.up_axis([tall], "bottle.gltf") == "y"
    assert from_model.up_axis([_box_mesh((0, 0, 0), (1, 1, 1.3))]) == "y"
    # a cube whose -x face is cut into many triangles: its front is -x (y-up) ...
    detail = _quad([[-1.01, -1, -1], [-1.01, -1, 1], [-1.01, 1, 1], [-1.01, 1, -1]])
    fine = {"type": "mesh", "vertices": detail["vertices"], "faces": np.repeat(detail["faces"], 8, axis=0)}
    np.testing.assert_allclose(from_model.front_direction([_box_mesh((-1, -1, -1), (1, 1, 1)), fine]), [-1, 0, 0])
    # ... and with z up the front of a plain cube is -y
    np.testing.assert_allclose(from_model.front_direction([_box_mesh((-1, -1, -1), (1, 1, 1))], "z"), [0, -1, 0])
    room = _box_mesh((-1, -1, -1), (1, 1, 1), inward=True)
    room["faces"] = room["faces"][[i for i in range(12) if i not in (2, 3)]]  # the +z wall left out: open at +z
    assert from_model.faces_inward([room]) and not from_model.faces_inward([_box_mesh((-1, -1, -1), (1, 1, 1))])
    scene, about = from_model.scene_from_model(ImportedModel(source=Path("room.obj"), objects=[room]))
    d = np.subtract(scene["camera"]["position"], scene["camera"]["look_at"])
    np.testing.assert_allclose(d / np.linalg.norm(d), [0, 0, 1], atol=1e-12)  # straight in through the opening
    assert len(scene["lights"]) == 2
    for light in scene["lights"]:  # each shines in through the opening: its ray to the centre crosses z = 1 inside
        p = np.asarray(light["position"])
        t = (p[2] - 1.0) / p[2]
        assert np.all(np.abs(p[:2] * (1 - t)) < 1.0)


@pytest.mark.parametrize("view, expected", [("front", [0, 0, 1]), ("back", [0, 0, -1]), ("left", [1, 0, 0]),
                                            ("right", [-1, 0, 0]), ("top", [0, 1, 0])])
def test_view_flag(view, expected, capsys, tmp_path):
    """--view front|back|left|right|top puts the camera on that side (the model's left is the viewer's right);
    --up z turns the frame; a scene file with its own camera refuses both, in one line."""
    scene = lumos.load_scene(BUNNY, view=view)
    d = np.subtract(scene.camera.position, scene.camera.look_at)
    np.testing.assert_allclose(d / np.linalg.norm(d), expected, atol=1e-12)
    if view == "top":
        np.testing.assert_allclose(scene.camera.up, [0, 0, -1], atol=1e-12)
    scene = lumos.load_scene(BUNNY, view=view, up="z")
    if view == "top":  # from above (+z), the front at the bottom of the image: the camera's up is horizontal
        d = np.subtract(scene.camera.position, scene.camera.look_at)
        np.testing.assert_allclose(d / np.linalg.norm(d), [0, 0, 1], atol=1e-12)
        assert scene.camera.up[2] == 0 and abs(np.linalg.norm(scene.camera.up) - 1) < 1e-12
    else:
        assert tuple(scene.camera.up) == (0, 0, 1)
    if view == "front":
        code, _, err = run(capsys, "render", BUNNY, "--view", "sideways", "-o", tmp_path / "o.png")
        assert code == 2 and "--view: unknown view 'sideways'" in one_error_line(err)
        scene_file = write(tmp_path, "objects: [{type: sphere}]\n")
        code, _, err = run(capsys, "render", scene_file, "--up", "z", "-o", tmp_path / "o.png")
        assert code == 2 and "frame a model file" in one_error_line(err)
        assert not (tmp_path / "o.png").exists()


def test_path_on_a_model_file_takes_enough_samples(fake_importer, tmp_path):
    """A model file's made-up render block is whitted's 4 spp; `--method path` gets PATH_SPP unless --spp says."""
    from lumos.api import resolve_settings

    scene = lumos.load_scene(touch(tmp_path, "plain.obj"))
    assert resolve_settings(scene, {"method": "path"}).spp == from_model.PATH_SPP
    assert resolve_settings(scene, {"method": "path", "spp": 2}).spp == 2
    assert resolve_settings(scene, {"method": "raycast"}).spp == 4
    yaml_scene = lumos.load_scene({"objects": [{"type": "sphere"}], "render": {"spp": 4}})
    assert resolve_settings(yaml_scene, {"method": "path"}).spp == 4 and not yaml_scene.made_for_model


def test_framing_closed_form():
    """A sphere of radius r seen from distance d subtends asin(r/d): the bounding sphere spans 1/MARGIN of the
    field of view's half-height (in tangent terms, what the image shows)."""
    center, r = np.array([1.0, -2.0, 3.0]), 0.7
    cam = from_model.framing_camera(center, r)
    d = np.linalg.norm(np.subtract(cam["position"], center))
    assert math.isclose(r / d, math.sin(math.radians(20)) / from_model.MARGIN, rel_tol=1e-12)


def test_bounding_sphere_holds_every_vertex():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(500, 3)) * [3, 1, 0.5]
    center, r = from_model.bounding_sphere([{"type": "mesh", "vertices": v}])
    assert np.linalg.norm(v - center, axis=1).max() == pytest.approx(r)
    assert r <= np.linalg.norm(v.max(0) - v.min(0)) / 2 + 1e-12


def image_of(path: Path) -> np.ndarray:
    return np.load(path)


def test_render_bunny_cli_frames_it(capsys, tmp_path):
    out, stats = tmp_path / "bunny.npy", tmp_path / "stats.json"
    code, _, err = run(capsys, "render", BUNNY, "-o", out, "--width", "80", "--height", "60", "--spp", "2",
                       "--method", "raycast", "--stats", stats, "--quiet")
    assert code == 0, err
    img = image_of(out)
    assert img.shape == (60, 80, 3)
    s = json.loads(stats.read_text())
    assert s["method"] == "raycast" and s["spp"] == 2 and s["width"] == 80
    covered = np.any(np.abs(img - from_model.BACKGROUND) > 1e-4, axis=2)
    assert 0.1 < covered.mean() < 0.7  # the bunny fills a good part of the frame, not all of it
    ys, xs = np.nonzero(covered)
    assert abs(xs.mean() / 80 - 0.5) < 0.12 and abs(ys.mean() / 60 - 0.5) < 0.12  # and is centred
    assert not covered[0].any() and not covered[-1].any() and not covered[:, 0].any()  # with a margin
    assert img[covered].mean() > 0.25  # lit: well exposed, not dim
    assert img.max() <= 1.0 + 1e-6  # and not blown out


def test_render_bunny_default_method_png(capsys, tmp_path):
    out = tmp_path / "x.png"
    code, _, err = run(capsys, "render", BUNNY, "-o", out, "--width", "40", "--height", "30", "--spp", "1",
                       "--quiet")
    assert code == 0 and out.is_file(), err


def test_info_on_a_model_file(capsys):
    code, out, _ = run(capsys, "info", BUNNY)
    assert code == 0
    assert "lights            3 (point 3)" in out and "three-point lights" in out and "method whitted" in out


def test_model_with_camera_and_lights_uses_them(fake_importer, tmp_path):
    cam = {"type": "perspective", "position": [0, 5, 0.1], "look_at": [0, 0, 0], "fov": 25}
    light = {"type": "directional", "direction": [0, -1, 0], "intensity": 2.0}
    fake_importer["m.gltf"] = lambda p: cube_model(p, cameras=[cam], lights=[light])
    scene = lumos.load_scene(touch(tmp_path, "m.gltf"))
    assert tuple(scene.camera.position) == (0, 5, 0.1) and scene.camera.fov == 25
    assert len(scene.lights) == 1 and scene.lights[0].type == "directional"
    assert set(scene.materials) == {"Metal", "Paint"}  # a model on its own keeps the file's names
    assert [o.material for o in scene.objects] == ["Metal", "Paint"]
    assert "the file's camera" in scene._included[0] and "the file's 1 light" in scene._included[0]


def test_an_emissive_model_keeps_the_made_up_lights(fake_importer, tmp_path):
    """A model with emissive parts seen from outside (the DamagedHelmet) is path-traced with the three-point
    lights on (its emission adds to them); they used to be dropped, leaving only the glowing parts."""
    fake_importer["box.obj"] = lambda p: cube_model(p, emission=True)
    scene = lumos.load_scene(touch(tmp_path, "box.obj"))
    assert scene.render.method == "path" and len(scene.lights) == 3 and scene.background == (0.05,) * 3
    scene = lumos.load_scene(touch(tmp_path, "plain.obj"))
    assert scene.render.method == "whitted" and len(scene.lights) == 3


def test_model_method_flag(fake_importer, tmp_path, capsys):
    fake_importer["box.obj"] = lambda p: cube_model(p, emission=True)
    out, stats = tmp_path / "o.npy", tmp_path / "s.json"
    code, _, err = run(capsys, "render", touch(tmp_path, "box.obj"), "-o", out, "--width", "16", "--height", "12",
                       "--method", "raycast", "--stats", stats, "--quiet")
    assert code == 0, err
    assert json.loads(stats.read_text())["method"] == "raycast"


def test_bad_model_file_one_line(capsys, tmp_path):
    bad = tmp_path / "broken.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
    code, _, err = run(capsys, "render", bad, "-o", tmp_path / "o.png")
    assert code == 2 and "broken.ply" in one_error_line(err)
    code, _, err = run(capsys, "render", tmp_path / "missing.stl", "-o", tmp_path / "o.png")
    assert code == 2 and "missing.stl: file not found" in one_error_line(err)
    assert not (tmp_path / "o.png").exists()


# ---------------------------------------------------------------------------------------------- includes


def test_include_ply_with_translate_lands_there(tmp_path):
    from lumos.compile import compile_scene

    path = write(tmp_path, f"""\
        objects:
          - {{type: model, file: {BUNNY}, transform: {{translate: [10, 0, 0]}}}}
        """)
    moved = compile_scene(lumos.load_scene(path)).bounds
    here = compile_scene(lumos.load_scene({"objects": [{"type": "mesh", "file": str(BUNNY)}]})).bounds
    assert np.allclose(moved, here + [10, 0, 0])


def test_include_composes_transforms(fake_importer, tmp_path):
    """world = include · own: the lid, moved by (0, 4, 0) in the file, then scaled by 2 and moved by x + 1."""
    from lumos.compile import compile_scene

    fake_importer["lidded.obj"] = lambda p: cube_model(p, own_translate=(0, 4, 0))
    touch(tmp_path, "lidded.obj")
    path = write(tmp_path, """\
        objects:
          - type: model
            file: lidded.obj
            transform: {translate: [1, 0, 0], scale: 2}
        """)
    scene = lumos.load_scene(path)
    assert [o.name for o in scene.objects] == ["lidded.obj/body", "lidded.obj/lid"]
    alone = [o.model_copy(update={"material": None}) for o in scene.objects]
    lid = compile_scene(lumos.load_scene({"objects": [alone[1]]})).bounds
    assert np.allclose(lid, [[1 - 0.5, 8 - 0.5, -0.5], [1 + 0.5, 8 + 0.5, 0.5]])
    body = compile_scene(lumos.load_scene({"objects": [alone[0]]})).bounds
    assert np.allclose(body, [[-1, -2, -2], [3, 2, 2]])


def test_materials_are_namespaced_and_overrides_merge(fake_importer, tmp_path):
    touch(tmp_path, "knob.obj")
    path = write(tmp_path, """\
        materials:
          floor: {kd: 0.3}
        objects:
          - {type: plane, material: floor}
          - type: model
            file: knob.obj
            materials_override:
              Metal: {kd: [1, 0, 0], kr: 0.5}
          - {type: model, file: knob.obj}
          - {type: model, file: knob.obj, name: third, material: floor}
        """)
    scene = lumos.load_scene(path)
    assert set(scene.materials) == {"floor", "knob.obj:Metal", "knob.obj:Paint", "knob.obj#2:Metal",
                                    "knob.obj#2:Paint"}
    metal = scene.materials["knob.obj:Metal"]
    assert metal.kd == (1, 0, 0) and metal.kr == (0.5, 0.5, 0.5)  # the keys given replace the file's
    assert metal.ks == (0.3, 0.3, 0.3) and metal.shininess == 20  # the others stay
    assert scene.materials["knob.obj#2:Metal"].kd == (0.5, 0.5, 0.5)  # the second copy is untouched
    assert [o.material for o in scene.objects] == [
        "floor", "knob.obj:Metal", "knob.obj:Paint", "knob.obj#2:Metal", "knob.obj#2:Paint", "floor", "floor"]
    assert [o.name for o in scene.objects[5:]] == ["third/body", "third/lid"]
    assert len(scene._included) == 3 and "Metal overridden" in scene._included[0]


def test_unknown_override_name_is_an_error_naming_the_known_ones(fake_importer, tmp_path, capsys):
    touch(tmp_path, "knob.obj")
    path = write(tmp_path, """\
        objects:
          - type: model
            file: knob.obj
            materials_override:
              Metl: {kd: 1}
        """)
    message = error_of(path)
    assert message == (f"{path}:5: objects[0].materials_override.Metl: 'knob.obj' has no material 'Metl' "
                       f"(its materials: Metal, Paint)")
    code, _, err = run(capsys, "render", path, "-o", tmp_path / "o.png")
    assert code == 2 and "has no material 'Metl'" in one_error_line(err)


def test_override_keys_are_validated_with_lines(fake_importer, tmp_path):
    touch(tmp_path, "knob.obj")
    path = write(tmp_path, """\
        objects:
          - type: model
            file: knob.obj
            materials_override:
              Metal: {kdd: 1}
        """)
    assert error_of(path).startswith(f"{path}:5: objects[0].materials_override.Metal: unknown key 'kdd'")


def test_include_paths_are_relative_to_the_scene_file(fake_importer, tmp_path, monkeypatch):
    touch(tmp_path, "models/knob.obj")
    (tmp_path / "scenes").mkdir()
    path = write(tmp_path / "scenes", "objects:\n  - {type: model, file: ../models/knob.obj}\n")
    monkeypatch.chdir(tmp_path / "models")  # not where the scene is
    scene = lumos.load_scene(path)
    assert len(scene.objects) == 2
    assert fake_importer["calls"][-1].resolve() == (tmp_path / "models" / "knob.obj").resolve()


def test_include_errors_name_the_line(fake_importer, tmp_path, capsys):
    path = write(tmp_path, """\
        objects:
          - {type: sphere}
          - type: model
            file: nope.obj
        """)
    assert error_of(path) == f"{path}:4: objects[1].file: nope.obj: file not found"
    code, _, err = run(capsys, "render", path, "-o", tmp_path / "o.png")
    assert code == 2 and f"{path}:4: objects[1].file" in one_error_line(err)
    path = write(tmp_path, "objects:\n  - {type: model, file: knob.txt}\n")
    assert "unsupported model format '.txt'" in error_of(path)
    path = write(tmp_path, "objects:\n  - {type: model}\n")
    assert error_of(path) == f"{path}:2: objects[0]: missing required key 'file'"


def test_importer_errors_keep_their_line(monkeypatch, tmp_path):
    def broken(path):
        raise LumosError(f"{path}:7: f 1 2 99: vertex 99 does not exist")

    mod = types.ModuleType("lumos.io.obj")
    mod.import_obj = broken
    monkeypatch.setitem(sys.modules, "lumos.io.obj", mod)
    touch(tmp_path, "bad.obj")
    path = write(tmp_path, "objects:\n  - type: model\n    file: bad.obj\n")
    assert error_of(path) == f"{path}:3: objects[0].file: bad.obj:7: f 1 2 99: vertex 99 does not exist"


def test_include_refuses_motion_and_both_material_keys(fake_importer, tmp_path):
    touch(tmp_path, "knob.obj")
    path = write(tmp_path, "objects:\n  - {type: model, file: knob.obj, motion: [1, 0, 0]}\n")
    assert "motion" in error_of(path)
    path = write(tmp_path, "objects:\n  - {type: model, file: knob.obj, material: {kd: 1}, "
                           "materials_override: {Metal: {kd: 1}}}\n")
    assert "not both" in error_of(path)


def test_include_lights_moved_by_the_transform(fake_importer, tmp_path):
    light = {"type": "point", "position": [0, 1, 0], "intensity": 3.0}
    fake_importer["lamp.gltf"] = lambda p: cube_model(p, lights=[light])
    touch(tmp_path, "lamp.gltf")
    path = write(tmp_path, """\
        lights: [{type: directional, direction: [0, -1, 0]}]
        objects:
          - {type: model, file: lamp.gltf, transform: {translate: [0, 0, 5], scale: 2}, lights: true}
          - {type: model, file: lamp.gltf}
        """)
    scene = lumos.load_scene(path)
    assert [light.type for light in scene.lights] == ["directional", "point"]
    assert tuple(scene.lights[1].position) == (0, 2, 5)


def test_camera_from_a_file(fake_importer, tmp_path, capsys):
    cams = [{"type": "perspective", "position": [0, 0, 9], "look_at": [0, 0, 0], "fov": 50},
            {"type": "orthographic", "position": [9, 0, 0], "look_at": [0, 0, 0], "size": 4}]
    fake_importer["shot.gltf"] = lambda p: cube_model(p, cameras=cams)
    touch(tmp_path, "shot.gltf")
    path = write(tmp_path, """\
        camera: {file: shot.gltf, fov: 30}
        objects:
          - {type: model, file: shot.gltf}
        """)
    scene = lumos.load_scene(path)
    assert tuple(scene.camera.position) == (0, 0, 9) and scene.camera.fov == 30  # a key given replaces the file's
    assert scene._included[0] == "camera: camera 0 of shot.gltf, with fov given"
    path = write(tmp_path, "camera: {file: shot.gltf, index: 1}\n")
    assert lumos.load_scene(path).camera.type == "orthographic"
    path = write(tmp_path, "camera:\n  file: shot.gltf\n  index: 2\n")
    assert error_of(path) == f"{path}:3: camera.index: 'shot.gltf' has no camera 2 (it has 2 (0 to 1))"
    path = write(tmp_path, "camera:\n  file: shot.gltf\n  index: -1\n")
    assert error_of(path).startswith(f"{path}:3: camera.index: expected a camera number >= 0")
    path = write(tmp_path, "camera:\n  file: shot.gltf\n  fov: 500\n")
    assert error_of(path).startswith(f"{path}:3: camera.fov: must be less than 180")
    code, out, _ = run(capsys, "info", write(tmp_path, "camera: {file: shot.gltf}\n"
                                                       "objects: [{type: model, file: shot.gltf}]\n"))
    assert code == 0 and "camera 0 of shot.gltf" in out and "objects[0]: shot.gltf: 2 objects" in out


def test_camera_file_without_cameras(fake_importer, tmp_path):
    touch(tmp_path, "plain.obj")
    path = write(tmp_path, "camera:\n  file: plain.obj\n")
    assert error_of(path) == f"{path}:2: camera.file: 'plain.obj' has no camera 0 (it has none)"


def test_dict_scene_includes_relative_to_cwd(monkeypatch):
    monkeypatch.chdir(DATA)
    scene = lumos.load_scene({"objects": [{"type": "model", "file": "bunny_res4.ply", "material": {"kd": 0.5}}]})
    assert scene.objects[0].type == "mesh" and scene.objects[0].material.kd == (0.5, 0.5, 0.5)
    assert scene.objects[0].name == "bunny_res4.ply/bunny_res4"


# --------------------------------------------------------------- real files (once the importers are on main)


def test_examples_load():
    scene = lumos.load_scene(EXAMPLES / "models/bunny_and_shapes.yaml")
    assert [o.type for o in scene.objects] == ["rect", "mesh", "sphere", "sphere", "box"]
    assert scene.objects[1].material == "clay"


def test_teapot_example_overrides_the_mtl_material():
    pytest.importorskip("lumos.io.obj")
    scene = lumos.load_scene(EXAMPLES / "models/teapot.yaml")
    glaze = scene.materials["teapot.obj:default"]
    assert glaze.kd == (0.6, 0.1, 0.08) and glaze.texture is None  # given
    # kept from the MTL file's Ks 0.2, which shares kd + ks <= 1 with its Kd 1 (docs/formats.md, "Energy")
    assert glaze.ks == pytest.approx((0.2 / 1.2,) * 3)


def test_mcguire_cornell_box_is_lit_by_its_ke_light(capsys, tmp_path):
    pytest.importorskip("lumos.io.obj")
    box = DATA / "models/CornellBox-Original.obj"
    scene = lumos.load_scene(box)
    # seen from inside, straight through its open side, and lit by its own lamp only
    assert scene.render.method == "path" and scene.lights == []
    assert any(max(m.emission) > 0 for m in scene.materials.values())
    d = np.subtract(scene.camera.position, scene.camera.look_at)
    np.testing.assert_allclose(d / np.linalg.norm(d), [0, 0, 1], atol=1e-9)
    out = tmp_path / "box.npy"
    code, _, err = run(capsys, "render", box, "-o", out, "--width", "32", "--height", "24", "--spp", "4", "--quiet")
    assert code == 0, err
    img = np.load(out)
    # the walls are lit, not just the light: with the real importer the mean is 0.039 at 64 spp (two thirds of
    # the frame are the black around the box)
    assert np.isfinite(img).all() and img.mean() > 0.02


def test_gltf_with_its_own_camera():
    pytest.importorskip("lumos.io.gltf")
    path = DATA / "models/Cameras.gltf"
    scene = lumos.load_scene(path)
    assert np.allclose(scene.camera.position, (0.5, 0.5, 3.0))
    assert scene.camera.type == "perspective" and scene.camera.fov == pytest.approx(math.degrees(0.7))
    scene = lumos.load_scene({"camera": {"file": str(path), "index": 1}, "objects": [
        {"type": "model", "file": str(path)}]})
    assert scene.camera.type == "orthographic"


def test_override_can_drop_a_file_texture(fake_importer, tmp_path):
    from PIL import Image as PILImage

    PILImage.new("RGB", (2, 2), (200, 10, 10)).save(tmp_path / "wood.png")

    def textured(p):
        m = cube_model(p)
        m.materials["Metal"]["texture"] = {"type": "image", "file": str((tmp_path / "wood.png").resolve())}
        return m

    fake_importer["wood.obj"] = textured
    touch(tmp_path, "wood.obj")
    path = write(tmp_path, "objects:\n  - {type: model, file: wood.obj}\n"
                           "  - {type: model, file: wood.obj, materials_override: {Metal: {texture: null}}}\n")
    scene = lumos.load_scene(path)
    kept, dropped = scene.materials["wood.obj:Metal"], scene.materials["wood.obj#2:Metal"]
    assert kept.texture is not None and kept.texture._path == (tmp_path / "wood.png").resolve()
    assert dropped.texture is None and dropped.kd == kept.kd


def test_importer_warnings_are_lumos_warnings(fake_importer, tmp_path, capsys):
    def sloppy(p):
        m = cube_model(p)
        m.warnings.append(f"{p}:3: mtllib missing.mtl: no such file; default materials used")
        return m

    fake_importer["sloppy.obj"] = sloppy
    touch(tmp_path, "sloppy.obj")
    with pytest.warns(lumos.LumosWarning, match="missing.mtl: no such file"):
        lumos.load_scene(write(tmp_path, "objects: [{type: model, file: sloppy.obj}]\n"))
    code, out, err = run(capsys, "info", tmp_path / "sloppy.obj")
    assert code == 0 and "lumos: warning: " in err and "missing.mtl" in err


def test_each_distinct_importer_warning_once_with_a_count(fake_importer, tmp_path, capsys):
    """26 map statements naming one missing texture are one warning with a count (Sibenik's MTL said it 26 times)."""
    def sloppy(p):
        m = cube_model(p)
        m.warnings += [f"{p.name}.mtl:{n}: texture 'stone.png' not found; map_Kd ignored" for n in (4, 9, 17)]
        m.warnings.append(f"{p.name}.mtl:20: texture 'wood.png' not found; map_Kd ignored")
        return m

    fake_importer["sloppy.obj"] = sloppy
    code, _, err = run(capsys, "info", touch(tmp_path, "sloppy.obj"))
    warned = [line for line in err.splitlines() if line.startswith("lumos: warning")]
    assert code == 0 and len(warned) == 2, err
    assert "stone.png' not found; map_Kd ignored (3 times; also lines 9, 17)" in warned[0]
    assert "wood.png" in warned[1] and "times" not in warned[1]


def test_a_scene_built_in_python_is_completed_like_a_loaded_one(tmp_path):
    """`Scene.model_validate` does not read files; `lumos.render` and `RayCaster` complete such a scene as
    `load_scene` would: its includes are expanded and its mesh files read (here the same bunny both ways)."""
    from lumos.scene.model import Scene

    built = Scene.model_validate({"objects": [{"type": "model", "file": str(BUNNY)},
                                              {"type": "mesh", "file": str(BUNNY),
                                               "transform": {"translate": [0.3, 0, 0]}}]})
    image = lumos.render(built, method="raycast", width=32, height=24)
    assert np.isfinite(image.array).all()
    assert [o.type for o in built.objects] == ["mesh", "mesh"]
    assert len(built.objects[0].faces) == len(built.objects[1].faces) > 900
    hits = lumos.RayCaster(built).closest([[0.3 - 0.02, 0.1, 1.0]], [[0, 0, -1]])
    assert hits.t[0] < np.inf
