"""lumos: one scene, every classic rendering method, in Python with Numba kernels.

    import lumos
    scene = lumos.load_scene("scene.yaml")          # or a dict
    img = lumos.render(scene, method="raycast", width=320, height=240)
    img.save("out.png")

`import lumos` is cheap: Numba, trimesh and the kernels load on the first render or mesh file.
"""

from .api import render
from .errors import LumosError, LumosWarning
from .scene import Scene, load_scene

__version__ = "0.1.0"
__all__ = ["Image", "LumosError", "LumosWarning", "RayCaster", "Scene", "__version__", "explain", "load_scene",
           "render", "render_frames"]


def __getattr__(name: str):
    if name == "Image":  # lumos.image pulls in NumPy image I/O: load it on first use
        from .image import Image

        return Image
    if name == "RayCaster":  # the ray-query API (lumos.queries)
        from .queries import RayCaster

        return RayCaster
    if name == "render_frames":  # the frames of an animation (lumos.animate)
        from .animate import render_frames

        return render_frames
    if name == "explain":
        from .tools.explain import explain

        return explain
    raise AttributeError(f"module 'lumos' has no attribute {name!r}")
