"""The path tracers lumos's `path` method is measured against, on Mitsuba's Cornell box: Mitsuba 3 and Cycles.

Importing this module does no work (Mitsuba and bpy are imported on first use). The functions:

    mitsuba_scene_dict(spp, max_depth, width, height)  Mitsuba's `mi.cornell_box()` as lumos renders it
                                                       (lamp_reflects=True: with its own reflecting lamp)
    mitsuba_render(variant, spp, max_depth, ...)       -> (float32 (H, W, 3) image, seconds), warm, 2 threads
    cycles_render(spp, max_depth, ...)                 -> (image, seconds), the same scene in Blender Cycles
    reference(spp, max_depth, ..., path)               a converged Mitsuba image, cached as EXR in .cache/
    rmse(a, b)                                         root mean square error over pixels and channels

Depths are **Mitsuba's** `max_depth` D everywhere here (D = 8 is `mi.cornell_box()`'s own; -1 = unbounded): it
counts the camera ray's segment and the segment that reaches the emitter, so D = 2 is direct light only.
lumos's `max_depth` and Cycles' `max_bounces` count bounces after the first hit: D - 2 (lumos 6 = Mitsuba 8).

The scene (`examples/path/cornell.yaml` is the same in lumos's format): `mi.cornell_box()` unchanged except
  - a box pixel filter (`{"type": "box"}`; Mitsuba's default there is a Gaussian) = lumos's and Cycles' BOX 1.0;
  - the light rectangle's BSDF is black (Mitsuba gives it the white diffuse BSDF; cornell.yaml's lamp has no
    `material`, and the Cycles light here does not reflect either), so all three render the same scene; with
    `lamp_reflects=True` (mitsuba_scene_dict, mitsuba_render, render_reference, reference) it keeps Mitsuba's own
    white diffuse BSDF, for comparing a lamp that reflects (tests/data/cornell_mitsuba/ref_lamp_*.npy);
  - spp, max_depth, width and height as asked (the camera keeps fov 39.3077° on the smaller axis).

Threads: every render uses `threads` (default 2) worker threads. Mitsuba's scalar and LLVM variants both run on
Dr.Jit's thread pool (nanothread), sized with `drjit.set_thread_count(threads)` before each render (the scalar
variant renders image blocks in parallel on that pool; the LLVM variant runs its kernels on it); measured on two
cores, 1 thread takes 1.9x (scalar) and 2.0x (LLVM) the 2-thread time, so the setting is in effect. Cycles:
`render.threads_mode = 'FIXED'`, `render.threads = threads`.

Timing: "warm" means the first render of each configuration is done untimed (Mitsuba: variant, depth, size, and
for the LLVM variant the spp too, as a new spp can need new kernels; Cycles: depth, size, threads), so that
Mitsuba's LLVM kernels are compiled (and Dr.Jit's kernel cache filled) and Cycles has built its BVH and compiled
its shaders; the timed figure is `time.perf_counter()` around `mi.render(...)` and the conversion of its result
to NumPy (which forces the LLVM variant's evaluation, so the whole render is inside) / around
`bpy.ops.render.render()`. Seeds change from call to call (a counter), so repeated renders are independent.

Mitsuba's LLVM variant needs Debian's libLLVM 19 (`apt-get install -y libllvm19`); this module sets
DRJIT_LIBLLVM_PATH to it when the file exists and the variable is unset (see /work/shared/PEERS.md).
Cycles: `pip install bpy` (Blender 5.0.1 as a Python module). Its wheel asks for numpy < 2 (and pip downgrades
numpy to 1.26 when installing it); with numpy 2.x it still imports and renders, after printing "A module that was
compiled using NumPy 1.x cannot be run in NumPy 2..." and "ImportError: numpy.core.multiarray failed to import"
(from a part of Blender this module does not use; import_bpy() sends that to /dev/null): the figures here were
measured so, with numpy 2.4.6.

Checked (Cornell box, 256×256 unless said): the Cycles image read back from its EXR has row 0 at the top and the red
wall on the left, as Mitsuba's and lumos's; its bounce counting is max_bounces = Mitsuba max_depth - 2 (image means
at Mitsuba depth 2, 3, 4 = Cycles 0, 1, 2, 64 spp at 128×128: within 0.06%, 0.07%, 0.5%, i.e. the noise); at depth
8 and 64 spp its mean RGB is within 0.03% of the converged Mitsuba reference's (Mitsuba's own: 0.05%).
"""

from __future__ import annotations

import itertools
import os
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CACHE = Path(__file__).resolve().parent / ".cache"
LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
VARIANTS = ("llvm_ad_rgb", "scalar_rgb")

