"""Mitsuba 3 scene files (lumos.io.mitsuba): the XML (defaults, includes, refs, values, transforms), the plugin
mapping and its unit conversions, one-line errors at the file's line, and renders of the same XML file by Mitsuba
and by lumos compared block by block (where Mitsuba is installed), plus Mitsuba's own Cornell box against the
stored converged Mitsuba render (no Mitsuba needed).
"""

from __future__ import annotations

import math
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from conftest import run_cli
from helpers import DATA

import lumos
from lumos.errors import LumosError, LumosWarning
from lumos.io import mitsuba_data
from lumos.io.mitsuba import read_mitsuba
from lumos.io.mitsuba_values import look_at, rotation
from lumos.io.mitsuba_xml import parse_scene
from lumos.scene.materials import Material

MITSUBA = DATA / "mitsuba"


def write(folder: Path, body: str, name: str = "scene.xml", version: str = "3.0.0") -> Path:
    """A Mitsuba scene file `name` in `folder` holding `body` inside <scene version=...>."""
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'<scene version="{version}">\n{body}\n</scene>\n')
    return path


def read(folder: Path, body: str, **kw) -> dict:
    return read_mitsuba(write(folder, body, **kw))[0]


def mitsuba(variant: str = "scalar_rgb"):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant(variant)
    return mi


# ------------------------------------------------------------------------------------------------ transforms


def test_transform_ops_compose_in_document_order(tmp_path):
    """Each op left-multiplies: scale, then rotate, then translate, then a matrix, then a lookat."""
    root = parse_scene(write(tmp_path, """
      <shape type="sphere"><transform name="to_world">
        <scale x="2" y="1" z="3"/>
        <rotate y="1" angle="30"/>
        <translate value="1 2 3"/>
        <matrix value="1 0 0 0  0 0 -1 0  0 1 0 0  0 0 0 1"/>
      </transform></shape>"""))
    shape = root.objects[0][1]
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    ry = np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]])
    t = np.eye(4)
    t[:3, 3] = (1, 2, 3)
    m = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
    np.testing.assert_allclose(shape.transform(), m @ t @ ry @ np.diag([2, 1, 3, 1]), atol=1e-12)


def test_rotation_and_lookat_are_mitsubas():
    """Rodrigues about a skew axis is a right-handed rotation; lookat's columns are left, up, dir, origin."""
    r = rotation((0, 0, 1), 90)
    np.testing.assert_allclose(r @ (1, 0, 0), (0, 1, 0), atol=1e-12)
    np.testing.assert_allclose(rotation((0, 0, 2), 90) @ (0, 0, 1), (0, 0, 4), atol=1e-12)  # as Mitsuba: not normalised
    m = look_at(np.array([1.0, 2, 3]), np.array([1.0, 2, 0]), np.array([0.0, 1, 0]))
    np.testing.assert_allclose(m[:3, 2], (0, 0, -1))  # looks along +z of to_world
    np.testing.assert_allclose(m[:3, 0], (-1, 0, 0))  # x points left in the image
    np.testing.assert_allclose(m[:3, 3], (1, 2, 3))
    no_up = look_at(np.zeros(3), np.array([0.0, 0, 1]), None)  # made up, orthonormal
    np.testing.assert_allclose(no_up[:3, :3].T @ no_up[:3, :3], np.eye(3), atol=1e-12)


def test_transforms_match_mitsubas_own_parser(tmp_path):
    """The same <transform> applied by Mitsuba (to an OBJ quad's vertices) and by lumos's reader."""
    mi = mitsuba()
    (tmp_path / "quad.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n")
    ops = """<scale x="2" y="1" z="3"/><rotate x="1" y="2" z="0.5" angle="33"/><translate value="1, 2, 3"/>
             <lookat origin="1, 2, 3" target="0, 0, 0"/><scale value="0.5"/><rotate z="1" angle="-70"/>"""
    shape = f'<shape type="obj"><string name="filename" value="{tmp_path / "quad.obj"}"/>' \
            f'<transform name="to_world">{ops}</transform></shape>'
    theirs = np.array(mi.traverse(mi.load_string(shape.replace("<shape", '<shape version="3.0.0"', 1)))
                      ["vertex_positions"]).reshape(-1, 3)
    m = parse_scene(write(tmp_path, shape)).objects[0][1].transform()
    quad = np.array([[-1, -1, 0, 1], [1, -1, 0, 1], [1, 1, 0, 1], [-1, 1, 0, 1]], float)
    np.testing.assert_allclose((quad @ m.T)[:, :3], theirs, atol=2e-5)


# ------------------------------------------------------------------------------------------------ the XML


def test_defaults_and_parameters(tmp_path):
    """<default> fills $name; a value given to read_mitsuba wins over it; the longest name is substituted."""
    body = """<default name="r" value="2"/><default name="rr" value="5"/>
      <shape type="sphere"><float name="radius" value="$r"/><point name="center" value="$rr, 0, 0"/></shape>"""
    path = write(tmp_path, body)
    sphere = read_mitsuba(path)[0]["objects"][0]
    assert sphere["radius"] == 2 and sphere["center"] == [5, 0, 0]
    assert read_mitsuba(path, {"r": 3})[0]["objects"][0]["radius"] == 3


