"""Scan-line rendering of a 1.3M-triangle mesh at 1920×1080: lumos `raster` vs Mesa's llvmpipe, same frame, one run.

    python benchmarks/bench_raster.py [--width 1920] [--height 1080] [--subdivisions 8] [--repeats 5]
                                      [--threads 2] [--out /tmp/bench_raster] [--lumos-method raster]
                                      [--gl-format f4|u1]

Setup (Debian, as root), besides `pip install -e ".[bench]"` (which brings moderngl):

    apt-get install -y libegl1 libegl-mesa0 libgl1-mesa-dri
    pip install moderngl

`moderngl.create_standalone_context(backend="egl")` then gives Mesa's llvmpipe (OpenGL 4.5 core on the CPU,
LLVM-compiled shaders, tiled and multithreaded); the script stops if the renderer is anything else.

Both renderers draw trimesh's `icosphere(subdivisions)` (unit sphere; 1,310,720 triangles at 8) with smooth
per-vertex normals (the vertex positions), seen by DESIGN.md's perspective camera from (0, 0, 3), fov 45°, and
shade every pixel with the classic local model on the interpolated normal, identically: ambient 0.1, material
ka = kd = (0.8, 0.5, 0.3), ks = 0.5, n = 32, a point light at (2, 3, 4) of intensity 1 (no attenuation) and a
directional light along (−1, −1, −1) of intensity 0.3. The shading normal faces the viewer; a light gives
nothing where N·L ≤ 0. Output is linear (no sRGB), background black, one sample at each pixel centre.

llvmpipe: the mesh is uploaded once (float32 positions + normals, int32 indices), 2 warm-up frames, then
`--repeats` frames of clear + draw + `ctx.finish()` into an off-screen RGBA32F colour buffer (`--gl-format f4`,
the default, as lumos's film is float; `u1` = RGBA8, which clamps the highlight, up to 1.38 in red, to 1 and
quantises, so the images then differ by ~0.02 RMSE) with a 24-bit depth buffer, depth test on, no face culling,
no multisampling; `LP_NUM_THREADS` = `--threads` is set before the context is created. One readback (rows
flipped, so row 0 is the top as in lumos) gives the image.

lumos: the same scene as a dict → `lumos.load_scene`; one warm-up `lumos.render` (JIT compile), then `--repeats`
renders on `--threads` Numba threads; a frame is `img.stats["render_s"]` (scene compile excluded; reported
separately as `build_s`).

Prints both frame times (median and best), the ratio lumos / llvmpipe (median over median), and how the two
images differ (RMSE, share of pixels off by more than 0.02 in some channel); writes llvmpipe.png, lumos.png and
diff.png (heat map) to `--out`.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

import numpy as np
from common import frame_times, gl_look_at, gl_perspective, icosphere, machine

CAMERA = {"type": "perspective", "position": [0.0, 0.0, 3.0], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
          "fov": 45.0}
NEAR, FAR = 0.1, 100.0
AMBIENT = 0.1
MATERIAL = {"ka": [0.8, 0.5, 0.3], "kd": [0.8, 0.5, 0.3], "ks": 0.5, "shininess": 32.0}
POINT = {"type": "point", "position": [2.0, 3.0, 4.0], "intensity": 1.0}
DIRECTIONAL = {"type": "directional", "direction": [-1.0, -1.0, -1.0], "intensity": 0.3}
DIFF_THRESHOLD = 0.02

VERTEX_SHADER = """
#version 330 core
uniform mat4 mvp;
in vec3 in_position;
in vec3 in_normal;
out vec3 v_position;   // world space (the model matrix is the identity)
out vec3 v_normal;
void main() {
    v_position = in_position;
    v_normal = in_normal;
    gl_Position = mvp * vec4(in_position, 1.0);
}
"""

FRAGMENT_SHADER = """
#version 330 core
uniform vec3 eye;
uniform vec3 ambient;
uniform vec3 ka;
uniform vec3 kd;
uniform vec3 ks;
uniform float shininess;
uniform vec3 point_position;
uniform vec3 point_intensity;
uniform vec3 dir_to_light;      // -direction, normalised
uniform vec3 dir_intensity;
in vec3 v_position;
in vec3 v_normal;
out vec4 frag_color;

vec3 local(vec3 N, vec3 V, vec3 L, vec3 I) {
    float ndl = dot(N, L);
    if (ndl <= 0.0) return vec3(0.0);
    vec3 R = 2.0 * ndl * N - L;
    return kd * I * ndl + ks * I * pow(max(dot(R, V), 0.0), shininess);
}

