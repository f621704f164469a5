"""Check that examples/path/cornell.yaml is Mitsuba's `mi.cornell_box()`: the same depth at every pixel centre.

    python benchmarks/check_cornell_depth.py [--variant scalar_rgb] [--out /tmp/cornell_depth]

lumos: `method="raycast"`, 1 spp (the pixel centres), `aov=["depth"]` (distance along the unit camera ray, inf on
misses). Mitsuba: the `aov` integrator with `dd.y:depth` (si.t, the distance along its unit ray; 0 on misses), a
box filter and a `stratified` sampler with one sample and `jitter: false`, i.e. the pixel centres too.

Mitsuba's perspective camera starts its rays at the near clip plane (`near_clip` 0.001 along the optical axis),
so its t is short by near_clip / cos(angle to the axis); that is added back before comparing. Prints the
fraction of pixels whose depths agree to 1e-3 relative (raw, and with the near-clip offset added back) and where
they disagree; writes both depth maps as .npy and a PNG of (Mitsuba path render | lumos raycast) to `--out`
to check by eye that nothing is mirrored (the red wall on the left in both).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import peers_path as peers

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "examples" / "path" / "cornell.yaml"


def mitsuba_depth(variant: str, size: int) -> np.ndarray:
    mi, dr = peers._mitsuba(variant)
    dr.set_thread_count(2)
    d = peers.mitsuba_scene_dict(1, 8, size, size)
    d["integrator"] = {"type": "aov", "aovs": "dd.y:depth"}
    d["sensor"]["sampler"] = {"type": "stratified", "sample_count": 1, "jitter": False}
    img = np.array(mi.render(mi.load_dict(d), spp=1))
    depth = img[..., -1].astype(np.float64)
    depth[depth == 0] = np.inf
    return depth


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--out", default="/tmp/cornell_depth")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    import lumos
    from lumos.io.image_files import write_image

    scene = lumos.load_scene(SCENE)
    size, fov = scene.render.width, scene.camera.fov
    lu = lumos.render(scene, method="raycast", width=size, height=size, spp=1, aov=["depth"], threads=2)
    ld = lu.aovs["depth"].astype(np.float64)
    md = mitsuba_depth(args.variant, size)
    np.save(out / "lumos_depth.npy", ld)
    np.save(out / "mitsuba_depth.npy", md)

    t = np.tan(np.radians(fov) / 2)
    ys, xs = np.mgrid[0:size, 0:size]
    sx, sy = (2 * (xs + 0.5) / size - 1) * t, (1 - 2 * (ys + 0.5) / size) * t
    cos_axis = 1 / np.sqrt(sx * sx + sy * sy + 1)
    near = float(peers.mitsuba_scene_dict()["sensor"]["near_clip"])

    both_miss = np.isinf(md) & np.isinf(ld)
    both_hit = np.isfinite(md) & np.isfinite(ld)
    print(f"{size}x{size} pixel centres, Mitsuba {args.variant}: both miss {both_miss.sum()}, both hit "
          f"{both_hit.sum()}, only lumos hits {(np.isinf(md) & np.isfinite(ld)).sum()}, only Mitsuba hits "
          f"{(np.isfinite(md) & np.isinf(ld)).sum()}")
    for label, m in (("raw", md), ("+ near-clip offset", md + near / cos_axis)):
        rel = np.zeros_like(ld)
        rel[both_hit] = np.abs(m[both_hit] - ld[both_hit]) / ld[both_hit]
        rel[~(both_hit | both_miss)] = np.inf
        ok = rel <= 1e-3
        print(f"  {label}: {ok.mean():.5f} of the pixels agree to 1e-3 relative ({(~ok).sum()} do not); where both "
              f"hit: median {np.median(rel[both_hit]):.2e}, max {rel[both_hit].max():.2e}")
    bad = np.argwhere(~(both_hit | both_miss))
    if len(bad):
        print(f"  pixels (row, column) hit by one only: {bad[:12].tolist()}{' ...' if len(bad) > 12 else ''}")

    mi, _ = peers._mitsuba(args.variant)
    path = np.array(mi.render(mi.load_dict(peers.mitsuba_scene_dict(64, 8, size, size)), spp=64))
    shaded = lumos.render(scene, method="raycast", width=size, height=size, spp=4, threads=2).array
    write_image(out / "mitsuba_vs_lumos.png",
                np.concatenate([path[..., :3], np.ones((size, 8, 3), np.float32), shaded], axis=1))
    print(f"wrote {out / 'mitsuba_vs_lumos.png'} (Mitsuba path 64 spp | lumos raycast) and the depth maps")


if __name__ == "__main__":
    main()