def test_include_splices_scenes_and_adds_objects(tmp_path):
    """An included <scene> adds its children; an included object (a <bsdf> file) becomes one, found relative to
    the including file; ids defined in one file are referenced from another."""
    write(tmp_path, '<shape type="sphere"><ref id="gold"/></shape>', "parts/shapes.xml")
    (tmp_path / "parts" / "gold.xml").write_text(
        '<bsdf version="3.0.0" type="conductor" id="gold"><string name="material" value="Au"/></bsdf>')
    data = read(tmp_path, '<include filename="parts/gold.xml"/><include filename="parts/shapes.xml"/>')
    assert data["objects"][0]["material"] == "gold"
    gold = data["materials"]["gold"]["conductor"]
    np.testing.assert_allclose(mitsuba_data.conductor_reflectance(gold["eta"], gold["k"]),
                               (0.96668, 0.80201, 0.32412), atol=1e-5)


def test_refs_forward_named_and_nested(tmp_path):
    """A ref may name an id defined later, with or without name="bsdf"; twosided is unwrapped."""
    data = read(tmp_path, """
      <shape type="sphere"><ref name="bsdf" id="red"/></shape>
      <shape type="cube"><ref id="red"/></shape>
      <bsdf type="twosided" id="red"><bsdf type="diffuse"><rgb name="reflectance" value="0.8 0.1 0.1"/></bsdf></bsdf>
    """)
    assert [o["material"] for o in data["objects"]] == ["red", "red"]
    assert data["materials"]["red"] == {"kd": [0.8, 0.1, 0.1]}


def test_a_file_older_than_mitsuba_2_has_its_camel_case_names_upgraded(tmp_path):
    data = read(tmp_path, """
      <shape type="sphere"><transform name="toWorld"><translate x="1"/></transform>
        <bsdf type="dielectric"><float name="intIOR" value="1.33"/></bsdf></shape>""", version="0.6.0")
    sphere = data["objects"][0]
    assert sphere["center"] == [1, 0, 0]
    assert sphere["material"]["dielectric"] == {"ior": 1.33, "ext_ior": pytest.approx(1.000277)}


# ------------------------------------------------------------------------------------------------ values and colour


def test_spectra_as_mitsubas_rgb_variants_read_them(tmp_path):
    """A uniform reflectance is grey, a uniform emitter slightly purple (XYZ = v); a flat spectrum over the
    visible range is white as a reflectance (D65-weighted)."""
    with pytest.warns(LumosWarning, match="constant: the environment lights the scene in path"):
        data = read(tmp_path, """
      <emitter type="constant"><spectrum name="radiance" value="2"/></emitter>
      <shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="0.25"/></bsdf></shape>
      <shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" value="360:1, 830:1"/></bsdf></shape>""")
    np.testing.assert_allclose(data["environment"]["color"], (2 * 1.204794, 2 * 0.948291, 2 * 0.908916), rtol=1e-6)
    assert data["objects"][0]["material"]["kd"] == [0.25] * 3
    np.testing.assert_allclose(data["objects"][1]["material"]["kd"], 1.0, atol=0.01)


def test_spectrum_conversion_matches_mitsuba():
    mi = mitsuba()
    wavelengths, values = [400, 480, 550, 610, 700], [0.1, 0.7, 0.3, 0.9, 0.2]
    for emitter in (False, True):
        ours = mitsuba_data.spectrum_rgb(wavelengths, values, d65=not emitter, bounded=not emitter)
        theirs = mi.spectrum_list_to_srgb(wavelengths, values, bounded=not emitter, d65=not emitter)
        np.testing.assert_allclose(ours, np.array(theirs), rtol=1e-4)


def test_conductor_presets_are_mitsubas_rgb_data():
    """Every preset's η and k as Mitsuba's RGB variants load them from its data/ior files, and the mirror
    reflectance lumos uses is Mitsuba's conductor at normal incidence."""
    mi = mitsuba()
    folder = Path(mi.__file__).parent / "data" / "ior"
    for name, (eta, k) in mitsuba_data.CONDUCTORS.items():
        for ours, part in ((eta, "eta"), (k, "k")):
            w, v = mitsuba_data.read_spd(folder / f"{name}.{part}.spd")
            np.testing.assert_allclose(ours, np.array(mi.spectrum_list_to_srgb(w, v, False, False)),
                                       rtol=1e-4, atol=1e-6, err_msg=f"{name}.{part}")
    for name in ("Au", "Ag", "Cu", "Al", "Cr"):
        bsdf = mi.load_dict({"type": "conductor", "material": name})
        si = mi.SurfaceInteraction3f()
        si.wi, si.sh_frame = [0, 0, 1], mi.Frame3f([0, 0, 1])
        _, weight = bsdf.sample(mi.BSDFContext(), si, 0.5, [0.5, 0.5])
        ours = mitsuba_data.conductor_reflectance(*mitsuba_data.CONDUCTORS[name])
        np.testing.assert_allclose(ours, np.array(weight), rtol=1e-4, err_msg=name)


