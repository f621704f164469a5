"""Render the before/after figures of docs/methods/raster.md from the scenes in this folder.

    python examples/raster/figures.py [NAME ...]   # writes docs/images/raster/*.png (only NAME.png with names)

Each figure loads one scene (`lumos.load_scene`), renders it twice or more with one key changed (a mesh key
set on the loaded scene, or a setting given to `lumos.render`), and puts the renders side by side with a
caption under each. `sheet.png` is `lumos sheet` of shading.yaml, made with `lumos.tools.sheet.make_sheet`.
The orientation figure also checks its claim in numbers: it prints the centre pixel of each render.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import lumos
from lumos import tonemap
from lumos.tools.sheet import make_sheet, save_sheet

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # examples/: the figure scripts' shared kit
from figure_kit import font  # noqa: E402

HERE = Path(__file__).resolve().parent
OUT = HERE.parents[1] / "docs" / "images" / "raster"

#: Caption strip under each panel, gap between panels, colours (white page, near-black text).
CAPTION_H, GAP, FONT_SIZE = 26, 6, 15
PAGE, INK = (255, 255, 255), (25, 25, 25)


# ------------------------------------------------------------------------------------------------ helpers


def load(name: str):
    return lumos.load_scene(HERE / name)


def shot(scene, **settings) -> np.ndarray:
    """The render as the PNG would hold it: uint8 (H, W, 3), sRGB after the scene's exposure."""
    img = lumos.render(scene, **settings)
    return tonemap.to_png8(img.array, img.exposure)


