"""Rendering methods, one module each, each with one public `render_<method>(compiled, camera, settings, progress)`.

The registry that maps names to entry points is `lumos.api.METHODS`.
"""
