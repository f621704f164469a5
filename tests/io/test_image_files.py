"""Image files: round trips per format, the PNG tone map, atomic writes and error messages."""

import os

import numpy as np
import pytest
from PIL import Image as PILImage

from lumos import tonemap
from lumos.errors import LumosError
from lumos.io import image_files as images
from lumos.io.image_files import SUPPORTED, check_output_path, read_image, write_image


@pytest.fixture
def rgb():
    """float32 (4, 5, 3) with distinct values, some above 1 and negative (linear formats keep them)."""
    return (np.arange(60, dtype=np.float32).reshape(4, 5, 3) - 5.0) / 17.0


# ------------------------------------------------------------------------------------------ sRGB and PNG


def test_srgb_curve_hand_values():
    # IEC 61966-2-1: 12.92·x below 0.0031308, 1.055·x^(1/2.4) − 0.055 above
    x = np.array([0.0, 0.001, 0.0031308, 0.5, 1.0])
    expected = [0.0, 0.01292, 0.04045, 1.055 * 0.5 ** (1 / 2.4) - 0.055, 1.0]
    np.testing.assert_allclose(tonemap.srgb_encode(x), expected, atol=2e-6)
    np.testing.assert_allclose(tonemap.srgb_decode(tonemap.srgb_encode(x)), x, atol=1e-7)
    assert tonemap.srgb_encode(np.float32([0.5])).dtype == np.float32


def test_to_png8_values_clamp_and_exposure():
    linear = np.array([[0.0, 0.5, 1.0, 2.0, -1.0, np.nan, 0.25]], dtype=np.float32)
    assert tonemap.to_png8(linear).tolist() == [[0, 188, 255, 255, 0, 0, 137]]
    # exposure scales before clamping: 0.25·2 = 0.5 → 188; 0.5·2 = 1 → 255
    assert tonemap.to_png8(linear, exposure=2.0)[0, [1, 6]].tolist() == [255, 188]
    assert tonemap.to_png8(linear, srgb=False)[0, :4].tolist() == [0, 128, 255, 255]


def test_png_written_with_srgb_values(tmp_path):
    linear = np.full((2, 3, 3), 0.5, dtype=np.float32)
    linear[0, 0] = [0.0, 1.0, 0.25]
    write_image(tmp_path / "a.PNG", linear)  # extension is case-insensitive
    with PILImage.open(tmp_path / "a.PNG") as img:
        assert img.format == "PNG" and img.mode == "RGB" and img.size == (3, 2)
        pixels = np.asarray(img)
    assert pixels[0, 0].tolist() == [0, 255, 137]
    assert (pixels[1] == 188).all()
    write_image(tmp_path / "e.png", linear, exposure=0.5)
    assert np.asarray(PILImage.open(tmp_path / "e.png"))[1, 1, 0] == 137  # 0.5 · 0.5 = 0.25 → 137


def test_png_grey_and_read_back_linear(tmp_path):
    grey = np.array([[0.0, 0.5], [1.0, 0.2]], dtype=np.float32)
    write_image(tmp_path / "g.png", grey)
    with PILImage.open(tmp_path / "g.png") as img:
        assert img.mode == "L"
    back = read_image(tmp_path / "g.png")
    assert back.shape == (2, 2, 3) and back.dtype == np.float32
    assert np.array_equal(back[..., 0], back[..., 2])
    np.testing.assert_allclose(back[..., 0], grey, atol=0.005)  # 8-bit quantisation, decoded to linear


def test_read_png_with_alpha_and_jpeg(tmp_path):
    rgba = np.zeros((2, 2, 4), dtype=np.uint8)
    rgba[..., 0], rgba[..., 3] = 188, 10
    PILImage.fromarray(rgba, mode="RGBA").save(tmp_path / "a.png")
    back = read_image(tmp_path / "a.png")
    assert back.shape == (2, 2, 3)
    np.testing.assert_allclose(back[0, 0], [tonemap.srgb_decode(188 / 255), 0, 0], atol=1e-6)
    PILImage.fromarray(np.full((8, 8, 3), 255, np.uint8)).save(tmp_path / "w.jpg")
    np.testing.assert_allclose(read_image(tmp_path / "w.jpg"), 1.0, atol=0.01)


