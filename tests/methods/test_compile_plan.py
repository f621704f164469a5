"""Compile plans (`lumos.methods.compile_plan`, recorded by `lumos.tools.plans`): what a helper process compiles
beside a cold first render, and how the roots are chosen."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from helpers import COUNT_COMPILES, run_script, write_sharing_package

from lumos.kernels.cache import closure_stamp
from lumos.kernels.jit import DeviceDispatcher
from lumos.methods import compile_plan as plan
from lumos.tools.plans import HELPER_START_S, choose, simulate

CHILD = COUNT_COMPILES + textwrap.dedent("""
    from pathlib import Path
    import numpy as np
    from numba import types
    from lumos.methods import compile_plan as plan
    from lumos.kernels.cache import closure_stamp
    import ctshare.device as device
    plan.PLAN_DIR = Path(sys.argv[1]) / "plans"
    result = {}
    if sys.argv[2] == "record":  # the plan: the helper takes g (and h under it), called with a float64
        plan.PLAN_DIR.mkdir(exist_ok=True)
        (plan.PLAN_DIR / "m.json").write_text(json.dumps({"top": ["ctshare.kernels", "first"], "roots": [
            {"module": "ctshare.device", "name": "g", "stamp": closure_stamp(device.g.py_func),
             "args": plan.encode_args((types.float64,))}]}))
    elif sys.argv[2] == "share":
        result["shared"] = plan.compile_share("m")
    else:
        import ctshare.kernels as k
        out = np.zeros(4)
        k.first(np.arange(4.0), out)
        result["out"] = out.tolist()
        result["top_cached"] = plan.top_cached("m")
    result["compiled"] = sorted(compiled)
    print(json.dumps(result))
""")


def _child(root: Path, cache: Path, mode: str) -> dict:
    return run_script(CHILD, root, mode, cache=cache)


def test_a_helper_compiles_the_plans_roots_and_the_render_loads_them(tmp_path):
    """The helper process compiles a root (and its callees) into the cache; the kernel compiled after it in
    another process compiles only itself. A root whose sources changed since the plan was recorded is skipped,
    never compiled for the recorded stamp, and the kernel then compiles what it needs."""
    write_sharing_package(tmp_path)
    _child(tmp_path, tmp_path / "unused", "record")
    cache = tmp_path / "cache"
    assert _child(tmp_path, cache, "share") == {"shared": 1, "compiled": ["g", "h"]}
    render = _child(tmp_path, cache, "render")
    assert render["compiled"] == ["first"] and render["out"] == [1.0, 3.0, 5.0, 7.0] and render["top_cached"]

    write_sharing_package(tmp_path, g_body="return x * 3.0 + 1.0")  # edited after the plan was recorded
    cache = tmp_path / "cache2"
    assert _child(tmp_path, cache, "share") == {"shared": 0, "compiled": []}
    render = _child(tmp_path, cache, "render")
    assert render["compiled"] == ["first", "g", "h"] and render["out"] == [1.0, 4.0, 7.0, 10.0]


# a call graph: top (4) calls B (1) and C (3); B calls leaf 0, C calls leaf 2; compiled in index order
EXCL = [2.0, 1.0, 2.0, 1.0, 1.0]
CALLS = [[1, 0], [3, 2], [4, 1], [4, 3]]
CLOSURES = [[0], [0, 1], [2], [2, 3], [0, 1, 2, 3, 4]]


def test_the_simulation_of_both_processes():
    assert simulate([], [], EXCL, CLOSURES, start=0.3) == (7.0, 0.3)
    # the helper takes C's subtree from t = 0.3: leaf 2 done at 2.3, C at 3.3. The render compiles leaf 0 and B
    # (3.0), loads leaf 2 (done before it got there), waits for C (claimed by the helper at 2.3) until 3.3, loads
    # it, then compiles top
    t_main, t_helper = simulate([], [3], EXCL, CLOSURES, start=0.3, load=0.01)
    assert t_main == pytest.approx(3.3 + 0.01 + 1.0) and t_helper == pytest.approx(3.3)
    # the render compiling C's subtree first and the helper B's, from the same moment: they never meet, and the
    # render loads B's
    t_main, t_helper = simulate([3], [1], EXCL, CLOSURES, start=0.0, load=0.01)
    assert t_main == pytest.approx(3.0 + 0.01 + 0.01 + 1.0) and t_helper == pytest.approx(3.0)
    # both wanting the same leaf first: the helper, 0.3 s late, finds it claimed, waits and loads it
    t_main, t_helper = simulate([1], [0], EXCL, CLOSURES, start=0.3, load=0.01)
    assert t_helper == pytest.approx(2.0 + 0.01) and t_main == pytest.approx(7.0)


def test_the_plan_splits_the_call_graph_between_the_two():
    first, roots, finish, alone = choose(EXCL, CALLS, {0, 1, 2, 3}, bvh_s=0.0)
    assert alone == 7.0 and finish < alone - 0.9  # about a leaf's compile off the render's 7 s
    t_main, t_helper = simulate(first, roots, EXCL, CLOSURES)
    assert finish == pytest.approx(max(t_main, t_helper)) and roots and not set(first) & set(roots)
    # a helper that must compile the BVH build's kernels for longer than the whole render takes no share
    first, roots, finish, alone = choose(EXCL, CALLS, {0, 1, 2, 3}, bvh_s=10.0)
    assert roots == [] and finish == pytest.approx(HELPER_START_S + 10.0)


@pytest.mark.parametrize("path", sorted(plan.PLAN_DIR.glob("*.json")), ids=lambda p: p.stem)
def test_the_shipped_plans_are_current(path):
    """Every root of a shipped plan is a device function with argument types that load, recorded from the
    sources as they are: a kernel change since leaves the helper nothing to do for the roots it touches (cold
    first renders slower again), until the plans are recorded again with `python -m lumos.tools.plans`."""
    recorded = json.loads(path.read_text())
    assert plan.resolve(*recorded["top"]) is not None
    assert recorded["roots"]
    for root in recorded["roots"] + recorded["first"]:
        dispatcher = plan.resolve(root["module"], root["name"])
        assert isinstance(dispatcher, DeviceDispatcher), root["name"]
        assert closure_stamp(dispatcher.py_func) == root["stamp"], (
            f"{path.name}: {root['module']}.{root['name']} changed since its plan was recorded; run "
            "`python -m lumos.tools.plans` (from a checkout) to record the plans again")
        assert isinstance(plan.decode_args(root["args"]), tuple)


def test_every_plan_is_recorded():
    """A plan for each method a helper shares with, and one for the kernels of plain scenes (`-lean`) of each
    method that compiles them (`compile.features`)."""
    from lumos.tools.plans import PLANS

    assert {"raycast", "raster", "whitted", "path", "path-lean", "whitted-lean", "raycast-lean"} == set(PLANS)
    assert sorted(p.stem for p in plan.PLAN_DIR.glob("*.json")) == sorted(PLANS)


def test_warmup_refuses_a_plan_for_an_unknown_method():
    proc = subprocess.run([sys.executable, "-m", "lumos", "warmup", "--methods", "bvh", "--plan", "nosuch"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "--plan: unknown method 'nosuch'" in proc.stderr
