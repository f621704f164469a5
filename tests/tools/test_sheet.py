"""`lumos sheet` and `lumos.sheet`: the grid's size, the cells are the renders pixel for pixel, captions carry text,
and bad input is one line with exit status 2.

Most tests register fake methods in `lumos.api.METHODS` (a fake `raster` whose grey level follows `shading`, and
a second fake method), so the grid holds several cells without compiling a kernel; the ones marked slow render
with the real `raycast`.
"""

import io
import re
import sys
import types
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import EXAMPLES, TINY
from PIL import Image as PILImage

import lumos
from lumos import api, cli, tonemap
from lumos.tools import sheet
from lumos.tools import sheet_drawing as drawing
from lumos.errors import LumosError
from lumos.methods.common import Film

#: Grey level of the fake raster per shading, and of the second fake method.
LEVELS = {("raster", "flat"): 0.1, ("raster", "gouraud"): 0.3, ("raster", "phong"): 0.9, ("ramp", None): 0.6}


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return path


def scene_file(tmp_path, width, height):
    path = tmp_path / f"scene{width}x{height}.yaml"
    path.write_text(TINY.replace("width: 32, height: 24", f"width: {width}, height: {height}"))
    return path


def fake_radiance(method, shading, width, height):
    """A horizontal ramp up to the method's level, with a bright first column so any offset shows."""
    level = LEVELS[(method, shading if method == "raster" else None)]
    radiance = np.empty((height, width, 3), np.float32)
    radiance[:] = np.linspace(0.0, level, width, dtype=np.float32)[None, :, None]
    radiance[:, 0] = (1.0, 0.0, 0.0)
    return radiance


@pytest.fixture
def fakes(monkeypatch):
    """`api.METHODS` = a fake 'raster' and a fake 'ramp'; returns the settings of every call, in order."""
    calls = []

    def render_fake(compiled, camera, settings, progress=None):
        calls.append(settings)
        return Film(fake_radiance(settings.method, settings.shading, settings.width, settings.height))

    module = types.ModuleType("lumos_sheet_fakes")
    module.render_fake = render_fake
    monkeypatch.setitem(sys.modules, module.__name__, module)
    monkeypatch.setattr(api, "METHODS", {"raster": f"{module.__name__}:render_fake",
                                         "ramp": f"{module.__name__}:render_fake"})
    return calls


def run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    _, err = capsys.readouterr()
    return code, err


def one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lumos: error: "), err
    return lines[0]


def read_png(path) -> np.ndarray:
    with PILImage.open(path) as img:
        assert img.format == "PNG" and img.mode == "RGB"
        return np.asarray(img)


def crop(pixels, box):
    x, y, w, h = box
    return pixels[y : y + h, x : x + w]


def cell_box(lay, i, width, height):
    """Where `compose_sheet` puts render `i`: at the top of its slot, centred across the slot."""
    x, y = lay.slot(i)
    return x + (lay.slot_w - width) // 2, y, width, height


def dark_pixels(pixels) -> int:
    return int((pixels.max(axis=2) < 128).sum())


# ------------------------------------------------------------------------------------------------- entries


def test_default_entries_follow_the_registry(monkeypatch):
    monkeypatch.setattr(api, "METHODS", {"raycast": "lumos.methods.raycast:render_raycast"})
    assert sheet.default_entries() == [("raycast", {"method": "raycast", "shading": None})]
    monkeypatch.setattr(api, "METHODS", {"raycast": "x:y", "raster": "x:y"})
    entries = sheet.default_entries()
    assert [label for label, _ in entries] == ["raster · flat", "raster · Gouraud", "raster · Phong", "raycast"]
    assert [s["shading"] for _, s in entries] == ["flat", "gouraud", "phong", None]


