"""Mesh import: each format's counts and values, normals and uvs only when the file has them, errors."""

import struct

import numpy as np
import pytest
from helpers import DATA, EXAMPLES

from lumos.errors import LumosError
from lumos.io.meshes import MeshData, load_mesh

EXAMPLE_DATA = EXAMPLES / "data"


def _check_types(mesh: MeshData):
    assert mesh.vertices.dtype == np.float64 and mesh.vertices.shape[1] == 3
    assert mesh.faces.dtype == np.int64 and mesh.faces.shape[1] == 3
    assert 0 <= mesh.faces.min() and mesh.faces.max() < len(mesh.vertices)
    for extra, width in ((mesh.normals, 3), (mesh.uvs, 2)):
        if extra is not None:
            assert extra.dtype == np.float64 and extra.shape == (len(mesh.vertices), width)


def _write_binary_ply(path, vertices, faces, normals=None, uvs=None):
    """A binary little-endian PLY written by hand (not by trimesh), optionally with nx ny nz and s t."""
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    fields += [("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4")] if normals is not None else []
    fields += [("s", "<f4"), ("t", "<f4")] if uvs is not None else []
    rows = np.zeros(len(vertices), dtype=fields)
    for i, name in enumerate("xyz"):
        rows[name] = vertices[:, i]
        if normals is not None:
            rows["n" + name] = normals[:, i]
    if uvs is not None:
        rows["s"], rows["t"] = uvs[:, 0], uvs[:, 1]
    tris = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    tris["n"], tris["i"] = 3, faces
    props = "".join(f"property float {name}\n" for name, _ in fields)
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n{props}"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    path.write_bytes(header.encode() + rows.tobytes() + tris.tobytes())
    return path


@pytest.fixture
def tetra():
    """A tetrahedron: float64 (4, 3) vertices and int64 (4, 3) faces."""
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.int64)
    return vertices, faces


# ------------------------------------------------------------------------------------------ formats


def test_ascii_ply_bunny():
    mesh = load_mesh(DATA / "bunny_res4.ply")
    _check_types(mesh)
    assert mesh.vertices.shape == (453, 3) and mesh.faces.shape == (948, 3)
    np.testing.assert_allclose(mesh.vertices[0], [-0.0312216, 0.126304, 0.00514924], rtol=1e-6)
    assert mesh.faces[0].tolist() == [164, 94, 98]  # the file's first face, indices unchanged
    assert mesh.normals is None and mesh.uvs is None


def test_ascii_ply_with_normals_uvs_and_a_quad():
    mesh = load_mesh(DATA / "quad_normals.ply")
    _check_types(mesh)
    assert mesh.vertices[1].tolist() == [2.0, 0.0, 0.0]
    assert mesh.faces.tolist() == [[0, 1, 2], [2, 3, 0]]  # the quad as two triangles
    np.testing.assert_array_equal(mesh.normals, np.tile([0.0, 0.0, 1.0], (4, 1)))
    np.testing.assert_array_equal(mesh.uvs, [[0, 0], [1, 0], [1, 1], [0, 1]])


def test_binary_ply(tmp_path, tetra):
    vertices, faces = tetra
    mesh = load_mesh(_write_binary_ply(tmp_path / "t.ply", vertices, faces))
    _check_types(mesh)
    np.testing.assert_array_equal(mesh.vertices, vertices)
    np.testing.assert_array_equal(mesh.faces, faces)
    assert mesh.normals is None and mesh.uvs is None


def test_binary_ply_keeps_file_normals_even_when_not_geometric(tmp_path, tetra):
    # Normals that no computation would give: they can only have come from the file.
    vertices, faces = tetra
    normals = np.array([[1, 0, 0], [0, 2, 0], [0, 0, -1], [1, 1, 0]], dtype=np.float64)
    uvs = np.array([[0, 0], [0.5, 0], [0, 0.5], [0.25, 0.75]])
    mesh = load_mesh(_write_binary_ply(tmp_path / "n.ply", vertices, faces, normals, uvs))
    expected = normals / np.linalg.norm(normals, axis=1, keepdims=True)  # returned at unit length
    np.testing.assert_allclose(mesh.normals, expected, atol=1e-7)
    np.testing.assert_allclose(mesh.uvs, uvs)