def test_materials_and_named_iors(tmp_path):
    data = read(tmp_path, """
      <shape type="sphere"><bsdf type="dielectric"><string name="int_ior" value="water"/></bsdf></shape>
      <shape type="sphere"><bsdf type="conductor"/></shape>
      <shape type="sphere"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.5"/></bsdf></shape>
      <shape type="sphere"><bsdf type="diffuse"/></shape>
      <shape type="sphere"/>""")
    glass, mirror, plastic, diffuse, bare = (o["material"] for o in data["objects"])
    assert glass == {"dielectric": {"ior": 1.333, "ext_ior": pytest.approx(1.000277)}}
    assert mirror == {"conductor": {"tint": [1.0] * 3}}  # material "none" (eta 0, k 1): F = 1
    assert plastic == {"kd": [0.5] * 3, "plastic": {"ior": pytest.approx(1.49 / 1.000277), "tint": [1.0] * 3}}
    assert diffuse == bare == {"kd": [0.5] * 3} or bare == {"kd": 0.5}


def test_rough_plugins_with_one_warning_each(tmp_path):
    """roughconductor and roughplastic are lumos's GGX conductor and plastic (Beckmann read as GGX); an unknown
    shape is left out. Each says so once."""
    body = "".join(f'<shape type="sphere"><bsdf type="roughconductor"><float name="alpha" value="{a}"/>'
                   f'<string name="material" value="Ag"/></bsdf></shape>' for a in (0.1, 0.2))
    body += "".join(f'<shape type="sphere"><bsdf type="roughplastic"><float name="alpha" value="{a}"/></bsdf>'
                    f'</shape>' for a in (0.1, 0.2))
    with pytest.warns(LumosWarning) as record:
        data = read(tmp_path, body + '<shape type="heightfield"/>')
    messages = [str(w.message) for w in record]
    assert sum("roughconductor: the beckmann distribution is read as GGX" in m for m in messages) == 1
    assert sum("roughplastic: the beckmann distribution is read as GGX" in m for m in messages) == 1
    assert any("shape 'heightfield' is not supported" in m for m in messages)
    silver = data["objects"][1]["material"]["conductor"]
    assert silver["alpha"] == 0.2 and silver["eta"] == pytest.approx(mitsuba_data.CONDUCTORS["Ag"][0])
    assert data["objects"][3]["material"]["plastic"]["alpha"] == 0.2


def test_rough_glass_is_lumos_dielectric(tmp_path):
    """roughdielectric is lumos's `dielectric` with Mitsuba's α (alpha_u/alpha_v anisotropic), named IORs and
    both tints; Beckmann is read as GGX with one warning for the plugin, ggx silently; `dielectric` is the same
    with α 0; the old "read as smooth" stand-in is gone."""
    body = "".join(f'<shape type="sphere"><bsdf type="roughdielectric"><float name="alpha" value="{a}"/>'
                   f'<string name="int_ior" value="water"/></bsdf></shape>' for a in (0.1, 0.3))
    body += """<shape type="sphere"><bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
        <float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.4"/><float name="int_ior" value="1.7"/>
        <float name="ext_ior" value="1.33"/><rgb name="specular_transmittance" value="0.9 0.8 0.7"/>
        <boolean name="sample_visible" value="false"/></bsdf></shape>
      <shape type="sphere"><bsdf type="dielectric"><float name="eta" value="1.4"/>
        <rgb name="specular_reflectance" value="0.5"/></bsdf></shape>"""
    with pytest.warns(LumosWarning) as record:
        data = read(tmp_path, body)
    messages = [str(w.message) for w in record]
    assert sum("roughdielectric: the beckmann distribution is read as GGX" in m for m in messages) == 1
    assert not any("smooth" in m for m in messages)
    water, rougher, tinted, plain = (o["material"]["dielectric"] for o in data["objects"])
    assert water == {"ior": 1.333, "ext_ior": pytest.approx(1.000277), "alpha": 0.1} and rougher["alpha"] == 0.3
    assert tinted == {"ior": 1.7, "ext_ior": 1.33, "alpha": [0.05, 0.4], "transmit_tint": [0.9, 0.8, 0.7]}
    assert plain == {"ior": 1.4, "ext_ior": 1.0, "tint": [0.5] * 3}
    with pytest.warns(LumosWarning):
        scene = lumos.load_scene(write(tmp_path, body))  # and the scene model takes them
    assert scene.objects[2].material.dielectric.eta == pytest.approx(1.7 / 1.33)


# ------------------------------------------------------------------------------------------------ units


