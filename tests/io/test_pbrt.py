"""pbrt-v4 scene files (`lumos.io.pbrt` and its pbrt_* modules): the tokenizer and parser, the graphics state
(transforms, attributes, instances, includes), the conventions (pbrt's left-handed camera, fov on the shorter
axis, light units, area-light sides), materials and textures, errors and warnings, and renders: a killeroo-like
scene, and a scene rendered by Mitsuba 3 from the same description (z-test per 8×8 block)."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import lumos
from lumos import cli
from lumos.errors import LumosError, LumosWarning
from lumos.io import pbrt_spectra
from lumos.io.pbrt import look_at, read_pbrt, rotation
from lumos.io.pbrt_tokens import Statements, tokenize
from helpers import DATA

PBRT = DATA / "pbrt"
#: pbrt's LookAt keeps handedness, so lumos reads the world mirrored in x (see pbrt_options)
MIRROR = np.diag([-1.0, 1.0, 1.0, 1.0])
HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 24 ]
WorldBegin
"""


def write(folder: Path, body: str, name: str = "scene.pbrt", header: str = HEADER) -> Path:
    path = folder / name
    path.write_text(header + body)
    return path


def read(folder: Path, body: str, header: str = HEADER):
    """(data, lines, warning messages) of a scene made of `header` + `body`."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        data, lines = read_pbrt(write(folder, body, header=header))
    return data, lines, [str(w.message) for w in caught if issubclass(w.category, LumosWarning)]


def error_of(folder: Path, text: str, name: str = "scene.pbrt") -> str:
    path = folder / name
    path.write_text(text)
    with pytest.raises(LumosError) as info:
        read_pbrt(path)
    return str(info.value)


# ------------------------------------------------------------------------------------- tokens and statements


def test_tokens_keep_strings_with_spaces_drop_comments_and_count_lines():
    text = 'Shape "sphere" # a comment "not a string"\n  "string name" [ "a b\\"c" ]\n\n"float r"[1.5e-1]#x\n'
    tokens = tokenize(text, "t.pbrt")
    assert tokens == [("word", "Shape", 1), ("string", "sphere", 1), ("string", "string name", 2), ("[", "[", 2),
                      ("string", 'a b"c', 2), ("]", "]", 2), ("string", "float r", 4), ("[", "[", 4),
                      ("words", "1.5e-1", 4), ("]", "]", 4)]  # a list without strings: converted at once


def test_statements_read_every_parameter_type(tmp_path):
    path = write(tmp_path, 'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" 0\n'
                 '  "bool flag" true "string filename" "my file.ply" "rgb c" [.1 .2 .3] "spectrum s" "metal-Au-eta"\n'
                 '  "blackbody b" 3000 "texture t" "checks" "normal N" [0 0 1 0 0 1 0 0 1]\n', header="")
    st = next(iter(Statements(path)))
    assert (st.directive, st.args, st.where.line) == ("Shape", ["trianglemesh"], 1)
    p = st.params
    assert p["P"].values == [0, 0, 0, 1, 0, 0, 0, 1, 0] and p["indices"].values == [0]
    assert p["flag"].values == [True] and p["filename"].values == ["my file.ply"] and p["filename"].type == "string"
    assert p["c"].type == "rgb" and p["s"].values == ["metal-Au-eta"] and p["b"].values == [3000]
    assert p["t"].type == "texture" and p["N"].where.line == 3


def test_nested_attributes_restore_material_transform_and_orientation(tmp_path):
    data, _, _ = read(tmp_path, """
Material "diffuse" "rgb reflectance" [0.1 0.1 0.1]
AttributeBegin
  Translate 1 0 0
  Material "diffuse" "rgb reflectance" [0.2 0.2 0.2]
  AttributeBegin
    Translate 0 2 0
    Material "diffuse" "rgb reflectance" [0.3 0.3 0.3]
    Shape "sphere"
  AttributeEnd
  Shape "sphere"
AttributeEnd
Shape "sphere"
""")
    centres = [o["center"] for o in data["objects"]]
    kd = [data["materials"][o["material"]]["kd"][0] for o in data["objects"]]
    assert centres == [[-1.0, 2.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]  # x mirrored (MIRROR)
    assert kd == [0.3, 0.2, 0.1]


def test_transforms_compose_as_in_pbrt(tmp_path):
    """Each directive multiplies the CTM on the right; Transform replaces it; matrices are column-major."""
    concat = np.array([[1, 0, 0, 0.5], [0, 2, 0, 0], [0, 0, 1, -1], [0, 0, 0, 1.0]])
    data, _, _ = read(tmp_path, f"""
