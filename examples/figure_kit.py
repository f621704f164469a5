"""What the example folders' figure scripts share: captioned panels in a grid, and saving them.

    from figure_kit import compose, png8, save_image        # (each script puts examples/ on sys.path)
    page = compose([("caption", png8(img.array)), ...], columns=2)
    save_image(page, OUT / "figure.png", root=ROOT)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from lumos import tonemap

#: Caption lines under each panel, gap between panels, colours (white page, near-black text).
LINE_H, GAP, FONT_SIZE = 18, 6, 14
PAGE, INK = (255, 255, 255), (25, 25, 25)


def png8(linear: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """A linear image as the PNG would hold it: uint8 (H, W, 3), sRGB after `exposure`."""
    return tonemap.to_png8(np.ascontiguousarray(linear, np.float32), exposure)


def font(size: int = FONT_SIZE):
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: the fixed bitmap font
        return ImageFont.load_default()


def compose(panels: list[tuple[str, np.ndarray]], columns: int) -> Image.Image:
    """Panels (caption, uint8 image of one size) in a grid, each caption (lines split at '\\n') centred under
    its panel."""
    h, w = panels[0][1].shape[:2]
    lines = max(caption.count("\n") + 1 for caption, _ in panels)
    cap_h = lines * LINE_H + 8
    rows = -(-len(panels) // columns)
    page = Image.new("RGB", (columns * w + (columns - 1) * GAP, rows * (h + cap_h) + (rows - 1) * GAP), PAGE)
    draw = ImageDraw.Draw(page)
    f = font()
    for i, (caption, pixels) in enumerate(panels):
        row, col = divmod(i, columns)
        x, y = col * (w + GAP), row * (h + cap_h + GAP)
        page.paste(Image.fromarray(np.ascontiguousarray(pixels), mode="RGB"), (x, y))
        for k, text in enumerate(caption.split("\n")):
            tw = draw.textlength(text, font=f)
            draw.text((x + (w - tw) / 2, y + h + 4 + k * LINE_H), text, fill=INK, font=f)
    return page


def shown(path: Path, root: Path) -> str:
    """`path` relative to the repository root when it is inside it (for the scripts' printouts)."""
    return str(path.relative_to(root)) if path.is_relative_to(root) else str(path)


def save_image(page: Image.Image | np.ndarray, path: Path, root: Path) -> None:
    """Write `page` (a PIL image or uint8 array) to `path` and print its size."""
    if isinstance(page, np.ndarray):
        page = Image.fromarray(page, mode="RGB")
    page.save(path, optimize=True)
    print(f"{shown(path, root)}: {page.width}x{page.height}, {path.stat().st_size // 1024} KB", flush=True)
