"""@njit code only: vector maths, RNG, camera rays, intersections, BVH build and traversal, illumination.

Kernels take flat NumPy arrays and scalars (see `layout.py`), allocate nothing per ray, and never import the
scene model. Every kernel is compiled with `cache=True` (set NUMBA_CACHE_DIR to choose where the cache lives).
"""
