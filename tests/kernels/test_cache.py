"""The kernel cache (`lumos.kernels.cache`) and `lumos warmup`: stamps over each kernel's source closure, a stale
entry recompiled and never loaded, parallel writers losing nothing, and an installed package that needs no compile.

The stamp tests build a tiny package of their own in tmp_path, with kernels made by lumos's own decorators, and run
it in child processes (each a fresh Numba), counting Numba's compile events; each compile there takes milliseconds.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from helpers import COUNT_COMPILES, run_script, write_sharing_package

import lumos
from lumos.jitwatch import ESTIMATE_S, estimate_s, save_timings
from lumos.kernels import cache

PACKAGE = Path(lumos.__file__).resolve().parent

CHILD = textwrap.dedent("""
    import json, os, sys
    import numba
    from numba.core import event
    numba.__version__ = os.environ.get("CT_NUMBA_VERSION", numba.__version__)  # another Numba, as its stamp sees it
    sys.path.insert(0, sys.argv[1])
    top = []
    class Count(event.Listener):
        depth = 0
        def on_start(self, ev):
            if Count.depth == 0:
                top.append(ev.data["dispatcher"].py_func.__name__)
            Count.depth += 1
        def on_end(self, ev):
            Count.depth -= 1
    event.register("numba:compile", Count())
    import ctpkg.a as a
    import numpy as np
    args = {"int": (3,), "float": (2.5,), "int32": (np.int32(3),), "float32": (np.float32(3),)}
    for kind in sys.argv[2].split(","):
        value = a.f(*args[kind])
    print(json.dumps({"compiled": top, "value": float(value)}))