def compose(panels: list[tuple[str, np.ndarray]], columns: int) -> Image.Image:
    """Panels (caption, uint8 image of one size) in a grid, each with its caption centred under it."""
    h, w = panels[0][1].shape[:2]
    rows = -(-len(panels) // columns)
    page = Image.new("RGB", (columns * w + (columns - 1) * GAP, rows * (h + CAPTION_H) + (rows - 1) * GAP), PAGE)
    draw = ImageDraw.Draw(page)
    f = font(FONT_SIZE)
    for i, (caption, pixels) in enumerate(panels):
        row, col = divmod(i, columns)
        x, y = col * (w + GAP), row * (h + CAPTION_H + GAP)
        page.paste(Image.fromarray(np.ascontiguousarray(pixels), mode="RGB"), (x, y))
        tw = draw.textlength(caption, font=f)
        draw.text((x + (w - tw) / 2, y + h + (CAPTION_H - FONT_SIZE) / 2 - 1), caption, fill=INK, font=f)
    return page


def save(page: Image.Image, name: str) -> None:
    path = OUT / name
    page.save(path, optimize=True)
    report(path, page)


def report(path: Path, page: Image.Image) -> None:
    print(f"{path.relative_to(HERE.parents[1])}: {page.width}x{page.height}, {path.stat().st_size // 1024} KB")


# ------------------------------------------------------------------------------------------------ figures


def shading_figure():
    """Flat, Gouraud and Phong shading of shading.yaml, one above the other."""
    scene = load("shading.yaml")
    panels = [(f"shading: {name}", shot(scene, shading=name, width=560, height=280))
              for name in ("flat", "gouraud", "phong")]
    save(compose(panels, 1), "shading.png")


def sheet_figure():
    """`lumos sheet examples/raster/shading.yaml --width 320 --height 160`."""
    sheet, _ = make_sheet(HERE / "shading.yaml", width=320, height=160, title="examples/raster/shading.yaml")
    report(save_sheet(sheet, OUT / "sheet.png"), sheet)


def mesh_key_figure(scene_file, key, values, figure, columns, width, height):
    """The scene rendered once per value of a mesh key (set on every mesh object), side by side."""
    panels = []
    for value in values:
        scene = load(scene_file)
        for obj in scene.objects:
            if obj.type == "mesh":
                setattr(obj, key, value)
        label = str(value).lower() if isinstance(value, bool) else value
        panels.append((f"{key}: {label}", shot(scene, width=width, height=height)))
    save(compose(panels, columns), figure)


def t_junctions_figure():
    mesh_key_figure("t_junctions.yaml", "repair_t_junctions", (False, True), "t_junctions.png", 2, 320, 280)


def subdivision_figure():
    mesh_key_figure("subdivision.yaml", "subdivide", (0, 3), "subdivision.png", 1, 480, 300)


def orientation_figure():
    """2 x 2: triangulate false / true, camera upright / rolled 90 degrees (that render turned back upright,
    so both show the polygon the same way up). Prints the centre pixel of each."""
    size = 239  # odd: the centre pixel samples the polygon's centre
    c = size // 2
    panels, centres = [], {}
    for triangulate in (False, True):
        for rolled in (False, True):
            scene = load("orientation.yaml")
            scene.objects[0].triangulate = triangulate
            scene.camera.up = (1.0, 0.0, 0.0) if rolled else (0.0, 1.0, 0.0)
            img = lumos.render(scene, width=size, height=size)
            linear = img.array
            if rolled:  # up = +x: world +y points left on screen; a quarter turn clockwise puts it back up
                linear = np.ascontiguousarray(np.rot90(linear, k=-1))
            centres[triangulate, rolled] = linear
            camera = "camera rolled 90°" if rolled else "camera upright"
            caption = f"triangulate: {str(triangulate).lower()}, {camera}"
            print(f"orientation: {caption:37} centre pixel (linear RGB) "
                  + ", ".join(f"{v:.4f}" for v in linear[c, c]))
            panels.append((caption, tonemap.to_png8(linear, img.exposure)))
    quad = abs(centres[False, True][c, c, 0] - centres[False, False][c, c, 0])
    tri = np.abs(centres[True, True] - centres[True, False]).max()
    print(f"orientation: polygon: the centre changes by {quad:.4f} when the camera rolls; "
          f"triangles: the largest difference over the whole image is {tri:.2e}")
    save(compose(panels, 2), "orientation.png")


def perspective_figure():
    panels = []
    for correct in (True, False):
        scene = load("perspective.yaml")
        panels.append((f"perspective_correct: {str(correct).lower()}",
                       shot(scene, perspective_correct=correct, width=480, height=300)))
    save(compose(panels, 1), "perspective.png")


def crease_figure():
    mesh_key_figure("crease.yaml", "crease_angle", (180, 60), "crease.png", 1, 480, 300)


def csg_figure():
    """2 x 2: the ivory die of the Whitted dice (csg: a rounded cube minus 21 spheres) under raster Phong, raycast
    (the exact solid), raster flat and raster Gouraud (the booleans' mesh at the default tessellation)."""
    scene = lumos.load_scene(HERE.parent / "whitted" / "dice.yaml")
    panels = []
    for caption, settings in (("raster, Phong", dict(method="raster", shading="phong")),
                              ("raycast (exact)", dict(method="raycast")),
                              ("raster, flat", dict(method="raster", shading="flat")),
                              ("raster, Gouraud", dict(method="raster", shading="gouraud"))):
        pixels = shot(scene, width=960, height=720, antialias="none", **settings)
        panels.append((caption, pixels[150:540, 105:465]))  # the ivory die
    compose(panels, 2).save(OUT / "csg.png")


def mipmap_figure():
    """textures.yaml with mip-mapping and without, one above the other."""
    scene = load("textures.yaml")
    panels = [(f"mipmap: {str(on).lower()}", shot(scene, mipmap=on, width=560, height=350)) for on in (True, False)]
    save(compose(panels, 1), "mipmap.png")


def affine_uvs_figure():
    """The floor of textures.yaml, perspective-correct uvs and screen-space (affine) ones."""
    scene = load("textures.yaml")
    scene.objects = scene.objects[:1]
    scene.camera.look_at = (0.0, 0.0, -2.0)
    panels = [(f"perspective_correct: {str(on).lower()}",
               shot(scene, perspective_correct=on, tessellation=4, width=400, height=250)) for on in (True, False)]
    save(compose(panels, 2), "affine_uvs.png")


def terms_figure():
    """`lumos sheet shading.yaml --terms` for Gouraud and for Phong: ambient, diffuse, specular, and the image."""
    from lumos.tools.sheet import make_terms_sheet

    panels = []
    for shading in ("gouraud", "phong"):
        _, cells = make_terms_sheet(HERE / "shading.yaml", f"raster:{shading}", width=320, height=160)
        for cell in cells:
            if cell["label"] in ("ambient", "diffuse", "specular", "sum: the image"):
                img = cell["image"]
                name = "image" if cell["label"].startswith("sum") else cell["label"]
                panels.append((f"{shading}: {name}", tonemap.to_png8(img.array, img.exposure)))
    save(compose(panels, 4), "terms.png")


def environment_figure():
    """The DamagedHelmet under the courtyard HDR (examples/path/helmet.yaml): raster and raycast with the
    environment's irradiance, glossy and mirror reflection, beside path."""
    scene = lumos.load_scene(HERE.parent / "path" / "helmet.yaml")
    size = dict(width=384, height=384)
    panels = [("raster, Phong, 8 passes", shot(scene, method="raster", spp=8, **size)),
              ("raycast, 4 spp", shot(scene, method="raycast", spp=4, **size)),
              ("path, 128 spp", shot(scene, method="path", spp=128, **size))]
    save(compose(panels, 3), "environment.png")


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    only = sys.argv[1:]  # figure names (e.g. `environment`) to make only those
    for make in (shading_figure, sheet_figure, t_junctions_figure, subdivision_figure, orientation_figure,
                 perspective_figure, crease_figure, csg_figure, mipmap_figure, affine_uvs_figure, terms_figure,
                 environment_figure):
        if not only or make.__name__.removesuffix("_figure") in only:
            make()


if __name__ == "__main__":
    main()