def test_entries_for_keeps_the_order_named(fakes):
    labels = [label for label, _ in sheet.entries_for(["ramp", " raster", "ramp"])]
    assert labels == ["ramp", "raster · flat", "raster · Gouraud", "raster · Phong"]
    with pytest.raises(LumosError, match="unknown method 'nope'"):
        sheet.entries_for(["raster", "nope"])
    with pytest.raises(LumosError, match="at least one method"):
        sheet.entries_for(["", " "])


def test_entries_of_unavailable_methods_are_skipped(fakes, tiny):
    entries = [("ghost", {"method": "ghost"}), ("ramp", {"method": "ramp"})]
    image, cells = sheet.make_sheet(tiny, entries)
    assert [c["label"] for c in cells] == ["ramp"] and image.size[0] < 2 * drawing.MIN_SLOT_WIDTH
    with pytest.raises(LumosError, match="no entry uses an available method"):
        sheet.make_sheet(tiny, [("ghost", {"method": "ghost"})])


# ------------------------------------------------------------------------------------------------ the grid


@pytest.mark.parametrize("columns, rows", [(None, 1), ("3", 2), ("2", 2), ("9", 1)])
def test_cli_sheet_size_is_columns_times_cells_plus_captions(capsys, fakes, tiny, tmp_path, columns, rows):
    out = tmp_path / "sheet.png"
    code, err = run(capsys, "sheet", tiny, "-o", out, "-q", *(["--columns", columns] if columns else []))
    assert code == 0, err
    n_columns = min(int(columns or 4), 4)  # 4 cells: raster ×3, ramp
    slot_w = max(32, drawing.MIN_SLOT_WIDTH)
    lay = drawing.layout(4, n_columns, 32, 24)
    assert (lay.columns, lay.rows) == (n_columns, rows)
    assert lay.caption_h >= drawing.LABEL_SIZE + drawing.TIME_SIZE and lay.header_h >= drawing.TITLE_SIZE
    expected = (drawing.MARGIN + n_columns * (slot_w + drawing.MARGIN),
                lay.header_h + rows * (24 + lay.caption_h + drawing.MARGIN))
    assert read_png(out).shape[1::-1] == expected


def test_wide_cells_set_the_column_width(capsys, fakes, tiny, tmp_path):
    out = tmp_path / "sheet.png"
    code, err = run(capsys, "sheet", tiny, "-o", out, "-q", "--width", 260, "--height", 10, "--columns", 2)
    assert code == 0, err
    lay = drawing.layout(4, 2, 260, 10)
    assert read_png(out).shape[1::-1] == (drawing.MARGIN + 2 * (260 + drawing.MARGIN),
                                          lay.header_h + 2 * (10 + lay.caption_h + drawing.MARGIN))


def test_cells_are_the_renders_in_reading_order(fakes, tiny):
    image, cells = sheet.make_sheet(tiny, columns=3)
    pixels = np.asarray(image)
    assert [c["label"] for c in cells] == ["raster · flat", "raster · Gouraud", "raster · Phong", "ramp"]
    lay = drawing.layout(4, 3, 32, 24)
    for i, cell in enumerate(cells):
        assert cell["box"] == cell_box(lay, i, 32, 24)
        alone = api.render(tiny, method=cell["method"], shading=cell["shading"])
        assert np.array_equal(crop(pixels, cell["box"]), tonemap.to_png8(alone.array)), cell["label"]
        assert cell["render_s"] == cell["image"].stats["render_s"] >= 0.0
    xs = sorted({c["box"][0] for c in cells})
    ys = sorted({c["box"][1] for c in cells})
    assert len(xs) == 3 and len(ys) == 2
    assert np.diff(xs).tolist() == [lay.slot_w + drawing.MARGIN] * 2
    assert ys[1] - ys[0] == 24 + lay.caption_h + drawing.MARGIN


