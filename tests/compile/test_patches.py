"""compile/patches.py: which sides of which objects are patches, found without meshing (`patch_sides`), and the
digest a saved radiosity solution is matched by."""

from __future__ import annotations

import numpy as np
import pytest

import lumos
from helpers import EXAMPLES
from lumos.api import resolve_settings
from lumos.compile import compile_scene, patches
from lumos.radiosity.solve import solve


def sides_of_the_patches(scene, settings):
    """The (object id, side) pairs of the patches as meshed: what `patch_sides` must give without meshing."""
    compiled = compile_scene(scene)
    patches.attach(compiled, scene, settings)
    p = compiled.patches
    return np.unique(np.stack([p.object_id.astype(np.int64), np.sign(p.patch_side).astype(np.int64)]), axis=1)


BOX = {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "material": {"kd": 0.5, "emission": 0.2}}


@pytest.mark.parametrize("scene", [
    str(EXAMPLES / "radiosity" / "cornell.yaml"),
    str(EXAMPLES / "radiosity" / "room.yaml"),
    {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]}, "objects": [BOX]},      # outside: outer sides
    {"camera": {"position": [0, 0, 0.5], "look_at": [0, 0, -1]}, "objects": [BOX]},   # inside: inner only
    {"camera": {"position": [0, 1, 4]}, "lights": [{"type": "area", "shape": "disk", "center": [0, 2, 0],
                                                    "normal": [0, -1, 0], "radius": 0.5}],
     "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]},
                 {"type": "sphere", "center": [0, 1, 0], "radius": 0.5, "material": {"kd": 0.5, "kt": 0.3}},
                 {"type": "cylinder", "base": [1, 0, 0], "top": [1, 1, 0], "radius": 0.3, "capped": False}]},
])
def test_patch_sides_are_those_of_the_meshed_patches(scene):
    """The sides found without meshing are exactly the sides the patches have (open surfaces both, closed solids
    their outside unless everything is inside, transparent ones both, area lights their lit side)."""
    scene = lumos.load_scene(scene)
    settings = resolve_settings(scene, {"method": "radiosity"})
    expected = sides_of_the_patches(scene, settings)
    np.testing.assert_array_equal(patches.patch_sides(scene, compile_scene(scene).bounds, settings.tessellation),
                                  expected)


def test_a_saved_solution_is_drawn_without_meshing(tmp_path, monkeypatch):
    """Drawing a saved solution computes the scene's digest and meshes nothing: with the mesher made to fail,
    the render from the saved solution is the render of a fresh solve, and a scene whose sides differ (the
    camera moved into the box) is still refused."""
    scene = {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]}, "objects": [BOX]}
    view = dict(width=16, height=12, radiosity={"patch_size": 0.5})
    fresh = lumos.render(scene, method="radiosity", **view)
    solve(scene, resolve_settings(lumos.load_scene(scene), {"method": "radiosity", **view})).save(tmp_path / "box.npz")

    def no_meshing(*args, **kwargs):
        raise AssertionError("mesh_scene called while drawing a saved solution")

    monkeypatch.setattr(patches, "mesh_scene", no_meshing)
    drawn = lumos.render(scene, method="radiosity", solution=tmp_path / "box.npz", **view)
    np.testing.assert_array_equal(drawn.array, fresh.array)
    inside = dict(scene, camera={"position": [0, 0, 0.5], "look_at": [0, 0, -1]})
    with pytest.raises(lumos.LumosError, match="different scene"):
        lumos.render(inside, method="radiosity", solution=tmp_path / "box.npz", **view)