def test_obj_quad_with_vn_vt():
    mesh = load_mesh(DATA / "quad_vn_vt.obj")
    _check_types(mesh)
    assert mesh.vertices.shape == (4, 3) and mesh.faces.shape == (2, 3)
    np.testing.assert_allclose(mesh.normals, np.tile([0.0, 0.0, 1.0], (4, 1)))
    np.testing.assert_allclose(mesh.uvs, mesh.vertices[:, :2])  # vt equals (x, y) on this square
    assert sorted(map(tuple, mesh.vertices[mesh.faces[0]].tolist())) == [(0, 0, 0), (1, 0, 0), (1, 1, 0)]


def test_obj_split_vertices_keep_faces_and_normals_together():
    mesh = load_mesh(DATA / "corner_split.obj")
    _check_types(mesh)
    assert mesh.faces.shape == (2, 3) and len(mesh.vertices) == 6  # positions 1 and 2 carry two normals each
    file_positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    np.testing.assert_array_equal(mesh.vertices[mesh.faces[0]], file_positions[[0, 1, 2]])
    np.testing.assert_array_equal(mesh.vertices[mesh.faces[1]], file_positions[[0, 3, 1]])
    np.testing.assert_array_equal(mesh.normals[mesh.faces[0]], np.tile([0.0, 0, 1], (3, 1)))
    np.testing.assert_array_equal(mesh.normals[mesh.faces[1]], np.tile([0.0, 1, 0], (3, 1)))


def test_obj_without_normals_and_polygon(tmp_path):
    path = tmp_path / "pentagon.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1.5 0\nv 0 1 0\nf 1 2 3 4 5\n")
    mesh = load_mesh(path)
    assert mesh.vertices.shape == (5, 3) and mesh.faces.shape == (3, 3)  # fan of a pentagon
    assert mesh.normals is None and mesh.uvs is None