def test_captions_and_title_carry_text(capsys, fakes, tiny, tmp_path):
    out = tmp_path / "sheet.png"
    code, err = run(capsys, "sheet", tiny, "-o", out, "-q", "--columns", 3)
    assert code == 0, err
    pixels = read_png(out)
    lay = drawing.layout(4, 3, 32, 24)

    def strip(i):  # the caption strip under slot i, below the frame line
        x, y = lay.slot(i)
        return pixels[y + 24 + 1 : y + 24 + lay.caption_h, x : x + lay.slot_w]

    for i in range(4):
        assert dark_pixels(strip(i)) > 30, f"caption {i} is blank"
    assert not np.array_equal(strip(0), strip(1))  # 'raster · flat' vs 'raster · Gouraud'
    assert dark_pixels(strip(4)) == 0  # an empty slot: the text above came from the captions
    assert dark_pixels(pixels[: lay.header_h]) > 50  # title and info line
    assert (pixels[0] == drawing.BACKGROUND).all()


def test_default_cell_size_is_capped_unless_a_width_is_given(fakes, tmp_path):
    wide = scene_file(tmp_path, 1280, 96)
    _, cells = sheet.make_sheet(wide, [("ramp", {"method": "ramp"})], warm_up=False)
    assert (cells[0]["image"].width, cells[0]["image"].height) == (640, 48)
    _, cells = sheet.make_sheet(wide, [("ramp", {"method": "ramp"})], warm_up=False, width=100)
    assert (cells[0]["image"].width, cells[0]["image"].height) == (100, 96)


def test_flags_reach_every_render_after_one_warm_up_each(capsys, fakes, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.png", "-q", "--spp", 3, "--threads", 1,
                    "--width", 20, "--height", 10)
    assert code == 0, err
    warm, timed = fakes[:4], fakes[4:]
    assert [(s.method, s.shading, s.width) for s in warm][:3] == [("raster", "flat", 8), ("raster", "gouraud", 8),
                                                                   ("raster", "phong", 8)]
    assert len(timed) == 4 and all((s.width, s.height, s.spp, s.threads) == (20, 10, 3, 1) for s in timed)
    assert [s.shading for s in timed[:3]] == ["flat", "gouraud", "phong"]