""")


def write_package(root: Path, g_body: str = "return x * 2", unrelated: str = "K = 1") -> None:
    pkg = root / "ctpkg"
    pkg.mkdir(exist_ok=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text(textwrap.dedent("""
        from lumos.kernels.jit import njit
        from .b import g, SCALE

        @njit
        def f(x):
            return g(x) * SCALE
    """))
    (pkg / "b.py").write_text(textwrap.dedent(f"""
        from lumos.kernels.jit import njit

        SCALE = 10

        @njit
        def g(x):
            {g_body}
    """))
    (pkg / "c.py").write_text(unrelated + "\n")


def run_child(root: Path, cache_dir: Path, kinds: str = "int") -> dict:
    return run_script(CHILD, root, kinds, cache=cache_dir)


def test_the_closure_of_a_kernel_holds_what_it_inlines_and_nothing_else():
    from lumos.methods import path_trace, raycast

    def rel(kernel):
        return {str(Path(p).relative_to(PACKAGE)) for p in cache.source_closure(kernel.py_func)}

    ray, pt = rel(raycast._raycast_rows), rel(path_trace.pass_rows)
    for closure in (ray, pt):
        assert {"kernels/traverse.py", "kernels/layout.py", "kernels/intersect.py", "config.py",
                "kernels/jit.py"} <= closure
        assert "kernels/raster.py" not in closure and "scene/model.py" not in closure
    assert "methods/raycast.py" in ray and "methods/path_trace.py" not in ray
    assert {"methods/path_trace.py", "kernels/sobol.py", "kernels/bsdf.py"} <= pt and "methods/raycast.py" not in pt


@pytest.mark.slow
def test_a_changed_source_byte_in_the_closure_recompiles_and_an_unrelated_one_does_not(tmp_path):
    write_package(tmp_path)
    cache_dir = tmp_path / "cache"
    first = run_child(tmp_path, cache_dir)
    assert first["compiled"] == ["f"] and first["value"] == 60.0
    assert run_child(tmp_path, cache_dir)["compiled"] == []  # loaded
    write_package(tmp_path, unrelated="K = 2")  # a file the kernel does not read
    assert run_child(tmp_path, cache_dir)["compiled"] == []
    write_package(tmp_path, g_body="return x * 3")  # the callee's file: the caller inlines it
    changed = run_child(tmp_path, cache_dir)
    assert changed["compiled"] == ["f"] and changed["value"] == 90.0  # new code, not the cached 60
    write_package(tmp_path, g_body="return x * 3  ")  # one byte more, same meaning: still a recompile
    assert run_child(tmp_path, cache_dir)["compiled"] == ["f"]


def test_the_cache_moves_with_its_folder(tmp_path):
    """Entries name no absolute path: a cache built in one place (the wheel's build folder) loads in another."""
    write_package(tmp_path)
    run_child(tmp_path, tmp_path / "built")
    # same package bytes in a new place, the cache copied beside it: nothing compiles
    moved = tmp_path / "moved"
    moved.mkdir()
    write_package(moved)
    import shutil

    shutil.copytree(tmp_path / "built", moved / "cache")
    again = run_child(moved, moved / "cache")
    assert again["compiled"] == [] and again["value"] == 60.0


@pytest.mark.slow
def test_parallel_writers_of_one_index_lose_no_entry(tmp_path):
    """Four processes compile four signatures of one kernel into one index at once; a fifth loads all four."""
    write_package(tmp_path)
    cache_dir = tmp_path / "cache"
    env = dict(os.environ, LUMOS_CACHE_DIR=str(cache_dir))
    env.pop("NUMBA_CACHE_DIR", None)
    procs = [subprocess.Popen([sys.executable, "-c", CHILD, str(tmp_path), kind], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for kind in ("int", "float", "int32", "float32")]
    for proc in procs:
        out, err = proc.communicate(timeout=300)
        assert proc.returncode == 0, err
        assert json.loads(out.strip().splitlines()[-1])["compiled"] == ["f"]
    assert run_child(tmp_path, cache_dir, "int,float,int32,float32")["compiled"] == []


SHARING_CHILD = COUNT_COMPILES + textwrap.dedent("""
    import numba
    numba.__version__ = os.environ.get("CT_NUMBA_VERSION", numba.__version__)  # another Numba, as its stamp sees it
    import numpy as np
    import ctshare.kernels as k
    out = np.zeros(4)
    getattr(k, sys.argv[2])(np.arange(4.0), out)
    print(json.dumps({"compiled": sorted(compiled), "out": out.tolist()}))
""")


def run_sharing_child(root: Path, cache_dir: Path, kernel: str, **extra_env) -> dict:
    return run_script(SHARING_CHILD, root, kernel, cache=cache_dir, **extra_env)


def test_a_kernel_in_another_process_loads_the_device_functions_it_shares(tmp_path):
    """Device functions are cached on their own (as linkable IR): a second kernel, compiled in a fresh process,
    compiles only itself; a changed byte in a device function's file recompiles it and its callers, never loads
    the stale code; a change to the kernels' file alone leaves the device functions loaded."""
    write_sharing_package(tmp_path)
    cache_dir = tmp_path / "cache"
    first = run_sharing_child(tmp_path, cache_dir, "first")
    assert first["compiled"] == ["first", "g", "h"] and first["out"] == [1.0, 3.0, 5.0, 7.0]
    second = run_sharing_child(tmp_path, cache_dir, "second")
    assert second["compiled"] == ["second"] and second["out"] == [0.0, 2.0, 4.0, 6.0]
    assert run_sharing_child(tmp_path, cache_dir, "second")["compiled"] == []

    write_sharing_package(tmp_path, g_body="return x * 3.0 + 1.0")  # the device function changes
    changed = run_sharing_child(tmp_path, cache_dir, "second")
    assert changed["compiled"] == ["g", "h", "second"] and changed["out"] == [0.0, 3.0, 6.0, 9.0]
    assert run_sharing_child(tmp_path, cache_dir, "first")["compiled"] == ["first"]  # g and h: loaded, new ones

    write_sharing_package(tmp_path, g_body="return x * 3.0 + 1.0", second="g(x[i]) + 1.0")  # the kernels' file
    edited = run_sharing_child(tmp_path, cache_dir, "second")
    assert edited["compiled"] == ["second"] and edited["out"] == [2.0, 5.0, 8.0, 11.0]


COUNTING = """event.register("numba:compile", Count())"""
CLAIMING_CHILD = SHARING_CHILD.replace(COUNTING, COUNTING + """
import time
class Slow(event.Listener):  # a compile of g that takes a while (with its claim held)
    def on_start(self, ev):
        if ev.data["dispatcher"].py_func.__name__ == "g" and len(sys.argv) > 3:
            print("compiling g", flush=True)
            time.sleep(float(sys.argv[3]))
    def on_end(self, ev):
        pass
event.register("numba:compile", Slow())""")
assert "Slow()" in CLAIMING_CHILD


def _claiming_child(root: Path, cache_dir: Path, kernel: str, *slow: str) -> subprocess.Popen:
    env = dict(os.environ, LUMOS_CACHE_DIR=str(cache_dir))
    env.pop("NUMBA_CACHE_DIR", None)
    return subprocess.Popen([sys.executable, "-c", CLAIMING_CHILD, str(root), kernel, *slow], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _started_compiling_g(proc: subprocess.Popen) -> None:
    line = proc.stdout.readline()
    assert line.strip() == "compiling g", proc.stderr.read()


def test_a_device_function_another_process_is_compiling_is_waited_for_not_compiled_again(tmp_path):
    """Two processes that need the same device function at once: the second finds the first's claim on it,
    waits, and loads what the first compiled (the warm-up's families and a cold render's helper share their
    device functions so). A claim left by a process that died is not waited for."""
    write_sharing_package(tmp_path)
    cache_dir = tmp_path / "cache"
    first = _claiming_child(tmp_path, cache_dir, "first", "2.0")
    _started_compiling_g(first)  # its claim on g is held from here for 2 s
    second = run_sharing_child(tmp_path, cache_dir, "second")
    out, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    assert json.loads(out.strip().splitlines()[-1])["compiled"] == ["first", "g", "h"]
    assert second["compiled"] == ["second"] and second["out"] == [0.0, 2.0, 4.0, 6.0]
    assert not list(cache_dir.rglob("*.claim"))  # every claim dropped once its entry was saved

    cache_dir = tmp_path / "cache2"
    dying = _claiming_child(tmp_path, cache_dir, "first", "600")
    _started_compiling_g(dying)
    dying.kill()
    dying.wait()
    assert list(cache_dir.rglob("*.claim"))  # left behind
    second = run_sharing_child(tmp_path, cache_dir, "second")  # (would wait CLAIM_WAIT_S for a live one)
    assert second["compiled"] == ["g", "h", "second"] and second["out"] == [0.0, 2.0, 4.0, 6.0]


def test_cache_folders_follow_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("LUMOS_CACHE_DIR", str(tmp_path / "mine"))
    assert cache.cache_dirs() == ((tmp_path / "mine").resolve(),)
    monkeypatch.delenv("LUMOS_CACHE_DIR")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "nb"))
    assert cache.cache_dirs() == ((tmp_path / "nb").resolve() / "lumos",)


def test_the_compile_estimate_is_what_the_last_warmup_measured(tmp_path, monkeypatch):
    monkeypatch.setenv("LUMOS_CACHE_DIR", str(tmp_path))
    assert estimate_s("path") == ESTIMATE_S["path"]  # nothing measured here yet: the table
    save_timings({"path": 20.0, "bvh": 5.0})
    save_timings({"raster": 30.0})  # a later warm-up of another family keeps the first's figures
    assert estimate_s("path") == pytest.approx(25.0) and estimate_s("raster") == pytest.approx(35.0)


def test_a_warmup_family_renders_general_kernels_without_a_helper_process(monkeypatch):
    """The warm-up runs a process per core already: its families' first renders start no helper beside them
    (`LUMOS_COMPILE_HELPER=0`), and compile the general kernels, not those of its plain scenes
    (`LUMOS_LEAN_KERNELS=0`, `methods.common.kernel_arrays`), while a family warms; the caller's settings are back
    afterwards."""
    from lumos.tools import warmup

    names = ("LUMOS_COMPILE_HELPER", "LUMOS_LEAN_KERNELS")
    seen = []
    monkeypatch.setitem(warmup._WORK, "bvh", lambda: seen.append(tuple(os.environ.get(n) for n in names)))
    monkeypatch.setenv("LUMOS_COMPILE_HELPER", "1")
    monkeypatch.delenv("LUMOS_LEAN_KERNELS", raising=False)
    assert warmup.warm_family("bvh").error == ""
    assert seen == [("0", "0")] and os.environ["LUMOS_COMPILE_HELPER"] == "1" and "LUMOS_LEAN_KERNELS" not in os.environ
    monkeypatch.delenv("LUMOS_COMPILE_HELPER")
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "1")
    warmup.warm_family("bvh")
    assert seen == [("0", "0")] * 2 and "LUMOS_COMPILE_HELPER" not in os.environ
    assert os.environ["LUMOS_LEAN_KERNELS"] == "1"


