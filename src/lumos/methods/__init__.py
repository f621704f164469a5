"""Rendering methods, one module each, each with one public `render_<method>(compiled, camera, settings, progress)`.

The registry that maps names to entry points is `lumos.api.METHODS`; `compile_for` gives each method the compiled
scene it reads.
"""


def compile_for(scene, settings, solved: bool = False, reuse=None, tree: bool = True):
    """`scene` compiled for `settings.method`: the flattened scene and its BVH (`compile.compile_scene`); for
    raster its polygons instead (`compile.compile_raster`); for path also the physical materials and the emitter
    table (`compile.emitters.attach`); for radiosity also the patches (`compile.patches.attach`), or with
    `solved` (a saved solution will be drawn) only the digest that matches it (`compile.patches.attach_digest`).
    `reuse`: an earlier compile whose BVH is kept where the geometry is the same (`compile.compile_scene`);
    `tree` False: an empty BVH (`compile.compile_scene`)."""
    from ..compile import compile_raster, compile_scene

    if settings.method == "raster":
        return compile_raster(scene, settings.tessellation, settings.shadows, tree)
    compiled = compile_scene(scene, reuse=reuse, tree=tree)
    if settings.method == "path":
        from ..compile import emitters

        emitters.attach(compiled, settings.light_selection)
    elif settings.method == "radiosity":
        from ..compile import patches

        (patches.attach_digest if solved else patches.attach)(compiled, scene, settings)
    return compiled
