"""Kernels compiled to plain scenes (`compile.features`): a scene with no csg object and no texture is rendered by
kernels compiled for its lean arrays, None where those features' arrays are, which Numba prunes: the same image
to the bit as the general kernels give, from less code. Compiling the lean variants costs this suite about
15 s of one core (the installed kernels are the general ones)."""

import numpy as np
import pytest
from helpers import EXAMPLES
from numba.core import types

import lumos
from lumos.compile import compile_scene
from lumos.compile.features import FEATURES, is_plain, lean_arrays
from lumos.methods import compile_plan
from lumos.methods.common import LEAN_METHODS, kernel_arrays
from lumos.methods.path_trace import pass_rows  # the methods' top-level kernels
from lumos.methods.raycast import _raycast_rows

TOPS = {"raycast": _raycast_rows, "path": pass_rows}

#: every material model the path tracer reads, an area light and a sky, and no texture or csg object
PLAIN_PATH = {
    "camera": {"position": [0, 1.2, 4.5], "look_at": [0, 0.5, 0], "fov": 45},
    "environment": {"color": [0.3, 0.35, 0.4]},
    "lights": [{"type": "area", "shape": "rect", "corner": [-0.5, 2.5, -0.5], "edge_u": [1, 0, 0],
                "edge_v": [0, 0, 1], "radiance": 6.0}],
    "materials": {"floor": {"kd": 0.6}},
    "objects": [
        {"type": "rect", "corner": [-3, 0, 3], "edge_u": [6, 0, 0], "edge_v": [0, 0, -6], "material": "floor"},
        {"type": "sphere", "center": [-1.6, 0.4, 0], "radius": 0.4,
         "material": {"principled": {"base_color": [0.8, 0.3, 0.1], "metallic": 0.3, "roughness": 0.4}}},
        {"type": "sphere", "center": [-0.55, 0.4, 0], "radius": 0.4, "material": {"conductor": {"metal": "Au",
                                                                                              "alpha": 0.2}}},
        {"type": "sphere", "center": [0.55, 0.4, 0], "radius": 0.4,
         "material": {"kd": [0.1, 0.3, 0.6], "plastic": {"alpha": 0.1}}},
        {"type": "sphere", "center": [1.6, 0.4, 0], "radius": 0.4, "material": {"dielectric": {"ior": 1.5,
                                                                                             "alpha": 0.1}}},
        {"type": "box", "min": [-0.3, 0, -1.2], "max": [0.3, 0.9, -0.6], "material": {"kr": 0.8, "kd": 0.1}},
    ],
}
TEXTURED = {**PLAIN_PATH, "materials": {"floor": {"kd": 0.6, "texture": {
    "type": "checker", "colors": [[0.7, 0.7, 0.7], [0.2, 0.2, 0.2]], "scale": 8, "apply_to": ["kd"]}}}}


def _lean(signature) -> bool:
    """Whether a kernel signature's scene arrays are lean (a feature's arrays None)."""
    return any(isinstance(t, types.NoneType) for t in signature[0].types)


def test_the_lean_arrays_of_a_plain_scene_leave_its_features_out():
    plain = compile_scene(lumos.load_scene(PLAIN_PATH)).arrays
    assert is_plain(plain)
    lean = lean_arrays(plain)
    for names in FEATURES.values():
        for name in names:
            assert getattr(lean, name) is None
    assert lean.materials is plain.materials and lean.tri_verts is plain.tri_verts
    textured = compile_scene(lumos.load_scene(TEXTURED)).arrays
    assert not is_plain(textured) and lean_arrays(textured) is textured
    csg = compile_scene(lumos.load_scene({**PLAIN_PATH, "objects": PLAIN_PATH["objects"] + [
        {"type": "csg", "op": "difference", "material": "floor",
         "left": {"type": "box", "min": [1, 0, -2], "max": [2, 1, -1]},
         "right": {"type": "sphere", "center": [1.5, 0.5, -1.5], "radius": 0.6}}]})).arrays
    assert not is_plain(csg) and lean_arrays(csg) is csg


@pytest.mark.slow
@pytest.mark.parametrize("method, scene", [("raycast", EXAMPLES / "showcase.yaml"), ("path", PLAIN_PATH)],
                         ids=["raycast", "path"])
def test_a_plain_scene_renders_the_same_to_the_bit_with_its_lean_kernels(method, scene, monkeypatch):
    """Ray casting reaches every gated reader whitted's kernel does (`material_in_cone`, `closest_visible_hit`,
    the shadow rays' cut-outs, the csg test), the path tracer the others (`principled_at`, `bump_frame`,
    `bump_normal`, `material_coeffs`). Whitted's lean kernel, another 10 s of this suite's compile, is compared
    by `benchmarks/ab_cold.py` (identical images, BENCHMARKS.md)."""
    settings = {"method": method, "width": 40, "height": 30, "spp": 2}
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "0")
    general = lumos.render(scene, **settings)
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "1")
    lean = lumos.render(scene, **settings)
    assert any(_lean(sig) for sig in TOPS[method].overloads)  # the lean variant was the one run
    assert general.array.mean() > 0.01
    np.testing.assert_array_equal(lean.array, general.array)


def test_a_render_keeps_the_general_kernels_it_has(monkeypatch):
    """Without LUMOS_LEAN_KERNELS, a plain scene takes its lean arrays only where the kernel is neither compiled
    nor cached for the general ones (after `pip install .`, it always is); a scene with a feature always takes the
    general arrays."""
    plain = compile_scene(lumos.load_scene(PLAIN_PATH)).arrays
    textured = compile_scene(lumos.load_scene(TEXTURED)).arrays
    monkeypatch.delenv("LUMOS_LEAN_KERNELS", raising=False)

    class Cold:  # a kernel compiled for nothing yet, on an empty cache
        overloads = {}

        class _cache:
            @staticmethod
            def _index_files():
                return []

    assert kernel_arrays(Cold, textured) is textured
    assert lean_arrays(plain) is not plain and kernel_arrays(Cold, plain)._fields == plain._fields
    assert kernel_arrays(Cold, plain).csg_nodes is None
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "0")
    lumos.render(PLAIN_PATH, method="raycast", width=8, height=6, spp=1)  # the general kernel, compiled or loaded
    monkeypatch.delenv("LUMOS_LEAN_KERNELS")
    assert any(not _lean(sig) for sig in _raycast_rows.overloads)
    assert kernel_arrays(_raycast_rows, plain) is plain
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "1")
    assert kernel_arrays(_raycast_rows, plain).csg_nodes is None
    assert kernel_arrays(_raycast_rows, textured) is textured


@pytest.mark.parametrize("method", LEAN_METHODS)
def test_a_plain_scene_has_a_compile_plan_of_its_own(method, monkeypatch):
    plain = compile_scene(lumos.load_scene(PLAIN_PATH)).arrays
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "1")
    assert compile_plan.plan_for(method, plain) == method + compile_plan.LEAN
    lean, general = compile_plan.load(method + compile_plan.LEAN), compile_plan.load(method)
    assert lean["roots"] and any("none" in str(compile_plan.decode_args(root["args"])) for root in lean["roots"])
    # the top-level kernel's arrays each plan was recorded with, which `top_cached` looks up in the cache
    assert _lean(compile_plan.decode_args(lean["top_arg"])) and not _lean(compile_plan.decode_args(general["top_arg"]))
    monkeypatch.setenv("LUMOS_LEAN_KERNELS", "0")
    assert compile_plan.plan_for(method, plain) == method
    assert compile_plan.plan_for("raster", plain) == "raster"
