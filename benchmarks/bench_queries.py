"""Ray queries (`lumos.RayCaster`) against Embree 4 (embreex) and Open3D's RaycastingScene: same meshes, same rays,
one run.

    python benchmarks/bench_queries.py [--rays 1000000] [--repeat 3] [--threads 1 2] [--meshes icosphere bunny]

Meshes: trimesh's icosphere(8) (1.31M triangles, closed) and the Stanford bunny (69k triangles, open: it has
holes, so `contains` and `path_length` run on the icosphere only). Rays: `--rays` coherent ones (a pinhole
camera's pixel rays, framing the mesh) and as many incoherent ones (random origins around the mesh aimed at
random points in its box). Queries and their peers:

    closest       lumos closest (t, ids, point, normal, uv)   Embree run(INTERSECT)      Open3D cast_rays
    occluded      lumos occluded                              Embree run(OCCLUDED)       Open3D test_occlusions
    all_hits      lumos all_hits                              -                          Open3D list_intersections
    path_length   lumos path_length                           -                          Open3D count_intersections
    contains      lumos contains(points, object=0)            -                          Open3D compute_occupancy

Threads: lumos with numba.set_num_threads(k); Embree with k Python threads over k slices of the rays (its `run`
releases the GIL, PEERS.md); Open3D with its `nthreads=k`. Every call is warmed once, then the tracers alternate
`--repeat` times; the table gives min/median/max wall time, Mrays/s (of the median) and lumos/peer throughput
ratios (of the medians). BVH builds are excluded (Embree's commit happens in the warm-up call).
"""

from __future__ import annotations

import argparse
import statistics
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from common import icosphere, machine, primary_rays

import lumos

BUNNY = Path(__file__).resolve().parent.parent / "tests" / "data" / "bun_zipper.ply"


def load_mesh(name, subdivisions):
    if name == "icosphere":
        v, f = icosphere(subdivisions)
        return f"icosphere({subdivisions})", v, f
    from lumos.io.meshes import load_mesh as load

    m = load(BUNNY)
    return "Stanford bunny", np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


