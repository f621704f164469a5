"""What an environment costs the local methods: tabulating its glossy reflection when a scene compiles, and rendering
the DamagedHelmet under it with raster and raycast beside path.

    python benchmarks/bench_environment.py [--repeats 5]

Prints, for the example HDR (examples/data/env/courtyard.exr, 1024×512) and a 2048×1024 one, the time of
`compile.environment.glossy_levels` (min / median / max over the repeats) and the size of the table; then the
helmet (examples/path/helmet.yaml, 384×384) rendered by raster (8 passes), raycast (4 spp) and path (128 spp),
render time only, kernels compiled beforehand by a small render of each.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from common import machine  # noqa: E402


def spread(times: list[float]) -> str:
    return f"{min(times):.3f} / {statistics.median(times):.3f} / {max(times):.3f} s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    import lumos
    from lumos.compile.environment import glossy_levels
    from lumos.io.image_files import read_image

    print(f"# {machine()}")
    courtyard = read_image(ROOT / "examples/data/env/courtyard.exr")
    large = np.repeat(np.repeat(courtyard, 2, axis=0), 2, axis=1)
    for name, image in (("courtyard 1024x512", courtyard), ("2048x1024", large)):
        times = []
        for _ in range(args.repeats):
            t = time.perf_counter()
            table = glossy_levels(image, 30.0)
            times.append(time.perf_counter() - t)
        print(f"glossy_levels, {name}: {spread(times)} (min / median / max); {table.nbytes / 1e6:.1f} MB")

    scene = lumos.load_scene(ROOT / "examples/path/helmet.yaml")
    for method, kw in (("raster", {"spp": 8}), ("raycast", {"spp": 4}), ("path", {"spp": 128})):
        lumos.render(scene, method=method, width=32, height=32, spp=1)  # compile first
        times = [lumos.render(scene, method=method, width=384, height=384, **kw).stats["render_s"]
                 for _ in range(max(1, args.repeats // 2))]
        print(f"helmet 384x384, {method} {kw}: render {spread(times)}")


if __name__ == "__main__":
    main()
