"""Every model file of the shared test data rendered as `lumos render FILE` frames and lights it: the contact sheet
of docs/formats.md ("Every test model as lumos frames it").

    python examples/formats/model_sheet.py [DATA]    # DATA: ../shared/data; writes docs/images/formats/models.png

Each model (OBJ with its MTL, glTF, PLY) is loaded with `lumos.load_scene(FILE)`, the scene lumos makes up for a
bare model file (its up axis, front, three-quarter view, lights and method: `lumos.scene.from_model`), and
rendered at 200×150 with that scene's method (whitted at 4 spp; path at 64 spp for the self-lit ones). A file
that is refused (tinyobjloader's test-nan.obj, whose vertices are NaN) is captioned with its one-line error.
Takes a few minutes on 2 cores.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

import lumos

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # examples/: the figure scripts' shared kit
from figure_kit import compose, png8, save_image  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "images" / "formats" / "models.png"
SUFFIXES = (".obj", ".gltf", ".glb", ".ply", ".stl", ".off")
W, H = 200, 150


def main() -> None:
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT.parent / "shared" / "data"
    files = sorted(p for p in data.rglob("*") if p.suffix.lower() in SUFFIXES)
    panels = []
    for path in files:
        name = str(path.relative_to(data))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                scene = lumos.load_scene(path)
                img = lumos.render(scene, width=W, height=H)
                pixels = png8(img.array)
                caption = f"{path.name[:30]}\n{scene.render.method}, {int(img.stats.get('spp', scene.render.spp))} spp"
            except lumos.LumosError as exc:
                pixels = np.full((H, W, 3), 40, np.uint8)
                caption = f"{path.name[:30]}\nrefused: {str(exc).split(': ')[-1][:28]}"
        print(f"{name}: {caption.splitlines()[1]}", flush=True)
        panels.append((caption, pixels))
    save_image(compose(panels, columns=6), OUT, ROOT)


if __name__ == "__main__":
    main()