Translate 1 2 3
Rotate 30 0 0 1
Scale 2 1 0.5
ConcatTransform [ {' '.join(str(v) for v in concat.T.ravel())} ]
Shape "trianglemesh" "point3 P" [1 0 0  0 1 0  0 0 1] "integer indices" [0 1 2]
Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  7 8 9 1 ]
Translate 0 1 0
Shape "sphere" "float radius" 2
""")
    t = np.eye(4)
    t[:3, 3] = (1, 2, 3)
    expected = MIRROR @ t @ rotation(30, np.array([0, 0, 1.0])) @ np.diag([2, 1, 0.5, 1]) @ concat
    points = np.c_[np.eye(3), np.ones(3)] @ expected.T
    mesh, sphere = data["objects"]
    assert np.allclose(mesh["vertices"], points[:, :3])
    assert np.allclose(sphere["center"], [-7, 9, 9]) and sphere["radius"] == 2


def test_rotate_and_look_at_follow_pbrts_formulas():
    r = rotation(90, np.array([0, 0, 2.0]))
    assert np.allclose(r[:3, :3] @ [1, 0, 0], [0, 1, 0])  # counter-clockwise about +z
    cam = look_at(np.array([0, 0, 5.0]), np.zeros(3), np.array([0, 1.0, 0]))
    world_from_camera = np.linalg.inv(cam)
    assert np.allclose(world_from_camera[:3, 2], [0, 0, -1])  # camera +z looks at the target
    assert np.allclose(world_from_camera[:3, 0], [-1, 0, 0])  # camera +x = cross(up, view): pbrt is left-handed


@pytest.mark.parametrize("width, height, fov", [(64, 32, 40.0), (32, 64, 2 * math.degrees(math.atan(2 * math.tan(
    math.radians(20)))))])
def test_fov_spans_the_shorter_axis(tmp_path, width, height, fov):
    header = HEADER.replace("32 ] \"integer yresolution\" [ 24", f"{width} ] \"integer yresolution\" [ {height}")
    data, _, _ = read(tmp_path, 'Shape "sphere"', header=header)
    assert data["camera"]["fov"] == pytest.approx(fov)
    assert (data["render"]["width"], data["render"]["height"]) == (width, height)


def test_the_image_is_pbrts_not_its_mirror(tmp_path):
    """pbrt's LookAt 0 0 5 → origin shows world +x on the image's LEFT; a camera transform that mirrors (the
    `Scale -1 1 1` exporters write) shows it on the right, and lumos then reads the world as it is."""
    body = 'Material "diffuse" "rgb reflectance" [0.8 0.8 0.8]\nTranslate 1.2 0 0\nShape "sphere" "float radius" 0.6\n'
    light = 'LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0] "rgb L" [3 3 3]\n'
    for header, side in ((HEADER, "left"), ("Scale -1 1 1\n" + HEADER, "right")):
        path = write(tmp_path, light + body, header=header)
        img = lumos.render(lumos.load_scene(path), method="raycast", filter="box", spp=1).array.mean(axis=2)
        left, right = img[:, :16].sum(), img[:, 16:].sum()
        assert (left > 5 * right) if side == "left" else (right > 5 * left), (side, left, right)
    data, _, _ = read(tmp_path, body, header="Scale -1 1 1\n" + HEADER)
    assert data["objects"][0]["center"] == [1.2, 0.0, 0.0]


def test_camera_lens_and_defaults(tmp_path):
    data, _, _ = read(tmp_path, 'Shape "sphere"', header='LookAt 0 0 5 0 0 0 0 1 0\nCamera "perspective" '
                      '"float lensradius" 0.1 "float focaldistance" 4\nWorldBegin\n')
    cam, render = data["camera"], data["render"]
    assert cam["aperture"] == 0.1 and cam["focus_distance"] == 4 and cam["fov"] == 90
    assert (render["width"], render["height"], render["spp"], render["max_depth"]) == (1280, 720, 16, 4)
    assert render["method"] == "path" and render["filter"] == "gaussian"  # pbrt's default filter


@pytest.mark.parametrize("maxdepth, lumos_depth", [(5, 4), (1, 0), (2, 1), (-1, -1)])
def test_maxdepth_counts_scattering_events(tmp_path, maxdepth, lumos_depth):
    header = f'Integrator "path" "integer maxdepth" {maxdepth}\nSampler "independent" "integer pixelsamples" 7\n'
    data, _, _ = read(tmp_path, 'Shape "sphere"', header=header + HEADER)
    assert data["render"]["max_depth"] == lumos_depth
    assert data["render"]["spp"] == 7


# ------------------------------------------------------------------------------------- instances and files


def test_instances_are_copies_with_composed_transforms(tmp_path):
    data, _, _ = read(tmp_path, """
ObjectInstance "pair"
ObjectBegin "pair"
  Translate 1 0 0
  Shape "sphere" "float radius" 0.5
  Shape "disk" "float radius" 0.25
ObjectEnd
Translate 0 3 0
Scale 2 2 2
ObjectInstance "pair"
""")
    spheres = [o for o in data["objects"] if o["type"] == "sphere"]
    assert [s["center"] for s in spheres] == [[-1.0, 0.0, 0.0], [-2.0, 3.0, 0.0]]
    assert [s["radius"] for s in spheres] == [0.5, 1.0]
    assert len([o for o in data["objects"] if o["type"] == "disk"]) == 2


def test_include_and_import(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "material.pbrt").write_text('Material "diffuse" "rgb reflectance" [0.25 0.25 0.25]\n'
                                                      'Include "sphere.pbrt"\n')  # beside itself
    (tmp_path / "parts" / "sphere.pbrt").write_text('Shape "sphere" "float radius" 0.5\n')
    (tmp_path / "moved.pbrt").write_text('Translate 5 0 0\nMaterial "diffuse"\nShape "sphere"\n')
    data, lines, _ = read(tmp_path, 'Include "parts/material.pbrt"\nImport "moved.pbrt"\nShape "sphere"\n')
    first, imported, after = data["objects"]
    assert data["materials"][first["material"]]["kd"] == [0.25] * 3
    assert imported["center"] == [-5.0, 0.0, 0.0] and after["center"] == [0.0, 0.0, 0.0]
    assert data["materials"][after["material"]]["kd"] == [0.25] * 3  # Import's material does not leak either
    assert lines[("objects", 0)] == 5 and lines[("objects", 2)] == 7  # included: the Include's line


def test_named_materials_may_be_used_before_they_are_defined(tmp_path):
    data, _, _ = read(tmp_path, """
