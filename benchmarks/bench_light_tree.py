"""How long the light tree (`compile.light_tree`) takes to build: the glowing bunny's emissive mesh and an emissive
sphere of 1.3M triangles (trimesh's icosphere, subdivision 8).

    python benchmarks/bench_light_tree.py [--subdivisions 8]

Prints, per scene, the emissive triangles, the whole path compile (`compile_for`: BVH, emitter table, tree) with the
power table and with the tree, and the tree's own build (`with_light_tree`, best of 3). The first build in a fresh
kernel cache also compiles the build kernel: that is printed apart (`first build`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--subdivisions", type=int, default=8)
    args = ap.parse_args()
    import lumos
    from common import icosphere
    from lumos.compile.light_tree import with_light_tree
    from lumos.methods import compile_for

    v, f = icosphere(args.subdivisions)
    scenes = {
        "glowing_bunny.yaml": lumos.load_scene(ROOT / "examples" / "path" / "glowing_bunny.yaml"),
        f"icosphere({args.subdivisions})": lumos.load_scene({
            "objects": [{"type": "mesh", "vertices": v.tolist(), "faces": f.tolist(),
                         "material": {"emission": 1.0}}]}),
    }
    for name, scene in scenes.items():
        seconds = {}
        for selection in ("power", "tree"):
            t0 = time.perf_counter()
            compiled = compile_for(scene, scene.render.model_copy(update={"method": "path",
                                                                          "light_selection": selection}))
            seconds[selection] = time.perf_counter() - t0
        em, arrays = compiled.emitters, compiled.arrays
        t0 = time.perf_counter()
        with_light_tree(em, arrays)
        first = time.perf_counter() - t0
        best = min(_timed(lambda: with_light_tree(em, arrays)) for _ in range(3))
        print(f"{name}: {len(em.emit_kind):,} emitters, {len(em.tree_nodes):,} tree nodes; compile_for "
              f"{seconds['power']:.2f} s (power) / {seconds['tree']:.2f} s (tree); tree build {best:.3f} s "
              f"(first build {first:.3f} s)", flush=True)


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
