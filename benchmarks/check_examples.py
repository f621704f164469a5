"""Every example scene rendered by two lumos source trees, compared array for array: a refactor must leave each
image bit-identical.

    python benchmarks/check_examples.py BASE_SRC WORK_SRC [--width 96] [--height 72] [--max-spp 4]

Each tree renders every `examples/**/*.yaml` with the scene's own method and settings, at the given size and at
most `--max-spp` samples per pixel (radiosity solves each scene), in a process of its own with its own kernel cache.
Prints one line per scene and exits 1 if any image differs.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

CHILD = """
import sys, warnings
from pathlib import Path
import numpy as np
import lumos
warnings.simplefilter("ignore")
out, width, height, max_spp = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
for i, path in enumerate(sys.argv[5:]):
    scene = lumos.load_scene(path)
    spp = min(scene.render.spp, max_spp)
    image = lumos.render(scene, width=width, height=height, spp=spp)
    np.save(out / f"{i}.npy", image.array)
"""


def render_all(src: Path, scenes: list[Path], out: Path, args, cache: str) -> None:
    env = dict(os.environ, PYTHONPATH=str(src), LUMOS_CACHE_DIR=cache)
    subprocess.run([sys.executable, "-c", CHILD, str(out), str(args.width), str(args.height), str(args.max_spp),
                    *map(str, scenes)], env=env, check=True, cwd=ROOT)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base", type=Path)
    ap.add_argument("work", type=Path)
    ap.add_argument("--width", type=int, default=96)
    ap.add_argument("--height", type=int, default=72)
    ap.add_argument("--max-spp", type=int, default=4)
    args = ap.parse_args()
    import numpy as np

    scenes = sorted((ROOT / "examples").rglob("*.yaml"))
    with tempfile.TemporaryDirectory() as tmp:
        outs = {}
        for name in ("base", "work"):
            outs[name] = Path(tmp) / name
            outs[name].mkdir()
            render_all(getattr(args, name), scenes, outs[name], args, os.environ.get(
                f"LUMOS_CACHE_{name.upper()}", str(Path(tmp) / f"cache-{name}")))
        differ = 0
        for i, scene in enumerate(scenes):
            a, b = np.load(outs["base"] / f"{i}.npy"), np.load(outs["work"] / f"{i}.npy")
            same = a.shape == b.shape and np.array_equal(a, b)
            differ += not same
            detail = "" if same else f" (max |diff| {float(np.abs(a - b).max()) if a.shape == b.shape else 'shape'})"
            print(f"{'identical' if same else 'DIFFERENT'}  {scene.relative_to(ROOT)}{detail}")
    print(f"{len(scenes) - differ} of {len(scenes)} example images identical")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