NamedMaterial "red"
Shape "sphere"
MakeNamedMaterial "red" "string type" "diffuse" "rgb reflectance" [0.8 0.1 0.1]
MakeNamedMaterial "glass" "string type" "dielectric" "spectrum eta" "glass-BK7"
MakeNamedMaterial "half" "string type" "mix" "string materials" ["red" "glass"] "float amount" 0.25
NamedMaterial "half"
Shape "sphere"
""")
    assert data["objects"][0]["material"] == "red" and data["materials"]["red"]["kd"] == [0.8, 0.1, 0.1]
    assert data["materials"]["glass"] == {"dielectric": {"ior": 1.5185, "alpha": 0.0}}
    half = data["materials"]["half"]
    assert half["kd"] == pytest.approx([0.6, 0.075, 0.075]) and half["kt"] == pytest.approx([0.25] * 3)
    assert half["ior"] == 1.5185


def test_rough_dielectric_is_lumos_dielectric(tmp_path):
    """pbrt's dielectric with roughness is lumos's rough `dielectric`: α = √r (r itself with remaproughness
    false), uroughness/vroughness as [αu, αv]; below α 10⁻³ smooth, as pbrt's EffectivelySmooth; η 1 a
    pass-through."""
    data, _, _ = read(tmp_path, """
MakeNamedMaterial "a" "string type" "dielectric" "float eta" 1.33 "float roughness" 0.04
MakeNamedMaterial "b" "string type" "dielectric" "float uroughness" 0.01 "float vroughness" 0.25
MakeNamedMaterial "c" "string type" "dielectric" "float roughness" 0.3 "bool remaproughness" false
MakeNamedMaterial "d" "string type" "dielectric" "float roughness" 1e-7
MakeNamedMaterial "e" "string type" "dielectric" "float eta" 1
Shape "sphere"
""")
    m = data["materials"]
    assert m["a"] == {"dielectric": {"ior": 1.33, "alpha": pytest.approx(0.2)}}
    assert m["b"]["dielectric"]["alpha"] == pytest.approx([0.1, 0.5])
    assert m["c"]["dielectric"]["alpha"] == pytest.approx(0.3)
    assert m["d"]["dielectric"]["alpha"] == 0.0
    assert m["e"] == {"kt": 1.0, "ior": 1.0}


# ------------------------------------------------------------------------------------------- lights


def test_area_lights_are_one_sided_unless_twosided_and_reverse_orientation_flips_them(tmp_path):
    quad = 'Shape "trianglemesh" "point3 P" [-1 0 -1  1 0 -1  1 0 1  -1 0 1] "integer indices" [0 1 2 0 2 3]\n'
    data, _, _ = read(tmp_path, f"""
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [2 2 2]
  {quad}
  ReverseOrientation
  {quad}
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "blackbody L" 6500 "bool twosided" true "float scale" 3
  {quad}
AttributeEnd
""")
    down, up, both = data["lights"]
    normal = [np.cross(light["edge_u"], light["edge_v"]) for light in (down, up)]
    assert normal[0][1] < 0 < normal[1][1]  # counter-clockwise seen from below: pbrt's front faces -y
    assert down["two_sided"] is False and both["two_sided"] is True and down["radiance"] == [2, 2, 2]
    assert pbrt_spectra.luminance(both["radiance"]) == pytest.approx(3.0, rel=2e-3)  # a blackbody at 1 nit, × 3
    assert down["material"] == "pbrt-default"  # pbrt's area lights reflect with the shape's material
    data, _, _ = read(tmp_path, 'AreaLightSource "diffuse" "float power" 6\n'
                      'Shape "bilinearmesh" "point3 P" [0 0 0  2 0 0  0 3 0  2 3 0]\n' + quad)
    patch, pair = data["lights"]  # pbrt makes one light of a patch, and one of each triangle: power each
    assert patch["radiance"] == pytest.approx([6 / (6 * math.pi)] * 3)
    assert pair["radiance"] == pytest.approx([6 / (2 * math.pi)] * 3)


def test_emitting_shapes(tmp_path):
    data, _, _ = read(tmp_path, """