def test_warmup_refuses_an_unknown_family(capsys):
    from lumos import cli

    assert cli.main(["warmup", "--methods", "raycast,nope"]) == 2
    assert "unknown method or family 'nope'" in capsys.readouterr().err


@pytest.mark.skipif(not cache.packaged_dir().is_dir() or "site-packages" not in str(PACKAGE),
                    reason="lumos is not installed from a wheel (an editable install: run `lumos warmup`)")
def test_an_installed_wheel_compiles_nothing(tmp_path):
    """`pip install .` compiled every family into the package: warming again loads everything, compiles nothing."""
    env = {k: v for k, v in os.environ.items() if k not in ("LUMOS_CACHE_DIR", "NUMBA_CACHE_DIR")}
    proc = subprocess.run([sys.executable, "-m", "lumos", "warmup", "--jobs", "1"], env=env, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    from lumos.tools.warmup import families_for

    warmed = families_for(None)
    lines = [line for line in proc.stderr.splitlines() if line.split()[1:2] and line.split()[1] in warmed]
    assert len(lines) == len(warmed), proc.stderr
    assert all("up to date" in line for line in lines), proc.stderr


@pytest.mark.skipif(not cache.packaged_dir().is_dir() or "site-packages" not in str(PACKAGE),
                    reason="lumos is not installed from a wheel (an editable install: run `lumos warmup`)")
def test_the_first_render_of_every_methods_example_compiles_nothing(tmp_path):
    """After `pip install .`, the first render of each method on the scenes `bench_first_image.py` times (the
    showcase with the local methods, path's and radiosity's Cornell boxes, as they are: radiosity's refines its
    patches) compiles nothing: the warm-up reached every kernel they need, with their signatures."""
    env = {k: v for k, v in os.environ.items() if k not in ("LUMOS_CACHE_DIR", "NUMBA_CACHE_DIR")}
    root = Path(__file__).resolve().parents[2]
    scenes = {"raycast": "showcase.yaml", "raster": "showcase.yaml", "whitted": "showcase.yaml",
              "path": "path/cornell.yaml", "radiosity": "radiosity/cornell.yaml"}
    for method, scene in scenes.items():
        stats = tmp_path / f"{method}.json"
        proc = subprocess.run([sys.executable, "-m", "lumos", "render", str(root / "examples" / scene), "--method",
                               method, "--width", "32", "--height", "24", "--spp", "1", "-o",
                               str(tmp_path / f"{method}.png"), "--stats", str(stats)], env=env,
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        assert json.loads(stats.read_text())["jit_s"] == 0.0, (method, proc.stderr)


def test_numbas_own_overloads_are_cached_too(tmp_path):
    """The implementations Numba compiles for `np.empty`, `max` and the like (its `@overload`s) are kept in the
    kernel cache: a second kernel in a fresh process that uses them compiles only itself; under another Numba
    version they are compiled again, never loaded."""
    pkg = tmp_path / "ctshare"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "kernels.py").write_text(textwrap.dedent("""
        import numpy as np
        from lumos.kernels.jit import njit_serial

        @njit_serial
        def first(x, out):
            tmp = np.empty(x.size)
            for i in range(x.size):
                tmp[i] = max(x[i], 1.5)
            out[:] = tmp

        @njit_serial
        def second(x, out):
            tmp = np.empty(x.size)
            for i in range(x.size):
                tmp[i] = max(x[i], 2.5) + 1.0
            out[:] = tmp
    """))
    cache_dir = tmp_path / "cache"
    first = run_sharing_child(tmp_path, cache_dir, "first")
    assert "first" in first["compiled"] and len(first["compiled"]) > 3 and first["out"] == [1.5, 1.5, 2.0, 3.0]
    second = run_sharing_child(tmp_path, cache_dir, "second")
    assert second["compiled"] == ["second"] and second["out"] == [3.5, 3.5, 3.5, 4.0]
    assert any(p.name.startswith("dol-") for p in cache_dir.rglob("*.nbi"))
    (pkg / "kernels.py").write_text((pkg / "kernels.py").read_text() + "\n# edited: both kernels compile again\n")
    other = run_sharing_child(tmp_path, cache_dir, "second", CT_NUMBA_VERSION="0.0.other")
    assert "second" in other["compiled"] and len(other["compiled"]) > 3 and other["out"] == [3.5, 3.5, 3.5, 4.0]


def test_an_overload_is_cached_once_per_callers_options(tmp_path):
    """Numba compiles an overload's implementation once per caller's inherited options (a device function
    without the runtime, a kernel with it) and keeps both apart in a process; so does the cache: `max` called
    from each is two entries, not one that the other would load."""
    pkg = tmp_path / "ctshare"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "kernels.py").write_text(textwrap.dedent("""
        from lumos.kernels.jit import njit, njit_serial

        @njit
        def g(a):
            return max(a, 0.5) * 2.0

        @njit_serial
        def first(x, out):
            for i in range(x.size):
                out[i] = g(x[i]) + max(x[i], 0.25)
    """))
    cache_dir = tmp_path / "cache"
    assert run_sharing_child(tmp_path, cache_dir, "first")["out"] == [1.25, 3.0, 6.0, 9.0]
    entries = [p for p in cache_dir.rglob("dol-*ol_max*.nbc")]
    assert len(entries) == 2, entries
