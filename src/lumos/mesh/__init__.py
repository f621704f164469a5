"""Mesh operations that fix the classic problems of interpolated (Gouraud and Phong) shading.

Pure NumPy; the scan-line renderer calls them at compile time, and they work as well from Python:

- `face_normals`, `vertex_normals`: unrepresentative vertex normals. Angle-weighted averaging (Thürmer &
  Wüthrich) and a crease angle that splits vertices at sharp edges, so a cube stays a cube and a sphere smooth;
  repeated vertices along a seam are welded (`weld_ids`), so a teapot's patch borders do not show.
- `subdivide`: polygonal silhouettes. Loop subdivision rounds the outline; midpoint subdivision only refines.
- `repair_t_junctions`: shading discontinuities at T-junctions. A vertex lying inside a neighbour's edge is
  inserted into that edge, so both sides interpolate through it.
- `triangulate`, `triangulate_polygon`: orientation dependence. Interpolation over a polygon with more than
  three vertices changes as it turns on the screen; over triangles it does not.
"""

from .normals import face_normals, vertex_normals, weld_ids
from .subdivide import subdivide
from .tjunctions import repair_t_junctions
from .triangulate import triangulate, triangulate_polygon

__all__ = ["face_normals", "vertex_normals", "weld_ids", "triangulate", "triangulate_polygon", "repair_t_junctions",
           "subdivide"]