# ------------------------------------------------------------------------------------------ linear formats


@pytest.mark.parametrize("ext", [".exr", ".pfm", ".npy"])
def test_linear_round_trip_rgb(tmp_path, rgb, ext):
    rgb[0, 0, 0] = np.inf
    write_image(tmp_path / f"x{ext}", rgb)
    back = read_image(tmp_path / f"x{ext}")
    assert back.dtype == np.float32 and back.flags.c_contiguous
    np.testing.assert_array_equal(back, rgb)  # bit-exact, unclamped, inf kept


@pytest.mark.parametrize("ext", [".exr", ".pfm", ".npy"])
def test_linear_round_trip_grey(tmp_path, rgb, ext):
    grey = rgb[..., 1].copy()
    write_image(tmp_path / f"y{ext}", grey)
    back = read_image(tmp_path / f"y{ext}")
    assert back.shape == (4, 5, 3)
    for c in range(3):
        np.testing.assert_array_equal(back[..., c], grey)


def test_exr_channels(tmp_path, rgb):
    import OpenEXR

    write_image(tmp_path / "c.exr", rgb)
    write_image(tmp_path / "y.exr", rgb[..., 0].copy())
    write_image(tmp_path / "i.exr", np.array([[-1, 3]], dtype=np.int32))
    with OpenEXR.File(str(tmp_path / "c.exr"), separate_channels=True) as f:
        assert sorted(f.channels()) == ["B", "G", "R"]
        np.testing.assert_array_equal(f.channels()["G"].pixels, rgb[..., 1])
    with OpenEXR.File(str(tmp_path / "y.exr"), separate_channels=True) as f:
        assert list(f.channels()) == ["Y"]
    with OpenEXR.File(str(tmp_path / "i.exr"), separate_channels=True) as f:
        pixels = f.channels()["Y"].pixels
        assert pixels.dtype == np.float32 and pixels.tolist() == [[-1.0, 3.0]]


def test_pfm_layout_bottom_row_first(tmp_path, rgb):
    write_image(tmp_path / "p.pfm", rgb)
    raw = (tmp_path / "p.pfm").read_bytes()
    header = b"PF\n5 4\n-1.0\n"
    assert raw.startswith(header) and len(raw) == len(header) + 4 * 60
    first_row = np.frombuffer(raw[len(header):], dtype="<f4", count=15).reshape(5, 3)
    np.testing.assert_array_equal(first_row, rgb[-1])  # the file starts with the image's bottom row
    write_image(tmp_path / "g.pfm", rgb[..., 0].copy())
    assert (tmp_path / "g.pfm").read_bytes().startswith(b"Pf\n5 4\n-1.0\n")


def test_pfm_big_endian_read(tmp_path):
    data = np.array([[1.5, 2.5], [3.5, 4.5]], dtype=">f4")  # stored bottom row first
    (tmp_path / "b.pfm").write_bytes(b"Pf\n2 2\n1.0\n" + data.tobytes())
    np.testing.assert_array_equal(read_image(tmp_path / "b.pfm")[..., 0], [[3.5, 4.5], [1.5, 2.5]])


def test_npy_stored_as_float32(tmp_path, rgb):
    write_image(tmp_path / "n.npy", rgb.astype(np.float64))
    stored = np.load(tmp_path / "n.npy")
    assert stored.dtype == np.float32 and stored.shape == (4, 5, 3)


# ------------------------------------------------------------------------------------------ atomic writes


@pytest.mark.parametrize("ext", SUPPORTED)
def test_failed_write_leaves_folder_unchanged(tmp_path, monkeypatch, rgb, ext):
    target = tmp_path / f"out{ext}"
    target.write_bytes(b"old contents")
    encoder = {".png": "_write_png", ".exr": "_write_exr", ".pfm": "_write_pfm", ".npy": "_write_npy"}[ext]

    def half_then_fail(path, data):
        with open(path, "wb") as f:
            f.write(b"half")
        raise RuntimeError("encoder crashed")

    monkeypatch.setattr(images, encoder, half_then_fail)
    with pytest.raises(RuntimeError, match="encoder crashed"):
        write_image(target, rgb)
    assert os.listdir(tmp_path) == [target.name]
    assert target.read_bytes() == b"old contents"