def ray_sets(vertices, n, rng):
    """{"coherent": (o, d), "incoherent": (o, d)}, float32-exact float64 arrays (all tracers get the same rays)."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    side = max(1, int(round(np.sqrt(n))))
    eye = centre + np.array([0.3, 0.2, 1.0]) / np.linalg.norm([0.3, 0.2, 1.0]) * radius * 2.6
    o_c, d_c = primary_rays(eye, centre, 45.0, side, side)
    o_i = rng.uniform(lo - 0.5 * radius, hi + 0.5 * radius, (side * side, 3))
    d_i = rng.uniform(lo, hi, (side * side, 3)) - o_i
    d_i /= np.linalg.norm(d_i, axis=1, keepdims=True)
    exact = lambda a: np.ascontiguousarray(a.astype(np.float32).astype(np.float64))  # noqa: E731
    return {"coherent": (exact(o_c), exact(d_c)), "incoherent": (exact(o_i), exact(d_i))}


class Embree:
    def __init__(self, vertices, faces):
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        self.scene = rtcore_scene.EmbreeScene(robust=True)
        TriangleMesh(self.scene, vertices.astype(np.float32), faces.astype(np.int32))
        self.pools = {}

    def _split(self, fn, o, threads):
        if threads == 1:
            return [fn(o[0], o[1])]
        pool = self.pools.setdefault(threads, ThreadPoolExecutor(threads))
        parts = np.array_split(np.arange(len(o[0])), threads)
        return list(pool.map(lambda idx: fn(o[0][idx], o[1][idx]), parts))

    def closest(self, o, d, threads):
        return self._split(lambda a, b: self.scene.run(a, b, output=True), (o, d), threads)

    def occluded(self, o, d, threads):
        return self._split(lambda a, b: self.scene.run(a, b, query="OCCLUDED"), (o, d), threads)


class Open3D:
    def __init__(self, vertices, faces):
        import open3d as o3d

        self.o3d = o3d
        self.scene = o3d.t.geometry.RaycastingScene()
        self.scene.add_triangles(o3d.core.Tensor(vertices.astype(np.float32)), o3d.core.Tensor(faces.astype(np.uint32)))

    def rays(self, o, d):
        return self.o3d.core.Tensor(np.concatenate([o, d], axis=1).astype(np.float32))

    def closest(self, rays, threads):
        return self.scene.cast_rays(rays, nthreads=threads)

    def occluded(self, rays, threads):
        return self.scene.test_occlusions(rays, nthreads=threads)

    def all_hits(self, rays, threads):
        return self.scene.list_intersections(rays, nthreads=threads)

    def count(self, rays, threads):
        return self.scene.count_intersections(rays, nthreads=threads)

    def occupancy(self, points, threads):
        return self.scene.compute_occupancy(points, nthreads=threads)


def timed(calls, repeat):
    """{name: [seconds...]}: each call warmed once, then all of them in turn, `repeat` rounds."""
    for fn in calls.values():
        fn()
    times = {name: [] for name in calls}
    for _ in range(repeat):
        for name, fn in calls.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return times


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--meshes", nargs="+", default=["icosphere", "bunny"], choices=["icosphere", "bunny"])
    ap.add_argument("--subdivisions", type=int, default=8)
    args = ap.parse_args()
    import numba

    print(f"machine: {machine()}")
    rng = np.random.default_rng(7)
    rows = []
    for mesh_name in args.meshes:
        label, vertices, faces = load_mesh(mesh_name, args.subdivisions)
        t0 = time.perf_counter()
        rc = lumos.RayCaster({"objects": [{"type": "mesh", "vertices": vertices, "faces": faces}]})
        build_s = time.perf_counter() - t0
        closed = mesh_name == "icosphere"
        print(f"mesh: {label}, {len(faces):,} triangles; lumos RayCaster build {build_s:.2f} s")
        embree, o3d = Embree(vertices, faces), Open3D(vertices, faces)
        for kind, (o, d) in ray_sets(vertices, args.rays, rng).items():
            n = len(o)
            o32, d32 = o.astype(np.float32), d.astype(np.float32)
            rays = o3d.rays(o, d)
            for threads in args.threads:
                numba.set_num_threads(threads)
                suites = {
                    "closest": {"lumos": lambda: rc.closest(o, d), "Embree": lambda: embree.closest(o32, d32, threads),
                                "Open3D": lambda: o3d.closest(rays, threads)},
                    "occluded": {"lumos": lambda: rc.occluded(o, d),
                                 "Embree": lambda: embree.occluded(o32, d32, threads),
                                 "Open3D": lambda: o3d.occluded(rays, threads)},
                    "all_hits": {"lumos": lambda: rc.all_hits(o, d), "Open3D": lambda: o3d.all_hits(rays, threads)},
                }
                if closed:
                    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
                    points = np.ascontiguousarray(rng.uniform(lo, hi, (n, 3)).astype(np.float32).astype(np.float64))
                    p3 = o3d.o3d.core.Tensor(points.astype(np.float32))
                    suites["path_length"] = {"lumos": lambda: rc.path_length(o, d),
                                             "Open3D": lambda: o3d.count(rays, threads)}
                    suites["contains"] = {"lumos": lambda: rc.contains(points, object=0),
                                          "Open3D": lambda: o3d.occupancy(p3, threads)}
                for query, calls in suites.items():
                    times = timed(calls, args.repeat)
                    med = {name: statistics.median(ts) for name, ts in times.items()}
                    for name, ts in times.items():
                        ratio = {peer: med[peer] / med["lumos"] for peer in times if peer != "lumos"}
                        rows.append((label, kind, threads, query, name, min(ts), med[name], max(ts),
                                     n / med[name] / 1e6, ratio if name == "lumos" else {}))
                    print_row(rows[-len(times):])
    print()
    print_table(rows)


def print_row(rows):
    for r in rows:
        label, kind, threads, query, name, lo, med, hi, mr, ratio = r
        extra = "  " + ", ".join(f"{v:.2f}x {k}" for k, v in ratio.items()) if ratio else ""
        print(f"  {label:18s} {kind:10s} {threads}T {query:11s} {name:7s} {lo * 1e3:8.1f} {med * 1e3:8.1f} "
              f"{hi * 1e3:8.1f} ms {mr:8.2f} Mrays/s{extra}", flush=True)


def print_table(rows):
    print("| mesh | rays | threads | query | tracer | min ms | median ms | max ms | Mrays/s | lumos / peer |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, kind, threads, query, name, lo, med, hi, mr, ratio in rows:
        ratios = ", ".join(f"{v:.2f}× {k}" for k, v in ratio.items())
        print(f"| {label} | {kind} | {threads} | {query} | {name} | {lo * 1e3:.1f} | {med * 1e3:.1f} | "
              f"{hi * 1e3:.1f} | {mr:.2f} | {ratios} |")


if __name__ == "__main__":
    main()
