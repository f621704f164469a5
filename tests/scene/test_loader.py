"""Scene loading: valid files and dicts, and one clear line (file, line, key path, gist) for every bad input."""

import importlib.util
import json
import textwrap

import pytest
from pydantic import ValidationError

from lumos.errors import LumosError, SceneError
from lumos.scene import Mesh, RenderSettings, Scene, Sphere, load_scene
from lumos.scene.loader import format_path, format_validation_error

needs_meshes = pytest.mark.skipif(
    importlib.util.find_spec("lumos.io.meshes") is None, reason="lumos.io.meshes has not landed yet"
)

TRIANGLE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"

VALID = """\
camera:
  position: [0, 1, 5]
  look_at: [0, 0, 0]
  fov: 40
render: {method: raycast, width: 32, height: 24}
ambient: 0.1
materials:
  base: &base {kd: 0.5, ks: 1e-3, shininess: 20}
  red:
    <<: *base
    kd: [0.8, 0.1, 0.1]
lights:
  - {type: point, position: [2, 4, 3], intensity: 1}
  - {type: area, shape: rect, corner: [0, 3, 0], edge_u: [1, 0, 0], edge_v: [0, 0, 1]}
objects:
  - {type: sphere, center: [0, 0, 0], radius: 1, material: red}
  - type: plane
    material: {kd: 0.7}
    transform: {translate: [0, -1, 0]}
"""