#: Mitsuba's max_depth of `mi.cornell_box()`; lumos max_depth 6 and Cycles max_bounces 6 are the same paths.
DEPTH = 8

_seeds = itertools.count(1)  # seed 0 is left for the untimed warm-up renders

#: figures of the last timed render besides its wall seconds: "cpu_s", the CPU seconds this process (all its
#: threads) spent in it, which other processes' load on the machine inflates less than the wall time.
LAST: dict = {}


def next_seed() -> int:
    return next(_seeds)


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    """Root mean square difference of two (H, W, 3) images, over every pixel and channel (float64)."""
    d = np.asarray(a, np.float64) - np.asarray(b, np.float64)
    return float(np.sqrt(np.mean(d * d)))


# ---------------------------------------------------------------------------------------------------- Mitsuba


def _mitsuba(variant: str):
    """Import Mitsuba (with libLLVM 19 for the LLVM variants) and switch to `variant`; returns (mi, dr)."""
    if variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(LIBLLVM):
        os.environ["DRJIT_LIBLLVM_PATH"] = LIBLLVM
    import drjit as dr
    import mitsuba as mi

    if mi.variant() != variant:
        mi.set_variant(variant)
    return mi, dr


def mitsuba_version() -> str:
    import mitsuba as mi

    return f"Mitsuba {mi.__version__}"


def mitsuba_scene_dict(spp: int = 64, max_depth: int = DEPTH, width: int = 256, height: int = 256,
                       lamp_reflects: bool = False) -> dict:
    """`mi.cornell_box()` with a box filter, a black BSDF on the light and these settings (a variant must be set).

    lamp_reflects: keep `mi.cornell_box()`'s own BSDF on the light (the white diffuse one) instead of the black."""
    import mitsuba as mi

    d = mi.cornell_box()
    d["integrator"] = {"type": "path", "max_depth": int(max_depth)}
    if not lamp_reflects:
        d["light"]["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}}
    sensor = d["sensor"]
    sensor["sampler"] = {"type": "independent", "sample_count": int(spp)}
    sensor["film"]["width"], sensor["film"]["height"] = int(width), int(height)
    sensor["film"]["rfilter"] = {"type": "box"}
    return d


_mi_scenes: dict = {}  # (variant, max_depth, width, height[, "lamp"]) -> loaded scene
_warm: set = set()  # configurations rendered once already


def mitsuba_render(variant: str = "llvm_ad_rgb", spp: int = 64, max_depth: int = DEPTH, width: int = 256,
                   height: int = 256, seed: int | None = None, threads: int = 2, warm: bool = True,
                   lamp_reflects: bool = False):
    """Render the Cornell box with Mitsuba; returns (float32 (H, W, 3) linear image, seconds of the render).

    warm: render once untimed first, the first time this configuration is asked for (see the module docstring).
    lamp_reflects: the light keeps mi.cornell_box()'s white diffuse BSDF (see mitsuba_scene_dict)."""
    mi, dr = _mitsuba(variant)
    dr.set_thread_count(threads)
    key = (variant, int(max_depth), int(width), int(height)) + (("lamp",) if lamp_reflects else ())
    if key not in _mi_scenes:
        _mi_scenes[key] = mi.load_dict(mitsuba_scene_dict(spp, max_depth, width, height, lamp_reflects))
    scene = _mi_scenes[key]
    # LLVM: a new spp can mean new kernels (e.g. 17 after 16), so each spp is warmed; scalar: once per scene
    wkey = (key, int(spp)) if variant.startswith("llvm") else key
    if warm and wkey not in _warm:
        np.array(mi.render(scene, spp=int(spp), seed=0))
        _warm.add(wkey)
    seed = next_seed() if seed is None else seed
    c0, t0 = time.process_time(), time.perf_counter()
    out = mi.render(scene, spp=int(spp), seed=int(seed))
    image = np.array(out, dtype=np.float32)  # forces the evaluation of the LLVM variant's kernels
    seconds = time.perf_counter() - t0
    LAST["cpu_s"] = time.process_time() - c0
    return image[..., :3].copy(), seconds


# ---------------------------------------------------------------------------------------------------- Cycles

#: Mitsuba's cornell_box() transforms as (translate, axis, degrees, scale), applied to the rectangle [-1, 1]² in
#: z = 0 (normal +z) or the cube [-1, 1]³: to_world = T · R(axis, degrees) · S.
CORNELL_SHAPES = {
    "floor": ("rectangle", (0.0, -1.0, 0.0), (1, 0, 0), -90.0, (1.0, 1.0, 1.0), "white"),
    "ceiling": ("rectangle", (0.0, 1.0, 0.0), (1, 0, 0), 90.0, (1.0, 1.0, 1.0), "white"),
    "back": ("rectangle", (0.0, 0.0, -1.0), (1, 0, 0), 0.0, (1.0, 1.0, 1.0), "white"),
    "green-wall": ("rectangle", (1.0, 0.0, 0.0), (0, 1, 0), -90.0, (1.0, 1.0, 1.0), "green"),
    "red-wall": ("rectangle", (-1.0, 0.0, 0.0), (0, 1, 0), 90.0, (1.0, 1.0, 1.0), "red"),
    "small-box": ("cube", (0.335, -0.7, 0.38), (0, 1, 0), -17.0, (0.3, 0.3, 0.3), "white"),
    "large-box": ("cube", (-0.33, -0.4, -0.28), (0, 1, 0), 18.25, (0.3, 0.61, 0.3), "white"),
    "light": ("rectangle", (0.0, 0.99, 0.01), (1, 0, 0), 90.0, (0.23, 0.19, 0.19), "light"),
}
CORNELL_REFLECTANCE = {"white": (0.885809, 0.698859, 0.666422), "green": (0.105421, 0.37798, 0.076425),
                       "red": (0.570068, 0.0430135, 0.0443706)}
CORNELL_RADIANCE = (18.387, 13.9873, 6.75357)
CORNELL_CAMERA = {"origin": (0.0, 0.0, 3.9), "fov": 39.3077}  # looks at the origin, up +y; fov on the smaller axis


def to_world(translate, axis, degrees, scale) -> np.ndarray:
    """4×4 T · R(axis, degrees) · S (float64), as Mitsuba's ScalarTransform4f().translate().rotate().scale()."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    t = np.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    r = np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * (k @ k)  # Rodrigues: right-handed about `axis`
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(scale)
    m[:3, 3] = translate
    return m


def cornell_meshes() -> dict:
    """name -> (vertices (n, 3) float64 in world space, faces (list of index tuples, counter-clockwise about the
    outward / Mitsuba normal), material name): Mitsuba's rectangles and cubes mapped by their to_world."""
    rect = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)  # index 4x + 2y + z
    cube_faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    out = {}
    for name, (kind, tr, axis, deg, sc, material) in CORNELL_SHAPES.items():
        m = to_world(tr, axis, deg, sc)
        local, faces = (rect, [(0, 1, 2, 3)]) if kind == "rectangle" else (cube, cube_faces)
        out[name] = (local @ m[:3, :3].T + m[:3, 3], faces, material)
    return out