void main() {
    vec3 N = normalize(v_normal);
    vec3 V = normalize(eye - v_position);
    if (dot(N, V) < 0.0) N = -N;
    vec3 c = ka * ambient
           + local(N, V, normalize(point_position - v_position), point_intensity)
           + local(N, V, dir_to_light, dir_intensity);
    frag_color = vec4(c, 1.0);
}
"""


def _rgb(x) -> tuple[float, float, float]:
    a = np.broadcast_to(np.asarray(x, dtype=float), (3,))
    return tuple(float(c) for c in a)


def llvmpipe(vertices, faces, normals, width, height, threads, repeats, gl_format):
    """Time llvmpipe frames; returns (frame times, image float32 (H, W, 3) with row 0 at the top, renderer)."""
    os.environ["LP_NUM_THREADS"] = str(threads)  # read when the Gallium screen is created
    os.environ.setdefault("LIBGL_ALWAYS_SOFTWARE", "1")
    import moderngl

    ctx = moderngl.create_standalone_context(backend="egl")
    renderer = ctx.info["GL_RENDERER"]
    version = ctx.info["GL_VERSION"]
    if "llvmpipe" not in renderer:
        sys.exit(f"expected Mesa's llvmpipe, got OpenGL renderer {renderer!r} ({version})")

    prog = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=FRAGMENT_SHADER)
    aspect = width / height
    view = gl_look_at(CAMERA["position"], CAMERA["look_at"], CAMERA["up"])
    proj = gl_perspective(CAMERA["fov"], aspect, NEAR, FAR)
    prog["mvp"].write((proj @ view).T.astype("f4").tobytes())  # GL wants column-major
    prog["eye"].value = _rgb(CAMERA["position"])
    prog["ambient"].value = _rgb(AMBIENT)
    prog["ka"].value = _rgb(MATERIAL["ka"])
    prog["kd"].value = _rgb(MATERIAL["kd"])
    prog["ks"].value = _rgb(MATERIAL["ks"])
    prog["shininess"].value = float(MATERIAL["shininess"])
    prog["point_position"].value = _rgb(POINT["position"])
    prog["point_intensity"].value = _rgb(POINT["intensity"])
    d = -np.asarray(DIRECTIONAL["direction"], float)
    prog["dir_to_light"].value = _rgb(d / np.linalg.norm(d))
    prog["dir_intensity"].value = _rgb(DIRECTIONAL["intensity"])

    vbo = ctx.buffer(np.hstack([vertices, normals]).astype("f4").tobytes())
    ibo = ctx.buffer(faces.astype("i4").tobytes())
    vao = ctx.vertex_array(prog, [(vbo, "3f 3f", "in_position", "in_normal")], index_buffer=ibo,
                           index_element_size=4)
    color = ctx.renderbuffer((width, height), components=4, dtype=gl_format)
    depth = ctx.depth_renderbuffer((width, height))
    fbo = ctx.framebuffer(color_attachments=[color], depth_attachment=depth)
    fbo.use()
    ctx.viewport = (0, 0, width, height)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.disable(moderngl.CULL_FACE)

    def frame():
        fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        vao.render(moderngl.TRIANGLES)
        ctx.finish()

    times = frame_times(frame, repeats, warmup=2)
    raw = np.frombuffer(fbo.read(components=3, dtype=gl_format, alignment=1),
                        dtype=np.float32 if gl_format == "f4" else np.uint8)
    image = raw.reshape(height, width, 3)[::-1].astype(np.float32)
    if gl_format == "f1":
        image /= 255.0
    return times, image, f"{renderer}; {version}"


def lumos_frames(vertices, faces, normals, width, height, threads, repeats, method):
    """Time lumos renders; returns (render_s list, build_s list, image) or None if `method` is not registered."""
    import lumos
    from lumos.errors import LumosError

    scene_dict = {
        "camera": dict(CAMERA),
        "render": {"method": method, "shading": "phong", "width": width, "height": height, "threads": threads},
        "ambient": AMBIENT,
        "lights": [dict(POINT), dict(DIRECTIONAL)],
        "materials": {"m": dict(MATERIAL)},
        "objects": [{"type": "mesh", "vertices": vertices, "faces": faces, "normals": normals, "material": "m"}],
    }
    try:
        scene = lumos.load_scene(scene_dict)
        warm = lumos.render(scene)  # JIT compile
    except LumosError as exc:
        if "unknown method" in str(exc) or method not in lumos.api.method_names():
            print(f"\nlumos: method {method!r} is not registered yet ({exc}); lumos half skipped. "
                  f"Try --lumos-method raycast to exercise this half.")
            return None
        raise
    print(f"lumos warm-up (includes JIT): render_s {warm.stats['render_s']:.3f} s, "
          f"build_s {warm.stats['build_s']:.3f} s")
    render_s, build_s, img = [], [], warm
    for _ in range(repeats):
        img = lumos.render(scene)
        render_s.append(img.stats["render_s"])
        build_s.append(img.stats["build_s"])
    return render_s, build_s, img


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=1920)
    ap.add_argument("--height", type=int, default=1080)
    ap.add_argument("--subdivisions", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default="/tmp/bench_raster")
    ap.add_argument("--lumos-method", default="raster", help="lumos method to time (default raster)")
    ap.add_argument("--gl-format", choices=("f4", "u1"), default="f4",
                    help="llvmpipe colour buffer: f4 = RGBA32F (default), u1 = RGBA8")
    args = ap.parse_args()
    gl_format = "f1" if args.gl_format == "u1" else "f4"  # moderngl's name for normalised 8-bit
    import numba

    numba.set_num_threads(args.threads)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    vertices, faces = icosphere(args.subdivisions)
    normals = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)  # smooth normals of the unit sphere
    W, H = args.width, args.height
    print(f"machine: {machine()}")
    print(f"mesh: icosphere({args.subdivisions}) = {len(faces):,} triangles, {len(vertices):,} vertices; "
          f"{W}x{H}; per-pixel Phong, 1 point + 1 directional light")
    print(f"threads: Numba {numba.get_num_threads()} (numba.set_num_threads), llvmpipe LP_NUM_THREADS={args.threads}")

    gl_times, gl_img, gl_renderer = llvmpipe(vertices, faces, normals, W, H, args.threads, args.repeats, gl_format)
    fmt_name = "RGBA32F" if gl_format == "f4" else "RGBA8"
    print(f"Mesa: {gl_renderer}; {fmt_name} colour + 24-bit depth, depth test, no culling, no MSAA")
    gl_med, gl_best = statistics.median(gl_times), min(gl_times)
    print(f"llvmpipe frames (clear + draw + finish): {', '.join(f'{t:.3f}' for t in gl_times)} s")

    from lumos.io.image_files import write_image
    from lumos.tools.metrics import compare, diff_image

    write_image(out / "llvmpipe.png", gl_img)
    result = lumos_frames(vertices, faces, normals, W, H, args.threads, args.repeats, args.lumos_method)

    rows = [("Mesa llvmpipe", gl_med, gl_best, "")]
    if result is not None:
        render_s, build_s, img = result
        lu_med, lu_best = statistics.median(render_s), min(render_s)
        print(f"lumos {args.lumos_method} frames (render_s): {', '.join(f'{t:.3f}' for t in render_s)} s; "
              f"build_s (scene compile, every render): median {statistics.median(build_s):.3f} s, "
              f"best {min(build_s):.3f} s; threads used {img.stats.get('threads')}")
        rows.append((f"lumos {args.lumos_method}", lu_med, lu_best, f"{lu_med / gl_med:.2f}"))

    print()
    print("| renderer | median frame s | best frame s | lumos / llvmpipe (median) |")
    print("|---|---:|---:|---:|")
    for name, med, best, ratio in rows:
        print(f"| {name} | {med:.3f} | {best:.3f} | {ratio} |")
    print()

    if result is not None:
        lu_img = img.array
        img.save(out / "lumos.png", aovs=False)
        figures = compare(lu_img, gl_img)  # llvmpipe as the reference
        off = np.abs(lu_img.astype(np.float64) - gl_img).max(axis=2) > DIFF_THRESHOLD
        write_image(out / "diff.png", diff_image(lu_img, gl_img), srgb=False)
        print(f"images (lumos vs llvmpipe, linear): RMSE {figures['rmse']:.5f}, PSNR {figures['psnr']:.1f} dB, "
              f"max |diff| {figures['max_abs_error']:.3f}, pixels off by > {DIFF_THRESHOLD}: "
              f"{off.mean() * 100:.3f}% ({int(off.sum()):,})")
        print(f"wrote {out / 'llvmpipe.png'}, {out / 'lumos.png'}, {out / 'diff.png'}")
    else:
        print(f"wrote {out / 'llvmpipe.png'}")


if __name__ == "__main__":
    main()