AreaLightSource "diffuse" "rgb L" [1 2 3] "float power" 10
Shape "sphere" "float radius" 0.5
Shape "disk" "float radius" 2
Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "normal N" [0 0 -1 0 0 -1 0 0 -1]
ReverseOrientation
Shape "sphere" "float radius" 4
""")
    sphere, disk = data["lights"]
    assert sphere["shape"] == "sphere" and sphere["radius"] == 0.5 and disk["normal"] == [0.0, 0.0, 1.0]
    k = 10 / (4 * math.pi * 0.25 * math.pi)  # power / (area π), pbrt's k_e for one side
    assert sphere["radiance"] == pytest.approx([k, 2 * k, 3 * k])
    tri, inside = data["objects"]  # ReverseOrientation: the sphere emits inward, so it is a mesh wound inward
    v, f = inside["vertices"], inside["faces"]
    centres = v[f].mean(axis=1)
    normals = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    assert np.all(np.einsum("ij,ij->i", normals, centres) < 0) and inside["two_sided"] is False
    corner = tri["vertices"][tri["faces"][0]]
    assert np.cross(corner[1] - corner[0], corner[2] - corner[0])[2] < 0  # the side of N, whatever the winding
    assert data["materials"][tri["material"]]["emission"] == pytest.approx([1 * 20 / math.pi, 2 * 20 / math.pi,
                                                                            3 * 20 / math.pi])


def test_point_distant_and_spot_lights_deliver_pbrts_irradiance(tmp_path):
    """A diffuse plane of reflectance ρ facing the light: pbrt's radiance there is ρ/π·E with E = I/d² (point,
    spot on its axis) and E = L (distant, head on); lumos renders the same value (raycast: no noise)."""
    rho, intensity, d = 0.6, 5.0, 2.5
    plane = f'Material "diffuse" "rgb reflectance" [{rho} {rho} {rho}]\n' \
            'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'
    lights = {
        "point": (f'LightSource "point" "rgb I" [{intensity} {intensity} {intensity}] "point3 from" [0 0 {d}]',
                  intensity / d ** 2),
        "spot": (f'LightSource "spot" "rgb I" [{intensity} {intensity} {intensity}] "point3 from" [0 0 {d}] '
                 '"point3 to" [0 0 0] "float coneangle" 60', intensity / d ** 2),
        "distant": ('LightSource "distant" "rgb L" [1.5 1.5 1.5] "point3 from" [0 0 1] "point3 to" [0 0 0]', 1.5),
        "point-power": ('LightSource "point" "float power" 100 "point3 from" [0 0 2]', 100 / (4 * math.pi) / 4),
    }
    for name, (light, irradiance) in lights.items():
        path = write(tmp_path, light + "\n" + plane)
        img = lumos.render(lumos.load_scene(path), method="raycast", filter="box", width=9, height=9, spp=1).array
        assert img[4, 4] == pytest.approx([rho / math.pi * irradiance] * 3, rel=1e-4), name


def test_infinite_light_is_the_background(tmp_path):
    data, lines, _ = read(tmp_path, 'LightSource "infinite" "rgb L" [0.2 0.3 0.4] "float scale" 2\n'
                          'LightSource "infinite"\nShape "sphere"\n')
    assert data["environment"]["color"] == pytest.approx([1.4, 1.6, 1.8]) and lines[("environment",)] == 6


def _cap_map(n=64, cos_cap=0.8, bright=5.0, dim=0.1):
    """An equal-area map of radiance `bright` within the cap cos θ > cos_cap about the map's +z, `dim` elsewhere."""
    from lumos.mesh.directions import equal_area_square_to_sphere

    u, v = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n)
    z = equal_area_square_to_sphere(u, v)[..., 2]
    return np.repeat(np.where(z > cos_cap, bright, dim)[..., None], 3, axis=2).astype(np.float32)


def _lat_long_solid_angles(h, w):
    edges = np.cos(np.arange(h + 1) / h * np.pi)
    return np.broadcast_to(((edges[:-1] - edges[1:]) * 2 * np.pi / w)[:, None], (h, w))


def test_an_equal_area_environment_map_becomes_the_lat_long_environment(tmp_path):
    """pbrt-v4's image infinite light (an equal-area octahedral square) is resampled into lumos's lat-long image
    through the light's transform: a bright cap about the map's +z lands where a distant light placed by the same
    transform comes from, and the light it sends (the mean over the sphere) is kept."""
    from lumos.mesh.directions import lat_long_directions

    cap = _cap_map()
    np.save(tmp_path / "cap.npy", cap)
    data, lines, said = read(tmp_path, 'AttributeBegin\nRotate 70 1 0.3 0\n'
                             'LightSource "infinite" "string filename" "cap.npy"\n'
                             'LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0]\nAttributeEnd\n'
                             'Shape "sphere"\n')
    assert not any("infinite" in m for m in said), said
    image = np.load(data["environment"]["file"])
    h, w = image.shape[:2]
    assert (h, w) == (64, 128) and lines[("environment",)] == 7
    axis = -np.asarray(data["lights"][0]["direction"], float)  # towards the distant light: the map's +z
    axis /= np.linalg.norm(axis)
    cos = lat_long_directions(h, w) @ axis
    assert (image[cos > 0.83] == 5.0).mean() > 0.98 and (image[cos < 0.77] == 0.1).mean() > 0.98
    omega = _lat_long_solid_angles(h, w)
    mean_sphere = (image[..., 1] * omega).sum() / (4 * np.pi)
    assert mean_sphere == pytest.approx(cap[..., 1].mean(), rel=0.01)  # (equal-area: the mean over pixels)