def test_point_and_directional_lights_deliver_mitsubas_irradiance(tmp_path):
    """Mitsuba: a point light of intensity I gives irradiance I·cosθ/d², a directional one E·cosθ. lumos: a
    point light of intensity I′ and attenuation [c, l, q] gives π·I′·cosθ/att(d), a directional one
    π·I′·cosθ."""
    data = read(tmp_path, """
      <emitter type="point"><point name="position" value="0, 2, 0"/><rgb name="intensity" value="5"/></emitter>
      <emitter type="directional"><vector name="direction" value="0, -1, 0"/><rgb name="irradiance" value="3"/>
      </emitter>""")
    point, sun = data["lights"]
    d = 2.0
    c, l, q = point["attenuation"]
    assert math.pi * point["intensity"][0] / (c + l * d + q * d * d) == pytest.approx(5 / d ** 2)
    assert math.pi * sun["intensity"][0] == pytest.approx(3.0) and sun["direction"] == [0, -1, 0]


def test_a_diffuse_floor_under_a_point_light_renders_mitsubas_radiance(tmp_path):
    """Straight below a point light of intensity I at height d, a Lambertian floor of albedo ρ has radiance
    ρ/π · I/d² (Mitsuba's units); lumos's raycast of the converted scene gives it to 0.5%."""
    path = write(tmp_path, """
      <sensor type="perspective"><float name="fov" value="1"/>
        <transform name="to_world"><lookat origin="0, 1, 0" target="0, 0, 0" up="0, 0, -1"/></transform>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
      <emitter type="point"><point name="position" value="0, 2, 0"/><rgb name="intensity" value="5"/></emitter>
      <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>""")
    img = lumos.render(path, method="raycast", spp=1, filter="box")  # (one ray per pixel: no filter to read)
    np.testing.assert_allclose(img.array[1:3, 1:3], 0.6 / math.pi * 5 / 4, rtol=5e-3)


def test_camera_fields_of_view(tmp_path):
    """Mitsuba's fov on x, y, smaller, diagonal or from a focal length → lumos's vertical fov."""
    def fov(params: str, w=200, h=100) -> float:
        data = read(tmp_path, f'<sensor type="perspective">{params}<film type="hdrfilm"><integer name="width" '
                              f'value="{w}"/><integer name="height" value="{h}"/></film></sensor>')
        return data["camera"]["fov"]

    half = math.tan(math.radians(30))
    assert fov('<float name="fov" value="60"/>') == pytest.approx(math.degrees(2 * math.atan(half / 2)))
    assert fov('<float name="fov" value="60"/><string name="fov_axis" value="smaller"/>') == pytest.approx(60)
    assert fov('<float name="fov" value="60"/><string name="fov_axis" value="y"/>', 100, 300) == pytest.approx(60)
    diag = fov('<float name="fov" value="60"/><string name="fov_axis" value="diagonal"/>')
    assert diag == pytest.approx(math.degrees(2 * math.atan(half / math.sqrt(5))))
    f = fov('<string name="focal_length" value="35mm"/>', 360, 240)  # 35 mm film: the height is 24 mm
    assert f == pytest.approx(math.degrees(2 * math.atan(12 / 35)))


def test_sensor_film_sampler_and_integrator(tmp_path):
    data = read(tmp_path, """
      <integrator type="aov"><string name="aovs" value="dd.y:depth"/>
        <integrator type="path"><integer name="max_depth" value="5"/></integrator></integrator>
      <sensor type="thinlens"><float name="aperture_radius" value="0.1"/><float name="focus_distance" value="4"/>
        <transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/></transform>
        <sampler type="stratified"><integer name="sample_count" value="9"/></sampler>
        <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/>
          <rfilter type="box"/></film></sensor>""")
    assert data["camera"] == {"position": [1, 2, 3], "look_at": [1, 2, 2], "up": [0, 1, 0],
                              # no fov: Mitsuba's 50 mm lens, a 43.3 mm film diagonal over the 4:3 image's diagonal
                              "fov": pytest.approx(math.degrees(2 * math.atan(math.hypot(36, 24) / 100 / 5 * 3))),
                              "aperture": 0.1, "focus_distance": 4}
    assert data["render"] == {"method": "path", "max_depth": 3, "width": 40, "height": 30, "filter": "box",
                              "spp": 9}
    direct = read(tmp_path, '<integrator type="direct"/>')
    assert direct["render"]["max_depth"] == 0 and direct["render"]["spp"] == 4  # Mitsuba's default sampler


def test_area_lights_emit_on_mitsubas_normal_side(tmp_path):
    """A rectangle's normal is to_world's inverse transpose of +z: lumos's cross(edge_u, edge_v) follows it
    under a mirroring to_world and against it with flip_normals; other shapes become one-sided emitters."""
    def light(transform: str, flip: bool = False) -> np.ndarray:
        data = read(tmp_path, f'<shape type="rectangle"><transform name="to_world">{transform}</transform>'
                              f'<boolean name="flip_normals" value="{str(flip).lower()}"/>'
                              f'<emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>')
        (lamp,) = data["lights"]
        assert "material" not in lamp  # an emitter without a BSDF reflects nothing in Mitsuba
        return np.cross(lamp["edge_u"], lamp["edge_v"])

    assert light('<rotate x="1" angle="90"/>')[1] < 0  # +z turned to -y: shines down
    assert light('<rotate x="1" angle="90"/>', flip=True)[1] > 0
    assert light('<scale x="-1"/>')[2] > 0  # a mirror in x keeps the normal +z
    data = read(tmp_path, '<shape type="cube"><emitter type="area"><rgb name="radiance" value="3"/></emitter>'
                          '</shape>')
    assert data["objects"][0]["two_sided"] is False and data["objects"][0]["material"] == {"emission": [3.0] * 3}