_bpy_scene = None


def import_bpy():
    """`import bpy`, with what it prints while importing (under numpy 2: a numpy 1.x ABI warning and a traceback
    from a part of Blender not used here; "Unable to initialise audio") sent to /dev/null. Raises ImportError."""
    import sys

    if "bpy" in sys.modules:
        return sys.modules["bpy"]
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    null = os.open(os.devnull, os.O_WRONLY)
    old_streams = sys.stdout, sys.stderr
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        import io

        sys.stdout = sys.stderr = io.StringIO()
        import bpy
    finally:
        sys.stdout, sys.stderr = old_streams
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)
    return bpy


def cycles_available() -> bool:
    try:
        import_bpy()
    except Exception:
        return False
    return True


def cycles_version() -> str:
    bpy = import_bpy()

    return f"Blender {bpy.app.version_string} Cycles"


def _cycles_build():
    """Build the Cornell box in a fresh, empty Blender scene (once per process); returns bpy.context.scene."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    materials = {}
    for name, rgb in CORNELL_REFLECTANCE.items():
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        nodes, links = mat.node_tree.nodes, mat.node_tree.links
        nodes.clear()
        bsdf = nodes.new("ShaderNodeBsdfDiffuse")  # Lambertian at roughness 0
        bsdf.inputs["Color"].default_value = (*rgb, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.0
        out = nodes.new("ShaderNodeOutputMaterial")
        links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
        materials[name] = mat
    # The light: emission of radiance S·C on the front (normal -y) only, black and non-reflecting behind.
    mat = bpy.data.materials.new("light")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    strength = max(CORNELL_RADIANCE)
    emit = nodes.new("ShaderNodeEmission")
    emit.inputs["Color"].default_value = (*(c / strength for c in CORNELL_RADIANCE), 1.0)
    emit.inputs["Strength"].default_value = strength
    black = nodes.new("ShaderNodeEmission")
    black.inputs["Strength"].default_value = 0.0
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")  # Fac 0: first shader (front), 1: second (back)
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(emit.outputs["Emission"], mix.inputs[1])
    links.new(black.outputs["Emission"], mix.inputs[2])
    out = nodes.new("ShaderNodeOutputMaterial")
    links.new(mix.outputs["Shader"], out.inputs["Surface"])
    if hasattr(mat, "emission_sampling"):
        mat.emission_sampling = "FRONT"  # light sampling from the front side only (it emits nothing behind)
    materials["light"] = mat

    for name, (verts, faces, material) in cornell_meshes().items():
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata([tuple(v) for v in verts], [], faces)
        mesh.update()
        mesh.materials.append(materials[material])
        obj = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(obj)

    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "VERTICAL"  # square image: vertical = smaller axis
    cam_data.angle_y = np.radians(CORNELL_CAMERA["fov"])
    cam_data.clip_start, cam_data.clip_end = 0.001, 100.0  # Mitsuba's near_clip and far_clip
    cam = bpy.data.objects.new("camera", cam_data)
    # Blender's camera looks along its -z with +y up: Mitsuba's to_world diag(-1, 1, -1) × diag(-1, 1, -1) = I.
    cam.location = CORNELL_CAMERA["origin"]
    cam.rotation_euler = (0.0, 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam

    world = bpy.data.worlds.new("black")  # rays that leave the box see black (Mitsuba: no environment)
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        bg.inputs["Strength"].default_value = 0.0
    scene.world = world

    r = scene.render
    r.engine = "CYCLES"
    r.threads_mode = "FIXED"
    r.use_compositing = False
    r.use_sequencer = False
    r.film_transparent = False
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.caustics_reflective = c.caustics_refractive = True
    c.blur_glossy = 0.0
    c.use_animated_seed = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    return scene


def _cycles_set(scene, spp, max_depth, width, height, seed, threads):
    scene.render.resolution_x, scene.render.resolution_y = int(width), int(height)
    scene.render.threads = int(threads)
    c = scene.cycles
    c.samples = int(spp)
    bounces = 1024 if max_depth < 0 else int(max_depth) - 2  # Cycles counts bounces after the first hit
    if bounces < 0:
        raise ValueError(f"Mitsuba max_depth {max_depth} has no Cycles equivalent (needs >= 2 or -1)")
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = bounces
    c.volume_bounces = c.transparent_max_bounces = bounces
    c.seed = int(seed)


def cycles_render(spp: int = 64, max_depth: int = DEPTH, width: int = 256, height: int = 256,
                  seed: int | None = None, threads: int = 2, warm: bool = True):
    """Render the Cornell box with Cycles; returns (float32 (H, W, 3) linear image, seconds of the render).

    max_depth is Mitsuba's (8 = Cycles max_bounces 6; -1 = 1024 bounces). The image is the 32-bit float EXR of
    the render result (linear; row 0 at the top), read back after the timed render."""
    global _bpy_scene
    bpy = import_bpy()
    if _bpy_scene is None:
        _bpy_scene = _cycles_build()
    scene = _bpy_scene
    key = ("cycles", int(max_depth), int(width), int(height), int(threads))
    if warm and key not in _warm:  # the first render builds the BVH and compiles the shaders
        _cycles_set(scene, spp, max_depth, width, height, 0, threads)
        bpy.ops.render.render()
        _warm.add(key)
    _cycles_set(scene, spp, max_depth, width, height, next_seed() if seed is None else seed, threads)
    c0, t0 = time.process_time(), time.perf_counter()
    bpy.ops.render.render()
    seconds = time.perf_counter() - t0
    LAST["cpu_s"] = time.process_time() - c0
    return _cycles_pixels(), seconds


def _cycles_pixels() -> np.ndarray:
    import tempfile

    import bpy

    from lumos.io.image_files import read_image

    with tempfile.TemporaryDirectory(prefix="cycles-") as tmp:
        path = os.path.join(tmp, "render.exr")
        bpy.data.images["Render Result"].save_render(path)
        return read_image(path).astype(np.float32)


# ---------------------------------------------------------------------------------------------------- reference


def reference_path(spp: int, max_depth: int = DEPTH, width: int = 256, height: int = 256,
                   lamp_reflects: bool = False) -> Path:
    depth = "inf" if max_depth < 0 else str(max_depth)
    lamp = "_lamp" if lamp_reflects else ""
    return CACHE / f"cornell_mitsuba{lamp}_depth{depth}_{width}x{height}_{spp}spp.exr"


def render_reference(spp: int = 16384, max_depth: int = DEPTH, width: int = 256, height: int = 256,
                     variant: str = "llvm_ad_rgb", threads: int = 2, pass_spp: int = 256, seed: int = 1_000_000,
                     verbose: bool = False, lamp_reflects: bool = False):
    """A converged Mitsuba image: the mean of spp/pass_spp renders of pass_spp samples each, with seeds seed,
    seed+1, ... (independent sampler, so this is the same estimator as one render of spp samples; passes keep the
    LLVM variant's wavefront small). Returns (float32 (H, W, 3) image, seconds of rendering in all, noise), where
    noise estimates the image's own RMSE against the exact one: RMSE(mean of the even passes, mean of the odd
    passes) / 2, since each half has twice the variance of the whole and their difference four times.
    lamp_reflects: the light keeps mi.cornell_box()'s white diffuse BSDF (see mitsuba_scene_dict)."""
    if spp % pass_spp or spp // pass_spp < 2:
        raise ValueError(f"spp {spp} must be a multiple of pass_spp {pass_spp}, at least twice it")
    passes = spp // pass_spp
    halves = np.zeros((2, height, width, 3), np.float64)
    total = 0.0
    for i in range(passes):
        img, s = mitsuba_render(variant, pass_spp, max_depth, width, height, seed=seed + i, threads=threads,
                                warm=False, lamp_reflects=lamp_reflects)
        halves[i % 2] += img
        total += s
        if verbose:
            print(f"  pass {i + 1}/{passes}: {s:.2f} s", flush=True)
    n_even, n_odd = (passes + 1) // 2, passes // 2
    noise = rmse(halves[0] / n_even, halves[1] / n_odd) / 2
    return (halves.sum(0) / passes).astype(np.float32), total, noise