def test_illuminance_scales_an_environment_map_as_pbrt_does(tmp_path):
    """`illuminance` E: the map is scaled so that a surface facing its +z receives E (pbrt-v4), plus a constant
    infinite light added on top."""
    from lumos.mesh.directions import lat_long_directions

    np.save(tmp_path / "cap.npy", _cap_map())
    data, _, _ = read(tmp_path, 'LightSource "infinite" "string filename" "cap.npy" "float illuminance" 3\n'
                      'LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0]\n'
                      'LightSource "infinite" "rgb L" [0.5 0.5 0.5]\nShape "sphere"\n')
    image = np.load(data["environment"]["file"]).astype(float)
    axis = -np.asarray(data["lights"][0]["direction"], float)
    axis /= np.linalg.norm(axis)
    h, w = image.shape[:2]
    cos = np.maximum(lat_long_directions(h, w) @ axis, 0)
    e = ((image[..., 1] - 0.5) * cos * _lat_long_solid_angles(h, w)).sum()
    assert e == pytest.approx(3.0, rel=0.02)


def test_a_map_that_is_not_square_is_refused_in_one_line(tmp_path):
    np.save(tmp_path / "wide.npy", np.ones((8, 16, 3), np.float32))
    message = error_of(tmp_path, HEADER + 'LightSource "infinite" "string filename" "wide.npy"\nShape "sphere"\n')
    assert "16x8" in message and "square" in message and "\n" not in message


def test_shapes(tmp_path):
    import gzip
    import shutil

    shutil.copy(DATA / "quad_normals.ply", tmp_path / "quad.ply")
    (tmp_path / "quad.ply.gz").write_bytes(gzip.compress((DATA / "quad_normals.ply").read_bytes()))
    data, _, said = read(tmp_path, """
Attribute "shape" "float radius" 0.25
Shape "cylinder" "float zmin" 0 "float zmax" 2
Shape "cylinder" "float phimax" 180
Shape "sphere" "float zmax" 0.1
Shape "disk" "float innerradius" 0.1
Shape "plymesh" "string filename" "quad.ply"
Shape "plymesh" "string filename" "quad.ply.gz"
Shape "loopsubdiv" "integer levels" 2 "point3 P" [0 0 0 1 0 0 0 1 0 0 0 1] "integer indices" [0 2 1 0 1 3 0 3 2 1 2 3]
AttributeBegin
  CoordSysTransform "camera"
  Translate 0 0 3
  Shape "sphere"
AttributeEnd
AttributeBegin
  Scale 1 0 1
  Shape "sphere"
AttributeEnd
AreaLightSource "diffuse" "rgb L" [1 1 1]
Shape "plymesh" "string filename" "quad.ply"
""")
    cylinder, half, cap, ring, ply, gz, subdiv, in_front = data["objects"]
    assert cylinder == {"type": "cylinder", "base": [0.0, 0.0, 0.0], "top": [0.0, 0.0, 2.0], "radius": 0.25,
                        "capped": False, "material": "pbrt-default"}
    for partial in (half, cap, ring):  # tessellated: pbrt's partial quadrics
        assert partial["type"] == "mesh" and len(partial["faces"]) > 16
    assert np.all(half["vertices"][:, 1] >= -1e-12)  # φ in [0°, 180°]: y ≥ 0
    assert cap["vertices"][:, 2].max() <= 0.1 + 1e-12
    assert np.linalg.norm(ring["vertices"][:, :2], axis=1).min() >= 0.1 - 1e-9
    assert ply["file"] == "quad.ply" and ply["transform"]["matrix"][0][0] == -1.0 and ply["smooth"] is False
    assert gz["file"].endswith(".ply") and Path(gz["file"]).is_file()
    assert subdiv["subdivide"] == 2 and subdiv["subdivision"] == "loop"
    assert in_front["center"] == [0.0, 0.0, 2.0] and in_front["radius"] == 0.25  # 3 units in front of the camera
    assert [light["shape"] for light in data["lights"]] == ["rect"]  # an emitting flat quad from a PLY file
    assert sum("flattens" in s for s in said) == 1  # Scale 1 0 1: a flat sphere is left out, with a warning
    assert not any("radius" in s for s in said)  # Attribute defaults may go unused, as in pbrt
    with pytest.warns(LumosWarning, match="flattens"):
        scene = lumos.load_scene(write(tmp_path, "", "main.pbrt", header='Include "scene.pbrt"\n'))
    assert len(scene.objects) == 8


def test_spot_light_cone(tmp_path):
    data, _, _ = read(tmp_path, 'LightSource "spot" "point3 from" [0 4 0] "point3 to" [0 0 0] "float coneangle" 40 '
                      '"float conedeltaangle" 10 "float power" 50 "rgb I" [1 0.5 0.25]\n')
    spot = data["lights"][0]
    assert (spot["angle"], spot["inner_angle"], spot["direction"]) == (40.0, 30.0, [0.0, -4.0, 0.0])
    cos_end, cos_start = math.cos(math.radians(40)), math.cos(math.radians(30))
    i = 50 / (2 * math.pi * ((1 - cos_start) + (cos_start - cos_end) / 2)) / math.pi
    assert spot["intensity"] == pytest.approx([i, i / 2, i / 4])


# ------------------------------------------------------------------------------------------- materials