def test_serialized_meshes(tmp_path):
    """A two-mesh .serialized file (version 4) written as Mitsuba documents it: shape_index picks the second
    mesh (the one Mitsuba reads); its uvs come back with v flipped (lumos's images run up). And version 5."""
    tri = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), np.array([[0, 1, 2]], np.uint32))
    quad = (np.array([[0, 0, 1], [2, 0, 1], [2, 2, 1], [0, 2, 1]], np.float32),
            np.array([[0, 1, 2], [0, 2, 3]], np.uint32))
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    blob, offsets = bytearray(), []
    for (v, f), uv in ((tri, None), (quad, uvs)):
        offsets.append(len(blob))
        flags = 0x1000 | (0x2 if uv is not None else 0)
        body = struct.pack("<I", flags) + b"part\0" + struct.pack("<QQ", len(v), len(f)) + v.tobytes() \
            + (uv.tobytes() if uv is not None else b"") + f.tobytes()
        blob += struct.pack("<HH", 0x041C, 4) + zlib.compress(body)
    blob += b"".join(struct.pack("<Q", o) for o in offsets) + struct.pack("<I", 2)
    (tmp_path / "m.serialized").write_bytes(bytes(blob))
    data = read(tmp_path, '<shape type="serialized"><string name="filename" value="m.serialized"/>'
                          '<integer name="shape_index" value="1"/></shape>')
    mesh = data["objects"][0]
    np.testing.assert_array_equal(mesh["vertices"], quad[0])
    np.testing.assert_array_equal(mesh["faces"], quad[1])
    np.testing.assert_array_equal(mesh["uvs"][:, 1], 1 - uvs[:, 1])
    assert lumos.load_scene(data).objects[0].triangle_count == 2  # inline arrays validate as a mesh
    # version 5 (Mitsuba's newest layout, documented in its serialized.cpp): packed 8-float vertex records
    records = np.zeros((4, 8), np.float32)
    records[:, :3], records[:, 6:] = quad[0], uvs
    body = struct.pack("<II", 0x1000 | 0x4, 4) + b"part" + struct.pack("<QQQQ", 4, 2, 0, 0) + records.tobytes() \
        + np.hstack([quad[1], np.zeros((2, 1), np.uint32)]).tobytes() + struct.pack("<I", 0)
    (tmp_path / "v5.serialized").write_bytes(struct.pack("<HH", 0x041C, 5) + zlib.compress(body))
    v5 = read(tmp_path, '<shape type="serialized"><string name="filename" value="v5.serialized"/></shape>')
    np.testing.assert_array_equal(v5["objects"][0]["faces"], quad[1])
    np.testing.assert_array_equal(v5["objects"][0]["uvs"], mesh["uvs"])
    try:
        mi = mitsuba()
    except pytest.skip.Exception:
        return
    shape = mi.load_dict({"type": "serialized", "filename": str(tmp_path / "m.serialized"), "shape_index": 1})
    theirs = np.array(mi.traverse(shape)["vertex_positions"]).reshape(-1, 3)
    np.testing.assert_allclose(np.sort(theirs, axis=0), np.sort(quad[0], axis=0))


def test_shapes_lights_and_instances(tmp_path):
    """Disk and sphere emitters become lumos area lights of the same shape; a spot's cone and a shapegroup placed
    twice by instances."""
    with pytest.warns(LumosWarning, match="spot"):
        data = read(tmp_path, """
      <shape type="disk"><transform name="to_world"><scale value="0.5"/><translate y="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
      <shape type="sphere"><point name="center" value="1 1 1"/><float name="radius" value="0.25"/>
        <transform name="to_world"><scale value="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
      <emitter type="spot"><float name="cutoff_angle" value="30"/><rgb name="intensity" value="3.14159265"/>
        <transform name="to_world"><lookat origin="0, 4, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
        <texture type="bitmap" name="texture"/></emitter>
      <shape type="shapegroup" id="pair">
        <shape type="cube"/><shape type="cylinder"><float name="radius" value="0.5"/></shape></shape>
      <shape type="instance"><ref id="pair"/><transform name="to_world"><translate x="5"/></transform></shape>
      <shape type="instance"><ref id="pair"/><transform name="to_world"><translate x="-5"/></transform></shape>
    """)
    disk, ball, spot = data["lights"]
    assert disk == {"type": "area", "shape": "disk", "center": [0, 2, 0], "normal": [0, 0, 1], "radius": 0.5,
                    "radiance": [4.0] * 3}
    assert ball["shape"] == "sphere" and ball["center"] == [2, 2, 2] and ball["radius"] == 0.5
    assert spot["type"] == "spot" and spot["angle"] == 30 and spot["inner_angle"] == 22.5
    assert spot["direction"] == pytest.approx([0, -1, 0]) and spot["intensity"] == pytest.approx([1.0] * 3)
    boxes = [o for o in data["objects"] if o["type"] == "box"]
    tubes = [o for o in data["objects"] if o["type"] == "cylinder"]
    assert [b["min"] for b in boxes] == [[4, -1, -1], [-6, -1, -1]]
    assert [t["base"] for t in tubes] == [[5, 0, 0], [-5, 0, 0]] and tubes[0]["capped"] is False


