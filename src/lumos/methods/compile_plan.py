"""A cold first render's compile, shared with a second process: compile plans.

A method's first render on a cold cache compiles one top-level kernel and the device functions under it, one after
the other, in the order Numba types them (whitted's and the path tracer's: about 190 and 225 functions, 20 s on
one core). Device functions are cached on their own (`kernels.jit.DeviceLibrary`), so another process can
compile some of them meanwhile: the render, when its compile reaches one that process has finished, loads it
instead.

That process needs to know what to compile before the render's own compile has typed anything: which device
functions, for which argument types. A *plan* (`plans/<method>.json`) says so. It is recorded from a cold render
(`python -m lumos.tools.plans`), which also chooses, by simulating both processes on the recorded compile
times and call graph, the subtrees (*roots*) the helper takes, and those the render compiles *first*, before
its top-level kernel (whose compile reaches the others in call order): so the two start on different parts of
the call graph, and the render finds the helper's done when it gets there. Each root holds its
function's module and name, its argument types (pickled Numba types) and the stamp of its source closure when it
was recorded (`kernels.cache.closure_stamp`): a root whose sources have changed since is skipped, so a stale plan costs
nothing but the help it no longer gives, and the kernels compiled are always those of the sources as they are.

    compile_share("whitted")             # in the helper process (`lumos warmup --plan whitted`)
    compile_share("whitted", "first")    # in the render's, before its kernel (`api.compile_with_helper`)

A method whose kernels compile to plain scenes (`compile.features`, `methods.common.LEAN_METHODS`) has a second
plan, `<method>-lean`, for its kernels compiled for a plain scene's lean arrays: `plan_for` names the one a render
compiles.
"""

from __future__ import annotations

import base64
import importlib
import json
import pickle
from functools import lru_cache
from pathlib import Path

PLAN_DIR = Path(__file__).resolve().parent / "plans"


#: the suffix of a plan for the kernels compiled for a plain scene's lean arrays
LEAN = "-lean"


def plan_for(method: str, sa) -> str:
    """The name of the plan a first render of `method` on scene arrays `sa` (a `layout.SceneArrays`) compiles:
    `method`, or `method` + LEAN where its kernels take `sa`'s lean arrays (`methods.common.kernel_arrays`)."""
    from .common import LEAN_METHODS, kernel_arrays

    kernel = top_kernel(method)
    if method in LEAN_METHODS and kernel is not None and kernel_arrays(kernel, sa) is not sa:
        return method + LEAN
    return method


@lru_cache(maxsize=None)
def load(method: str) -> dict:
    """The plan `method` (a method's name, or with LEAN after it), its JSON object: `top` the top-level kernel as
    [module, name] and `top_arg` its first argument's type, `roots` in the order the helper compiles them, `first`
    what the render compiles first; or an empty one where there is none."""
    path = PLAN_DIR / f"{method}.json"
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {"top": None, "roots": [], "first": []}


def top_kernel(method: str):
    """The top-level kernel of plan `method` (its dispatcher), or None where there is no such plan."""
    top = load(method).get("top")
    return resolve(*top) if top else None


def resolve(module: str, name: str):
    """The dispatcher `module.name`, or None where it is gone."""
    try:
        obj = importlib.import_module(module)
        for part in name.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError):
        return None
    return obj if hasattr(obj, "py_func") else None


def top_cached(method: str) -> bool:
    """Whether the top-level kernel of plan `method` has cache entries for its sources as they are, for the scene
    arrays the plan was recorded with (its `top_arg`: the general arrays, or with LEAN a plain scene's lean ones);
    then there is nothing to share: its render loads it. True where there is no such plan."""
    from ..kernels.cache import has_entries, has_entry_for

    kernel = top_kernel(method)
    if kernel is None:
        return True
    try:
        arrays = decode_args(load(method)["top_arg"])[0]
    except Exception:  # (a plan recorded without it, or a type that no longer unpickles)
        return has_entries(kernel)
    return has_entry_for(kernel, arrays)


def compile_share(method: str, side: str = "roots") -> int:
    """Compile (or load) the roots of `method`'s plan for `side` ("roots": the helper's; "first": the render's)
    whose sources are as recorded, in the plan's order, into the kernel cache; returns how many were compiled or
    loaded. A root that fails (a type that no longer unpickles, a signature the function no longer takes) is
    skipped: the render compiles whatever it needs itself."""
    from ..kernels.cache import closure_stamp

    done = 0
    for root in load(method).get(side, []):
        dispatcher = resolve(root["module"], root["name"])
        if dispatcher is None or closure_stamp(dispatcher.py_func) != root["stamp"]:
            continue
        try:
            dispatcher.compile(decode_args(root["args"]))
        except Exception:  # (best effort: see the docstring)
            continue
        done += 1
    return done


def encode_args(args: tuple) -> str:
    """A root's argument types as the plan stores them."""
    return base64.b64encode(pickle.dumps(tuple(args), protocol=4)).decode("ascii")


def decode_args(text: str) -> tuple:
    """The argument types `encode_args` stored."""
    return pickle.loads(base64.b64decode(text))
