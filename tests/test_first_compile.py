"""A first run on a cold cache compiles the method's kernels while another process compiles the BVH build's
(`api.compile_with_helper`): against the scene compiled with an empty tree, whose arrays have the types of the
real one, so that nothing compiles twice."""

from __future__ import annotations

import numpy as np
import pytest

import lumos
from lumos import api
from lumos.compile import compile_raster, compile_scene
from lumos.scene.loader import load_scene

SHOWCASE = "examples/showcase.yaml"


def numba_types(arrays):
    from numba import typeof

    return {name: typeof(value) for name, value in arrays._asdict().items()}


@pytest.mark.parametrize("compile_", [lambda s, tree: compile_scene(s, tree=tree),
                                      lambda s, tree: compile_raster(s, 24, True, tree)], ids=["scene", "raster"])
def test_a_scene_compiled_without_its_tree_has_the_arrays_types(compile_):
    """Every array of the scene compiled with an empty tree has the Numba type (dtype, dimensions, layout) of the
    real one's: the kernels compiled against it are the ones the real render calls. It holds nothing to hit."""
    scene = load_scene(SHOWCASE)
    real, empty = compile_(scene, True), compile_(scene, False)
    assert numba_types(empty.arrays) == numba_types(real.arrays)
    assert len(real.arrays.wide_nodes) and len(empty.arrays.wide_nodes) == 0 and len(empty.arrays.prim_ref) == 0
    np.testing.assert_array_equal(empty.bounds, real.bounds)


def test_has_entries_tells_a_cold_cache(tmp_path, monkeypatch):
    from lumos.kernels.bvh_build import build_nodes
    from lumos.kernels.cache import has_entries

    assert has_entries(build_nodes)  # this run's cache: the tests have built trees
    monkeypatch.setenv("LUMOS_CACHE_DIR", str(tmp_path))
    assert not has_entries(build_nodes)


def test_a_cold_first_render_compiles_beside_the_bvh_build(monkeypatch):
    """With the method's and the BVH build's kernels not cached, render starts `lumos warmup --plan raycast
    --methods bvh` in a process of its own, renders the scene compiled without its tree at 2×2 (compiling the
    method's kernels), waits for the process, then renders as always: the same image. Its kernels compiled for a
    plain scene's lean arrays (`compile.features`) have a plan of their own, `raycast-lean`."""
    import lumos.kernels.cache as cache
    from lumos import methods

    started, trees = [], []

    class Process:
        def __init__(self, args, **kwargs):
            started.append(args)

        def wait(self, timeout=None):
            return 0

    compile_for = methods.compile_for

    def recording(scene, settings, *args, tree=True, **kwargs):
        trees.append((tree, settings.width))
        return compile_for(scene, settings, *args, tree=tree, **kwargs)

    want = lumos.render(SHOWCASE, method="raycast", width=40, height=30, spp=1).array
    monkeypatch.setattr(cache, "has_entries", lambda dispatcher: False)
    monkeypatch.setattr(cache, "has_entry_for", lambda dispatcher, arrays: False)
    monkeypatch.setattr("subprocess.Popen", Process)
    monkeypatch.setattr(methods, "compile_for", recording)
    monkeypatch.setattr(api, "compile_for", recording, raising=False)
    got = lumos.render(SHOWCASE, method="raycast", width=40, height=30, spp=1).array
    assert started and started[0][1:4] == ["-m", "lumos", "warmup"]
    assert started[0][-4:] == ["--plan", "raycast", "--methods", "bvh"]  # raycast's compile plan, then the BVH
    assert trees == [(False, 2), (True, 40)]
    np.testing.assert_array_equal(got, want)
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "1")
    started.clear()
    lumos.render(SHOWCASE, method="raycast", width=40, height=30, spp=1)
    assert started[0][-4:] == ["--plan", "raycast-lean", "--methods", "bvh"]


def test_a_warm_cache_and_a_saved_solution_start_no_process(monkeypatch):
    started = []
    monkeypatch.setattr("subprocess.Popen", lambda *a, **k: started.append(a))
    lumos.render(SHOWCASE, method="raycast", width=8, height=6, spp=1)  # the BVH build's kernels are cached
    lumos.render(SHOWCASE, method="raster", width=8, height=6, spp=1, shadows=False)  # no tree to build
    assert started == []
