"""Primary-ray throughput on a 1.3M-triangle mesh at 1024×1024: lumos vs Embree 4 (embreex), same rays, one run.

    python benchmarks/bench_primary_rays.py [--subdivisions 8] [--size 1024] [--threads 2]

Embree traces with `EmbreeScene.run` (closest hit, one ray at a time inside C, GIL released) over chunks of the
rays on `--threads` Python threads; lumos traces the same rays with `kernels.batch.trace_closest` on as many
Numba threads. Also reports the full `raycast` render (camera rays + closest hit + shading) of the same view,
and checks that both tracers agree on what each ray hits.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from common import best_of, icosphere, machine, primary_rays

import lumos
from lumos.compile import compile_scene
from lumos.kernels.batch import trace_closest


def embree_tracer(vertices, faces, threads):
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene(robust=True)
    TriangleMesh(scene, vertices.astype(np.float32), faces.astype(np.int32))
    pool = ThreadPoolExecutor(threads)

    def trace(o, d):
        chunks = np.array_split(np.arange(len(o)), threads * 8)
        parts = list(pool.map(lambda idx: scene.run(o[idx], d[idx], output=True), chunks))
        return np.concatenate([p["tfar"] for p in parts]), np.concatenate([p["primID"] for p in parts])

    return scene, trace


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subdivisions", type=int, default=8)
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    import numba

    numba.set_num_threads(args.threads)
    vertices, faces = icosphere(args.subdivisions)
    camera = {"position": [0.0, 0.0, 2.5], "look_at": [0.0, 0.0, 0.0], "fov": 45}
    o, d = primary_rays(camera["position"], camera["look_at"], camera["fov"], args.size, args.size)
    n = len(o)
    print(f"machine: {machine()}")
    print(f"mesh: icosphere({args.subdivisions}) = {len(faces):,} triangles; {args.size}x{args.size} primary rays; "
          f"{args.threads} threads")

    # lumos: compile (BVH build), warm the JIT, then time the closest-hit kernel
    scene = lumos.load_scene({"camera": camera, "lights": [{"type": "directional", "direction": [-1, -1, -1]}],
                              "render": {"width": args.size, "height": args.size},
                              "objects": [{"type": "mesh", "vertices": vertices, "faces": faces,
                                           "material": {"kd": 0.8}}]})
    compile_scene(lumos.load_scene({"objects": [{"type": "triangle", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}]}))
    compiled = compile_scene(scene)  # the builder is warm: this times the build, not the JIT
    sa = compiled.arrays
    t_out, ref_out, b_out = np.empty(n), np.empty(n, np.int64), np.empty((n, 2))
    trace_closest(sa, o[:1024], d[:1024], 1e30, t_out[:1024], ref_out[:1024], b_out[:1024])
    lumos_s = best_of(lambda: trace_closest(sa, o, d, 1e30, t_out, ref_out, b_out), args.repeats)

    # Embree: the first run commits (builds) its BVH
    o32, d32 = o.astype(np.float32), d.astype(np.float32)
    _, embree_trace = embree_tracer(vertices, faces, args.threads)
    t0 = time.perf_counter()
    embree_trace(o32[:1], d32[:1])
    commit_s = time.perf_counter() - t0
    embree_s = best_of(lambda: embree_trace(o32, d32), args.repeats)
    e_t, e_prim = embree_trace(o32, d32)

    # agreement: same rays hit/miss, same distance
    ours_hit = t_out > 0
    theirs_hit = e_prim >= 0
    agree = np.mean(ours_hit == theirs_hit)
    both = ours_hit & theirs_hit
    t_err = np.max(np.abs(t_out[both] - e_t[both])) if both.any() else 0.0

    # the whole raycast method on the same view (camera rays + BVH + shading)
    render_s = min(lumos.render(scene, method="raycast", threads=args.threads).stats["render_s"] for _ in range(3))

    lumos_mr, embree_mr = n / lumos_s / 1e6, n / embree_s / 1e6
    print(f"BVH build: lumos {compiled.bvh_build_s:.3f} s, Embree commit {commit_s:.3f} s "
          f"(ratio {compiled.bvh_build_s / commit_s:.2f}x the time)")
    print(f"closest hit: lumos {lumos_mr:.2f} Mrays/s ({lumos_s * 1e3:.0f} ms), "
          f"Embree {embree_mr:.2f} Mrays/s ({embree_s * 1e3:.0f} ms)")
    print(f"throughput ratio lumos/Embree: {lumos_mr / embree_mr:.2f}")
    print(f"agreement: hit/miss {agree * 100:.4f}% of rays, max |t difference| {t_err:.2e}")
    print(f"raycast render (camera rays + closest hit + shading + film, compile excluded): {render_s:.3f} s = "
          f"{n / render_s / 1e6:.2f} Mrays/s, {n / render_s / 1e6 / embree_mr:.2f}x Embree's closest-hit rate")


if __name__ == "__main__":
    main()
