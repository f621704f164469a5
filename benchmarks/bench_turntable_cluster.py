"""An animation rendered through a Dask cluster against the same frames rendered here, on this machine.

    python benchmarks/bench_turntable_cluster.py [--scene examples/animation/turntable.yaml] [--workers 2]
                                                 [--width 320] [--height 240] [--method raycast] [-o turntable.mp4]

Renders every frame of the scene's animation here (one process, all threads) and on a LocalCluster of N worker
processes × 1 thread (one task per frame), checks that every frame is the same to the bit, and encodes the
cluster's frames to a video (`-o`). Prints both wall times and their ratio.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default=str(ROOT / "examples" / "animation" / "turntable.yaml"))
    parser.add_argument("--method", default=None)
    parser.add_argument("--spp", type=int, default=None)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=240)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("-o", "--output", default=None, help="encode the cluster's frames to this video")
    args = parser.parse_args()

    import lumos
    from lumos.animate import frames_of
    from lumos.cluster import connect
    from lumos.io.video import write_video

    settings = {k: v for k, v in dict(method=args.method, spp=args.spp, width=args.width,
                                       height=args.height).items() if v is not None}
    scene = lumos.load_scene(args.scene)
    lumos.render_frames(scene, frames=[0], **settings)  # kernels loaded
    t0 = time.perf_counter()
    local = list(lumos.render_frames(scene, **settings))
    local_s = time.perf_counter() - t0
    client, close = connect(f"local:{args.workers}")
    try:
        list(lumos.render_frames(scene, frames=[0], client=client, **settings))  # workers load their kernels
        t0 = time.perf_counter()
        remote = list(lumos.render_frames(scene, client=client, **settings))
        cluster_s = time.perf_counter() - t0
    finally:
        close()
    same = all(np.array_equal(a.array, b.array) for a, b in zip(local, remote)) and len(local) == len(remote)
    if args.output:
        write_video(args.output, frames_of(remote), fps=scene.animation.fps)
    stats = remote[0].stats
    print(f"{Path(args.scene).name}: {len(local)} frames, {stats['method']} {stats['width']}x{stats['height']}, "
          f"{stats['spp']} spp")
    print(f"one process, all threads: {local_s:.2f} s; cluster, {args.workers} workers x 1 thread: {cluster_s:.2f} s; "
          f"cluster / local {cluster_s / local_s:.3f}")
    print(f"every frame the same to the bit: {'yes' if same else 'NO'}" +
          (f"; video {args.output} ({Path(args.output).stat().st_size / 1e6:.1f} MB)" if args.output else ""))
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
