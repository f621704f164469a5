"""compile_scene: a recompile of the same geometry can keep the BVH it built (`reuse`), as the live preview does
when only materials or lights change; the arrays are those of a compile from scratch."""

from __future__ import annotations

import copy

import numpy as np
import yaml
from helpers import EXAMPLES

import lumos
from lumos.compile import compile_scene

SHOWCASE = yaml.safe_load((EXAMPLES / "showcase.yaml").read_text())


def scene_with(edit):
    data = copy.deepcopy(SHOWCASE)
    edit(data)
    return lumos.load_scene(data, folder=EXAMPLES)


def test_a_material_edit_keeps_the_bvh_and_gives_the_arrays_of_a_fresh_compile():
    first = compile_scene(scene_with(lambda d: None))
    shiny = scene_with(lambda d: d["materials"]["red"].update(ks=0.9))
    reused, fresh = compile_scene(shiny, reuse=first), compile_scene(shiny)
    assert reused.bvh_build_s == 0.0 and fresh.bvh_build_s > 0.0
    for name, value in fresh.arrays._asdict().items():
        np.testing.assert_array_equal(getattr(reused.arrays, name), value, err_msg=name)
    assert not np.array_equal(reused.arrays.materials, first.arrays.materials)


def test_moved_geometry_builds_a_new_bvh():
    first = compile_scene(scene_with(lambda d: None))
    moved = scene_with(lambda d: d["objects"][0].update(radius=d["objects"][0].get("radius", 1.0) * 1.5)
                       if "radius" in d["objects"][0] else d["objects"].pop())
    again = compile_scene(moved, reuse=first)
    assert again.bvh_build_s > 0.0 and again.bvh[0] != first.bvh[0]
