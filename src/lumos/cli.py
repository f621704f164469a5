"""The `lumos` command: parse arguments, call the Python API, print. No rendering logic lives here.

    lumos render SCENE [-o OUT] [--method M] [--width W] ... [--stats FILE.json] [--quiet]
    lumos info SCENE
    lumos compare A B [--diff D.png]
    lumos sheet SCENE [-o OUT.png] [--width W] [--height H] [--spp N] [--threads T] [--columns C] [--methods M,...]
                [--reference METHOD [--diff]]
    lumos explain SCENE --pixel X Y [--method M] [--json] [every render flag]
    lumos serve SCENE [--host H] [--port P] [--method M] [--width W --height H] [--open]

Exit codes: 0 success; 2 bad input or usage (one line `lumos: error: <message>` on stderr); 1 internal error
(rerun with LUMOS_DEBUG=1 for the traceback); 130 interrupted.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any, Optional, Sequence

from . import __version__
from .errors import LumosError, LumosWarning

#: render flags that override the scene's `render:` block (argparse dest == setting name).
SETTING_FLAGS = ("method", "shading", "width", "height", "spp", "max_depth", "seed", "threads", "exposure", "aov",
                 "antialias", "time_limit", "denoise", "filter", "sampling", "sampler", "light_selection", "mipmap")
#: The methods, for the help text (kept in step with `api.METHODS` by a test).
METHOD_HELP = ("raycast (ray casting), raster (scan-line, z-buffer), whitted (recursive ray tracing), path "
               "(path tracing, global illumination) or radiosity (diffuse global illumination over patches)")
#: radiosity flags: argparse dest -> key of the render.radiosity block
RADIOSITY_FLAGS = {"solver": "solver", "form_factors": "form_factors", "patch_size": "patch_size",
                   "tolerance": "tolerance", "display": "display"}


def run() -> None:
    """The `lumos` console script (and `python -m lumos`): `main` in a short-lived process of our own.

    Python's cyclic garbage collector is off (reference counting still frees every image buffer; what it would
    find are the small cycles that imports and Numba's type registries leave), and the process ends with
    os._exit once the output is written and closed and stdout and stderr are flushed, skipping the interpreter's
    teardown of the Numba and LLVM objects: together 0.2 s of a 1.4 s render of Whitted's scene at 1024x768
    (bench_whitted.py, 1.41 -> 1.21 s; `--plain-main` times it without). In-process callers use `main`, which
    does neither."""
    gc.disable()
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command line `argv` (default: sys.argv[1:]) and return the exit code."""
    started = time.perf_counter()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors (argparse prints them)
        return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
    try:
        if args.command in ("render", "sheet", "explain", "serve"):
            _skip_numba_blas_probe()
        with warnings.catch_warnings():
            warnings.simplefilter("default", LumosWarning)  # each message once
            warnings.showwarning = _show_warning
            return args.run(args, started) or 0
    except LumosError as exc:
        print(f"lumos: error: {_one_line(str(exc))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("lumos: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        if os.environ.get("LUMOS_DEBUG"):
            raise
        print(f"lumos: internal error: {type(exc).__name__}: {_one_line(str(exc))}", file=sys.stderr)
        print("lumos: this is a bug in lumos; rerun with LUMOS_DEBUG=1 to see the traceback", file=sys.stderr)
        return 1


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line each on stderr: `lumos: warning: <message>` (lumos's own) or the usual form."""
    if issubclass(category, LumosWarning):
        print(f"lumos: warning: {_one_line(str(message))}", file=sys.stderr)
    else:
        print(warnings.formatwarning(message, category, filename, lineno, line).rstrip(), file=sys.stderr)


def _skip_numba_blas_probe() -> None:
    """Numba probes for BLAS by importing SciPy's linear algebra the first time it loads its array functions:
    0.14 s of a small render's 0.9 s, and SciPy's OpenBLAS starts threads that compete with the render's on a
    small machine. No lumos kernel uses BLAS (no np.dot or @ in Numba code), so this process, which is ours,
    lets the probe fail once; Numba then only uses its own loop for np.correlate. Library users are untouched."""
    if "numba.np.arraymath" in sys.modules:
        return
    import numba.np.linalg as numba_linalg

    probe = numba_linalg.ensure_blas

    def no_blas():
        raise ImportError("the lumos command runs without Numba's BLAS")

    numba_linalg.ensure_blas = no_blas
    try:
        import numba.np.arraymath  # noqa: F401  (runs the probe)
    finally:
        numba_linalg.ensure_blas = probe  # np.dot in later Numba code still finds SciPy


def _render_flags(render: argparse.ArgumentParser) -> None:
    """The flags that override the scene's render: block (lumos render and lumos explain share them)."""
    render.add_argument("--method", metavar="M", help=f"rendering method: {METHOD_HELP}")
    render.add_argument("--shading", metavar="S", help="flat, gouraud or phong (method raster)")
    render.add_argument("--width", type=int, metavar="W", help="image width in pixels")
    render.add_argument("--height", type=int, metavar="H", help="image height in pixels")
    render.add_argument("--spp", type=int, metavar="N", help="samples per pixel")
    render.add_argument("--max-depth", type=int, metavar="D", help="bounces after the first hit (whitted: secondary "
                        "rays, default 5; path: 0 = direct light only, -1 or unset = unbounded)")
    render.add_argument("--antialias", metavar="A", help="none, supersample (spp jittered samples) or adaptive")
    render.add_argument("--seed", type=int, metavar="S", help="random seed")
    render.add_argument("--threads", type=int, metavar="T", help="worker threads (default: all cores)")
    render.add_argument("--exposure", type=float, metavar="E", help="exposure multiplier for PNG output")
    render.add_argument("--aov", action="extend", nargs="+", metavar="NAME",
                        help="also write these buffers beside OUT: depth, normal, albedo, object_id, samples; "
                        "raycast, raster and whitted also the terms of the model, which add up to the image: "
                        "ambient, diffuse, specular, emitted, reflected, transmitted; path also variance (of each "
                        "pixel's mean), noisy (the image before --denoise), direct (what --max-depth 0 gathers) and "
                        "indirect (the rest)")
    tex = render.add_argument_group("textures (--method raster, raycast or whitted)")
    tex.add_argument("--no-mipmap", dest="mipmap", action="store_const", const=False, help="look textures up at "
                     "each pixel's centre instead of filtering them over its footprint (mip-mapping; ray cones in "
                     "raycast and whitted): shows the aliasing that filtering removes")
    path = render.add_argument_group("path tracing (--method path)")
    path.add_argument("--time-limit", type=float, metavar="SECONDS", help="stop after the pass of samples that "
                      "crosses this time; the image holds the samples taken so far (Ctrl-C also stops after the "
                      "current pass)")
    path.add_argument("--checkpoint-every", type=float, metavar="SECONDS", help="rewrite OUT with the samples so "
                      "far at most this often, so that a killed render leaves a valid image")
    path.add_argument("--denoise", action="store_const", const=True, help="denoise the final image with Intel Open "
                      "Image Denoise (pip install pyoidn), guided by the albedo and normal AOVs")
    path.add_argument("--filter", metavar="F", help="pixel filter: box (default) or gaussian (also raycast's, "
                      "whitted's supersampling and raster's passes)")
    path.add_argument("--sampler", metavar="S", help="sobol (default: stratified Owen-scrambled Sobol points) or "
                      "independent (uniform random numbers)")
    path.add_argument("--sampling", metavar="S", help="direct light by mis (default: light and BSDF sampling, "
                      "multiple importance sampling), light (light sampling only) or bsdf (BSDF sampling only)")
    path.add_argument("--light-selection", metavar="S", help="how light sampling picks an emitter: tree (default: "
                      "by its estimated contribution at the point, a light BVH) or power (by its power alone)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lumos", description="Render scenes with classic rendering methods.")
    parser.add_argument("--version", action="version", version=f"lumos {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    render = commands.add_parser("render", help="render a scene to an image", description="Render SCENE. "
                                 "Flags override the scene's render: block.")
    render.add_argument("scene", metavar="SCENE", help="scene file (.yaml, .yml or .json; a Mitsuba 3 .xml or "
                        "pbrt-v4 .pbrt scene), or a model file (.obj, .gltf, .glb, .ply, .stl, .off) framed and lit by "
                        "lumos")
    render.add_argument("-o", "--output", metavar="OUT", help="image to write: .png, .exr, .pfm or .npy "
                        "(default: <scene name>.png in the current folder)")
    _render_flags(render)
    render.add_argument("--frames", metavar="A:B[:STEP]|K", help="render these frames of the scene's animation "
                        "(A:B half-open, A:B:STEP, or one frame K); OUT is then a pattern such as "
                        "frames/f_%%04d.png, or a .mp4 or .gif video (which alone renders every frame). Without "
                        "--frames an animated scene renders frame 0")
    render.add_argument("--stats", metavar="FILE.json", help="write timings and ray counts as JSON")
    render.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary")
    render.add_argument("--preview", nargs="?", const="browser", metavar="TARGET", help="show the render as it "
                        "refines: browser (the default: a page on 127.0.0.1 whose address is printed, served until "
                        "Ctrl-C once the image is written), browser:PORT, browser:HOST:PORT, tev or tev:HOST:PORT (a "
                        "running tev viewer, 127.0.0.1:14158 by default). Put it after SCENE (docs/preview.md)")
    farm = render.add_argument_group("a cluster, and resuming a stopped render (docs/cluster.md)")
    farm.add_argument("--cluster", metavar="SPEC", help="render on Dask workers: local or local:N (N worker "
                      "processes here), or a scheduler's address (tcp://HOST:8786, tls://… with Dask's TLS "
                      "settings); the image is the same to the bit as a render here")
    farm.add_argument("--checkpoint", metavar="DIR", help="keep every finished piece of the render (path: bands "
                      "of rows of each block of samples; raycast, whitted: bands of rows; --frames: frames) in DIR")
    farm.add_argument("--resume", action="store_true", help="with --checkpoint: go on from the pieces in DIR")
    model = render.add_argument_group("a model file as SCENE")
    model.add_argument("--view", metavar="V", help="three-quarter (default: from the front, swung and raised), "
                       "front, back, left, right or top")
    model.add_argument("--up", metavar="A", help="the model's up axis, y or z (default: y for glTF; for other "
                       "formats z when the model is much taller along z than along y)")
    rad = render.add_argument_group("radiosity (--method radiosity)")
    rad.add_argument("--solution", metavar="FILE.npz", help="draw this saved solution (lumos radiosity solve) "
                     "instead of solving")
    _radiosity_flags(rad)
    render.set_defaults(run=run_render)

    radiosity = commands.add_parser("radiosity", help="solve a scene's radiosity once, save it, bake it",
                                    description="Radiosity solutions: solve once, then render any view from the "
                                    "saved solution, or export it for other tools.")
    rad_commands = radiosity.add_subparsers(dest="radiosity_command", metavar="COMMAND", required=True)
    rsolve = rad_commands.add_parser("solve", help="solve SCENE and save the solution (and/or export it)",
                                     description="Mesh SCENE into patches, solve the radiosity equation, and write "
                                     "the solution (.npz, for lumos render --method radiosity --solution) and/or "
                                     "the baked display mesh (.ply, .glb: per-vertex radiance as float attributes "
                                     "and sRGB colours).")
    rsolve.add_argument("scene", metavar="SCENE", help="scene file (.yaml, .yml, .json; Mitsuba .xml, pbrt .pbrt)")
    rsolve.add_argument("-o", "--output", metavar="OUT.npz", help="the solution to write (default: <scene "
                        "name>.npz in the current folder, unless only --export is given)")
    rsolve.add_argument("--export", action="append", metavar="BAKED", help="also write the display mesh with "
                        "its radiance: .ply or .glb (repeatable)")
    rsolve.add_argument("--exposure", type=float, metavar="E", help="exposure of the exported sRGB colours")
    rsolve.add_argument("--seed", type=int, metavar="S", help="random seed")
    rsolve.add_argument("--threads", type=int, metavar="T", help="worker threads (default: all cores)")
    _radiosity_flags(rsolve)
    rsolve.add_argument("--stats", metavar="FILE.json", help="write the solve's figures as JSON")
    rsolve.add_argument("-q", "--quiet", action="store_true", help="no progress lines and no summary")
    rsolve.set_defaults(run=run_radiosity_solve)

    warm = commands.add_parser("warmup", help="compile every kernel now (in parallel), so no render waits for it",
                               description="Compile (or check) lumos's kernels ahead of the first render, one "
                               "process per kernel family, and say where the cache lives. `pip install .` does this "
                               "when it builds the wheel; editable installs, Dask workers and CI run it themselves.")
    warm.add_argument("--methods", metavar="M,...", help="only these families (default: all): "
                      "bvh, raycast, raster, whitted, path, radiosity, queries")
    warm.add_argument("--jobs", type=int, metavar="N", help="processes at once (default: one per core)")
    warm.add_argument("--quiet", action="store_true", help="print nothing")
    warm.add_argument("--plan", metavar="METHOD", help="compile the device functions METHOD's compile plan gives "
                      "a helper (what a cold first render runs beside its own compile: "
                      "lumos.methods.compile_plan; METHOD-lean: the plan of its kernels for plain scenes), "
                      "then only the families --methods names")
    warm.set_defaults(run=run_warmup)

    info = commands.add_parser("info", help="print what a scene holds")
    info.add_argument("scene", metavar="SCENE", help="scene file (.yaml, .yml, .json; Mitsuba .xml, pbrt .pbrt)")
    info.set_defaults(run=run_info)

    compare = commands.add_parser("compare", help="error figures between two images (B is the reference)")
    compare.add_argument("a", metavar="A", help="image (.png, .exr, .pfm, .npy, .jpg)")
    compare.add_argument("b", metavar="B", help="reference image")
    compare.add_argument("--diff", metavar="D.png", help="write a heat map of the per-pixel error")
    compare.set_defaults(run=run_compare)

    explain = commands.add_parser("explain", help="say what produced one pixel: its ray tree, polygon, terms",
                                  description="Explain pixel X Y (column, row from the top left) of SCENE as lumos "
                                  "render makes it with the same flags: for whitted the ray tree (every ray, what "
                                  "it hit, the local terms per light with their shadows, the reflected and "
                                  "transmitted weights, and how they add up to the pixel); for raster the polygon, "
                                  "its vertices (and their light, Gouraud), the interpolated normal, depth and "
                                  "coverage; for raycast the hit and its terms.")
    explain.add_argument("scene", metavar="SCENE", help="scene file (.yaml, .yml, .json; Mitsuba .xml, pbrt .pbrt)")
    explain.add_argument("--pixel", type=int, nargs=2, metavar=("X", "Y"), required=True,
                         help="the pixel: column X and row Y, from the top left, from 0")
    explain.add_argument("--json", action="store_true", help="print one JSON object: value (the pixel's linear "
                         "RGB) and the tree, instead of the text")
    _render_flags(explain)
    explain.set_defaults(run=run_explain)

    sheet = commands.add_parser("sheet", help="render a scene with every method, side by side in one image",
                                description="Render SCENE with each method (and each shading of raster) and "
                                "write the renders as one labelled grid with their render times (and, with --reference, their "
                                "errors against one of them).")
    sheet.add_argument("scene", metavar="SCENE", help="scene file (.yaml, .yml, .json; Mitsuba .xml, pbrt .pbrt)")
    sheet.add_argument("-o", "--output", metavar="OUT", help="sheet to write: .png or .jpg "
                       "(default: <scene name>-sheet.png in the current folder)")
    sheet.add_argument("--width", type=int, metavar="W", help="width of each render (default: the scene's, "
                       "at most 640)")
    sheet.add_argument("--height", type=int, metavar="H", help="height of each render")
    sheet.add_argument("--spp", type=int, metavar="N", help="samples per pixel")
    sheet.add_argument("--threads", type=int, metavar="T", help="worker threads (default: all cores)")
    sheet.add_argument("--columns", type=int, metavar="C", help="renders per row (default: up to 4)")
    sheet.add_argument("--methods", metavar="M,...", help="only these methods, in this order (e.g. raster,raycast)")
    sheet.add_argument("--reference", metavar="METHOD", help="compare every other cell with this one: its "
                       "caption gets the RMSE and mean relative error against it (linear radiance). METHOD is a "
                       "method (raycast, raster, whitted, path, radiosity; raster alone: the scene's shading) or "
                       "raster:SHADING (raster:flat, raster:gouraud, raster:phong)")
    sheet.add_argument("--diff", action="store_true", help="with --reference: add difference images under the "
                       "grid, |cell - reference| (largest channel) on one false-colour scale, black 0 to white "
                       "at 0.5 of the display's white")
    sheet.add_argument("--terms", metavar="METHOD", help="instead of one cell per method: METHOD's render taken "
                       "apart into the terms of the model (ambient, diffuse, specular, emitted, reflected, "
                       "transmitted) and their sum, the image. METHOD: raycast, whitted or raster:SHADING")
    sheet.add_argument("-q", "--quiet", action="store_true", help="no progress lines and no summary")
    sheet.set_defaults(run=run_sheet)

    serve = commands.add_parser("serve", help="a live preview page: edit the scene and watch it render",
                                description="Serve a page that renders SCENE progressively and lets you edit it "
                                "live: method and shading, the camera (drag to orbit), lights, materials, exposure, "
                                "tone map, AOVs and terms, a pixel's explanation, and Save to a new scene file. "
                                "Prints the page's address (with its access token) and serves until Ctrl-C "
                                "(docs/preview.md). Needs pip install \"lumos[preview]\".")
    serve.add_argument("scene", metavar="SCENE", help="scene file (.yaml, .yml or .json)")
    serve.add_argument("--host", default="127.0.0.1", metavar="H", help="address to listen on (default 127.0.0.1, "
                       "this machine only; any other is warned about: the token is then all that guards the page)")
    serve.add_argument("--port", type=int, default=0, metavar="P", help="port (default 0: a free one)")
    serve.add_argument("--method", metavar="M", help=f"rendering method to start with: {METHOD_HELP}")
    serve.add_argument("--shading", metavar="S", help="flat, gouraud or phong (method raster)")
    serve.add_argument("--width", type=int, metavar="W", help="preview width in pixels (default: the scene's, "
                       "scaled to fit 320)")
    serve.add_argument("--height", type=int, metavar="H", help="preview height in pixels")
    serve.add_argument("--spp", type=int, metavar="N", help="samples per pixel (default: the scene's; path: at "
                       "least 256, refined pass by pass)")
    serve.add_argument("--exposure", type=float, metavar="E", help="exposure to start with")
    serve.add_argument("--open", action=argparse.BooleanOptionalAction, default=False, help="open the page in "
                       "the default web browser (default: --no-open)")
    serve.set_defaults(run=run_serve)
    return parser


# ------------------------------------------------------------------------------------------------ commands


def _radiosity_flags(group) -> None:
    group.add_argument("--solver", metavar="S", help="auto (default: progressive up to "
                       "20,000 patches, stochastic beyond), gauss_seidel, jacobi, progressive or stochastic")
    group.add_argument("--form-factors", metavar="F", help="raycast (default) or hemicube")
    group.add_argument("--patch-size", type=float, metavar="X", help="largest patch edge, in scene units")
    group.add_argument("--tolerance", type=float, metavar="T", help="stop when the unshot power or a sweep's "
                       "change falls below this fraction (default 0.01)")
    group.add_argument("--display", metavar="D", help="gouraud (default) or flat: how the solution is drawn "
                       "(a solve only records it)")


def _radiosity_overrides(args) -> dict:
    block = {key: getattr(args, dest) for dest, key in RADIOSITY_FLAGS.items() if getattr(args, dest, None) is not None}
    return {"radiosity": block} if block else {}


def run_radiosity_solve(args: argparse.Namespace, started: float) -> int:
    from . import api
    from .radiosity.export import FORMATS
    from .radiosity.solve import solve
    from .io.atomic import check_output_path
    from .scene.loader import load_scene

    out = Path(args.output) if args.output else (None if args.export else Path(Path(args.scene).stem + ".npz"))
    if out is not None and out.suffix.lower() != ".npz":
        raise LumosError(f"cannot write solution '{out}': a solution is an .npz file")
    for path in args.export or []:
        if Path(path).suffix.lower() not in FORMATS:
            raise LumosError(f"cannot export '{path}': the baked mesh is {' or '.join(FORMATS)}")
    # the outputs' folders are checked before the solve, which may take minutes
    if out is not None:
        check_output_path(out, (".npz",), "cannot write solution")
    for path in args.export or []:
        check_output_path(path, tuple(FORMATS), "cannot export")
    if args.stats:
        _check_stats_path(Path(args.stats))
    scene = load_scene(args.scene)
    overrides = {"method": "radiosity", "seed": args.seed, "threads": args.threads, **_radiosity_overrides(args)}
    cfg = api.resolve_settings(scene, overrides)
    say = None if args.quiet else (lambda text: print(f"lumos: radiosity {text}", file=sys.stderr, flush=True))
    from .methods.common import set_threads

    set_threads(cfg.threads)
    solution = solve(scene, cfg, say=say)
    if out is not None:
        solution.save(out)
    for path in args.export or []:
        solution.export(path, exposure=args.exposure if args.exposure is not None else cfg.exposure)
    stats = dict(solution.stats, total_s=time.perf_counter() - started)
    if args.stats:
        _write_json(Path(args.stats), stats)
    if not args.quiet:
        written = [str(p) for p in ([out] if out is not None else []) + list(args.export or [])]
        print(f"lumos: radiosity {_radiosity_summary(stats)} -> {', '.join(written)}", file=sys.stderr)
    return 0


def _radiosity_summary(stats: dict) -> str:
    """`progressive, raycast form factors: 4,812 patches, 2,610 iterations, residual 0.99%, form factors 3.1 s,
    solve 0.2 s, 4.0 s in all`."""
    return (f"{stats.get('solver')}, {stats.get('form_factors')} form factors: {stats.get('patches', 0):,} patches, "
            f"{stats.get('iterations', 0):,} iterations, residual {stats.get('residual', 0.0):.2%}, form factors "
            f"{stats.get('form_factor_s', 0.0):.2f} s, solve {stats.get('solve_s', 0.0):.2f} s, "
            f"{stats.get('total_s', 0.0):.2f} s in all")


def run_render(args: argparse.Namespace, started: float) -> int:
    from . import api
    from .io.image_files import check_output_path
    from .scene.loader import load_scene

    if args.frames is not None or _is_video(args.output):
        return run_render_frames(args, started)
    out = Path(args.output) if args.output else Path(Path(args.scene).stem + ".png")
    check_output_path(out)
    if args.stats:
        _check_stats_path(Path(args.stats))
    t0 = time.perf_counter()
    scene = load_scene(args.scene, view=args.view, up=args.up)
    if scene.animation is not None:  # an animated scene without --frames: frame 0
        from .scene.animation import scene_at

        scene = scene_at(scene, 0.0)
    load_s = time.perf_counter() - t0
    overrides, cfg = _render_settings(args, scene)  # bad flags fail here, before anything is compiled
    on_pass = None
    if args.checkpoint_every is not None:
        if cfg.method != "path":
            raise LumosError(f"--checkpoint-every is a path feature; method {cfg.method} does not take it")
        if not args.checkpoint_every > 0:
            raise LumosError(f"--checkpoint-every: expected a positive number of seconds, got {args.checkpoint_every}")
        on_pass = _checkpointer(out, args.checkpoint_every)
    if args.resume and args.checkpoint is None:
        raise LumosError("--resume goes on from a --checkpoint folder: give it with --checkpoint DIR")
    if (args.cluster or args.checkpoint) and (on_pass is not None or args.solution is not None
                                              or cfg.time_limit is not None):
        flag = ("--checkpoint-every" if on_pass is not None else "--solution" if args.solution is not None
                else "--time-limit")
        raise LumosError(f"{flag} is for a render in this process, not with --cluster or --checkpoint")
    farm = {"checkpoint": args.checkpoint, "resume": args.resume}
    target = None
    if args.preview is not None:
        if args.cluster or args.checkpoint:
            raise LumosError("--preview shows a render made in this process, not with --cluster or --checkpoint")
        from .preview.targets import open_target

        target = open_target(args.preview, scene, cfg, Path(args.scene).name, quiet=args.quiet)
        on_pass = _both(on_pass, target.on_pass)
    try:
        img = _render_image(args, api, scene, on_pass, farm, overrides)
    except BaseException:
        if target is not None:
            target.close()
        raise
    if target is not None:
        target.done(img)
    img.save(out)
    stats = dict(img.stats, load_s=load_s, total_s=time.perf_counter() - started)
    if args.stats:
        _write_json(Path(args.stats), stats)
    if not args.quiet:
        if "radiosity" in stats and args.solution is None:
            print(f"lumos: radiosity {_radiosity_summary(dict(stats['radiosity'], total_s=stats['render_s']))}",
                  file=sys.stderr)
        print(f"lumos: {_summary(stats)} -> {out}", file=sys.stderr)
        if args.cluster or args.checkpoint:
            from .cluster import describe

            print(f"lumos: {describe(stats)}", file=sys.stderr)
    if target is not None:
        target.finish()
    return 0


def _both(first, second):
    """One `on_pass` callback that calls `first` (or nothing) and then `second`."""
    if first is None:
        return second
    return lambda image: (first(image), second(image))


def _render_image(args, api, scene, on_pass, farm, overrides):
    """The image of `lumos render`: here, or on the cluster `--cluster` names."""
    if args.cluster:
        from .cluster import connect

        client, close = connect(args.cluster)
        try:
            if not args.quiet and client.dashboard_link:
                print(f"lumos: Dask dashboard at {client.dashboard_link}", file=sys.stderr)
            return api.render(scene, progress=not args.quiet, client=client, **farm, **overrides)
        finally:
            close()
    return api.render(scene, progress=not args.quiet, on_pass=on_pass, solution=args.solution, **farm, **overrides)


def _is_video(output: Optional[str]) -> bool:
    from .io.video import is_video

    return is_video(output)


def _frame_name(pattern: str, frame: int) -> str:
    """`frames/f_%04d.png` and 7 -> `frames/f_0007.png`; a name without a % is the name (one frame)."""
    return pattern % frame if "%" in pattern else pattern


def parse_frames(spec: str):
    """`--frames`: 'A:B' and 'A:B:STEP' (half-open; A or B may be left out) -> slice, 'K' -> int."""
    parts = spec.split(":")
    try:
        if len(parts) == 1:
            return int(parts[0])
        if len(parts) in (2, 3):
            return slice(*(int(p) if p.strip() else None for p in parts))
    except ValueError:
        pass
    raise LumosError(f"--frames: expected A:B, A:B:STEP or one frame K (integers), got {spec!r}")


def run_render_frames(args: argparse.Namespace, started: float) -> int:
    """`lumos render SCENE --frames A:B -o frames/f_%04d.png` (or `-o video.mp4`): the frames of the scene's
    animation, each written as it is rendered, or encoded into one video written whole at the end."""
    from .animate import frame_indices
    from .io.image_files import SUPPORTED, check_output_path
    from .io.video import check_video_path
    from .scene.loader import load_scene

    if args.preview is not None:
        raise LumosError("--preview shows one render as it refines; it does not take --frames or a video output")
    video = _is_video(args.output)
    pattern = args.output or f"{Path(args.scene).stem}_%04d.png"
    if video:
        check_video_path(pattern)
    if args.stats:
        _check_stats_path(Path(args.stats))
    if args.checkpoint_every is not None:
        raise LumosError("--checkpoint-every rewrites one image as it renders; with --frames each frame is written "
                         "when it is done")
    if video and args.aov:
        raise LumosError("--aov writes image files beside the image; a video holds the image only (write frames: "
                         "-o frames/f_%04d.png)")
    if args.resume and args.checkpoint is None:
        raise LumosError("--resume goes on from a --checkpoint folder: give it with --checkpoint DIR")
    t0 = time.perf_counter()
    scene = load_scene(args.scene, view=args.view, up=args.up)
    load_s = time.perf_counter() - t0
    selection = parse_frames(args.frames) if args.frames is not None else None
    frames = frame_indices(scene, selection)
    if not video:
        names = []
        for k in (frames[0], frames[-1]):
            try:
                names.append(_frame_name(pattern, k))
            except (TypeError, ValueError):
                raise LumosError(f"-o {pattern}: a pattern for frames takes one %d-style number, such as "
                                 f"frames/f_%04d.png") from None
        if len(frames) > 1 and names[0] == names[1]:
            raise LumosError(f"-o {pattern}: {len(frames)} frames need a file name each: put the frame number in "
                             f"it, e.g. {Path(pattern).with_name(Path(pattern).stem + '_%04d' + Path(pattern).suffix)}")
        if Path(names[0]).suffix.lower() not in SUPPORTED:
            check_output_path(names[0])  # says which extensions there are
    overrides, cfg = _render_settings(args, scene)  # bad flags fail here, before anything is compiled
    client, close = None, (lambda: None)
    if args.cluster:
        from .cluster import connect

        client, close = connect(args.cluster)
        if not args.quiet and client.dashboard_link:
            print(f"lumos: Dask dashboard at {client.dashboard_link}", file=sys.stderr)
    try:
        return _write_frames(args, started, scene, load_s, frames, selection, pattern, video, overrides, client)
    finally:
        close()


def _write_frames(args, started, scene, load_s, frames, selection, pattern, video, overrides, client) -> int:
    """The frames of `run_render_frames` rendered (here or on the cluster's workers) and written."""
    from .animate import frames_of, render_frames
    from .io.image_files import check_output_path
    from .io.video import write_video

    # every frame's scene is made and checked here, before anything is written
    images = render_frames(scene, frames, progress=not args.quiet, solution=args.solution, client=client,
                           checkpoint=args.checkpoint, resume=args.resume, **overrides)
    if not video:
        for k in frames:
            Path(_frame_name(pattern, k)).parent.mkdir(parents=True, exist_ok=True)  # frames/ for frames/f_%04d.png
        check_output_path(_frame_name(pattern, frames[0]))
    per_frame = []

    def kept(source):
        for image in source:
            per_frame.append(dict(image.stats))
            yield image

    if video:  # every STEPth frame plays at fps/STEP: the video keeps the animation's speed
        step = selection.step if isinstance(selection, slice) and selection.step else 1
        write_video(pattern, frames_of(kept(images)), fps=(scene.animation.fps if scene.animation else 24.0) / step)
    else:
        for image in kept(images):
            image.save(_frame_name(pattern, image.stats["frame"]))
    total_s = time.perf_counter() - started
    stats = {"frames": len(per_frame), "load_s": load_s, "total_s": total_s,
             "render_s": sum(s.get("render_s", 0.0) for s in per_frame),
             "rays": sum(int(s.get("rays", 0)) for s in per_frame),
             "radiosity_solves": sum(s.get("radiosity_solves", 0) for s in per_frame), "per_frame": per_frame}
    if args.stats:
        _write_json(Path(args.stats), stats)
    if not args.quiet:
        last = per_frame[-1]
        solves = (f", radiosity solved {stats['radiosity_solves']} time{'s' if stats['radiosity_solves'] != 1 else ''}"
                  if last.get("method") == "radiosity" else "")
        print(f"lumos: {len(per_frame)} frame{'s' if len(per_frame) != 1 else ''} ({last.get('method')} "
              f"{last.get('width')}x{last.get('height')}, {last.get('spp')} spp), {total_s:.2f} s (render "
              f"{stats['render_s']:.2f} s){solves} -> {pattern}", file=sys.stderr)
    return 0


def _render_settings(args: argparse.Namespace, scene):
    """The render flags given, as overrides of the scene's `render:` block, and the settings they resolve to;
    refuses a flag the chosen method does not take."""
    from . import api

    overrides = {key: getattr(args, key) for key in SETTING_FLAGS if getattr(args, key) is not None}
    overrides.update(_radiosity_overrides(args))
    cfg = api.resolve_settings(scene, overrides)
    if args.solution is not None and cfg.method != "radiosity":
        raise LumosError(f"--solution is a radiosity solution; method {cfg.method} does not draw one")
    if args.mipmap is not None and cfg.method not in ("raster", "raycast", "whitted"):
        raise LumosError(f"--no-mipmap is a setting of raster, raycast and whitted; method {cfg.method} does not "
                         f"filter textures")
    radiosity_given = _radiosity_overrides(args)
    if radiosity_given and cfg.method != "radiosity":
        flag = "--" + next(iter(radiosity_given["radiosity"])).replace("_", "-")
        raise LumosError(f"{flag} is a radiosity setting; method {cfg.method} does not take it")
    return overrides, cfg


def _checkpointer(out: Path, every: float):
    """An `on_pass` callback that saves the image so far to `out` (atomically) once `every` seconds have passed
    since the last save."""
    last = [time.perf_counter()]

    def save(image) -> None:
        now = time.perf_counter()
        if now - last[0] >= every:
            image.save(out)
            last[0] = now

    return save


def run_serve(args: argparse.Namespace, started: float) -> int:
    """`lumos serve SCENE`: the preview page (lumos.preview), served until Ctrl-C."""
    from .preview.server import PreviewServer, warn_if_exposed
    from .preview.session import Session

    settings = {key: getattr(args, key) for key in ("method", "shading", "width", "height", "spp", "exposure")}
    session = Session.from_file(args.scene, start=False, **settings)  # a bad scene or flag fails here
    try:
        server = PreviewServer(session, args.host, args.port)
        session.start()  # the first image is on its way before the page asks for it
        warn_if_exposed(args.host)
        print(f"lumos: preview at {server.url}", file=sys.stderr, flush=True)
        if args.open:
            import webbrowser

            webbrowser.open(server.url)
        server.serve()  # until Ctrl-C: uvicorn shuts down, then raises it again
    except KeyboardInterrupt:
        pass  # Ctrl-C is how the preview ends
    finally:
        session.close()
    print("lumos: preview stopped", file=sys.stderr)
    return 0


def run_warmup(args: argparse.Namespace, started: float) -> int:
    from .tools import warmup

    try:
        families = warmup.families_for(args.methods.split(",") if args.methods else None)
    except ValueError as exc:
        raise LumosError(f"--methods: {exc}") from None
    if args.jobs is not None and args.jobs < 1:
        raise LumosError("--jobs: give at least 1")
    if args.plan is not None:
        from .api import METHODS
        from .methods import compile_plan as plan

        if args.plan.removesuffix(plan.LEAN) not in METHODS:
            raise LumosError(f"--plan: unknown method {args.plan!r} (choose from {', '.join(METHODS)}, each "
                             f"optionally with {plan.LEAN}: its kernels for plain scenes)")
        plan.compile_share(args.plan)
        if not args.methods:
            return 0
    return warmup.main(families, jobs=args.jobs, quiet=args.quiet)


def run_info(args: argparse.Namespace, started: float) -> int:
    from . import api
    from .scene.loader import load_scene

    info = api.scene_info(load_scene(args.scene))
    rows = [("scene", args.scene)] + [(key, _describe(key, value)) for key, value in info.items()]
    width = max(len(key) for key, _ in rows)
    for key, text in rows:
        print(f"{key.replace('_', ' '):<{width}}  {text}")
    return 0


def run_compare(args: argparse.Namespace, started: float) -> int:
    from .tools import metrics
    from .io.image_files import check_output_path, read_image, write_image

    if args.diff:
        check_output_path(args.diff)
    a, b = read_image(args.a), read_image(args.b)
    figures = metrics.compare(a, b)
    for key, value in figures.items():
        unit = " dB" if key == "psnr" and math.isfinite(value) else ""
        print(f"{key:<15} {value:.6g}{unit}")
    if args.diff:
        write_image(args.diff, metrics.diff_image(a, b), srgb=False)
    return 0


def run_explain(args: argparse.Namespace, started: float) -> int:
    from .tools.explain import explain, format_text
    from .scene.loader import load_scene

    scene = load_scene(args.scene)
    overrides = {key: getattr(args, key) for key in SETTING_FLAGS if getattr(args, key) is not None}
    overrides.update(_radiosity_overrides(args))
    if args.checkpoint_every is not None:
        raise LumosError("--checkpoint-every writes a render's image; lumos explain writes none")
    x, y = args.pixel
    tree = explain(scene, x, y, **overrides)
    if args.json:
        print(json.dumps(tree))
    else:
        print(format_text(tree))
    return 0


def run_sheet(args: argparse.Namespace, started: float) -> int:
    from .tools import sheet
    from .scene.loader import load_scene

    out = sheet.check_sheet_path(args.output or Path(args.scene).stem + "-sheet.png")
    entries = sheet.entries_for(args.methods.split(",")) if args.methods is not None else None
    scene = load_scene(args.scene)
    flags = ("width", "height", "spp", "threads")
    overrides = {key: getattr(args, key) for key in flags if getattr(args, key) is not None}
    if args.terms is not None:
        for flag, given in (("--methods", args.methods), ("--reference", args.reference), ("--diff", args.diff)):
            if given:
                raise LumosError(f"--terms takes one method apart; it does not combine with {flag}")
        image, cells = sheet.make_terms_sheet(scene, args.terms, args.columns, progress=not args.quiet,
                                              title=Path(args.scene).name, **overrides)
        sheet.save_sheet(image, out)
        if not args.quiet:
            print(f"lumos: terms of {args.terms} ({cells[0]['width']}x{cells[0]['height']}), "
                  f"{time.perf_counter() - started:.2f} s -> {out}", file=sys.stderr)
        return 0
    image, cells = sheet.make_sheet(scene, entries, args.columns, progress=not args.quiet,
                                    title=Path(args.scene).name, reference=args.reference, diff=args.diff,
                                    **overrides)
    sheet.save_sheet(image, out)
    if not args.quiet:
        first, count = cells[0], f"{len(cells)} render{'s' if len(cells) > 1 else ''}"
        failed = sum(cell["image"] is None for cell in cells)
        count += f", {failed} not rendered (the cells say why)" if failed else ""
        print(f"lumos: sheet of {count} ({first['width']}x{first['height']}), {time.perf_counter() - started:.2f} s "
              f"(warm-up {image.info['compile_s']:.2f} s) -> {out}", file=sys.stderr)
    return 0


# ------------------------------------------------------------------------------------------------- helpers


def _summary(stats: dict) -> str:
    """`raycast 640x480, 1 spp, 0.84 s (render 0.61 s), 307,200 rays, 0.50 Mrays/s`, and for a first run
    `(... compiling kernels 17.3 s, once)`; a path render stopped early says after how many samples."""
    spp = f"{stats.get('spp', '?')} spp"
    if stats.get("stopped"):
        spp += f" (stopped by the {stats['stopped']} after {stats.get('passes', '?')} passes)" \
            if stats["stopped"] == "time limit" else f" (interrupted after {stats.get('passes', '?')} passes)"
    jit = f", compiling kernels {stats['jit_s']:.1f} s, once" if stats.get("jit_s", 0.0) >= 0.5 else ""
    bad = f", {stats['discarded_samples']:,} non-finite samples dropped" if stats.get("discarded_samples") else ""
    return (
        f"{stats.get('method', '?')} {stats.get('width', '?')}x{stats.get('height', '?')}, "
        f"{spp}, {stats['total_s']:.2f} s (render {stats.get('render_s', 0.0):.2f} s{jit}), "
        f"{int(stats.get('rays', 0)):,} rays, {stats.get('mrays_per_s', 0.0):.2f} Mrays/s{bad}"
    )


def _describe(key: str, value: Any) -> str:
    """One readable line for a `scene_info` entry."""
    if isinstance(value, dict) and key in ("objects", "lights", "emissive_objects"):
        total = sum(value.values())
        parts = ", ".join(f"{kind} {count}" for kind, count in value.items())
        return f"{total} ({parts})" if parts else "0"
    if isinstance(value, dict):
        return ", ".join(f"{k}={_num(v)}" for k, v in value.items())
    if key == "bounds" and isinstance(value, (list, tuple)) and len(value) == 2:
        lo, hi = value
        return f"({', '.join(map(_num, lo))}) .. ({', '.join(map(_num, hi))})"
    return _num(value)


def _num(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, int) and not isinstance(value, bool):
        return f"{value:,}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(map(_num, value)) + "]"
    return str(value)


def _check_stats_path(path: Path) -> None:
    if path.is_dir():
        raise LumosError(f"cannot write stats '{path}': it is a directory")
    folder = path.parent
    if not folder.is_dir():
        raise LumosError(f"cannot write stats '{path}': folder '{folder}' does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise LumosError(f"cannot write stats '{path}': permission denied (folder '{folder}' is not writable)")


def _write_json(path: Path, data: dict) -> None:
    """Write `data` as JSON atomically: a temporary file beside `path`, then os.replace."""
    text = json.dumps(data, indent=2, default=str) + "\n"
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _one_line(text: str) -> str:
    return " ".join(text.split())