def write(tmp_path, text, name="scene.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def error_of(source) -> str:
    """The SceneError message for `source`; checks it is one line and printed (`pytest -s` shows them)."""
    with pytest.raises(SceneError) as info:
        load_scene(source)
    message = str(info.value)
    assert "\n" not in message and "Traceback" not in message
    print(message)
    return message


# ------------------------------------------------------------------------------------------- valid scenes


def test_valid_yaml_loads(tmp_path):
    path = write(tmp_path, VALID)
    scene = load_scene(path)
    assert isinstance(scene, Scene) and scene.source == path
    assert isinstance(scene.objects[0], Sphere) and scene.objects[0].radius == 1.0
    red = scene.materials["red"]
    assert red.kd == (0.8, 0.1, 0.1)  # explicit key beats the merged one
    assert red.ks == (0.001,) * 3 and red.shininess == 20  # merged from *base; 1e-3 is a float
    assert scene.render.width == 32 and scene.ambient == (0.1, 0.1, 0.1)
    assert load_scene(str(path)).source == path


def test_valid_json_loads(tmp_path):
    data = {"camera": {"fov": 1e1}, "objects": [{"type": "sphere", "radius": 2}]}
    path = write(tmp_path, json.dumps(data, indent="\t"), "scene.json")  # tabs are fine in JSON
    scene = load_scene(path)
    assert scene.camera.fov == 10.0 and scene.objects[0].radius == 2.0


def test_valid_dict_loads():
    scene = load_scene({"objects": [{"type": "sphere"}], "lights": [{"type": "point", "position": [0, 1, 0]}]})
    assert scene.source is None and len(scene.objects) == 1


def test_dates_and_yes_stay_plain_data(tmp_path):
    path = write(tmp_path, "objects:\n  - {type: sphere, name: 2024-01-01}\n")
    assert load_scene(path).objects[0].name == "2024-01-01"


def test_inline_mesh_needs_no_file():
    scene = load_scene({"objects": [{"type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                                     "faces": [[0, 1, 2]]}]})
    assert scene.objects[0].faces.shape == (1, 3)


@needs_meshes
def test_mesh_file_relative_to_scene_folder(tmp_path, monkeypatch):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "tri.obj").write_text(TRIANGLE_OBJ)
    path = write(tmp_path, "objects:\n  - {type: mesh, file: meshes/tri.obj}\n")
    monkeypatch.chdir("/")
    mesh = load_scene(path).objects[0]
    assert isinstance(mesh, Mesh)
    assert mesh.vertices.shape == (3, 3) and mesh.faces.tolist() == [[0, 1, 2]]


@needs_meshes
def test_mesh_file_relative_to_cwd_for_dicts(tmp_path, monkeypatch):
    (tmp_path / "tri.obj").write_text(TRIANGLE_OBJ)
    monkeypatch.chdir(tmp_path)
    assert load_scene({"objects": [{"type": "mesh", "file": "tri.obj"}]}).objects[0].triangle_count == 1


# ------------------------------------------------------------------------------- bad input: one line each

# (id, scene text, line of the error, fragments the message must contain)
BAD_SCENES = [
    ("unknown_key", "objects:\n  - type: sphere\n    radus: 1\n", 3,
     ["objects[0]: unknown key 'radus' (did you mean 'radius'?)"]),
    ("unknown_top_key", "objets: []\n", 1, ["unknown key 'objets' (did you mean 'objects'?)"]),
    ("wrong_type", "objects:\n  - type: sphere\n    radius: abc\n", 3,
     ["objects[0].radius: expected a number, got 'abc' (str)"]),
    ("wrong_type_int", "render:\n  width: 1.5\n", 2, ["render.width: expected an integer, got 1.5 (float)"]),
    ("wrong_vector_length", "objects:\n  - type: sphere\n    center: [1, 2]\n", 3,
     ["objects[0].center: must have 3 components, got 2"]),
    ("vector_too_long", "camera:\n  position: [1, 2, 3, 4]\n", 2,
     ["camera.position: must have 3 components, got 4"]),
    ("negative_radius", "objects:\n  - type: sphere\n    radius: -1\n", 3,
     ["objects[0].radius: must be greater than 0, got -1"]),
    ("zero_radius", "objects:\n- {type: sphere, radius: 0}\n- {type: disk, radius: 0}\n", 2,
     ["objects[0].radius: must be greater than 0, got 0"]),
    ("nan", "objects:\n  - type: sphere\n    radius: .nan\n", 3, ["objects[0].radius: is NaN or infinite"]),
    ("inf_in_vector", "lights:\n  - type: point\n    position: [0, 0, .inf]\n", 3,
     ["lights[0].position[2]: is NaN or infinite"]),
    ("negative_colour", "materials:\n  m:\n    kd: [0.5, -1, 0]\n", 3,
     ["materials.m.kd[1]: must be at least 0, got -1"]),
    ("unknown_material", "materials:\n  red: {kd: 1}\nobjects:\n  - type: sphere\n  - type: sphere\n"
     "    material: gold\n", 6, ["objects[1].material: unknown material 'gold' (defined: red)"]),
    ("light_unknown_material", "materials:\n  red: {kd: 1}\nlights:\n  - {type: point, position: [0, 1, 0]}\n"
     "  - type: area\n    shape: disk\n    center: [0, 1, 0]\n    normal: [0, -1, 0]\n    radius: 1\n"
     "    material: gold\n", 10, ["lights[1].material: unknown material 'gold' (defined: red)"]),
    ("light_material_emits", "materials:\n  glow: {emission: 2}\nlights:\n  - type: area\n    shape: disk\n"
     "    center: [0, 1, 0]\n    normal: [0, -1, 0]\n    radius: 1\n    material: glow\n", 9,
     ["lights[0].material: an area light's material must not emit (the light's emission is its radiance)"]),
    ("two_sided_sphere_light", "lights:\n  - {type: area, shape: sphere, center: [0, 1, 0], radius: 1, "
     "two_sided: true}\n", 2, ["lights[0]", "two_sided is for rect and disk lights"]),
    ("metal_unknown", "objects:\n  - type: sphere\n    material:\n      conductor: {metal: Gold}\n", 4,
     ["objects[0].material.conductor.metal: unknown value 'Gold' (choose from Au, Ag, Cu"]),
    ("metal_and_eta", "objects:\n  - type: sphere\n    material:\n      conductor: {metal: Au, eta: 1, k: 2}\n",
     4, ["objects[0].material.conductor: give metal or eta and k, not both"]),
    ("eta_without_k", "objects:\n  - type: sphere\n    material:\n      conductor: {eta: 1}\n", 4,
     ["objects[0].material.conductor: eta and k go together"]),
    ("alpha_over_one", "objects:\n  - type: sphere\n    material:\n      conductor: {alpha: [0.2, 1.5]}\n", 4,
     ["objects[0].material.conductor: alpha must be at most 1"]),
    ("environment_and_background", "background: [0, 0, 1]\nenvironment: {color: 1}\n", 1,
     ["give background (one colour) or environment, not both"]),
    ("environment_neither", "environment: {scale: 2}\n", 1,
     ["environment: give the environment one of a file (a lat-long image), a color or a sky"]),
    ("environment_missing_file", "environment:\n  file: nowhere.exr\n", 2,
     ["environment.file: no such image file 'nowhere.exr'"]),
    ("two_sided_not_bool", "objects:\n  - type: sphere\n    two_sided: maybe\n", 3,
     ["objects[0].two_sided:"]),
    ("inline_material_key", "objects:\n  - type: sphere\n    material:\n      kdd: 1\n", 4,
     ["objects[0].material: unknown key 'kdd' (did you mean 'kd'?)"]),
    ("unknown_object_type", "objects:\n  - type: sphre\n", 2,
     ["objects[0]: unknown object type 'sphre' (did you mean 'sphere'? types: sphere, plane"]),
    ("object_without_type", "objects:\n  - radius: 1\n", 2, ["objects[0]: missing required key 'type'"]),
    ("unknown_light_type", "lights:\n  - type: torch\n", 2,
     ["lights[0]: unknown light type 'torch'", "types: point, spot, directional, area"]),
    ("spot_light_without_direction", "lights:\n  - type: spot\n    position: [0, 1, 0]\n", 2,
     ["lights[0]: missing required key 'direction'"]),
    ("area_light_without_shape", "lights:\n  - type: area\n    radiance: 1\n", 2,
     ["lights[0]: missing required key 'shape' (area light shapes: rect, disk, sphere)"]),
    ("point_light_without_position", "lights:\n  - type: point\n", 2,
     ["lights[0]: missing required key 'position'"]),
    ("up_parallel_to_view", "camera:\n  position: [0, 5, 0]\n  up: [0, 1, 0]\n", 1,
     ["camera: up is parallel to the view direction"]),
    ("fov_0", "camera:\n  fov: 0\n", 2, ["camera.fov: must be greater than 0, got 0"]),
    ("fov_180", "camera:\n  fov: 180\n", 2, ["camera.fov: must be less than 180, got 180"]),
    ("absurd_resolution", "render:\n  width: 100000000\n", 2,
     ["render.width: must be at most 65536, got 100000000"]),
    ("too_many_pixels", "render:\n  width: 60000\n  height: 60000\n", 1, ["render: 60000x60000 is too large"]),
    ("unknown_aov", "render:\n  aov: [dept]\n", 2,
     ["render.aov[0]: unknown value 'dept' (did you mean 'depth'?"]),
    ("duplicate_key", "objects:\n  - type: sphere\n    radius: 1\n    radius: 2\n", 4,
     ["objects[0].radius: duplicate key 'radius' (first given on line 3)"]),
    ("yaml_syntax_error", "camera:\n  fov: 30\n   bad: [\n", 3, ["invalid YAML: mapping values are not allowed"]),
    ("top_level_list", "- type: sphere\n", 1, ["the top level must be a mapping", "got a list"]),
    ("top_level_scalar", "hello\n", 1, ["the top level must be a mapping", "got 'hello' (str)"]),
    ("many_errors", "objects:\n  - {type: sphere, radius: -1}\n  - {type: sphere, radius: -2}\n"
     "  - {type: sphere, center: [1, 2]}\n", 2, ["objects[0].radius: must be greater than 0", "(and 2 more errors)"]),
]


@pytest.mark.parametrize("text, line, fragments", [case[1:] for case in BAD_SCENES], ids=[c[0] for c in BAD_SCENES])
def test_bad_scene_is_one_clear_line(tmp_path, text, line, fragments):
    path = write(tmp_path, text)
    message = error_of(path)
    assert message.startswith(f"{path}:{line}:"), message
    for fragment in fragments:
        assert fragment in message


def test_python_tag_is_refused_and_not_run(tmp_path):
    marker = tmp_path / "pwned"
    path = write(tmp_path, f"objects: !!python/object/apply:os.system ['touch {marker}']\n")
    message = error_of(path)
    assert message.startswith(f"{path}:1: objects: YAML tag '!!python/object/apply:os.system' is not allowed")
    assert not marker.exists()


def test_empty_file(tmp_path):
    path = write(tmp_path, "")
    assert error_of(path) .startswith(f"{path}: the file is empty")
    assert "empty" in error_of(write(tmp_path, "# only a comment\n"))


def test_missing_file(tmp_path):
    assert error_of(tmp_path / "nope.yaml") == f"{tmp_path / 'nope.yaml'}: no such file"


def test_directory(tmp_path):
    assert "is a folder" in error_of(tmp_path)


def test_not_utf8(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_bytes(b"camera:\n  fov: \xff\xfe\n")
    assert error_of(path).startswith(f"{path}: not a UTF-8 text file (byte 0xff")


def test_wrong_extension(tmp_path):  # (model files, .obj and the rest, load as a scene: scene/test_from_model.py)
    path = write(tmp_path, TRIANGLE_OBJ, "bunny.txt")
    assert error_of(path).startswith(f"{path}: scene files must end in .yaml, .yml or .json")


def test_json_errors_have_lines(tmp_path):
    text = '{\n  "objects": [\n    {"type": "sphere",\n     "radius": "big"}\n  ]\n}\n'
    path = write(tmp_path, text, "scene.json")
    assert error_of(path) == f"{path}:4: objects[0].radius: expected a number, got 'big' (str)"


def test_dict_errors_name_the_key_path():
    message = error_of({"objects": [{"type": "sphere", "radius": -1}]})
    assert message == "scene: objects[0].radius: must be greater than 0, got -1"


def test_control_character(tmp_path):
    path = write(tmp_path, "camera: {}\nobjects: \x00\n")
    assert error_of(path).startswith(f"{path}:2: invalid YAML: special characters are not allowed")


def test_several_documents(tmp_path):
    path = write(tmp_path, "---\ncamera: {}\n---\nobjects: []\n")
    expected = "invalid YAML: expected a single document in the stream, but found another document"
    assert error_of(path) == f"{path}:3:1: {expected}"


def test_recursive_alias_is_an_error(tmp_path):
    path = write(tmp_path, "objects: &a\n  - *a\n")
    assert "objects" in error_of(path)


@needs_meshes
def test_missing_mesh_file(tmp_path):
    path = write(tmp_path, "objects:\n  - type: sphere\n  - type: mesh\n    file: nope.obj\n")
    message = error_of(path)
    assert message.startswith(f"{path}:4: objects[1].file: cannot read 'nope.obj': ")
    assert "not found" in message


@needs_meshes
def test_corrupt_mesh_file(tmp_path):
    (tmp_path / "bad.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n\x00\x01garbage")
    path = write(tmp_path, "objects:\n  - {type: mesh, file: bad.ply}\n")
    assert error_of(path).startswith(f"{path}:2: objects[0].file: cannot read 'bad.ply': ")


@needs_meshes
def test_mesh_arrays_checked_after_loading(tmp_path, monkeypatch):
    import numpy as np

    from lumos.io import meshes

    bad = meshes.MeshData(np.zeros((3, 3)), np.array([[0, 1, 7]]), None, None)
    monkeypatch.setattr(meshes, "load_mesh", lambda path: bad)
    path = write(tmp_path, "objects:\n  - {type: mesh, file: m.obj}\n")
    assert error_of(path) == (f"{path}:2: objects[0].file: bad mesh in 'm.obj': "
                              "faces[0] refers to a vertex that does not exist (there are 3)")


@needs_meshes
def test_mesh_parser_crash_is_still_bad_input(tmp_path, monkeypatch):
    from lumos.io import meshes

    def crash(path):
        raise IndexError("list index out of range")

    monkeypatch.setattr(meshes, "load_mesh", crash)
    path = write(tmp_path, "objects:\n  - {type: mesh, file: m.obj}\n")
    assert error_of(path).endswith("objects[0].file: cannot read 'm.obj': IndexError: list index out of range")


# --------------------------------------------------------------------------------- format_validation_error


def test_format_without_data_or_lines_strips_union_tags():
    bad = {"objects": [{"type": "sphere", "material": {"kdd": 1}}], "lights": [{"type": "area", "shape": "rect",
                                                                                 "corner": [0, 0]}]}
    with pytest.raises(ValidationError) as info:
        Scene.model_validate(bad)
    # lights come first; the other errors: edge_u and edge_v missing, the inline material's unknown key
    assert format_validation_error(info.value, source="x") == (
        "x: lights[0].corner: must have 3 components, got 2 (and 3 more errors)")
    with pytest.raises(ValidationError) as info:
        Scene.model_validate({"objects": bad["objects"]})
    assert format_validation_error(info.value, "x") == "x: objects[0].material: unknown key 'kdd' (did you mean 'kd'?)"


def test_settings_errors_get_the_prefix():
    with pytest.raises(ValidationError) as info:
        RenderSettings.model_validate({"width": 0, "method": "raycast"})
    message = format_validation_error(info.value, source="settings", prefix=("render",))
    assert message == "settings: render.width: must be at least 1, got 0"


def test_scene_error_is_a_lumos_error():
    assert issubclass(SceneError, LumosError)


def test_format_path():
    assert format_path(("objects", 2, "radius")) == "objects[2].radius"
    assert format_path(("lights", 0, "corner", 2)) == "lights[0].corner[2]"
    assert format_path(("materials", "my red", "kd")) == "materials['my red'].kd"
