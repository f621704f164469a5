"""Drawing a sheet (`lumos sheet`): the grid's layout, captions with each render's figures, difference images with
their legend, fonts and text fitting. `sheet` decides what to render; this module draws what it rendered.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Iterable, Optional

import numpy as np

from .. import tonemap
from ..errors import LumosError

#: Columns of the grid unless asked otherwise.
MAX_COLUMNS = 4
#: Narrowest column: a smaller render sits centred in a column this wide, so its caption stays legible.
MIN_SLOT_WIDTH = 200
#: Space around and between cells, and inside a caption strip above its first line.
MARGIN = 12
CAPTION_PAD = 5
#: Font sizes (pixels) of the title, the info line and the cell labels, and the render times.
TITLE_SIZE, INFO_SIZE, LABEL_SIZE, TIME_SIZE = 18, 12, 14, 12
#: Colours: white sheet, near-black text, grey secondary text, a light frame around each render.
BACKGROUND, INK, MUTED, FRAME = (255, 255, 255), (25, 25, 25), (105, 105, 105), (205, 205, 205)
#: Colour of a cell a method could not render, and of its text.
FAILED, FAILED_INK = (242, 242, 242), (150, 40, 40)
#: The error shown white in the difference images, in units of the display's white (linear radiance times
#: `exposure`: 1 is the PNG's full white); one scale for every difference image of a sheet, so equal colours
#: mean equal errors. Half of white: a missing texture or reflection saturates only where it is bright, and
#: noise and shading differences still show.
DIFF_SCALE = 0.5
#: Size of the colour bar in the difference images' legend, pixels.
LEGEND_BAR_W, LEGEND_BAR_H = 120, 10


def format_figures(figures: dict) -> str:
    """A cell's error figures as its caption gives them: `RMSE 0.0123 · rel. err. 4.5%`."""
    return f"RMSE {figures['rmse']:.3g} · rel. err. {format_percent(figures['mean_rel_error'])}"


def format_percent(fraction: float) -> str:
    """`4.5%`, `0.12%`, `12%`, `345%` (two significant figures, whole percents from 100%)."""
    percent = 100.0 * fraction
    return f"{percent:.0f}%" if abs(percent) >= 100 else f"{percent:.2g}%"


def format_seconds(seconds: float) -> str:
    """`0.84 s`, `12.3 s`, `4.2 ms`."""
    if seconds < 0.005:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds:.1f} s" if seconds >= 10 else f"{seconds:.2f} s"


# ------------------------------------------------------------------------------------------------- drawing


@dataclass(frozen=True)
class Layout:
    """Where everything goes on a sheet of `n` cells of at most `cell_w`×`cell_h` pixels, in `columns`."""

    columns: int
    rows: int
    cell_w: int
    cell_h: int
    slot_w: int     # column width: the cell, or MIN_SLOT_WIDTH if the cell is narrower
    header_h: int   # title and info lines, with the margin above them and the gap below
    caption_h: int  # label and time lines under each cell (and the figures line, with a reference)
    diff_rows: tuple[int, ...] = ()  # the grid rows that have a row of difference images under the grid
    legend_h: int = 0        # the difference images' colour scale, between the grid and them
    diff_caption_h: int = 0  # the label line under each difference image

    @property
    def grid_h(self) -> int:
        return self.rows * (self.cell_h + self.caption_h + MARGIN)

    @property
    def width(self) -> int:
        return MARGIN + self.columns * (self.slot_w + MARGIN)

    @property
    def height(self) -> int:
        diffs = self.legend_h + len(self.diff_rows) * (self.cell_h + self.diff_caption_h + MARGIN)
        return self.header_h + self.grid_h + diffs

    def slot(self, i: int) -> tuple[int, int]:
        """Top-left corner of cell `i`'s column slot (row-major)."""
        row, col = divmod(i, self.columns)
        return MARGIN + col * (self.slot_w + MARGIN), self.header_h + row * (self.cell_h + self.caption_h + MARGIN)

    def diff_slot(self, i: int) -> tuple[int, int]:
        """Top-left corner of the slot of cell `i`'s difference image: the cell's column, in the difference row
        of the cell's row (which must be one of `diff_rows`)."""
        row, col = divmod(i, self.columns)
        k = self.diff_rows.index(row)
        return (MARGIN + col * (self.slot_w + MARGIN),
                self.header_h + self.grid_h + self.legend_h + k * (self.cell_h + self.diff_caption_h + MARGIN))


