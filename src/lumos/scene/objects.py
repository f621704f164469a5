"""The objects of a scene: analytic shapes, triangles and meshes, csg objects and model includes.

Part of the scene model (`lumos.scene.model`, which re-exports every public name).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal, Optional, Union

import numpy as np
from pydantic import Field, PrivateAttr, field_validator, model_validator

from .types import Direction, Positive, StrictModel, Vec3, cross, norm, sub
from .materials import Material, MaterialRef
from .transform import Transform


class ObjectBase(StrictModel):
    name: Optional[str] = None
    material: Optional[MaterialRef] = None
    transform: Optional[Transform] = None
    #: velocity: at time τ of the camera's shutter interval the object is moved by τ·motion (motion blur)
    motion: Vec3 = (0.0, 0.0, 0.0)
    #: an emissive object's emission leaves both sides (true) or only the side its geometric normal faces: a
    #: solid's outside, a mesh's counter-clockwise side, a rect's cross(edge_u, edge_v). Reflection is two-sided.
    two_sided: bool = True


class Sphere(ObjectBase):
    type: Literal["sphere"]
    center: Vec3 = (0.0, 0.0, 0.0)
    radius: Positive = 1.0


class Plane(ObjectBase):
    type: Literal["plane"]
    point: Vec3 = (0.0, 0.0, 0.0)
    normal: Direction = (0.0, 1.0, 0.0)


class Box(ObjectBase):
    type: Literal["box"]
    min: Vec3 = (-1.0, -1.0, -1.0)
    max: Vec3 = (1.0, 1.0, 1.0)

    @model_validator(mode="after")
    def _check(self):
        if any(lo >= hi for lo, hi in zip(self.min, self.max)):
            raise ValueError("min must be smaller than max on every axis")
        return self


class _Axial(ObjectBase):
    base: Vec3 = (0.0, 0.0, 0.0)
    top: Vec3 = (0.0, 1.0, 0.0)
    radius: Positive = 1.0
    capped: bool = True

    @model_validator(mode="after")
    def _check(self):
        if norm(sub(self.top, self.base)) <= 1e-12:
            raise ValueError("base and top must differ")
        return self


class Cylinder(_Axial):
    type: Literal["cylinder"]


class Cone(_Axial):
    """A cone with radius `radius` at `base` and its apex at `top`."""

    type: Literal["cone"]


class Disk(ObjectBase):
    type: Literal["disk"]
    center: Vec3 = (0.0, 0.0, 0.0)
    normal: Direction = (0.0, 1.0, 0.0)
    radius: Positive = 1.0


class Rect(ObjectBase):
    """A parallelogram (a rectangle when the edges are perpendicular): the points corner + s·edge_u + t·edge_v,
    s and t in [0, 1], with (u, v) = (s, t). Two-sided like a disk; its normal is along cross(edge_u, edge_v)
    (which only matters for bump maps and for raster's back-face culling). Mitsuba's `rectangle`."""

    type: Literal["rect"]
    corner: Vec3 = (-1.0, 0.0, 1.0)
    edge_u: Vec3 = (2.0, 0.0, 0.0)
    edge_v: Vec3 = (0.0, 0.0, -2.0)

    @model_validator(mode="after")
    def _check(self):
        if norm(cross(self.edge_u, self.edge_v)) <= 1e-18:
            raise ValueError("edge_u and edge_v must be non-zero and not parallel")
        return self


class Triangle(ObjectBase):
    type: Literal["triangle"]
    vertices: tuple[Vec3, Vec3, Vec3]

    @field_validator("vertices", mode="before")
    @classmethod
    def _as_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check(self):
        a, b, c = self.vertices
        if norm(cross(sub(b, a), sub(c, a))) <= 1e-18:
            raise ValueError("the triangle is degenerate (its vertices are collinear)")
        return self


def _array(value, name: str, cols: int, dtype, allow_polygons: bool = False) -> np.ndarray:
    """Validate a list or NumPy array of rows of `cols` numbers; returns a contiguous array."""
    if isinstance(value, (str, bytes, dict)) or isinstance(value, bool):
        raise ValueError(f"{name} must be a list of [{', '.join('x' * 1 for _ in range(cols))}] rows")
    try:
        arr = np.asarray(value, dtype=dtype)
    except (ValueError, TypeError):
        raise ValueError(f"{name} must be a list of rows of {cols} numbers") from None
    if arr.ndim != 2 or arr.shape[1] != cols or arr.shape[0] == 0:
        raise ValueError(f"{name} must be a non-empty list of rows of {cols} numbers, got shape {arr.shape}")
    if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
        bad = int(np.argwhere(~np.isfinite(arr))[0][0])
        raise ValueError(f"{name}[{bad}] is not finite (NaN or Inf)")
    return np.ascontiguousarray(arr)


class Mesh(ObjectBase):
    """A triangle mesh from a `file` (OBJ, PLY, STL, glTF…) or from inline `vertices` + `faces`.

    After loading, `vertices` (n, 3) float64, `faces` (m, 3) int64 and the optional per-vertex `normals`
    (n, 3) and `uvs` (n, 2) are NumPy arrays whichever way the mesh was given. Polygon faces are
    triangulated by ear clipping (concave ones too); `polygons` keeps them as given.
    """

    model_config = dict(StrictModel.model_config, arbitrary_types_allowed=True)
    type: Literal["mesh"]
    file: Optional[str] = None
    vertices: Optional[Any] = None
    faces: Optional[Any] = None
    normals: Optional[Any] = None
    uvs: Optional[Any] = None
    #: per-vertex tangents (n, 4): xyz along +u, w = ±1 the handedness (bitangent = w·normal × tangent), as
    #: glTF TANGENT; normal maps use them (without them, the tangent frame comes from the uvs)
    tangents: Optional[Any] = None
    # vertex normals when the mesh has none, and the fix-ups for interpolated shading
    smooth: bool = True
    normal_weighting: Literal["angle", "area", "average"] = "angle"
    crease_angle: Annotated[float, Field(ge=0.0, le=180.0)] = 180.0
    subdivide: Annotated[int, Field(ge=0, le=6)] = 0
    subdivision: Literal["loop", "midpoint"] = "loop"
    repair_t_junctions: bool = False
    triangulate: bool = True
    _source: Optional[Path] = PrivateAttr(default=None)
    _polygons: Optional[list] = PrivateAttr(default=None)
    _face_polygon: Optional[np.ndarray] = PrivateAttr(default=None)

    @field_validator("vertices", "normals", mode="after")
    @classmethod
    def _vec_rows(cls, v, info):
        return None if v is None else _array(v, info.field_name, 3, np.float64)

    @field_validator("uvs", mode="after")
    @classmethod
    def _uv_rows(cls, v):
        return None if v is None else _array(v, "uvs", 2, np.float64)

    @field_validator("tangents", mode="after")
    @classmethod
    def _tangent_rows(cls, v):
        if v is None:
            return None
        arr = _array(v, "tangents", 4, np.float64)
        if np.any(arr[:, 3] == 0.0):
            bad = int(np.argwhere(arr[:, 3] == 0.0)[0][0])
            raise ValueError(f"tangents[{bad}]: w (the handedness) must be 1 or -1, not 0")
        arr[:, 3] = np.sign(arr[:, 3])
        return arr

    @field_validator("faces", mode="after")
    @classmethod
    def _faces(cls, v):
        if v is None:
            return None
        if isinstance(v, np.ndarray):
            if v.dtype.kind not in "iu":
                raise ValueError("faces must hold integer vertex indices")
            return _array(v, "faces", 3, np.int64)
        if not isinstance(v, (list, tuple)) or not v:
            raise ValueError("faces must be a non-empty list of vertex-index lists")
        for i, f in enumerate(v):
            if not isinstance(f, (list, tuple)) or len(f) < 3:
                raise ValueError(f"faces[{i}] must list at least 3 vertex indices")
            if not all(isinstance(k, int) and not isinstance(k, bool) for k in f):
                raise ValueError(f"faces[{i}] must hold integer vertex indices")
        if all(len(f) == 3 for f in v):
            return np.asarray(v, dtype=np.int64).reshape(-1, 3)
        return [np.asarray(f, dtype=np.int64) for f in v]  # polygons: triangulated once vertices are known

    @model_validator(mode="after")
    def _check(self):
        if (self.file is None) == (self.vertices is None):
            raise ValueError("give either file or vertices + faces")
        if self.file is not None:
            for key in ("faces", "normals", "uvs", "tangents"):
                if getattr(self, key) is not None:
                    raise ValueError(f"{key} cannot be given with file (it comes from the file)")
            return self
        if self.faces is None:
            raise ValueError("vertices need faces")
        if isinstance(self.faces, list):
            self._polygons = self.faces
            n = len(self.vertices)
            for i, f in enumerate(self._polygons):
                if f.min() < 0 or f.max() >= n:
                    raise ValueError(f"faces[{i}] refers to a vertex that does not exist (there are {n})")
            from ..mesh import triangulate

            self.faces, self._face_polygon = triangulate(self.vertices, self._polygons)
        self.check_arrays()
        return self

    @property
    def face_polygon(self) -> Optional[np.ndarray]:
        """For polygon faces: the polygon each triangle of `faces` was cut from (None when all are triangles)."""
        return self._face_polygon

    @property
    def polygons(self) -> list:
        """The faces as given: a list of index arrays (polygons of any size), or the triangles as (m, 3)."""
        return self._polygons if self._polygons is not None else list(self.faces)

    def check_arrays(self) -> None:
        """Index range and per-vertex array lengths (also run after a file is loaded)."""
        n = len(self.vertices)
        if self.faces.size and (self.faces.min() < 0 or self.faces.max() >= n):
            bad = int(np.argwhere((self.faces < 0) | (self.faces >= n))[0][0])
            raise ValueError(f"faces[{bad}] refers to a vertex that does not exist (there are {n})")
        for key in ("normals", "uvs", "tangents"):
            arr = getattr(self, key)
            if arr is not None and len(arr) != n:
                raise ValueError(f"{key} has {len(arr)} rows but there are {n} vertices")

    @property
    def triangle_count(self) -> int:
        return 0 if self.faces is None else len(self.faces)


class Csg(ObjectBase):
    """Constructive solid geometry: `op` of two solids (sphere, box, cylinder, cone, closed mesh, or csg).
    A solid without a material takes the csg node's. `transform` and `motion` apply to the whole node."""

    type: Literal["csg"]
    op: Literal["union", "intersection", "difference"]
    left: "Solid"
    right: "Solid"

    @model_validator(mode="after")
    def _check(self):
        for side in ("left", "right"):
            child = getattr(self, side)
            if getattr(child, "capped", True) is False:
                raise ValueError(f"{side}: an uncapped {child.type} is not a solid (set capped: true)")
            if any(getattr(child, "motion", (0.0, 0.0, 0.0))):
                raise ValueError(f"{side}: give motion to the csg node, not to its solids")
        return self


Solid = Annotated[Union[Sphere, Box, Cylinder, Cone, Mesh, Csg], Field(discriminator="type")]
Csg.model_rebuild()


class ModelInclude(ObjectBase):
    """A model file (OBJ+MTL, glTF, GLB, PLY, STL, OFF) included as objects. The loader expands it into the
    file's meshes, with `transform` applied after their own, and its materials, named `<name or file name>:<the
    file's name>`: `materials_override` merges keys over a file's material, `material` replaces them all;
    `lights: true` adds the file's lights (moved by `transform`). Paths are relative to the scene file."""

    type: Literal["model"]
    file: str
    materials_override: dict[str, Material] = Field(default_factory=dict)
    lights: bool = False

    @model_validator(mode="after")
    def _check(self):
        if any(self.motion):
            raise ValueError("motion: a model's meshes cannot move (motion blur takes analytic shapes)")
        if self.material is not None and self.materials_override:
            raise ValueError("give material (replaces every material of the file) or materials_override, not both")
        return self


Object = Annotated[
    Union[Sphere, Plane, Box, Cylinder, Cone, Disk, Rect, Triangle, Mesh, Csg, ModelInclude],
    Field(discriminator="type"),
]
OBJECT_TYPES = ("sphere", "plane", "box", "cylinder", "cone", "disk", "rect", "triangle", "mesh", "csg", "model")
