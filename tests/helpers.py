"""Helpers that more than one test module uses (test modules import this, never each other), and the paths tests
read files from: `DATA` (tests/data), `EXAMPLES` (examples/) and `ROOT` (the repository).

tests/ is on sys.path (`pythonpath` in pyproject.toml), so a test file in any subfolder says `from helpers import
DATA`; fixtures live in conftest.py, the slow reference twins in naive.py and chi2.py beside this file.
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np

#: The repository root, tests/data and examples/.
ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
EXAMPLES = ROOT / "examples"

#: The smallest lit scene, as YAML text: one Lambert sphere under one point light, 32 × 24 (test_cli.py,
#: tools/test_sheet.py).
TINY = """\
camera: {position: [0, 0, 4], look_at: [0, 0, 0], fov: 40}
render: {width: 32, height: 24}
lights:
  - {type: point, position: [2, 3, 4], intensity: 1}
objects:
  - {type: sphere, center: [0, 0, 0], radius: 1, material: {kd: 0.8}}
"""


#: Lights and camera of the textured scenes that raster and raycast draw alike (methods/test_raster_textures.py,
#: kernels/test_texture_maps.py).
TEXTURE_LIGHTS = [
    {"type": "point", "position": [3.0, 4.0, 5.0], "intensity": [1.0, 0.95, 0.9]},
    {"type": "directional", "direction": [0.4, -1.0, -0.6], "intensity": 0.3},
]
TEXTURE_CAMERA = {"position": [0.3, 0.4, 3.2], "look_at": [0.0, 0.0, 0.0], "fov": 40.0}


def interior_of(object_id):
    hit = object_id >= 0
    inner = hit.copy()
    for axis in (0, 1):
        for shift in (1, -1):
            inner &= np.roll(hit, shift, axis=axis)
    return inner


def agree(ras, ray, tolerance=3e-3, share=0.99, min_pixels=2000):
    """Raster and raycast agree to `tolerance` on `share` of the pixels inside both silhouettes."""
    inner = interior_of(ray.aovs["object_id"]) & interior_of(ras.aovs["object_id"])
    assert inner.sum() > min_pixels
    err = np.abs(ras.array - ray.array).max(axis=2)[inner]
    assert np.mean(err < tolerance) >= share, np.quantile(err, share)


def sphere_mesh(segments=64):
    """A smooth uv sphere (vertices, faces, normals, uvs) from lumos's own tessellator."""
    from lumos.compile.tessellate import tessellate_shape
    from lumos.kernels import layout as L

    t = tessellate_shape(L.SHAPE_SPHERE, np.eye(4), segments, True)
    return t.vertices, t.faces, t.normals, t.uvs


def check_pieces(model) -> None:
    """An imported model's objects are well-formed scene pieces (io.models)."""
    for obj in model.objects:
        n = len(obj["vertices"])
        assert obj["vertices"].dtype == np.float64 and obj["vertices"].shape == (n, 3)
        assert obj["faces"].dtype == np.int64 and obj["faces"].shape[1] == 3
        assert obj["faces"].min() >= 0 and obj["faces"].max() < n
        assert np.isfinite(obj["vertices"]).all()
        assert obj["material"] is None or obj["material"] in model.materials
        if "normals" in obj:
            assert obj["normals"].shape == (n, 3)
            np.testing.assert_allclose(np.linalg.norm(obj["normals"], axis=1), 1.0, atol=1e-9)
        if "uvs" in obj:
            assert obj["uvs"].shape == (n, 2) and np.isfinite(obj["uvs"]).all()


#: Display radiance of the 8 vertices of the `solution` fixture (conftest.py): rows 0–1 hold the hand-checked values 0, 0.25, 0.5, 1, 2.
RADIANCE = np.array([[0.0, 0.5, 1.0], [2.0, 0.25, 0.0], [0.3, 1.7, 0.01], [0.002, 0.8, 5.0],
                     [1.0, 1.0, 1.0], [0.5, 0.5, 0.5], [0.9, 0.1, 0.6], [3.0, 0.04, 0.7]])


def one_line_error(excinfo, path) -> str:
    message = str(excinfo.value)
    assert "\n" not in message and str(path) in message, message
    return message


#: The start of a child process's script (`python -c`) that counts Numba's compiles: the names of the functions
#: compiled (not loaded from the cache), in `compiled`, with the folder `sys.argv[1]` on `sys.path`.
COUNT_COMPILES = """\
import json, os, sys
from numba.core import event
sys.path.insert(0, sys.argv[1])
compiled = []
class Count(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__name__)
    def on_end(self, ev):
        pass
event.register("numba:compile", Count())
"""


def write_sharing_package(root: Path, g_body: str = "return x * 2.0 + 1.0", second: str = "g(x[i]) - 1.0") -> None:
    """A package `ctshare` under `root` for the kernel cache's tests: two top-level kernels in one file (`first`,
    `second`), both calling the device function `g` (which calls `h`) in another (`ctshare.device`)."""
    pkg = root / "ctshare"
    pkg.mkdir(exist_ok=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "device.py").write_text(textwrap.dedent(f"""
        from lumos.kernels.jit import njit, njit_inline

        @njit
        def h(x):
            return x * x

        @njit_inline
        def g(x):
            {g_body} + h(x) * 0.0
    """))
    (pkg / "kernels.py").write_text(textwrap.dedent(f"""
        from lumos.kernels.jit import njit_serial
        from .device import g

        @njit_serial
        def first(x, out):
            for i in range(x.size):
                out[i] = g(x[i])

        @njit_serial
        def second(x, out):
            for i in range(x.size):
                out[i] = {second}
    """))


def run_script(script: str, *args: str, cache: Path, **extra_env) -> dict:
    """Run Python `script` with `args` in a fresh process whose kernel cache is `cache` (alone: no NUMBA_CACHE_DIR)
    and `extra_env` added; returns the JSON object its last line prints (test_cache.py, test_compile_plan.py)."""
    env = dict(os.environ, LUMOS_CACHE_DIR=str(cache), **extra_env)
    env.pop("NUMBA_CACHE_DIR", None)
    proc = subprocess.run([sys.executable, "-c", script, *map(str, args)], env=env, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])