def layout(n: int, columns: Optional[int], cell_w: int, cell_h: int, *, figures: bool = False,
           diff_rows: Iterable[int] = ()) -> Layout:
    """The `Layout` of `n` cells; `columns` None means min(MAX_COLUMNS, n), more than `n` means `n`.

    figures: the captions have a third line (error figures against a reference); diff_rows: the grid rows (from
    0) whose cells have difference images, each such row getting a row of them under the grid, in order, with
    the legend above them (none: no legend).
    """
    diff_rows = tuple(sorted(set(diff_rows)))
    columns = min(columns or MAX_COLUMNS, n)
    fonts = _fonts()
    header_h = MARGIN + _line_height(fonts["title"]) + _line_height(fonts["info"]) + MARGIN // 2
    caption_h = CAPTION_PAD + _line_height(fonts["label"]) + _line_height(fonts["time"]) * (2 if figures else 1)
    legend_h = 2 * _line_height(fonts["info"]) + 2 * CAPTION_PAD if diff_rows else 0
    diff_caption_h = CAPTION_PAD + _line_height(fonts["time"]) if diff_rows else 0
    return Layout(columns, -(-n // columns), cell_w, cell_h, max(cell_w, MIN_SLOT_WIDTH), header_h, caption_h,
                  diff_rows, legend_h, diff_caption_h)


def compose_sheet(cells: list[dict], columns: Optional[int] = None, title: str = "", info: str = "",
                  diff: bool = False):
    """Draw `cells` (dicts with label, render_s and image, a lumos `Image`) as a grid; returns a PIL RGB image.

    A cell whose "reference" is true is captioned "reference", one with "figures" gets them in its caption;
    with `diff`, every cell with figures also gets its difference image against the reference cell's image.
    Sets each cell's "box": (x, y, width, height) of its render in the sheet, and "diff_box" (or None).
    """
    from PIL import Image as PILImage
    from PIL import ImageDraw

    if not cells:
        raise LumosError("sheet: no cells to draw")
    sizes = [(c["image"].width, c["image"].height) if c.get("image") is not None else (c["width"], c["height"])
             for c in cells]
    ref = next((c for c in cells if c.get("reference")), None)
    with_diff = [i for i, c in enumerate(cells) if diff and ref is not None and c.get("figures") is not None]
    columns = min(columns or MAX_COLUMNS, len(cells))
    lay = layout(len(cells), columns, max(w for w, _ in sizes), max(h for _, h in sizes), figures=ref is not None,
                 diff_rows=[i // columns for i in with_diff])  # no row of differences where there are none
    sheet = PILImage.new("RGB", (lay.width, lay.height), BACKGROUND)
    draw = ImageDraw.Draw(sheet)
    fonts = _fonts()
    inner = lay.width - 2 * MARGIN
    draw.text((MARGIN, MARGIN), _fit(draw, title, fonts["title"], inner), fill=INK, font=fonts["title"])
    draw.text((MARGIN, MARGIN + _line_height(fonts["title"])), _fit(draw, info, fonts["info"], inner),
              fill=MUTED, font=fonts["info"])
    for i, (cell, (w, h)) in enumerate(zip(cells, sizes)):
        img = cell.get("image")
        slot_x, slot_y = lay.slot(i)
        x = slot_x + (lay.slot_w - w) // 2
        cell["box"] = (x, slot_y, w, h)
        if img is not None:
            sheet.paste(PILImage.fromarray(tonemap.to_png8(img.array, img.exposure), mode="RGB"), (x, slot_y))
        else:
            draw.rectangle((x, slot_y, x + w - 1, slot_y + h - 1), fill=FAILED)
            _wrapped(draw, "not rendered: " + cell.get("error", ""), fonts["time"], FAILED_INK, x, slot_y, w, h)
        draw.rectangle((x - 1, slot_y - 1, x + w, slot_y + h), outline=FRAME)
        y = slot_y + lay.cell_h + CAPTION_PAD
        when = (format_seconds(cell["render_s"]) if cell.get("render_s") is not None
                else cell.get("caption", "not rendered"))
        lines = [(cell["label"], fonts["label"], INK), (when, fonts["time"], MUTED)]
        if cell.get("reference"):
            lines.append(("reference", fonts["time"], INK))
        elif cell.get("figures") is not None:
            lines.append((format_figures(cell["figures"]), fonts["time"], MUTED))
        for text, font, colour in lines:
            _centred(draw, text, font, colour, slot_x, lay.slot_w, y)
            y += _line_height(font)
        cell["diff_box"] = None
    if with_diff:
        _draw_diffs(sheet, draw, lay, [cells[i] for i in with_diff], with_diff, ref)
    return sheet


def diff_scale(exposure: float = 1.0) -> float:
    """The error (linear radiance) that the difference images show white: DIFF_SCALE of the display's white."""
    return DIFF_SCALE / exposure


def _draw_diffs(sheet, draw, lay: Layout, cells: list[dict], slots: list[int], ref: dict) -> None:
    """The legend, then each cell's difference image against `ref` in its slot `slots[k]`, with its label."""
    from PIL import Image as PILImage

    from . import metrics

    fonts = _fonts()
    scale = diff_scale(ref["image"].exposure)
    # legend: what the images show, and the colour bar from 0 to the scale's maximum
    y = lay.header_h + lay.grid_h
    info_h = _line_height(fonts["info"])
    text = "difference from the reference, |cell - reference|: largest channel, linear radiance, one scale"
    draw.text((MARGIN, y), _fit(draw, text, fonts["info"], lay.width - 2 * MARGIN), fill=INK, font=fonts["info"])
    y += info_h
    draw.text((MARGIN, y), "0", fill=MUTED, font=fonts["info"])
    bar_x = MARGIN + round(draw.textlength("0 ", font=fonts["info"]))
    bar_y = y + (info_h - 3 - LEGEND_BAR_H) // 2
    bar = tonemap.quantize8(metrics.heat_ramp(np.linspace(0.0, 1.0, LEGEND_BAR_W)[None, :].repeat(LEGEND_BAR_H, 0)))
    sheet.paste(PILImage.fromarray(bar, mode="RGB"), (bar_x, bar_y))
    draw.rectangle((bar_x - 1, bar_y - 1, bar_x + LEGEND_BAR_W, bar_y + LEGEND_BAR_H), outline=FRAME)
    tail_x = bar_x + LEGEND_BAR_W + round(draw.textlength(" ", font=fonts["info"]))
    tail = f"{scale:.3g} and more"
    if draw.textlength(tail, font=fonts["info"]) > lay.width - MARGIN - tail_x:
        tail = f"{scale:.3g}"  # a narrow sheet: the maximum alone
    draw.text((tail_x, y), tail, fill=MUTED, font=fonts["info"])
    for cell, i in zip(cells, slots):
        img = cell["image"]
        slot_x, slot_y = lay.diff_slot(i)
        x = slot_x + (lay.slot_w - img.width) // 2
        heat = metrics.diff_image(img.array, ref["image"].array, scale=scale)
        sheet.paste(PILImage.fromarray(tonemap.quantize8(heat), mode="RGB"), (x, slot_y))
        draw.rectangle((x - 1, slot_y - 1, x + img.width, slot_y + img.height), outline=FRAME)
        cell["diff_box"] = (x, slot_y, img.width, img.height)
        _centred(draw, cell["label"], fonts["time"], MUTED, slot_x, lay.slot_w, slot_y + lay.cell_h + CAPTION_PAD)


def _wrapped(draw, text: str, font, colour, x: int, y: int, width: int, height: int) -> None:
    """`text` word-wrapped into the box (x, y, width, height), from its top, lines that do not fit dropped."""
    pad = CAPTION_PAD
    line_h = _line_height(font)
    lines, line = [], ""
    for word in _printable(text, font).split():
        trial = f"{line} {word}".strip()
        if line and draw.textlength(trial, font=font) > width - 2 * pad:
            lines.append(line)
            line = word
        else:
            line = trial
    lines.append(line)
    for k, text_line in enumerate(lines[: max(1, (height - 2 * pad) // line_h)]):
        draw.text((x + pad, y + pad + k * line_h), _fit(draw, text_line, font, width - 2 * pad), fill=colour, font=font)


def _centred(draw, text: str, font, colour, x: int, width: int, y: int) -> None:
    text = _fit(draw, text, font, width)
    draw.text((x + (width - draw.textlength(text, font=font)) // 2, y), text, fill=colour, font=font)


def _fit(draw, text: str, font, width: int) -> str:
    """`text`, shortened with an ellipsis until it is at most `width` pixels wide."""
    text = _printable(text, font)
    if draw.textlength(text, font=font) <= width:
        return text
    dots = _printable("…", font)
    while text and draw.textlength(text + dots, font=font) > width:
        text = text[:-1]
    return text.rstrip() + dots


def _printable(text: str, font) -> str:
    """The bitmap fallback font has Latin-1 at best: spell the middle dot and the ellipsis in ASCII."""
    from PIL import ImageFont

    if isinstance(font, ImageFont.FreeTypeFont):
        return text
    return text.replace("·", "-").replace("…", "...").encode("ascii", "replace").decode("ascii")


@lru_cache(maxsize=None)
def _fonts() -> dict:
    """Pillow's built-in font at each size (scalable since Pillow 10.1; the fixed bitmap font before that)."""
    from PIL import ImageFont

    def font(size: int):
        try:
            return ImageFont.load_default(size=size)
        except (TypeError, OSError):  # Pillow < 10.1 has no size; no FreeType means no scalable font
            return ImageFont.load_default()

    return {"title": font(TITLE_SIZE), "info": font(INFO_SIZE), "label": font(LABEL_SIZE), "time": font(TIME_SIZE)}


def _line_height(font) -> int:
    """Pixels from one line's top to the next: the glyph box of 'Ag' (ascender to descender) plus a gap."""
    return font.getbbox("Ag")[3] + 3
