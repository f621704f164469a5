"""A render on a Dask cluster against the same render in one process, on this machine.

    python benchmarks/bench_cluster.py [--scene examples/path/cornell.yaml] [--spp 1024] [--workers 2] [--rounds 3]

One process with W threads against a LocalCluster of W worker processes × 1 thread, same scene, seed and spp,
rounds alternated in one run. Prints min/median/max wall time of each, the overhead ratio, the image's
bit-identity, the pieces, the bytes scattered once and returned per piece, the scheduler's own cost per task
(no-op tasks), and a projected scaling table (docs/cluster.md explains the model).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _noop(x):
    return x


def scheduler_cost(client, n: int = 400) -> float:
    """Seconds per task of submitting and gathering n trivial tasks (the scheduler's round trip, amortised)."""
    client.gather(client.map(_noop, range(20), pure=False))  # warm the connections
    t0 = time.perf_counter()
    client.gather(client.map(_noop, range(n), pure=False))
    return (time.perf_counter() - t0) / n


def _ones(nbytes, k):
    return np.ones(nbytes // 8)


def receive_cost(client, nbytes: int, n: int = 20) -> float:
    """Seconds to bring one piece of `nbytes` from a worker to this process (amortised over n)."""
    client.gather(client.submit(_ones, nbytes, -1, pure=False))
    t0 = time.perf_counter()
    client.gather(client.map(_ones, [nbytes] * n, range(n), pure=False))
    return (time.perf_counter() - t0) / n


def add_cost(job, repeat: int = 20) -> float:
    """Seconds this process takes to add one block's sums to the image's (`PathSums.add`)."""
    from lumos.methods.path import PathSums

    total, part = PathSums(job), PathSums(job)
    t0 = time.perf_counter()
    for _ in range(repeat):
        total.add(part, first_block=False)
    return (time.perf_counter() - t0) / repeat


def project(work_per_block: float, blocks: int, job, n: int, c_task: float, c_block: float, fixed: float):
    """Projected wall time on n workers: the pieces in waves of n, plus the scheduler's cost per piece and this
    process's cost per block (receiving and adding it), plus the fixed cost (scatter, warm-up) measured here."""
    from lumos.cluster import _path_layout

    groups, bands = _path_layout(_Job(job, blocks), n, local=False)
    pieces = len(groups) * len(bands)
    per_piece = work_per_block * blocks / pieces
    waves = -(-pieces // n)
    wall = waves * per_piece + pieces * c_task + blocks * c_block + fixed
    return wall, work_per_block * blocks / n, pieces


class _Job:
    """A job's stand-in with another number of blocks (for the projection)."""

    def __init__(self, job, blocks):
        self.blocks, self.height = blocks, job.height


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default=str(ROOT / "examples" / "path" / "cornell.yaml"))
    parser.add_argument("--method", default="path")
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--width", type=int, default=None)
    parser.add_argument("--height", type=int, default=None)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()

    import lumos
    from lumos.cluster import connect

    settings = dict(method=args.method, spp=args.spp, threads=args.workers)
    if args.width:
        settings.update(width=args.width, height=args.height or args.width)
    client, close = connect(f"local:{args.workers}")
    try:
        lumos.render(args.scene, **{**settings, "spp": 1})  # kernels loaded here
        lumos.render(args.scene, client=client, **{**settings, "spp": 1})  # and on the workers
        local_s, cluster_s, stats = [], [], None
        for _ in range(args.rounds):
            t0 = time.perf_counter()
            local = lumos.render(args.scene, **settings)
            local_s.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            remote = lumos.render(args.scene, client=client, **settings)
            cluster_s.append(time.perf_counter() - t0)
            stats = remote.stats
            if not np.array_equal(local.array, remote.array):
                print("the cluster's image differs from the local one", file=sys.stderr)
                return 1
        per_task = scheduler_cost(client)
        from lumos.methods import compile_for
        from lumos.methods.path import path_job

        scene = lumos.load_scene(args.scene)
        cfg = lumos.api.resolve_settings(scene, settings)
        job = path_job(compile_for(scene, cfg), scene.camera, cfg) if args.method == "path" else None
        block_bytes = stats["cluster_result_bytes"] / max(job.blocks if job else stats["cluster_pieces"], 1)
        c_recv = receive_cost(client, int(block_bytes))
        c_add = add_cost(job) if job else 0.0
    finally:
        close()

    def row(name, xs):
        return f"{name:<34} {min(xs):8.2f} {statistics.median(xs):8.2f} {max(xs):8.2f}"

    pieces = stats["cluster_pieces"]
    worker_s = sum(w["seconds"] for w in stats["cluster_workers"].values())
    print(f"{args.method} {Path(args.scene).name} {stats['width']}x{stats['height']} {args.spp} spp, "
          f"{args.rounds} rounds, {args.workers} workers x 1 thread vs 1 process x {args.workers} threads")
    print(f"{'wall s':<34} {'min':>8} {'median':>8} {'max':>8}")
    print(row(f"one process, {args.workers} threads", local_s))
    print(row(f"cluster, {args.workers} workers x 1 thread", cluster_s))
    ratio = statistics.median(cluster_s) / statistics.median(local_s)
    print(f"cluster / one process (medians): {ratio:.3f} ({ratio - 1:+.1%})")
    print(f"images identical to the bit: yes; {pieces} pieces; scattered once: {stats['cluster_scatter_bytes'] / 1e3:.1f} kB "
          f"per worker; returned: {stats['cluster_result_bytes'] / pieces / 1e6:.2f} MB per piece, "
          f"{block_bytes / 1e6:.2f} MB per block")
    c_block = c_recv + c_add
    print(f"per piece: scheduler {per_task * 1e3:.2f} ms; per block: receive {c_recv * 1e3:.2f} ms + add "
          f"{c_add * 1e3:.2f} ms; work in pieces {worker_s:.2f} s (sum over workers)")
    if args.method != "path":
        return 0
    fixed = max(statistics.median(cluster_s) - worker_s / args.workers, 0.0)
    work_per_block = worker_s / job.blocks
    print(f"fixed cost here (median wall - work / workers): {fixed:.2f} s")
    print("projection (waves of pieces + scheduler per piece + receive/add per block + the fixed cost):")
    print(f"{'spp':>8} {'workers':>8} {'pieces':>7} {'ideal s':>9} {'wall s':>9} {'overhead':>9}")
    for spp in (args.spp, 4 * args.spp, 16 * args.spp, 64 * args.spp):
        blocks = -(-spp // job.block)
        for n in (args.workers, 16, 100):
            wall, ideal, p = project(work_per_block, blocks, job, n, per_task, c_block, fixed)
            print(f"{spp:8d} {n:8d} {p:7d} {ideal:9.2f} {wall:9.2f} {wall / ideal - 1:9.1%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
