"""The public Image: AOV files beside the image, display views of AOVs, PNG bytes for Jupyter."""

import io
import os

import numpy as np
import pytest
from PIL import Image as PILImage

from lumos.errors import LumosError
from lumos.image import Image, id_colors
from lumos.io.image_files import read_image

H, W = 3, 4


@pytest.fixture
def image():
    """A 4×3 image, radiance 0.5 everywhere; the left column hit nothing, the rest two objects at depth 2 and 4."""
    hit = np.ones((H, W), dtype=bool)
    hit[:, 0] = False
    depth = np.where(hit, 2.0, np.inf).astype(np.float32)
    depth[:, 3] = 4.0
    normal = np.where(hit[..., None], [0.0, 0.0, 1.0], 0.0).astype(np.float32)
    albedo = np.where(hit[..., None], [0.5, 0.25, 1.0], 0.0).astype(np.float32)
    object_id = np.where(hit, 0, -1).astype(np.int32)
    object_id[:, 3] = 7
    aovs = {"depth": depth, "normal": normal, "albedo": albedo, "object_id": object_id}
    stats = {"method": "raycast", "total_s": 0.8412, "render_s": 0.5}
    return Image(np.full((H, W, 3), 0.5), aovs=aovs, stats=stats)


def test_attributes_and_repr(image):
    assert image.array.dtype == np.float32 and image.array.flags.c_contiguous
    assert (image.width, image.height) == (W, H)
    assert repr(image) == "<lumos.Image 4x3 raycast 0.84 s>"
    assert repr(Image(np.zeros((2, 5, 3)))) == "<lumos.Image 5x2>"
    with pytest.raises(LumosError, match=r"\(2, 5\)"):
        Image(np.zeros((2, 5)))


def test_save_exr_writes_raw_aovs_beside_the_image(tmp_path, image):
    written = image.save(tmp_path / "out.exr")
    names = ["out.exr", "out.depth.exr", "out.normal.exr", "out.albedo.exr", "out.object_id.exr"]
    assert written == [tmp_path / n for n in names]
    assert sorted(os.listdir(tmp_path)) == sorted(names)
    np.testing.assert_array_equal(read_image(tmp_path / "out.exr"), image.array)
    depth = read_image(tmp_path / "out.depth.exr")[..., 0]
    assert np.isinf(depth[:, 0]).all() and (depth[:, 1] == 2.0).all()  # inf stays inf
    np.testing.assert_array_equal(read_image(tmp_path / "out.object_id.exr")[..., 0], image.aovs["object_id"])
    np.testing.assert_array_equal(read_image(tmp_path / "out.normal.exr"), image.aovs["normal"])


def test_save_npy_and_pfm_keep_depth_raw(tmp_path, image):
    image.save(tmp_path / "a.npy", aovs=["depth"])
    assert sorted(os.listdir(tmp_path)) == ["a.depth.npy", "a.npy"]
    depth = np.load(tmp_path / "a.depth.npy")
    assert depth.shape == (H, W) and depth.dtype == np.float32
    np.testing.assert_array_equal(depth, image.aovs["depth"])
    image.save(tmp_path / "b.pfm", aovs=["depth"])
    assert (tmp_path / "b.depth.pfm").read_bytes().startswith(b"Pf\n4 3\n")
    np.testing.assert_array_equal(read_image(tmp_path / "b.depth.pfm")[..., 0], image.aovs["depth"])


def test_save_png_uses_display_views(tmp_path, image):
    written = image.save(tmp_path / "out.png")
    assert [p.name for p in written] == ["out.png", "out.depth.png", "out.normal.png", "out.albedo.png",
                                         "out.object_id.png"]
    beauty = np.asarray(PILImage.open(tmp_path / "out.png"))
    assert beauty.shape == (H, W, 3) and (beauty == 188).all()  # 0.5 linear → 188 sRGB
    normal = np.asarray(PILImage.open(tmp_path / "out.normal.png"))
    assert normal[0, 1].tolist() == [128, 128, 255]  # 0.5·n + 0.5 stored as is
    assert (normal[:, 0] == 0).all()  # no hit: black
    depth = np.asarray(PILImage.open(tmp_path / "out.depth.png"))[..., 0]
    assert depth[0, 0] == 0 and depth[0, 1] > depth[0, 3] > 0  # near is bright, farthest still above black
    albedo = np.asarray(PILImage.open(tmp_path / "out.albedo.png"))
    assert albedo[0, 1].tolist() == [188, 137, 255]  # a colour: sRGB-encoded like the image


def test_save_without_aovs_and_bad_requests(tmp_path, image):
    assert image.save(tmp_path / "only.exr", aovs=False) == [tmp_path / "only.exr"]
    assert os.listdir(tmp_path) == ["only.exr"]
    with pytest.raises(LumosError, match="'specular'"):
        image.save(tmp_path / "x.exr", aovs=["specular"])
    with pytest.raises(LumosError, match="does not exist"):
        image.save(tmp_path / "missing" / "x.png")
    assert os.listdir(tmp_path) == ["only.exr"]


def test_aov_for_display(image):
    for name in image.aovs:
        view = image.aov_for_display(name)
        assert view.shape == (H, W, 3) and view.dtype == np.float32
        assert view.min() >= 0 and view.max() <= 1
        assert (view[:, 0] == 0).all()  # black where nothing was hit
    depth = image.aov_for_display("depth")
    np.testing.assert_allclose(depth[0, 1], 1 - 0.9 * 2 / 4, rtol=1e-6)  # normalised by the largest finite depth
    np.testing.assert_allclose(depth[0, 3], 0.1, rtol=1e-6)
    np.testing.assert_allclose(image.aov_for_display("normal")[1, 1], [0.5, 0.5, 1.0])
    np.testing.assert_allclose(image.aov_for_display("albedo")[1, 1], [0.5, 0.25, 1.0])
    ids = image.aov_for_display("object_id")
    assert not np.allclose(ids[0, 1], ids[0, 3])  # ids 0 and 7 get different colours
    np.testing.assert_array_equal(ids[0, 1], ids[2, 2])  # the same id, the same colour
    with pytest.raises(LumosError, match="no AOV 'nope'"):
        image.aov_for_display("nope")


def test_id_colors_are_fixed_and_distinct():
    colors = id_colors(np.arange(-1, 200).reshape(1, -1))[0]
    assert (colors[0] == 0).all() and (colors[1:] >= 0.25).all()
    assert len({tuple(c) for c in colors[1:].round(3).tolist()}) == 200
    np.testing.assert_array_equal(id_colors(np.array([[5]])), id_colors(np.array([[5]])))


def test_repr_png(image):
    data = image._repr_png_()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and data == image.to_png_bytes()
    with PILImage.open(io.BytesIO(data)) as png:
        assert png.format == "PNG" and png.size == (W, H)
        assert (np.asarray(png) == 188).all()
    brighter = Image(image.array, exposure=2.0).to_png_bytes()
    assert (np.asarray(PILImage.open(io.BytesIO(brighter))) == 255).all()
