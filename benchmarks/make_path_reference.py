"""Render the converged Mitsuba references of the Cornell box that lumos's tests compare `path` against.

    python benchmarks/make_path_reference.py [--spp 16384] [--unbounded-spp 16384] [--size 256]
                                             [--variant llvm_ad_rgb] [--threads 2] [--lamp black]
                                             [--out tests/data/cornell_mitsuba]

Writes to `--out`:

    ref_depth8_<size>.npy     Mitsuba max_depth 8 (mi.cornell_box()'s own; lumos max_depth 6), `--spp` samples
    ref_depthinf_<size>.npy   Mitsuba max_depth -1 (unbounded, Russian roulette ends the paths), `--unbounded-spp`
    info.json                 for each file: depth, size, spp, variant, Mitsuba version, seconds, the command,
                              and noise_rmse, the image's own estimated RMSE against the exact image

each a float32 (size, size, 3) array of linear RGB radiance, row 0 at the top (as lumos's `Image.array`). The
scene is peers_path.mitsuba_scene_dict(): `mi.cornell_box()` with a box pixel filter and a black BSDF on the light
(see that module), i.e. examples/path/cornell.yaml. Each image is the mean of spp/256 renders of 256 samples with
seeds 1000000, 1000001, ... (peers_path.render_reference), which is the same estimator as one render of `--spp`
samples (Mitsuba's independent sampler) without the LLVM variant's wavefront growing too large.
`--spp 0` skips the max_depth 8 image and `--unbounded-spp 0` the unbounded one.

`--lamp white` keeps `mi.cornell_box()`'s own white diffuse BSDF on the light (a lamp that reflects;
peers_path.mitsuba_scene_dict(lamp_reflects=True)); its files are named ref_lamp_depth8_<size>.npy and
ref_lamp_depthinf_<size>.npy, and their info.json entries have "lamp": "white". The default, `--lamp black`, is
the scene above. The README.md beside the files describes them for people.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np
from common import machine
from peers_path import ROOT, render_reference, rmse


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=16384, help="samples per pixel of the max_depth 8 reference (0: skip)")
    ap.add_argument("--unbounded-spp", type=int, default=16384, help="samples of the unbounded one (0: skip)")
    ap.add_argument("--size", type=int, default=256, help="width = height in pixels (the camera is unchanged)")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (llvm_ad_rgb or scalar_rgb)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--lamp", choices=("black", "white"), default="black",
                    help="the light's BSDF: black (lumos's lamp, the default) or white (mi.cornell_box()'s own)")
    ap.add_argument("--out", default=str(ROOT / "tests" / "data" / "cornell_mitsuba"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    import mitsuba as mi

    print(f"machine: {machine()}; Mitsuba {mi.__version__}, {args.variant}, {args.threads} threads", flush=True)
    info_path = out / "info.json"
    info = json.loads(info_path.read_text()) if info_path.is_file() else {"files": []}
    command = "python " + " ".join(shlex.quote(a) for a in [f"benchmarks/{Path(__file__).name}"] + sys.argv[1:])
    white = args.lamp == "white"
    jobs = ([(8, args.spp)] if args.spp else []) + ([(-1, args.unbounded_spp)] if args.unbounded_spp else [])
    for depth, spp in jobs:
        name = f"ref_{'lamp_' if white else ''}depth{'inf' if depth < 0 else depth}_{args.size}.npy"
        print(f"{name}: max_depth {depth}, {spp} spp, {args.size}x{args.size}, {args.lamp} lamp", flush=True)
        t0 = time.perf_counter()
        img, render_s, noise = render_reference(spp, depth, args.size, args.size, args.variant, args.threads,
                                                verbose=True, lamp_reflects=white)
        wall = time.perf_counter() - t0
        np.save(out / name, img.astype(np.float32))
        print(f"  done: {render_s:.1f} s rendering ({wall:.1f} s wall); mean RGB {img.mean(axis=(0, 1))}; "
              f"estimated noise (RMSE vs the exact image) {noise:.5f}", flush=True)
        entry = {"file": name, "max_depth": depth, "width": args.size, "height": args.size, "spp": spp,
                 "variant": args.variant, "mitsuba": mi.__version__, "threads": args.threads,
                 "render_s": round(render_s, 1), "wall_s": round(wall, 1), "machine": machine(),
                 "pass_spp": 256, "first_seed": 1_000_000, "noise_rmse": round(noise, 6), "command": command,
                 "mean_rgb": [round(float(x), 6) for x in img.mean(axis=(0, 1))]}
        if white:
            entry["lamp"] = "white"  # absent on the black-lamp entries, as before this option
        info["files"] = [e for e in info["files"] if e["file"] != name] + [entry]
        info_path.write_text(json.dumps(info, indent=2) + "\n")
    print(f"wrote {', '.join(e['file'] for e in info['files'])} and info.json to {out}")
    if len(info["files"]) > 1:
        a, b = (np.load(out / e["file"]) for e in info["files"][:2])
        print(f"RMSE between {info['files'][0]['file']} and {info['files'][1]['file']}: {rmse(a, b):.5f}")


if __name__ == "__main__":
    main()
