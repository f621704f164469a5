"""Render the animations of docs/animation.md from the scenes in this folder.

    python examples/animation/figures.py     # writes docs/images/animation/*.gif and *.png: about a minute

- `turntable.gif`: every second frame of turntable.yaml (48 frames, 12 per second: the animation's speed) at
  256×192.
- `gouraud_phong.gif`: every second frame of gouraud_phong.yaml rendered with `shading: gouraud` and with
  `shading: phong`, side by side with captions, at 12 frames per second.
- `gouraud_phong.png`: three moments of the same, as a still.
Each frame comes from `lumos.render_frames`; the GIFs are written by `lumos.io.video.write_video`.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import lumos
from lumos.animate import frames_of
from lumos.io.video import write_video

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # examples/: the figure scripts' shared kit
from figure_kit import compose, save_image  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OUT = ROOT / "docs" / "images" / "animation"


def turntable() -> None:
    scene = lumos.load_scene(HERE / "turntable.yaml")
    frames = frames_of(lumos.render_frames(scene, frames=range(0, 120, 3), width=256, height=192))
    n = write_video(OUT / "turntable.gif", frames, fps=scene.animation.fps / 3)
    print(f"turntable.gif: {n} frames, {(OUT / 'turntable.gif').stat().st_size / 1e3:.0f} kB")


def gouraud_phong() -> None:
    scene = lumos.load_scene(HERE / "gouraud_phong.yaml")
    picked = range(0, 96, 2)
    shadings = ("gouraud", "phong")
    runs = {s: [np.asarray(f) for f in frames_of(lumos.render_frames(scene, frames=picked, shading=s))]
            for s in shadings}
    pages = [np.asarray(compose([(f"{s.capitalize()} shading", runs[s][i]) for s in shadings], columns=2))
             for i in range(len(picked))]
    n = write_video(OUT / "gouraud_phong.gif", pages, fps=scene.animation.fps / 2)
    print(f"gouraud_phong.gif: {n} frames, {(OUT / 'gouraud_phong.gif').stat().st_size / 1e3:.0f} kB")
    moments = (4, 6, 8)  # frames 8, 12, 16: the cube's corner, then its face, catch the light's mirror direction
    panels = [(f"{s.capitalize()}, frame {picked[i]}", runs[s][i]) for i in moments for s in shadings]
    save_image(compose(panels, columns=2), OUT / "gouraud_phong.png", root=ROOT)


if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    turntable()
    gouraud_phong()