def test_ascii_stl():
    mesh = load_mesh(DATA / "triangle.stl")
    _check_types(mesh)
    np.testing.assert_array_equal(mesh.vertices[mesh.faces[0]], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert mesh.normals is None  # STL has face normals only


def test_binary_stl(tmp_path, tetra):
    vertices, faces = tetra
    body = b"".join(struct.pack("<12fH", 0, 0, 0, *vertices[f].ravel(), 0) for f in faces)
    path = tmp_path / "t.STL"  # extension is case-insensitive
    path.write_bytes(b"binary stl".ljust(80, b" ") + struct.pack("<I", len(faces)) + body)
    mesh = load_mesh(path)
    _check_types(mesh)
    assert mesh.faces.shape == (4, 3)
    np.testing.assert_array_equal(mesh.vertices[mesh.faces], vertices[faces])
    assert mesh.normals is None


def test_off(tetra):
    mesh = load_mesh(DATA / "tetra.off")
    _check_types(mesh)
    np.testing.assert_array_equal(mesh.vertices, tetra[0])
    np.testing.assert_array_equal(mesh.faces, tetra[1])
    assert mesh.normals is None and mesh.uvs is None


def test_example_bunny():
    mesh = load_mesh(EXAMPLE_DATA / "bunny.ply")
    assert mesh.vertices.shape == (35947, 3) and mesh.faces.shape == (69451, 3)
    assert mesh.normals is None


# ------------------------------------------------------------------------------------------ glTF scenes


def _gltf_scene(path, with_normals):
    """Two nodes: a triangle moved by +5 in x, and the same triangle scaled by (2, 1, 1) and mirrored in z."""
    import trimesh

    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
    normals = np.array([[1, 1, 0], [0, 0, 1], [0, 0, 1]], dtype=np.float64) / [[np.sqrt(2)], [1], [1]]
    scene = trimesh.Scene()
    for name, matrix in (("moved", np.eye(4)), ("scaled", np.diag([2.0, 1.0, -1.0, 1.0]))):
        if name == "moved":
            matrix[:3, 3] = [5, 0, 0]
        uv = trimesh.visual.TextureVisuals(uv=vertices[:, :2])
        tri = trimesh.Trimesh(vertices, [[0, 1, 2]], vertex_normals=normals if with_normals else None,
                              visual=uv, process=False)
        scene.add_geometry(tri, node_name=name, geom_name=name, transform=matrix)
    scene.export(path)
    return path


@pytest.mark.parametrize("ext", [".glb", ".gltf"])
def test_gltf_scene_flattened_with_transforms(tmp_path, ext):
    mesh = load_mesh(_gltf_scene(tmp_path / f"s{ext}", with_normals=True))
    _check_types(mesh)
    assert mesh.vertices.shape == (6, 3) and mesh.faces.shape == (2, 3)
    triangles = {tuple(map(tuple, mesh.vertices[f].round(6).tolist())): i for i, f in enumerate(mesh.faces)}
    moved = triangles.pop(((5, 0, 0), (6, 0, 0), (5, 1, 0)))
    (scaled_corners, scaled), = triangles.items()
    assert scaled_corners == ((0, 0, 0), (0, 1, 0), (2, 0, 0))  # mirrored: winding reversed
    # normals go by the inverse transpose: (1, 1, 0)/√2 under diag(2, 1, −1) → (0.5, 1, 0), normalised
    np.testing.assert_allclose(mesh.normals[mesh.faces[moved][0]], [2 ** -0.5, 2 ** -0.5, 0], atol=1e-6)
    np.testing.assert_allclose(mesh.normals[mesh.faces[scaled][0]], np.array([0.5, 1, 0]) / np.sqrt(1.25), atol=1e-6)
    np.testing.assert_allclose(mesh.normals[mesh.faces[scaled][1]], [0, 0, -1], atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)
    np.testing.assert_allclose(mesh.uvs[mesh.faces[moved]], [[0, 0], [1, 0], [0, 1]], atol=1e-6)


def test_gltf_without_normals(tmp_path):
    mesh = load_mesh(_gltf_scene(tmp_path / "s.glb", with_normals=False))
    assert mesh.faces.shape == (2, 3) and mesh.normals is None and mesh.uvs is not None


# ------------------------------------------------------------------------------------------ errors


@pytest.mark.parametrize(
    "name, content, reason",
    [
        ("empty.ply", b"", "empty"),
        ("garbage.ply", b"hello world\n", "not a valid PLY file"),
        ("garbage.glb", b"hello world\n", "not a valid GLB file"),
        ("points.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no triangles"),
        ("nan.off", b"OFF\n3 1 0\n0 0 0\nnan 0 0\n1 1 0\n3 0 1 2\n", "NaN or Inf"),
        ("inf.obj", b"v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or Inf"),
        ("badindex.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 7\n", "not a valid OFF file"),
        ("mesh.xyz", b"1 2 3\n", "unsupported extension '.xyz'"),
    ],
)
def test_bad_files(tmp_path, name, content, reason):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(LumosError) as info:
        load_mesh(path)
    message = str(info.value)
    assert message.startswith(f"cannot read mesh '{path}': ") and reason in message and "\n" not in message


def test_truncated_binary_ply(tmp_path, tetra):
    path = _write_binary_ply(tmp_path / "t.ply", *tetra)
    path.write_bytes(path.read_bytes()[:-20])
    with pytest.raises(LumosError, match="cannot read mesh .*t.ply"):
        load_mesh(path)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(LumosError, match=r"cannot read mesh '.*nope\.obj': file not found"):
        load_mesh(tmp_path / "nope.obj")
    (tmp_path / "d.ply").mkdir()
    with pytest.raises(LumosError, match="is a directory"):
        load_mesh(tmp_path / "d.ply")