def test_material_mappings(tmp_path):
    data, _, said = read(tmp_path, """
MakeNamedMaterial "gold" "string type" "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
MakeNamedMaterial "copper" "string type" "conductor"
MakeNamedMaterial "rough" "string type" "conductor" "rgb reflectance" [0.9 0.5 0.2] "float roughness" 0.04
MakeNamedMaterial "rgbmetal" "string type" "conductor" "rgb eta" [0.2 0.9 1.1] "rgb k" [3.9 2.4 2.1]
MakeNamedMaterial "coated" "string type" "coateddiffuse" "rgb reflectance" [0.5 0.2 0.1]
MakeNamedMaterial "paper" "string type" "diffusetransmission"
MakeNamedMaterial "flat" "string type" "diffuse" "spectrum reflectance" [300 0.3 800 0.3]
Shape "sphere"
""")
    m = data["materials"]
    assert m["gold"] == {"conductor": {"metal": "Au", "alpha": 0}}  # lumos's GGX metal with its named index
    assert m["copper"] == {"conductor": {"metal": "Cu", "alpha": 0}}  # pbrt's default conductor is copper
    assert m["rough"]["shininess"] == pytest.approx(0.5 * (0.2 ** -2 - 1))  # a reflectance: the Phong stand-in
    assert np.add(m["rough"]["ks"], m["rough"]["kr"]) == pytest.approx([0.9, 0.5, 0.2])
    assert m["rgbmetal"] == {"conductor": {"eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.1], "alpha": 0}}
    assert m["coated"] == {"kd": [0.5, 0.2, 0.1], "plastic": {"alpha": 0, "ior": 1.5}}  # lumos's plastic
    assert m["paper"] == {"kd": [0.25] * 3, "kt": [0.25] * 3, "ior": 1.0}
    assert m["flat"]["kd"] == pytest.approx([0.3] * 3, abs=1e-5)
    assert sum("conductor" in s and "roughness" in s for s in said) == 1
    assert sum("coateddiffuse" in s for s in said) == 1


def test_textures(tmp_path):
    from PIL import Image

    Image.new("RGB", (4, 4), (200, 100, 50)).save(tmp_path / "wood.png")
    data, _, said = read(tmp_path, """
Texture "checks" "spectrum" "checkerboard" "float uscale" 8 "float vscale" 4 "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
Texture "wood" "spectrum" "imagemap" "string filename" "wood.png" "float udelta" 0.5
Texture "dark wood" "spectrum" "scale" "texture tex" "wood" "float scale" 0.5
Texture "noise" "float" "fbm"
Material "diffuse" "texture reflectance" "checks"
Shape "sphere"
Material "coateddiffuse" "texture reflectance" "dark wood" "texture roughness" "noise"
Shape "sphere"
Texture "leaf" "float" "imagemap" "string filename" "wood.png"
Texture "bumps" "float" "imagemap" "string filename" "wood.png" "float scale" 0.01
Material "diffuse" "texture displacement" "bumps"
Shape "sphere" "texture alpha" "leaf"
Material "conductor" "texture roughness" "leaf"
Shape "sphere"
""")
    checks, wood, leaf, metal = (data["materials"][o["material"]] for o in data["objects"])
    assert checks["texture"] == [{"type": "checker", "colors": [[1, 0, 0], [0, 0, 1]], "scale": [8, 4],
                                  "offset": [0, 0], "apply_to": ["kd"], "mode": "multiply"}]
    assert checks["kd"] == [1, 1, 1]
    assert wood["texture"][0]["file"] == "wood.png" and wood["texture"][0]["offset"] == [0.5, 0]
    assert wood["kd"] == pytest.approx([0.5] * 3) and 0 < wood["plastic"]["alpha"] <= 1  # the coat's α from the mean
    assert any("fbm" in s for s in said)
    assert leaf["bump"] == {"type": "image", "file": "wood.png", "scale": [1, 1], "offset": [0, 0], "wrap": "repeat",
                            "strength": 0.01}  # pbrt's displacement is a bump map
    assert leaf["texture"][-1]["apply_to"] == ["opacity"] and leaf["texture"][-1]["file"] == "wood.png"
    mean = np.mean([(200 / 255) ** 2.2, (100 / 255) ** 2.2, (50 / 255) ** 2.2])  # the image's mean, roughly
    assert metal["conductor"]["alpha"] == pytest.approx(math.sqrt(mean), rel=0.05)  # α = √r of the map's mean
    with pytest.warns(LumosWarning):
        scene = lumos.load_scene(write(tmp_path, 'Include "scene.pbrt"', "main.pbrt", header=""))
    assert any(t.file == "wood.png" for m in scene.materials.values() for t in m.textures)  # the loader found it


def test_spectra_become_rgb():
    assert pbrt_spectra.reflectance_rgb([300, 800], [0.7, 0.7]) == pytest.approx((0.7,) * 3, abs=1e-6)
    assert pbrt_spectra.illuminant_rgb([300, 800], [5, 5]) == pytest.approx((1.2045, 0.9483, 0.9096), abs=1e-3)
    warm, cool = pbrt_spectra.blackbody_rgb(2700), pbrt_spectra.blackbody_rgb(10000)
    assert warm[0] > warm[2] and cool[2] > cool[0]
    assert pbrt_spectra.luminance(warm) == pytest.approx(1.0, rel=2e-3)
    assert pbrt_spectra.NAMED_METALS["Au"] == pytest.approx((1.0, 0.766, 0.336), abs=0.04)  # glTF's gold F0


# ------------------------------------------------------------------------------------------- bad input


BAD = [
    ("truncated", HEADER + 'Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0\n', 5, "never closed"),
    ("unknown directive", HEADER + "Shape \"sphere\"\nSphere 1\n", 6, "unknown directive 'Sphere'"),
    ("bad number", HEADER + "Translate 1 2 x3\n", 5, "expected a number, got 'x3'"),
    ("bad number in a list", HEADER + 'Shape "trianglemesh" "point3 P" [ 0 0 0\n 1 0 1,5\n 0 1 0 ]\n', 6,
     "expected a number, got '1,5'"),
    ("missing include", HEADER + 'Include "nowhere.pbrt"\n', 5, "no such file 'nowhere.pbrt'"),
    ("cycle", HEADER + 'Include "scene.pbrt"\n', 5, "includes itself"),
    ("AttributeEnd", HEADER + "AttributeEnd\n", 5, "AttributeEnd without AttributeBegin"),
    ("named material", HEADER + 'NamedMaterial "shiny"\nShape "sphere"\n', 5, "unknown material 'shiny'"),
    ("unclosed attribute", HEADER + "AttributeBegin\nShape \"sphere\"\n", 5, "AttributeBegin without AttributeEnd"),
    ("bad type", HEADER + 'Shape "sphere" "flaot radius" 1\n', 5, "unknown parameter type 'flaot'"),
    ("string", HEADER + 'Shape "sphere\n', 5, "unterminated string"),
    ("index", HEADER + 'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 3]\n', 5,
     "index 3 is out of range"),
    ("no world", HEADER.replace("WorldBegin\n", ""), None, "ends before WorldBegin"),
    ("option in world", HEADER + 'Film "rgb"\n', 5, "must come before WorldBegin"),
    ("import outside world", 'Import "scene.pbrt"\n' + HEADER, 1, "must come after WorldBegin"),
    ("mix", HEADER + 'Material "mix" "string materials" ["a" "b"]\nShape "sphere"\n', 5, "unknown named material 'a'"),
    ("radiance", HEADER + 'AreaLightSource "diffuse" "rgb L" [1e31 1 1]\nShape "sphere"\n', 6, "lights[0].radiance"),
]


@pytest.mark.parametrize("case, text, line, what", BAD, ids=[b[0] for b in BAD])
def test_bad_input_is_one_line_with_file_and_line_and_exit_code_2(tmp_path, capsys, case, text, line, what):
    path = tmp_path / "scene.pbrt"
    path.write_text(text)
    code = cli.main(["render", str(path), "-o", str(tmp_path / "out.png")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    message = [e for e in err if "warning" not in e]
    assert len(message) == 1 and what in message[0], err
    assert f"{path}:{line}: " in message[0] if line else f"{path}: " in message[0]


def test_unknown_plugins_warn_once_and_are_not_errors(tmp_path):
    data, _, said = read(tmp_path, """
Shape "curve" "point3 P" [0 0 0 1 1 1 2 0 0 3 1 1]
Shape "curve" "point3 P" [0 0 0 1 1 1 2 0 0 3 1 1]
Material "velvet" "float fuzz" 1
Shape "sphere"
Shape "sphere"
LightSource "laser" "rgb I" [1 1 1]
MakeNamedMedium "fog" "string type" "homogeneous"
""")
    assert len(data["objects"]) == 2 and data["lights"] == []
    for name in ("'curve'", "'velvet'", "'laser'", "MakeNamedMedium"):
        assert sum(name in s for s in said) == 1, (name, said)
    assert data["materials"][data["objects"][0]["material"]] == {"kd": 0.5}
    assert all(s.startswith(str(tmp_path / "scene.pbrt") + ":") for s in said)


def test_lumos_validation_errors_point_at_the_pbrt_line(tmp_path):
    path = write(tmp_path, 'Material "diffuse"\nShape "sphere"\nLightSource "spot" "rgb I" [1e31 0 0]\n')
    with pytest.raises(LumosError, match=r"scene\.pbrt:7: lights\[0\]"):
        lumos.load_scene(path)


# ------------------------------------------------------------------------------------------- renders


def test_killeroo_like_scene_renders_sensibly():
    """tests/data/pbrt/killeroo_like.pbrt (pbrt-v4's killeroo-simple with a sphere for the killeroo): the ground
    under the lamp (the image's left: world +x seen through pbrt's LookAt) is brighter than the far side."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LumosWarning)
        img = lumos.render(str(PBRT / "killeroo_like.pbrt"), width=48, height=32, spp=16).array
    assert img.shape == (32, 48, 3) and np.isfinite(img).all()
    ground = img[22:].mean(axis=2)
    assert ground[:, :16].mean() > 2 * ground[:, 32:].mean() > 0


def _blocks(a: np.ndarray, k: int = 8) -> np.ndarray:
    h, w = a.shape[:2]
    return a.reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))


def _mitsuba_twin(mi, spp: int) -> dict:
    """tests/data/pbrt/sphere_on_ground.pbrt, written for Mitsuba from the pbrt file's own numbers: pbrt's image
    is the mirror of a right-handed camera's, so the sensor's x axis is flipped (scale −1 in x); fov on the
    shorter axis is Mitsuba's fov_axis "smaller"; pbrt maxdepth 5 is Mitsuba max_depth 6; the lamp is one-sided
    in both and reflects with pbrt's default diffuse 0.5 (Mitsuba's default for an emitter is black)."""
    T = mi.ScalarTransform4f

    def diffuse(rgb):
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}

    return {
        "type": "scene", "integrator": {"type": "path", "max_depth": 6},
        "sensor": {"type": "perspective", "fov": 40, "fov_axis": "smaller",
                   "to_world": T().look_at(origin=[0, 2, 6], target=[0, 0.6, 0], up=[0, 1, 0]) @ T().scale([-1, 1, 1]),
                   "film": {"type": "hdrfilm", "width": 48, "height": 64, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "point": {"type": "point", "position": [1.5, 2, 1.5], "intensity": {"type": "rgb", "value": [1.5] * 3}},
        "lamp": {"type": "rectangle", "bsdf": diffuse([0.5] * 3),
                 "to_world": T().translate([-1, 2.5, 0]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.5),
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [10, 10, 10]}}},
        "ground": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90) @ T().scale(4),
                   "bsdf": diffuse([0.5] * 3)},
        "sphere": {"type": "sphere", "center": [0.8, 0.6, 0], "radius": 0.6, "bsdf": diffuse([0.7, 0.3, 0.2])},
    }


@pytest.mark.slow
def test_a_pbrt_scene_matches_mitsuba_rendering_the_same_description():
    """Both renderers at 48×64 (a tall image: pbrt's fov is horizontal there): lumos 256 spp with its variance
    AOV, Mitsuba four independent 256-spp renders (their spread gives its noise); a z-test on every 8×8 block
    and channel, and no bias across the image."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    runs = [np.asarray(mi.render(mi.load_dict(_mitsuba_twin(mi, 256)), seed=s), np.float64) for s in range(4)]
    theirs, var_theirs = np.mean(runs, axis=0), np.var(runs, axis=0, ddof=1) / len(runs)
    img = lumos.render(str(PBRT / "sphere_on_ground.pbrt"), spp=256, aov=["variance"], seed=3)
    ours = img.array.astype(np.float64)
    se = np.sqrt((_blocks(img.aovs["variance"].astype(np.float64)) + _blocks(var_theirs)) / 64 + 1e-12)
    z = (_blocks(ours) - _blocks(theirs)) / se
    assert np.abs(z).max() < 5.0, np.abs(z).max()
    assert abs(z.mean()) < 0.4, z.mean()
    assert ours.mean() == pytest.approx(theirs.mean(), rel=0.01)


# ------------------------------------------------------------------------------------------- hostile files

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as hs  # noqa: E402

_WORDS = ["WorldBegin", "AttributeBegin", "AttributeEnd", "ObjectBegin", "ObjectEnd", "ObjectInstance", "Shape",
          "Material", "MakeNamedMaterial", "NamedMaterial", "Texture", "LightSource", "AreaLightSource", "Translate",
          "Scale", "Rotate", "LookAt", "Transform", "ConcatTransform", "ReverseOrientation", "Camera", "Film",
          "Include", "Import", "CoordSysTransform", "Attribute", "Identity", "Frobnicate", "true", "false"]
_STRINGS = ['"sphere"', '"disk"', '"cylinder"', '"trianglemesh"', '"bilinearmesh"', '"loopsubdiv"', '"plymesh"',
            '"diffuse"', '"conductor"', '"dielectric"', '"mix"', '"point"', '"spot"', '"distant"', '"infinite"',
            '"float radius"', '"point3 P"', '"integer indices"', '"normal N"', '"point2 uv"', '"rgb L"', '"rgb I"',
            '"rgb reflectance"', '"spectrum eta"', '"metal-Au-eta"', '"string type"', '"string materials"',
            '"texture reflectance"', '"blackbody L"', '"float power"', '"bool twosided"', '"a"', '"spectrum"',
            '"imagemap"', '"checkerboard"', '"camera"', '"shape"', '"x.pbrt"', '"float"', '"junk type"', '"']
_NUMBERS = ["0", "1", "-1", "2.5", "0.5", "3", "1e40", "-1e-3", "nan", "1x", ".5", "90", "360"]
_TOKEN = hs.one_of(hs.sampled_from(_WORDS), hs.sampled_from(_STRINGS), hs.sampled_from(_NUMBERS),
                   hs.sampled_from(["[", "]", "[ 0 0 0 1 0 0 0 1 0 ]", "# comment\n", "\n"]))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(tokens=hs.lists(_TOKEN, max_size=40), world=hs.booleans())
def test_hostile_files_give_a_scene_or_one_line_error(tmp_path, tokens, world):
    path = tmp_path / "fuzz.pbrt"
    path.write_text(("WorldBegin\n" if world else "") + " ".join(tokens))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            lumos.load_scene(path)
        except LumosError as exc:
            assert "\n" not in str(exc) and str(exc).startswith(str(path)), str(exc)