def reference(spp: int = 16384, max_depth: int = DEPTH, width: int = 256, height: int = 256,
              path: str | os.PathLike | None = None, variant: str = "llvm_ad_rgb", verbose: bool = False,
              lamp_reflects: bool = False) -> np.ndarray:
    """The converged Mitsuba image of the Cornell box (float32 (H, W, 3)), from the cache if there.

    path: the EXR to read or write (default benchmarks/.cache/cornell_mitsuba_depth{D}_{W}x{H}_{spp}spp.exr).
    When no path is given, 256×256 at depth 8 or unbounded is asked and the cache is empty, the stored references of
    tests/data/cornell_mitsuba/ (made by benchmarks/make_path_reference.py) are used if they have at least `spp`
    samples; otherwise it is rendered with render_reference (depth 8, 16384 spp: about 4 minutes on two cores
    with llvm_ad_rgb; unbounded twice that) and written to `path`. lamp_reflects: the light keeps
    mi.cornell_box()'s white diffuse BSDF (see mitsuba_scene_dict; stored: ref_lamp_*.npy)."""
    from lumos.io.image_files import read_image, write_image

    out = Path(path) if path is not None else reference_path(spp, max_depth, width, height, lamp_reflects)
    if out.is_file():
        return read_image(out)
    stored = None if path is not None else stored_reference(max_depth, width, height, min_spp=spp,
                                                            lamp_reflects=lamp_reflects)
    if stored is not None:
        return stored
    if verbose:
        print(f"rendering the Mitsuba reference ({variant}, {spp} spp, max_depth {max_depth}, {width}x{height}) "
              f"into {out}", flush=True)
    img, _, _ = render_reference(spp, max_depth, width, height, variant, verbose=verbose,
                                 lamp_reflects=lamp_reflects)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_image(out, img)
    return img


STORED = ROOT / "tests" / "data" / "cornell_mitsuba"


def stored_reference(max_depth: int = DEPTH, width: int = 256, height: int = 256, min_spp: int = 0,
                     lamp_reflects: bool = False):
    """The reference stored in tests/data/cornell_mitsuba/ for this depth and size (None if there is none, or it
    has fewer than min_spp samples). Its sample count is in that folder's info.json; its entries' "lamp" is
    "white" for the references whose light keeps Mitsuba's reflecting BSDF (lamp_reflects), else absent/"black"."""
    import json

    info = STORED / "info.json"
    if not info.is_file():
        return None
    for entry in json.loads(info.read_text()).get("files", []):
        if (entry["max_depth"] == max_depth and entry["width"] == width and entry["height"] == height
                and entry["spp"] >= min_spp and (entry.get("lamp", "black") == "white") == lamp_reflects):
            return np.load(STORED / entry["file"]).astype(np.float32)
    return None
