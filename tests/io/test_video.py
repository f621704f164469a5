"""Video files (`lumos.io.video`): MP4 and GIF read back with imageio (frame count, size), odd sizes, atomic
writes, missing packages."""

import sys

import numpy as np
import pytest

from lumos.errors import LumosError
from lumos.io.video import check_video_path, even, write_video

imageio = pytest.importorskip("imageio.v3")


def frames(n=5, h=24, w=32):
    """Frames whose brightness ramps up, with a moving bar, so consecutive frames differ."""
    out = []
    for k in range(n):
        f = np.full((h, w, 3), 30 + 40 * k, np.uint8)
        f[:, (3 * k) % w] = (255, 0, 0)
        out.append(f)
    return out


def test_mp4_encodes_every_frame(tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    out = tmp_path / "clip.mp4"
    assert write_video(out, iter(frames()), fps=12) == 5
    read = imageio.imread(out, index=None, plugin="FFMPEG")
    assert read.shape == (5, 24, 32, 3)
    # H.264 is lossy: the flat grey levels come back close
    assert abs(float(read[2, 12, 20].mean()) - 110) < 6
    assert [p.name for p in tmp_path.iterdir()] == ["clip.mp4"]  # no temporary file left


def test_mp4_of_an_odd_size_gets_even_dimensions(tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    out = tmp_path / "odd.mp4"
    write_video(out, frames(3, 23, 31), fps=24)
    assert imageio.imread(out, index=None, plugin="FFMPEG").shape == (3, 24, 32, 3)
    padded = even(np.arange(3 * 5 * 3, dtype=np.uint8).reshape(3, 5, 3))
    assert padded.shape == (4, 6, 3) and np.array_equal(padded[3, 5], padded[2, 4])


def test_gif_encodes_every_frame(tmp_path):
    out = tmp_path / "clip.gif"
    assert write_video(out, frames(), fps=10) == 5
    read = imageio.imread(out, index=None)
    assert read.shape[:3] == (5, 24, 32)
    assert np.array_equal(read[1, 0, 0, :3], [70, 70, 70])  # few colours: the palette holds them exactly
    assert np.array_equal(read[1, 0, 3, :3], [255, 0, 0])


def test_a_failing_frame_source_leaves_no_file(tmp_path):
    def failing():
        yield from frames(2)
        raise LumosError("frame 2 went wrong")

    for name in ("clip.gif", "clip.mp4"):
        with pytest.raises(LumosError, match="frame 2 went wrong"):
            write_video(tmp_path / name, failing(), fps=10)
    assert list(tmp_path.iterdir()) == []
    old = tmp_path / "old.gif"
    old.write_bytes(b"previous")
    with pytest.raises(ZeroDivisionError):  # an internal error is not turned into bad input
        write_video(old, (1 / 0 for _ in range(1)), fps=10)
    assert old.read_bytes() == b"previous"


def test_bad_video_paths_and_frames(tmp_path):
    with pytest.raises(LumosError, match=r"cannot write video '.*clip.avi': unsupported extension '.avi' "
                                         r"\(supported: .mp4, .gif\)"):
        check_video_path(tmp_path / "clip.avi")
    with pytest.raises(LumosError, match="folder '.*nowhere' does not exist"):
        check_video_path(tmp_path / "nowhere" / "clip.gif")
    with pytest.raises(LumosError, match="there are no frames"):
        write_video(tmp_path / "empty.gif", [], fps=10)
    with pytest.raises(LumosError, match="must all have one size"):
        write_video(tmp_path / "sizes.gif", [frames(1)[0], frames(1, 10, 10)[0]], fps=10)
    with pytest.raises(LumosError, match=r"\(H, W, 3\) uint8"):
        write_video(tmp_path / "float.gif", [np.zeros((4, 4, 3))], fps=10)
    assert list(tmp_path.iterdir()) == []


def test_mp4_without_imageio_ffmpeg_says_what_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # import fails
    with pytest.raises(LumosError) as info:
        write_video(tmp_path / "clip.mp4", frames(1), fps=10)
    assert str(info.value) == ('writing .mp4 video needs imageio-ffmpeg: pip install "lumos[animation]" (or pip '
                               'install imageio imageio-ffmpeg)')
    write_video(tmp_path / "clip.gif", frames(1), fps=10)  # GIF needs only Pillow
    assert [p.name for p in tmp_path.iterdir()] == ["clip.gif"]
