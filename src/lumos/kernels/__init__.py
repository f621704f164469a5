"""@njit code only: vector maths, RNG, camera rays, intersections, BVH build and traversal, illumination.

Kernels take flat NumPy arrays and scalars (see `layout.py`), allocate nothing per ray, and never import the
scene model. Every kernel is made by `jit.py`'s decorators and kept in lumos's kernel cache (`cache.py`: stamped
with the hash of its source closure; `pip install .` fills it, `lumos warmup` too; LUMOS_CACHE_DIR moves it).
"""
