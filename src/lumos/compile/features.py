"""A scene's arrays without the optional features it does not use: kernels compiled to plain scenes.

A kernel is compiled for the types of its arguments. In the arrays `lean_arrays` returns for a *plain* scene, one
with none of the optional FEATURES (no csg object, no texture, bump or normal map), the arrays that hold those
features are None (`csg_nodes`; `tex_info`, `tex_pixels`, `tri_tangents`). The kernels read them through functions
that test `is None` on an argument (`traverse._csg_hit`, `views.textures_of` and the texture readers), a test
Numba settles before typing: it prunes the branch not taken, so a kernel compiled for the lean arrays holds no csg
intersection and no texture lookup, and a cold first render of a plain scene compiles a quarter less
(BENCHMARKS.md, "Kernels compiled to plain scenes"). Its image is the same to the bit: what it leaves out is code
the scene never reaches. A scene with any of the features keeps the general arrays: two variants of a kernel in
all, each with its compile plan (`methods.compile_plan`), not one per combination.

Which arrays a render passes is `methods.common.kernel_arrays`'s choice: the general ones wherever their kernel
is compiled or cached already (after `pip install .` or `lumos warmup`, always), so that no render compiles a
second variant of a kernel it has.

    lean = lean_arrays(compiled.arrays)   # the same arrays for a scene that is not plain
"""

from __future__ import annotations

#: feature -> the `layout.SceneArrays` fields that hold it
FEATURES = {
    "csg": ("csg_nodes",),
    "textures": ("tex_info", "tex_pixels", "tri_tangents"),
}


def is_plain(sa) -> bool:
    """Whether the arrays `sa` (a `layout.SceneArrays`) hold none of the FEATURES: no csg node and no texture row
    (tangents are read only under a normal map, which is a texture row)."""
    return len(sa.csg_nodes) == 0 and len(sa.tex_info) == 0


def lean_arrays(sa):
    """`sa` with None for the arrays of every feature where the scene is plain, else `sa` itself."""
    if not is_plain(sa):
        return sa
    return sa._replace(**{name: None for names in FEATURES.values() for name in names})