def test_textures(tmp_path):
    """A bitmap becomes an image texture (its path relative to the scene's folder) and turns a rectangle's v
    edge downwards (Mitsuba's v runs down the image, lumos's up); a checkerboard is lumos's checker at twice
    the uv scale."""
    from PIL import Image

    (tmp_path / "img").mkdir()
    Image.new("RGB", (4, 4), (200, 20, 20)).save(tmp_path / "img" / "wood.png")
    data = read(tmp_path, """
      <shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
        <string name="filename" value="img/wood.png"/><string name="wrap_mode" value="clamp"/>
        <transform name="to_uv"><scale x="2" y="3"/><translate x="0.5"/></transform></texture></bsdf></shape>
      <shape type="rectangle"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="1"/><transform name="to_uv"><scale value="4"/></transform></texture></bsdf></shape>
    """)
    wood, board = data["objects"]
    assert wood["material"]["texture"] == [{"type": "image", "file": "img/wood.png", "apply_to": ["kd"],
                                            "wrap": "clamp", "scale": [2, 3], "offset": [0.5, 0]}]
    assert wood["corner"] == [-1, 1, 0] and wood["edge_v"] == [0, -2, 0]
    assert board["material"]["texture"] == [{"type": "checker", "colors": [[1, 1, 1], [0.2, 0.2, 0.2]],
                                             "apply_to": ["kd"], "scale": [8, 8]}]
    assert board["corner"] == [-1, -1, 0] and board["edge_v"] == [0, 2, 0]


def test_other_bsdfs(tmp_path):
    """thindielectric: a mirror of 2R/(1 + R) and the rest passed straight on; blendbsdf mixes coefficients;
    principled reads as lumos's principled material, glTF's metallic-roughness BRDF (whose classic reading of a
    metal has no kd and its colour in ks and kr)."""
    with pytest.warns(LumosWarning):
        data = read(tmp_path, """
      <shape type="sphere"><bsdf type="thindielectric"/></shape>
      <shape type="sphere"><bsdf type="blendbsdf"><float name="weight" value="0.25"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf><bsdf type="conductor"/></bsdf></shape>
      <shape type="sphere"><bsdf type="principled"><rgb name="base_color" value="0.9 0.6 0.2"/>
        <float name="metallic" value="1"/><float name="roughness" value="0.5"/></bsdf></shape>""")
    thin, blend, metal = (o["material"] for o in data["objects"])
    r = ((1.5046 / 1.000277 - 1) / (1.5046 / 1.000277 + 1)) ** 2
    assert thin == {"kr": pytest.approx(2 * r / (1 + r)), "kt": pytest.approx(1 - 2 * r / (1 + r)), "ior": 1.0}
    assert blend == {"kd": pytest.approx([0.6] * 3), "kr": pytest.approx([0.25] * 3)}
    principled = dict(metal["principled"])
    assert principled.pop("base_color") == pytest.approx([0.9, 0.6, 0.2])
    assert principled == pytest.approx({"metallic": 1.0, "roughness": 0.5, "ior": 1.5, "transmission": 0.0,
                                        "clearcoat": 0.0, "clearcoat_roughness": math.sqrt(0.1)})
    classic = Material.model_validate(metal).classic()
    assert classic["kd"] == (0, 0, 0) and classic["kr"] == pytest.approx([0.9 * 0.25, 0.6 * 0.25, 0.2 * 0.25])


def test_an_environment_map_is_lumos_image_environment_mirrored_and_turned(tmp_path):
    """An envmap becomes `environment: {file, scale, rotation}`: its image rolled by half its width (Mitsuba looks
    along −z at the image's left edge, lumos at its middle), a to_world about +y as the rotation."""
    from lumos.io.image_files import write_image

    image = np.zeros((4, 8, 3), np.float32)
    image[:, 1] = 2.0
    write_image(tmp_path / "sky.exr", image, srgb=False)
    data = read(tmp_path, '<emitter type="envmap"><string name="filename" value="sky.exr"/>'
                          '<float name="scale" value="0.5"/><transform name="to_world"><rotate y="1" angle="30"/>'
                          '</transform></emitter>')
    env = data["environment"]
    assert env["scale"] == 0.5 and env["rotation"] == pytest.approx(30.0)
    np.testing.assert_array_equal(np.load(env["file"]), np.roll(image, 4, axis=1))