def test_write_replaces_and_keeps_usual_permissions(tmp_path, rgb):
    target = tmp_path / "out.npy"
    write_image(target, rgb)
    write_image(target, rgb * 2)
    assert os.listdir(tmp_path) == ["out.npy"]
    np.testing.assert_array_equal(np.load(target), rgb * 2)
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask  # not the 0600 of a temporary file


# ------------------------------------------------------------------------------------------ errors


def test_unknown_extension_lists_supported(tmp_path, rgb):
    with pytest.raises(LumosError, match=r"out\.tif.*\.png, \.exr, \.pfm, \.npy"):
        write_image(tmp_path / "out.tif", rgb)
    with pytest.raises(LumosError, match="no extension"):
        check_output_path(tmp_path / "out")
    assert os.listdir(tmp_path) == []


def test_missing_folder_and_directory(tmp_path, rgb):
    with pytest.raises(LumosError, match="folder .*nope.* does not exist") as info:
        write_image(tmp_path / "nope" / "out.png", rgb)
    assert "\n" not in str(info.value) and "out.png" in str(info.value)
    (tmp_path / "dir.png").mkdir()
    with pytest.raises(LumosError, match="is a directory"):
        check_output_path(tmp_path / "dir.png")
    (tmp_path / "file").write_text("x")
    with pytest.raises(LumosError, match="not a folder"):
        check_output_path(tmp_path / "file" / "out.png")


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root may write anywhere")
def test_read_only_folder(tmp_path, rgb):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        with pytest.raises(LumosError, match="permission denied"):
            check_output_path(folder / "out.png")
    finally:
        folder.chmod(0o755)


def test_check_output_path_writes_nothing(tmp_path):
    assert check_output_path(str(tmp_path / "ok.exr")) == tmp_path / "ok.exr"
    assert os.listdir(tmp_path) == []


def test_bad_array_shape(tmp_path):
    with pytest.raises(LumosError, match=r"\(2, 2, 4\)"):
        write_image(tmp_path / "x.exr", np.zeros((2, 2, 4), np.float32))


@pytest.mark.parametrize("ext", [".png", ".exr", ".pfm", ".npy", ".jpg"])
def test_read_corrupt_file(tmp_path, ext):
    path = tmp_path / f"bad{ext}"
    path.write_bytes(b"this is not an image\n" * 3)
    with pytest.raises(LumosError, match=f"cannot read image '.*bad{ext}'") as info:
        read_image(path)
    assert "\n" not in str(info.value)


def test_read_truncated_pfm_and_missing_file(tmp_path):
    (tmp_path / "t.pfm").write_bytes(b"PF\n2 2\n-1.0\n" + b"\0" * 8)
    with pytest.raises(LumosError, match="truncated"):
        read_image(tmp_path / "t.pfm")
    with pytest.raises(LumosError, match="missing.exr': file not found"):
        read_image(tmp_path / "missing.exr")
    with pytest.raises(LumosError, match="unsupported extension '.gif'"):
        read_image(tmp_path / "x.gif")


def test_permission_errors_become_lumos_errors(tmp_path, monkeypatch, rgb):
    # Works as root too: fake the folder check, then an OSError from the encoder itself.
    monkeypatch.setattr(images.os, "access", lambda path, mode: False)
    with pytest.raises(LumosError, match="out.png': permission denied"):
        check_output_path(tmp_path / "out.png")
    monkeypatch.undo()

    def denied(path, data):
        raise PermissionError(13, "Permission denied", path)

    monkeypatch.setattr(images, "_write_npy", denied)
    with pytest.raises(LumosError, match="cannot write image '.*out.npy': .*Permission denied"):
        write_image(tmp_path / "out.npy", rgb)
    assert os.listdir(tmp_path) == []
