"""Veach's MIS scene: lumos's light selection (power table against light tree) and Mitsuba 3, error at equal spp.

    python benchmarks/bench_veach.py [--spp 16,64] [--seeds 4] [--width 384] [--height 216] [--ref-spp 8192]
                                     [--lumos-ref-spp 0]

The scene is `benchmarks/scenes/veach_mis.xml` (Mitsuba 3's format; lumos reads the same file): four small sphere
lights of equal power above four rough plastic plates, and a large light that lights the room and holds 98% of
the scene's power. Each renderer draws it at each spp with a few seeds (a box pixel filter, direct light only);
each image's RMSE against a converged Mitsuba image (cached as `.cache/veach_mitsuba_{W}x{H}_{spp}spp.exr`,
rendered with `llvm_ad_rgb` the first time: a minute or two) is printed, and the ratio lumos / Mitsuba for each
seed (min / median / max over the seeds). Mitsuba uses its `independent` sampler and picks its five emitters
uniformly (its `sampling_weight` defaults to 1); lumos runs with `sampler: independent` (the same estimator
apart from light selection) and with its default Sobol points.

With `--lumos-ref-spp N` lumos also renders N spp (light tree) and prints its RMSE against Mitsuba's reference,
next to what the noise of N spp alone would give: the two renderers draw the same image when they are close.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import peers_path  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCENE = Path(__file__).resolve().parent / "scenes" / "veach_mis.xml"
#: The sphere lights (centre, radius), as in the scene file.
LIGHTS = (((10.0, 10.0, 4.0), 0.5), ((-3.75, 0.0, 0.0), 0.03333), ((-1.25, 0.0, 0.0), 0.1), ((1.25, 0.0, 0.0), 0.3),
          ((3.75, 0.0, 0.0), 0.9))
SIZE: dict = {}  # width and height of every lumos render (main sets them)

#: The lumos configurations compared: (label, render settings).
LUMOS = (
    ("lumos power, independent", {"light_selection": "power", "sampler": "independent"}),
    ("lumos tree, independent", {"light_selection": "tree", "sampler": "independent"}),
    ("lumos power, sobol", {"light_selection": "power", "sampler": "sobol"}),
    ("lumos tree, sobol", {"light_selection": "tree", "sampler": "sobol"}),
)


def mitsuba_scene(spp: int, width: int, height: int):
    mi, dr = peers_path._mitsuba("llvm_ad_rgb")
    dr.set_thread_count(2)
    return mi.load_file(str(SCENE), spp=int(spp), width=int(width), height=int(height))


def mitsuba_image(scene, spp: int, seed: int) -> np.ndarray:
    import mitsuba as mi

    return np.array(mi.render(scene, spp=int(spp), seed=int(seed)), dtype=np.float32)[..., :3].copy()


def reference(width: int, height: int, spp: int, pass_spp: int = 256) -> np.ndarray:
    """Mitsuba's converged image (the mean of spp / pass_spp renders of independent seeds), cached."""
    from lumos.io.image_files import read_image, write_image

    path = peers_path.CACHE / f"veach_mitsuba_{width}x{height}_{spp}spp.exr"
    if path.is_file():
        return read_image(path)
    print(f"rendering Mitsuba's reference ({spp} spp) into {path}", flush=True)
    scene = mitsuba_scene(pass_spp, width, height)
    total = np.zeros((height, width, 3))
    t0 = time.perf_counter()
    passes = max(spp // pass_spp, 1)
    for i in range(passes):
        total += mitsuba_image(scene, pass_spp, 1_000_000 + i)
    image = (total / passes).astype(np.float32)
    print(f"  {time.perf_counter() - t0:.1f} s", flush=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_image(path, image)
    return image


def light_mask(width: int, height: int, margin_px: float = 2.0) -> np.ndarray:
    """bool (H, W): the pixels that see no light directly (their ray through the centre passes farther than the
    sphere's radius plus `margin_px` pixels from its centre). Those that do are left out of the error: the
    noise of a pixel that a light of radiance 900 covers in part is the pixel filter's, not light selection's."""
    from common import primary_rays

    o, d = primary_rays((0.0, 2.0, 15.0), (0.0, -2.0, 2.5), 28.0, width, height)
    pixel_angle = 2.0 * np.tan(np.radians(14.0)) / height
    keep = np.ones(len(d), bool)
    for centre, radius in LIGHTS:
        to = np.asarray(centre) - o
        along = np.einsum("ij,ij->i", to, d)
        miss = np.sqrt(np.maximum(np.einsum("ij,ij->i", to, to) - along * along, 0.0))
        keep &= ~((along > 0) & (miss < radius + margin_px * pixel_angle * along))
    return keep.reshape(height, width)


def masked_rmse(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64))[mask]
    return float(np.sqrt(np.mean(d * d)))


def lumos_image(scene, spp: int, seed: int, settings: dict) -> tuple[np.ndarray, float]:
    import lumos

    image = lumos.render(scene, spp=int(spp), seed=int(seed), threads=2, **settings, **SIZE)
    return image.array.astype(np.float32), float(image.stats["render_s"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", default="16,64")
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--width", type=int, default=384)
    ap.add_argument("--height", type=int, default=216)
    ap.add_argument("--ref-spp", type=int, default=8192)
    ap.add_argument("--lumos-ref-spp", type=int, default=0)
    args = ap.parse_args()
    import lumos

    SIZE.update(width=args.width, height=args.height)

    ref = reference(args.width, args.height, args.ref_spp)
    scene = lumos.load_scene(str(SCENE))
    for label, settings in LUMOS:  # compile the kernels before anything is timed
        lumos_image(scene, 1, 0, settings)
    if args.lumos_ref_spp:
        image, seconds = lumos_image(scene, args.lumos_ref_spp, 99, {"light_selection": "tree"})
        print(f"lumos tree at {args.lumos_ref_spp} spp against Mitsuba's reference: RMSE "
              f"{masked_rmse(image, ref, light_mask(args.width, args.height)):.5f} ({seconds:.1f} s)")
    print(f"Veach's MIS scene, {args.width}x{args.height}, box filter, direct light; RMSE against Mitsuba at "
          f"{args.ref_spp} spp; {args.seeds} seeds")
    mask = light_mask(args.width, args.height)
    print(f"({np.count_nonzero(~mask)} pixels that see a light directly are left out; 'all': every pixel)")
    for spp in (int(s) for s in args.spp.split(",")):
        mi_scene = mitsuba_scene(spp, args.width, args.height)
        mitsuba_image(mi_scene, spp, 0)  # warm (its LLVM kernels)
        errors = {}
        for seed in range(1, args.seeds + 1):
            images = [("mitsuba", mitsuba_image(mi_scene, spp, seed))]
            images += [(label, lumos_image(scene, spp, seed, settings)[0]) for label, settings in LUMOS]
            for label, image in images:
                errors.setdefault(label, []).append(masked_rmse(image, ref, mask))
                errors.setdefault(label + " all", []).append(peers_path.rmse(image, ref))
        print(f"\n{spp} spp")
        for suffix in ("", " all"):
            base = errors["mitsuba" + suffix]
            print(f"  {'Mitsuba 3 (uniform selection)' + suffix:38s} RMSE median {statistics.median(base):.5f}")
            for label, _ in LUMOS:
                ratios = [a / b for a, b in zip(errors[label + suffix], base)]
                print(f"  {label + suffix:38s} RMSE median {statistics.median(errors[label + suffix]):.5f}   / "
                      f"Mitsuba: min {min(ratios):.3f}  median {statistics.median(ratios):.3f}  "
                      f"max {max(ratios):.3f}")


if __name__ == "__main__":
    main()