@pytest.mark.slow
def test_an_envmap_lit_sphere_matches_mitsuba(tmp_path):
    """Where Mitsuba 3 is installed: a diffuse sphere and a gold one on a floor under an environment map with a
    small sun (an EXR) and a turn about +y, the same XML file rendered by both: every 8×8 block on the objects
    within noise, and their mean within 1%."""
    mi = pytest.importorskip("mitsuba")
    from lumos.io.image_files import write_image

    h, w = 32, 64
    v = (np.arange(h) + 0.5) / h
    sky = np.stack([0.2 + 0.3 * (1 - v), 0.3 + 0.3 * (1 - v), 0.5 + 0.4 * (1 - v)], axis=1)[:, None, :]
    image = np.repeat(sky, w, axis=1).astype(np.float32)
    image[h // 2:] *= 0.3
    image[6:8, 40:43] = 60.0  # a sun, off to one side
    write_image(tmp_path / "sky.exr", image, srgb=False)
    xml = tmp_path / "env.xml"
    xml.write_text("""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/><string name="fov_axis" value="y"/>
    <transform name="to_world"><lookat origin="0, 1.2, 4" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/>
      <rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="256"/></sampler></sensor>
  <emitter type="envmap"><string name="filename" value="sky.exr"/>
    <transform name="to_world"><rotate y="1" angle="40"/></transform></emitter>
  <shape type="rectangle"><transform name="to_world"><scale value="10"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="-0.8" y="0.5" z="0"/><float name="radius" value="0.5"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="0.6" y="0.5" z="0"/><float name="radius" value="0.5"/>
    <bsdf type="roughconductor"><string name="material" value="Au"/><string name="distribution" value="ggx"/>
      <float name="alpha" value="0.2"/></bsdf></shape>
</scene>""")
    mi.set_variant("scalar_rgb")
    scene = mi.load_file(str(xml))
    blocks = lambda a: a.reshape(6, 8, 8, 8, 3).mean(axis=(1, 3))  # noqa: E731
    runs = [blocks(np.asarray(mi.render(scene, seed=s), np.float64)) for s in range(4)]
    theirs = np.mean(runs, axis=0)
    var_t = np.var(runs, axis=0, ddof=1) / len(runs)
    img = lumos.render(str(xml), spp=1024, aov=["variance", "object_id"], seed=3)
    ours = blocks(img.array.astype(np.float64))
    z = (ours - theirs) / np.sqrt(blocks(img.aovs["variance"].astype(np.float64)) / 64 + var_t + 1e-12)
    # the blocks wholly on the spheres and the floor: the sky seen directly is looked up bilinearly by Mitsuba and
    # per pixel by lumos (a difference of a few thousandths there, where neither image has any noise)
    lit = blocks(np.repeat((img.aovs["object_id"] >= 0)[..., None], 3, axis=2).astype(np.float64)) == 1.0
    assert lit.sum() > 60
    assert np.abs(z[lit]).max() < 5.0, np.abs(z[lit]).max()
    # Mitsuba filters the map bilinearly, lumos reads it per pixel (what its sampling draws): the sun's edges and
    # the horizon differ a little, and the mean by 0.3% (measured: 0.9970, z mean −0.9 over the blocks)
    assert ours[lit].mean() == pytest.approx(theirs[lit].mean(), rel=0.01)


# ------------------------------------------------------------------------------------------------ bad input


def _truncated(tmp_path):
    text = (MITSUBA / "cornell_box.xml").read_text()
    path = tmp_path / "cut.xml"
    path.write_text(text[: len(text) // 2])
    return path, text[: len(text) // 2].count("\n") + 1, "invalid XML"


BAD = {
    "truncated": _truncated,
    "missing include": lambda d: (write(d, '\n<include filename="nope.xml"/>'), 3,
                                  "included file 'nope.xml' not found"),
    "bad number": lambda d: (write(d, '<shape type="sphere">\n<float name="radius" value="1,5"/></shape>'), 3,
                             "'1,5' is not a number"),
    "undefined parameter": lambda d: (write(d, '\n\n<shape type="sphere"><float name="radius" value="$r"/></shape>'),
                                      4, "undefined parameter $r"),
    "unknown ref": lambda d: (write(d, '<shape type="sphere">\n<ref id="gold"/></shape>'), 3,
                              "<ref id=\"gold\">: no object has that id"),
    "include cycle": lambda d: (write(d, '<include filename="b.xml"/>', "a.xml")
                                and write(d, '\n<include filename="a.xml"/>', "b.xml"), 3, "<include> cycle"),
    "duplicate id": lambda d: (write(d, '<bsdf type="diffuse" id="a"/>\n<bsdf type="diffuse" id="a"/>'), 3,
                               "duplicate id 'a' (first at"),
    "ref cycle": lambda d: (write(d, '\n<bsdf type="twosided" id="a"><ref id="a"/></bsdf>'), 3,
                           "contains itself through <ref>s"),
    "entity": lambda d: (d.joinpath("scene.xml").write_text('<?xml version="1.0"?>\n<!DOCTYPE s [<!ENTITY a "a">]>'
                                                            '<scene version="3.0.0"/>') and d / "scene.xml", 2,
                         "entity declarations are not read"),
    "invalid value": lambda d: (write(d, '\n<shape type="cylinder"><float name="radius" value="-1"/></shape>'), 3,
                                "objects[0].radius: must be greater than 0"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_is_one_line_at_the_files_line(tmp_path, capsys, case):
    """Each problem: exit code 2 and one line `<file>:<line>: <what>` from the CLI (never a traceback)."""
    path, line, what = BAD[case](tmp_path)
    if case == "include cycle":
        path = tmp_path / "a.xml"
    code, out, err = run_cli(capsys, "info", path)
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("lumos: error: "), err
    where = tmp_path / "b.xml" if case == "include cycle" else path
    assert f"{where}:{line}: " in err and what in err, err
    with pytest.raises(LumosError):
        lumos.load_scene(path)


def test_an_unknown_plugin_is_a_warning_not_an_error(tmp_path, capsys):
    path = write(tmp_path, '<shape type="sphere"><bsdf type="hair"/></shape><emitter type="sunsky"/>')
    code, out, err = run_cli(capsys, "info", path)
    assert code == 0, err
    assert "bsdf 'hair' is not supported; a diffuse 0.5 grey" in err and "emitter 'sunsky'" in err


# ------------------------------------------------------------------------------------------------ against Mitsuba


def _blocks(a, k=8):
    h, w = a.shape[:2]
    return a.reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*the environment lights the scene:lumos.errors.LumosWarning")
@pytest.mark.parametrize("name", ["sphere_lights", "area_lights", "glass", "metals", "cornell_box"])
def test_the_same_file_renders_as_mitsuba_renders_it(name):
    """tests/data/mitsuba/<name>.xml rendered by Mitsuba 3 (scalar_rgb, two seeds: their difference gives its
    noise) and by lumos (its variance AOV) at 64×64: a z-test on every 8×8 block and channel."""
    mi = mitsuba()
    path = MITSUBA / f"{name}.xml"
    size = {"resx": "64", "resy": "64"} if name == "cornell_box" else {"res": "64"}
    scene = mi.load_file(str(path), spp="128", **size)
    a, b = (np.array(mi.render(scene, seed=seed), np.float64) for seed in (11, 12))
    ours = lumos.render(path, width=64, height=64, spp=256, aov=["variance"], seed=3)
    var_theirs = _blocks(0.25 * (a - b) ** 2) / 64  # variance of the block mean of (a + b)/2
    var_ours = _blocks(ours.aovs["variance"].astype(np.float64)) / 64
    z = (_blocks(ours.array.astype(np.float64)) - _blocks(0.5 * (a + b))) / np.sqrt(var_ours + var_theirs + 1e-8)
    assert np.abs(z).max() < 5.5, (name, np.abs(z).max())
    assert abs(z.mean()) < 0.3, (name, z.mean())


@pytest.mark.slow
@pytest.mark.parametrize("alpha", ["0.05", "0.2", "0.5"])
def test_rough_glass_renders_as_mitsuba_renders_it(alpha):
    """tests/data/mitsuba/rough_glass.xml (a `roughdielectric` sphere, GGX, bk7 in air, over a checkerboard under
    a lamp and a dim sky) at three widths, rendered by Mitsuba 3 and by lumos from the same file: a z-test on
    every 8×8 block and channel (measured: max |z| 2.0, 2.0, 2.4; means within 0.1%)."""
    mi = mitsuba()
    path = MITSUBA / "rough_glass.xml"
    scene = mi.load_file(str(path), spp="128", res="64", alpha=alpha)
    a, b = (np.array(mi.render(scene, seed=seed), np.float64) for seed in (11, 12))
    ours = lumos.render(read_mitsuba(path, {"alpha": alpha})[0], spp=256, aov=["variance"], seed=3)
    var_theirs = _blocks(0.25 * (a - b) ** 2) / 64
    var_ours = _blocks(ours.aovs["variance"].astype(np.float64)) / 64
    z = (_blocks(ours.array.astype(np.float64)) - _blocks(0.5 * (a + b))) / np.sqrt(var_ours + var_theirs + 1e-8)
    assert np.abs(z).max() < 5.5, (alpha, np.abs(z).max())
    assert abs(z.mean()) < 0.3, (alpha, z.mean())


@pytest.mark.slow
def test_mitsubas_cornell_box_file_matches_the_stored_mitsuba_render():
    """tests/data/mitsuba/cornell_box.xml (mi.cornell_box() written out by Mitsuba: unbounded depth, box filter,
    the lamp reflecting with its white BSDF) read by lumos against Mitsuba's converged 256×256 render of it
    (tests/data/cornell_mitsuba/ref_lamp_depthinf_256.npy, 8,192 spp), as tests/methods/test_path.py tests
    examples/path/cornell.yaml."""
    reference = np.load(DATA / "cornell_mitsuba" / "ref_lamp_depthinf_256.npy").astype(np.float64)
    img = lumos.render(MITSUBA / "cornell_box.xml", spp=128, aov=["variance"], seed=5)
    assert img.array.shape == reference.shape
    se = np.sqrt(_blocks(img.aovs["variance"].astype(np.float64)) / 64 + (0.0021 / 8) ** 2)
    z = (_blocks(img.array.astype(np.float64)) - _blocks(reference)) / se
    assert np.abs(z).max() < 5.5, np.abs(z).max()
    assert abs(z.mean()) < 0.15, z.mean()