def test_methods_flag_picks_cells(capsys, fakes, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.png", "-q", "--methods", "ramp")
    assert code == 0, err
    assert {s.method for s in fakes} == {"ramp"}
    assert read_png(tmp_path / "s.png").shape[1] == drawing.MARGIN * 2 + drawing.MIN_SLOT_WIDTH


def test_progress_line_per_cell_unless_quiet(capsys, fakes, tiny, tmp_path):
    out = tmp_path / "s.png"
    code, err = run(capsys, "sheet", tiny, "-o", out)
    assert code == 0, err
    for i, label in enumerate(["raster · flat", "raster · Gouraud", "raster · Phong", "ramp"], 1):
        assert f"[{i}/4] {label}: 32x24, " in err
    assert err.rstrip().splitlines()[-1].endswith(f"-> {out}")
    code, err = run(capsys, "sheet", tiny, "-o", out, "-q")
    assert code == 0 and err == ""


def test_jpeg_output(capsys, fakes, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.JPG", "-q")
    assert code == 0, err
    with PILImage.open(tmp_path / "s.JPG") as img:
        assert img.format == "JPEG" and img.size == (drawing.layout(4, None, 32, 24).width,
                                                     drawing.layout(4, None, 32, 24).height)


def test_default_output_in_cwd(capsys, monkeypatch, fakes, tiny, tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    code, err = run(capsys, "sheet", tiny, "-q")
    assert code == 0, err
    assert read_png(work / "tiny-sheet.png").shape[2] == 3


# ----------------------------------------------------------------------------------------------- bad input


def test_unknown_method_in_methods(capsys, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.png", "--methods", "raycast,nope")
    assert code == 2 and "--methods: unknown method 'nope' (available: " in one_error_line(err)
    assert not (tmp_path / "s.png").exists()


@pytest.mark.parametrize("name", ["s.exr", "s.npy", "s.gif", "s"])
def test_only_png_or_jpeg_output(capsys, tiny, tmp_path, name):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / name)
    assert code == 2 and "a sheet is .png, .jpg, .jpeg" in one_error_line(err)
    assert list(tmp_path.iterdir()) == [tiny]


def test_missing_output_folder(capsys, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "no" / "s.png")
    assert code == 2 and "does not exist" in one_error_line(err)


def test_missing_scene(capsys, tmp_path):
    code, err = run(capsys, "sheet", tmp_path / "nope.yaml", "-o", tmp_path / "s.png")
    assert code == 2 and "nope.yaml: no such file" in one_error_line(err)


@pytest.mark.parametrize("flags, message", [
    (["--columns", "0"], "columns must be at least 1, got 0"),
    (["--spp", "0"], "render.spp: must be at least 1, got 0"),
    (["--width", "-3"], "render.width"),
])
def test_bad_values_fail_before_any_render(capsys, fakes, tiny, tmp_path, flags, message):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.png", *flags)
    assert code == 2 and message in one_error_line(err)
    assert fakes == [] and not (tmp_path / "s.png").exists()


def test_help_lists_sheet(capsys):
    assert cli.main(["--help"]) == 0 and "sheet" in capsys.readouterr().out
    assert cli.main(["sheet", "--help"]) == 0 and "--columns" in capsys.readouterr().out


# ---------------------------------------------------------------------------------------- real renders


@pytest.mark.slow
def test_raycast_cell_is_the_single_render_png(capsys, tiny, tmp_path):
    out = tmp_path / "sheet.png"
    code, err = run(capsys, "sheet", tiny, "-o", out, "-q", "--methods", "raycast")
    assert code == 0, err
    pixels = read_png(out)
    lay = drawing.layout(1, None, 32, 24)
    assert pixels.shape[1::-1] == (lay.width, lay.height)
    with PILImage.open(io.BytesIO(lumos.render(tiny, method="raycast").to_png_bytes())) as alone:
        expected = np.asarray(alone.convert("RGB"))
    assert dark_pixels(expected) < expected.shape[0] * expected.shape[1]  # the sphere is lit: not all black
    assert np.array_equal(crop(pixels, cell_box(lay, 0, 32, 24)), expected)


# ----------------------------------------------------------------------------- any scene: stand-ins, failures


@pytest.fixture
def broken(monkeypatch, fakes):
    """Beside the fakes, a method that refuses every scene, as a real one refuses what it cannot draw."""

    def render_broken(compiled, camera, settings, progress=None):
        raise LumosError("objects[0]: csg objects cannot be drawn by broken")

    module = sys.modules["lumos_sheet_fakes"]
    module.render_broken = render_broken
    monkeypatch.setitem(api.METHODS, "broken", f"{module.__name__}:render_broken")
    return fakes


def test_a_method_that_cannot_draw_the_scene_gets_a_cell_that_says_why(capsys, broken, tiny, tmp_path):
    out = tmp_path / "s.png"
    code, err = run(capsys, "sheet", tiny, "--methods", "ramp,broken", "-o", out)
    assert code == 0, err
    assert "1 not rendered" in err
    img, cells = sheet.make_sheet(tiny, sheet.entries_for(["ramp", "broken"]), warm_up=False)
    assert cells[0]["image"] is not None and cells[0]["error"] is None
    assert cells[1]["image"] is None and "csg objects cannot be drawn by broken" in cells[1]["error"]
    assert not cells[1]["error"].startswith(str(tiny))  # the title names the file
    # the failed cell is drawn: a light box with dark red text, the size the render would have had
    pixels = np.asarray(img)
    x, y, w, h = cells[1]["box"]
    assert (w, h) == (32, 24)
    box = pixels[y : y + h, x : x + w].reshape(-1, 3)
    assert (box == drawing.FAILED).all(axis=1).mean() > 0.5
    assert (box[:, 0].astype(int) - box[:, 2].astype(int) > 60).any()


def test_a_sheet_where_no_method_can_draw_the_scene_is_an_error(capsys, broken, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "--methods", "broken", "-q", "-o", tmp_path / "s.png")
    assert code == 2
    assert "no method could render the scene" in one_error_line(err)
    assert not (tmp_path / "s.png").exists()


def test_adaptive_anti_aliasing_becomes_supersampling_for_the_other_methods(fakes, tmp_path, monkeypatch):
    path = tmp_path / "adaptive.yaml"
    path.write_text(TINY.replace("width: 32, height: 24", "width: 32, height: 24, antialias: adaptive"))
    img, cells = sheet.make_sheet(path, sheet.entries_for(["ramp"]), warm_up=False)
    assert fakes[-1].antialias == "supersample" and fakes[-1].spp == sheet.ADAPTIVE_STAND_IN_SPP
    assert "supersampled" in cells[0]["label"]
    monkeypatch.setitem(api.METHODS, "whitted", api.METHODS["ramp"])
    jobs = sheet._jobs(lumos.scene.loader.load_scene(path), [("whitted", {"method": "whitted"})], {}, None)
    assert "antialias" not in jobs[0][1] and jobs[0][0] == "whitted"  # whitted keeps its own


# ------------------------------------------------------------------------------ --reference and --diff


def test_reference_syntax():
    assert sheet.parse_reference("whitted") == ("whitted", None)
    assert sheet.parse_reference(" raster:gouraud ") == ("raster", "gouraud")
    assert sheet.parse_reference("raster") == ("raster", None)
    choices = sheet.reference_choices()
    assert choices[:5] == ["raycast", "raster", "raster:flat", "raster:gouraud", "raster:phong"]
    for text, message in [("", "name the method of one cell"), ("nope", "unknown method 'nope' (choose from"),
                          ("whitted:phong", "only raster has shadings"),
                          ("raster:toon", "unknown raster shading 'toon' (choose from flat, gouraud, phong)")]:
        with pytest.raises(LumosError, match=re.escape(message)):
            sheet.parse_reference(text)


def test_figures_are_the_metrics_of_each_cell_against_the_reference(fakes, tiny):
    from lumos.tools import metrics

    _, cells = sheet.make_sheet(tiny, reference="raster:gouraud", warm_up=False)
    ref = cells[1]
    assert ref["reference"] and ref["figures"] is None and ref["label"] == "raster · Gouraud"
    for cell in (cells[0], cells[2], cells[3]):
        assert not cell["reference"]
        assert cell["figures"] == metrics.compare(cell["image"].array, ref["image"].array)
        assert cell["figures"]["rmse"] > 0.01 and cell["figures"]["mean_rel_error"] > 0.01
    # without a reference no cell has figures
    _, plain = sheet.make_sheet(tiny, warm_up=False)
    assert all(c["figures"] is None and not c["reference"] and c["diff_box"] is None for c in plain)


def test_raster_alone_names_the_cell_of_the_scenes_shading(fakes, tmp_path, tiny):
    _, cells = sheet.make_sheet(tiny, reference="raster", warm_up=False)
    assert [c["reference"] for c in cells] == [False, False, True, False]  # the scene's default, phong
    gouraud = tmp_path / "gouraud.yaml"
    gouraud.write_text(TINY.replace("height: 24}", "height: 24, shading: gouraud}"))
    _, cells = sheet.make_sheet(gouraud, reference="raster", warm_up=False)
    assert [c["reference"] for c in cells] == [False, True, False, False]


def test_the_reference_renders_first_and_progress_gives_the_figures(capsys, fakes, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.png", "--reference", "ramp")
    assert code == 0, err
    assert [(s.method, s.shading) for s in fakes[-4:]] == [("ramp", "phong"), ("raster", "flat"),
                                                           ("raster", "gouraud"), ("raster", "phong")]
    lines = [line for line in err.splitlines() if "] " in line]
    assert lines[0].startswith("lumos: sheet [4/4] ramp: 32x24, ") and lines[0].endswith(", reference")
    assert lines[1].startswith("lumos: sheet [1/4] raster · flat: 32x24, ")
    assert ", RMSE 0." in lines[1] and " · rel. err. " in lines[1] and lines[1].endswith("%")


def test_captions_get_a_figures_line(capsys, fakes, tiny, tmp_path):
    plain, with_ref = tmp_path / "plain.png", tmp_path / "ref.png"
    assert run(capsys, "sheet", tiny, "-o", plain, "-q")[0] == 0
    assert run(capsys, "sheet", tiny, "-o", with_ref, "-q", "--reference", "raster:flat")[0] == 0
    lay, lay_ref = drawing.layout(4, None, 32, 24), drawing.layout(4, None, 32, 24, figures=True)
    assert lay_ref.caption_h - lay.caption_h == drawing._line_height(drawing._fonts()["time"])
    pixels = read_png(with_ref)
    assert pixels.shape[:2] == (lay_ref.height, lay_ref.width) and read_png(plain).shape[0] == lay.height
    for i in range(4):  # the third caption line: "reference" or the figures, both text
        x, y = lay_ref.slot(i)
        third = pixels[y + 24 + lay.caption_h : y + 24 + lay_ref.caption_h, x : x + lay_ref.slot_w]
        assert dark_pixels(third) > 20 or (third.min(axis=2) < 200).sum() > 20, f"caption {i} has no third line"


@pytest.mark.parametrize("reference, columns, diff_rows", [("ramp", 3, [0]), ("raster:flat", 3, [0, 1]),
                                                            ("raster:flat", None, [0]), ("raster:flat", 1, [1, 2, 3])])
def test_diff_adds_rows_of_difference_images_on_one_scale(fakes, tiny, reference, columns, diff_rows):
    from lumos.tools import metrics

    plain, plain_cells = sheet.make_sheet(tiny, columns=columns, reference=reference, warm_up=False)
    image, cells = sheet.make_sheet(tiny, columns=columns, reference=reference, diff=True, warm_up=False)
    lay = drawing.layout(4, columns, 32, 24, figures=True, diff_rows=diff_rows)
    assert image.size == (lay.width, lay.height) and plain.size[1] == drawing.layout(4, columns, 32, 24,
                                                                                     figures=True).height
    # the sheet grows by the legend and the rows (none for a row that would only hold the reference)
    assert image.size[1] - plain.size[1] == lay.legend_h + len(diff_rows) * (24 + lay.diff_caption_h + drawing.MARGIN)
    pixels = np.asarray(image)
    assert [c["box"] for c in cells] == [c["box"] for c in plain_cells]  # the grid above is where it was
    ref = next(c for c in cells if c["reference"])
    scale = drawing.DIFF_SCALE / ref["image"].exposure
    for i, cell in enumerate(cells):
        if cell["reference"]:
            assert cell["diff_box"] is None
            continue
        x, y = lay.diff_slot(i)
        assert cell["diff_box"] == (x + (lay.slot_w - 32) // 2, y, 32, 24)
        expected = tonemap.quantize8(metrics.diff_image(cell["image"].array, ref["image"].array, scale=scale))
        assert np.array_equal(crop(pixels, cell["diff_box"]), expected), cell["label"]
        assert cell["diff_box"][1] > cell["box"][1] and cell["diff_box"][0] == cell["box"][0]  # under its cell
    # the legend's colour bar holds the ramp from black to white
    legend = pixels[lay.header_h + lay.grid_h : lay.header_h + lay.grid_h + lay.legend_h]
    assert (legend == 0).all(axis=2).any() and ((legend[..., 0] > 200) & (legend[..., 2] < 60)).any()


def test_a_failed_cell_has_no_figures_and_no_diff(broken, tiny):
    _, cells = sheet.make_sheet(tiny, sheet.entries_for(["ramp", "broken"]), reference="ramp", diff=True,
                                warm_up=False)
    assert cells[1]["image"] is None and cells[1]["figures"] is None and cells[1]["diff_box"] is None


@pytest.mark.parametrize("flags, message", [
    (["--reference", "nope"], "--reference: unknown method 'nope' (choose from raster, raster:flat, "),
    (["--reference", ""], "--reference: name the method of one cell"),
    (["--reference", "ramp:phong"], "only raster has shadings"),
    (["--reference", "raster:toon"], "unknown raster shading 'toon'"),
    (["--reference", "raster", "--methods", "ramp"], "--reference: the sheet has no raster:phong cell (its cells: "
                                                     "ramp)"),
    (["--diff"], "--diff: difference images are against a reference cell: give --reference METHOD too"),
])
def test_bad_reference_fails_before_any_render(capsys, fakes, tiny, tmp_path, flags, message):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.png", *flags)
    assert code == 2 and message in one_error_line(err)
    assert fakes == [] and not (tmp_path / "s.png").exists()


def test_a_reference_that_cannot_be_drawn_stops_the_sheet(capsys, broken, tiny, tmp_path):
    code, err = run(capsys, "sheet", tiny, "-o", tmp_path / "s.png", "-q", "--methods", "ramp,broken",
                    "--reference", "broken")
    line = one_error_line(err)
    assert code == 2 and "--reference: the reference cell (broken) could not be rendered: " in line
    assert "csg objects cannot be drawn by broken" in line
    assert not (tmp_path / "s.png").exists()
    assert len(broken) == 1  # the warm-up of ramp only: nothing rendered after the reference failed


def test_help_gives_reference_and_diff(capsys):
    assert cli.main(["sheet", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "--reference METHOD" in out and "raster:SHADING" in out and "--diff" in out
    assert f"at {drawing.DIFF_SCALE} of the display's white" in out
    for name in api.METHODS:
        assert name in out


# ----------------------------------------------------------------------------------------- every example

#: Radiosity kept cheap: each primitive one patch (a mesh triangle, a box face), a coarse tessellation, one
#: shadow ray per form factor, no refinement and a few solver steps; the shading is not what is tested here.
CHEAP_RADIOSITY = {"patch_size": 1e6, "subdivide": False, "visibility_samples": 1, "max_iterations": 4,
                   "rays": 20000}


def example_scenes() -> list[Path]:
    """Every scene file under examples/ (YAML or JSON holding `objects`; other YAML, if any, is not a scene)."""
    found = []
    for path in sorted(p for ext in ("yaml", "yml", "json") for p in EXAMPLES.glob(f"**/*.{ext}")):
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
        if isinstance(data, dict) and "objects" in data:
            found.append(path)
    return found


def test_the_examples_are_found():
    scenes = example_scenes()
    assert len(scenes) >= 10 and EXAMPLES / "whitted" / "classic.yaml" in scenes


@pytest.mark.slow
@pytest.mark.parametrize("path", example_scenes(), ids=lambda p: str(p.relative_to(EXAMPLES)))
def test_sheet_on_every_example(path):
    """The sheet of every example, tiny (48x36, 1 spp, radiosity kept cheap), against raycast with diffs: each
    cell either rendered, a finite image with finite figures, or is a failed cell that says why in one line."""
    image, cells = sheet.make_sheet(path, width=48, height=36, spp=1, tessellation=8, radiosity=CHEAP_RADIOSITY,
                                    warm_up=False, reference="raycast", diff=True)
    assert image.size[0] > 0 and len(cells) == len(sheet.default_entries())
    for cell in cells:
        if cell["image"] is not None:
            assert cell["error"] is None and np.isfinite(cell["image"].array).all(), cell["label"]
            assert cell["image"].array.shape == (36, 48, 3)
            if not cell["reference"]:
                assert np.isfinite([cell["figures"]["rmse"], cell["figures"]["mean_rel_error"]]).all()
                assert cell["diff_box"] is not None
        else:
            why = cell["error"]
            assert isinstance(why, str) and why.strip() and "\n" not in why, (cell["label"], why)
            assert cell["figures"] is None and cell["diff_box"] is None and cell["box"][2:] == (48, 36)
