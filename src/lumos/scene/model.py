"""The validated scene model: camera, render settings, lights, materials and objects.

Plain pydantic models, pure Python (NumPy only for mesh arrays; never Numba). Field names are the scene-file
keys of `docs/scene-format.md`; the conventions (camera basis, light units, shading normal) are those of
DESIGN.md. The compile step (`lumos.compile`) turns a `Scene` into flat arrays for the kernels.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, Optional, Union

import numpy as np
from pydantic import Discriminator, Field, PrivateAttr, Tag, field_validator, model_validator

from .types import (
    Color,
    Direction,
    Finite,
    NonNegative,
    Positive,
    StrictModel,
    Vec3,
    cross,
    norm,
    sub,
)

# --------------------------------------------------------------------------------------------------- camera


class Camera(StrictModel):
    """Pinhole or thin-lens perspective camera (vertical `fov` in degrees), or orthographic (`size` tall)."""

    type: Literal["perspective", "orthographic"] = "perspective"
    position: Vec3 = (0.0, 0.0, 5.0)
    look_at: Vec3 = (0.0, 0.0, 0.0)
    up: Vec3 = (0.0, 1.0, 0.0)
    fov: Annotated[float, Field(gt=0, lt=180)] = 45.0
    size: Positive = 2.0
    aperture: NonNegative = 0.0
    focus_distance: Optional[Positive] = None
    #: [open, close] times of the shutter; objects with a `motion` move during it (motion blur)
    shutter: tuple[Finite, Finite] = (0.0, 0.0)

    @field_validator("shutter", mode="before")
    @classmethod
    def _shutter_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check_basis(self):
        if self.shutter[1] < self.shutter[0]:
            raise ValueError("shutter: [open, close] must not close before it opens")
        view = sub(self.position, self.look_at)
        if norm(view) <= 1e-12:
            raise ValueError("position and look_at must differ")
        if norm(self.up) <= 1e-12:
            raise ValueError("up must not be the zero vector")
        c = cross(self.up, view)
        if norm(c) <= 1e-9 * norm(self.up) * norm(view):
            raise ValueError("up is parallel to the view direction (position - look_at); choose another up")
        return self

    def basis(self):
        """(u, v, w) as in DESIGN.md: w = normalize(position − look_at), u = normalize(up × w), v = w × u."""
        w = np.subtract(self.position, self.look_at)
        w = w / np.linalg.norm(w)
        u = np.cross(self.up, w)
        u = u / np.linalg.norm(u)
        v = np.cross(w, u)
        return u, v, w

    def resolved_focus_distance(self) -> float:
        if self.focus_distance is not None:
            return self.focus_distance
        return float(np.linalg.norm(np.subtract(self.position, self.look_at)))


# ------------------------------------------------------------------------------------------ render settings

AOV_NAMES = ("depth", "normal", "albedo", "object_id", "samples", "variance", "noisy", "ambient", "diffuse",
             "specular", "emitted", "reflected", "transmitted", "direct", "indirect")
#: AOVs of the classic model's terms (raycast, raster, whitted): they add up to the image.
TERM_AOVS = ("ambient", "diffuse", "specular", "emitted", "reflected", "transmitted")
#: AOVs only the path tracer makes: the variance of each pixel's mean, the image before denoising, and the image
#: split into its direct light (what max_depth 0 gathers) and the indirect rest.
PATH_AOVS = ("variance", "noisy", "direct", "indirect")
#: `max_depth` of each method when the scene and the flags leave it unset (None: unbounded, roulette ends paths).
DEFAULT_MAX_DEPTH = {"whitted": 5, "path": None, "radiosity": 5}


class RadiositySettings(StrictModel):
    """The `render.radiosity` block: how method radiosity meshes, computes form factors, solves and displays."""

    #: gauss_seidel and jacobi store the full form-factor matrix; progressive shoots from the patch with the
    #: most unshot power (no matrix); stochastic shoots power by random rays (Monte Carlo); auto: progressive
    #: up to 20,000 patches, stochastic beyond
    solver: Literal["auto", "gauss_seidel", "jacobi", "progressive", "stochastic"] = "auto"
    #: raycast: Lambert's contour formula with shadow-ray visibility; hemicube: an item buffer per patch
    form_factors: Literal["hemicube", "raycast"] = "raycast"
    hemicube_resolution: Annotated[int, Field(ge=8, le=4096)] = 128
    #: shadow rays per ray-cast form factor (and per patch for the direct light of point and directional lights)
    visibility_samples: Annotated[int, Field(ge=1, le=1024)] = 8
    #: largest patch edge in world units (default: 1/24 of the scene's bounds' diagonal)
    patch_size: Optional[Positive] = None
    #: adaptive refinement: split patches whose radiance differs from a neighbour's by more than the threshold
    #: (relative), down to `subdivide_levels` levels
    subdivide: bool = False
    subdivide_threshold: Positive = 0.25
    subdivide_levels: Annotated[int, Field(ge=1, le=8)] = 2
    #: stop when the unshot power (progressive, stochastic) or the largest change of a sweep (gauss_seidel,
    #: jacobi), relative to the light sent out, falls below this
    tolerance: Annotated[float, Field(gt=0, lt=1)] = 0.01
    #: at most this many shots (progressive), sweeps (gauss_seidel, jacobi) or iterations (stochastic)
    max_iterations: Optional[Annotated[int, Field(ge=1)]] = None
    #: stochastic: rays per iteration (default: 100 per patch)
    rays: Optional[Annotated[int, Field(ge=1)]] = None
    #: gouraud: radiance averaged to the vertices and interpolated; flat: each patch its own colour
    display: Literal["gouraud", "flat"] = "gouraud"


class RenderSettings(StrictModel):
    """The `render:` block: which method and its settings. CLI flags and `render(**settings)` override it."""

    method: str = "raycast"
    width: Annotated[int, Field(ge=1, le=65536)] = 640
    height: Annotated[int, Field(ge=1, le=65536)] = 480
    spp: Annotated[int, Field(ge=1, le=1 << 20)] = 1
    #: bounces after the first hit; -1 is unbounded (path: roulette ends paths); unset, the method's default:
    #: 5 for whitted, unbounded for path
    max_depth: Optional[Annotated[int, Field(ge=-1, le=1024)]] = None
    seed: Annotated[int, Field(ge=0, lt=1 << 32)] = 0
    shading: Literal["flat", "gouraud", "phong"] = "phong"
    exposure: Positive = 1.0
    threads: Optional[Annotated[int, Field(ge=1, le=1024)]] = None
    aov: list[Literal["depth", "normal", "albedo", "object_id", "samples", "variance", "noisy", "ambient", "diffuse",
                      "specular", "emitted", "reflected", "transmitted", "direct", "indirect"]] = Field(
        default_factory=list)
    # anti-aliasing of the ray methods: `spp` jittered samples (supersample) or the classic adaptive method
    antialias: Literal["none", "supersample", "adaptive"] = "supersample"
    adaptive_threshold: Positive = 0.03
    adaptive_depth: Annotated[int, Field(ge=0, le=6)] = 3
    # scan-line rendering (method: raster)
    perspective_correct: bool = True
    #: raster: filter textures over each pixel's footprint (mip-mapped images, box-filtered checker and stripes)
    mipmap: bool = True
    cull_backfaces: bool = False
    shadows: bool = False
    tessellation: Annotated[int, Field(ge=3, le=4096)] = 48
    # path tracing (method: path)
    #: pixel filter: box (each sample counts for its own pixel) or a Gaussian of standard deviation 0.5 pixel
    filter: Literal["box", "gaussian"] = "box"
    #: where samples fall: stratified Owen-scrambled Sobol points (lower error at equal spp) or independent ones
    sampler: Literal["sobol", "independent"] = "sobol"
    #: how direct light is found: multiple importance sampling, or light (emitter) sampling or BSDF sampling alone
    sampling: Literal["mis", "light", "bsdf"] = "mis"
    #: stop after the pass that crosses this many seconds of rendering (the image holds the samples taken so far)
    time_limit: Optional[Positive] = None
    #: run Intel Open Image Denoise on the final image (needs the optional `pyoidn`)
    denoise: bool = False
    # radiosity (method: radiosity)
    radiosity: RadiositySettings = Field(default_factory=RadiositySettings)

    def resolved_max_depth(self) -> Optional[int]:
        """`max_depth`, or the method's default when it is unset (None: unbounded)."""
        if self.max_depth is not None:
            return None if self.max_depth < 0 else self.max_depth
        return DEFAULT_MAX_DEPTH.get(self.method, 5)

    @model_validator(mode="after")
    def _check_size(self):
        from ..config import MAX_PIXELS

        if self.width * self.height > MAX_PIXELS:
            raise ValueError(
                f"{self.width}x{self.height} is too large ({self.width * self.height:,} pixels; "
                f"at most {MAX_PIXELS:,})"
            )
        return self


# -------------------------------------------------------------------------------------------------- material


class Material(StrictModel):
    """Coefficients of the classic model, per RGB channel (a scalar means grey). Missing ones are 0."""

    ka: Color = (0.0, 0.0, 0.0)
    kd: Color = (0.0, 0.0, 0.0)
    ks: Color = (0.0, 0.0, 0.0)
    shininess: NonNegative = 1.0
    kr: Color = (0.0, 0.0, 0.0)
    kt: Color = (0.0, 0.0, 0.0)
    ior: Positive = 1.0
    emission: Color = (0.0, 0.0, 0.0)
    #: whitted: weight reflection and transmission by Schlick's approximation of the Fresnel factor
    fresnel: bool = False
    #: one texture or a list of them, applied in list order (a later one sees what the earlier ones made)
    texture: Optional[Union["Texture", list["Texture"]]] = None
    bump: Optional["Bump"] = None

    @field_validator("texture", mode="after")
    @classmethod
    def _texture_list(cls, v):
        if isinstance(v, list) and not v:
            return None
        return v

    @property
    def textures(self) -> list["Texture"]:
        """The material's textures as a list, in the order they apply (empty when it has none)."""
        if self.texture is None:
            return []
        return list(self.texture) if isinstance(self.texture, list) else [self.texture]


TEXTURE_TARGETS = ("ka", "kd", "ks", "kr", "emission", "opacity")


class _UVMap(StrictModel):
    """What textures and bump maps share: an image `file` or a procedural pattern, repeated `scale` times across
    the uv square, wrapped or clamped outside it."""

    type: str
    file: Optional[str] = None
    #: repeats across the uv square: (u, v) multipliers (a scalar means both)
    scale: Union[tuple[Positive, Positive], Positive] = 1.0
    wrap: Literal["repeat", "clamp"] = "repeat"
    #: added to the scaled coordinates: the pattern is looked up at (scale_u·u + offset_u, scale_v·v + offset_v)
    offset: tuple[Finite, Finite] = (0.0, 0.0)
    _path: Optional[Path] = PrivateAttr(default=None)
    _noun: ClassVar[str] = "map"  # for error messages
    _file_types: ClassVar[tuple[str, ...]] = ("image",)  # the types read from a file

    @field_validator("scale", "offset", mode="before")
    @classmethod
    def _scale_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check_file(self):
        if (self.type in self._file_types) != (self.file is not None):
            kind = " or ".join(self._file_types)
            raise ValueError(f"an {kind} {self._noun} needs file (and only an {kind} {self._noun} takes one)")
        return self

    @property
    def uv_scale(self) -> tuple[float, float]:
        return self.scale if isinstance(self.scale, tuple) else (self.scale, self.scale)


class Texture(_UVMap):
    """A colour that varies over a surface, looked up at the hit's (u, v), replacing (`mode: replace`) or
    multiplying (`mode: multiply`) the coefficients named in `apply_to`. `image`: a PNG/JPEG file (relative to
    the scene file), bilinearly filtered; `checker`, `stripes` (along u) and `noise` (gradient noise, blending
    `colors`) are procedural. `apply_to: [opacity]` reads the coverage α instead of a colour: an image's alpha
    channel (its luminance when it has none), a pattern's luminance; α < 0.5 is a cut-out hole."""

    type: Literal["image", "checker", "stripes", "noise"]
    colors: tuple[Color, Color] = ((0.9, 0.9, 0.9), (0.1, 0.1, 0.1))
    apply_to: list[Literal["ka", "kd", "ks", "kr", "emission", "opacity"]] = Field(
        default_factory=lambda: ["ka", "kd"])
    mode: Literal["replace", "multiply"] = "replace"
    _noun: ClassVar[str] = "texture"

    @field_validator("colors", mode="before")
    @classmethod
    def _colors_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check(self):
        if not self.apply_to:
            raise ValueError("apply_to must name at least one of ka, kd, ks, kr, emission, opacity")
        return self


class Bump(_UVMap):
    """Bump mapping: the shading normal tilted by the gradient of a height field over (u, v): an image's
    luminance or gradient noise, times `strength`; or (`type: normal`) replaced by a tangent-space normal map,
    an image whose raw RGB in [0, 1] is the normal's (x, y, z) in [-1, 1] along (tangent, bitangent, normal),
    x and y scaled by `strength`."""

    type: Literal["image", "noise", "normal"]
    strength: Finite = 1.0
    _noun: ClassVar[str] = "bump map"
    _file_types: ClassVar[tuple[str, ...]] = ("image", "normal")


Material.model_rebuild()


#: The material of an object that names none: a matte light grey.
DEFAULT_MATERIAL = Material(ka=0.8, kd=0.8)


def _material_tag(value: Any) -> str:
    return "name" if isinstance(value, str) else "inline"


MaterialRef = Annotated[
    Union[Annotated[str, Tag("name")], Annotated[Material, Tag("inline")]],
    Discriminator(_material_tag),
]

# ------------------------------------------------------------------------------------------------- transform


Row4 = tuple[Finite, Finite, Finite, Finite]


class Transform(StrictModel):
    """world_from_object = T(translate) · Rz · Ry · Rx · S(scale), or an explicit 4×4 `matrix`."""

    translate: Vec3 = (0.0, 0.0, 0.0)
    rotate: Vec3 = (0.0, 0.0, 0.0)
    scale: Union[Vec3, Finite] = 1.0
    matrix: Optional[tuple[Row4, Row4, Row4, Row4]] = None

    @field_validator("scale", mode="before")
    @classmethod
    def _scale_list(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @field_validator("matrix", mode="before")
    @classmethod
    def _matrix_rows(cls, v):
        if isinstance(v, list):
            return tuple(tuple(r) if isinstance(r, list) else r for r in v)
        return v

    @model_validator(mode="after")
    def _check(self):
        s = self.scale if isinstance(self.scale, tuple) else (self.scale,) * 3
        if any(c == 0 for c in s):
            raise ValueError("scale must not be zero on any axis")
        if any(not 1e-100 <= abs(c) <= 1e100 for c in s):  # beyond, products of three scales leave float64
            raise ValueError(f"scale must be between 1e-100 and 1e100 in size on every axis, got {list(s)}")
        if self.matrix is not None:
            explicit = self.model_fields_set & {"translate", "rotate", "scale"}
            if explicit:
                raise ValueError(f"give either matrix or {'/'.join(sorted(explicit))}, not both")
            m = np.array(self.matrix, dtype=np.float64)
            if not np.allclose(m[3], [0, 0, 0, 1]):
                raise ValueError("matrix: the last row must be [0, 0, 0, 1] (affine transforms only)")
            if abs(np.linalg.det(m[:3, :3])) < 1e-12:
                raise ValueError("matrix is singular")
        return self

    def to_matrix(self) -> np.ndarray:
        """The 4×4 world_from_object matrix (float64)."""
        if self.matrix is not None:
            return np.array(self.matrix, dtype=np.float64)
        s = self.scale if isinstance(self.scale, tuple) else (self.scale,) * 3
        rx, ry, rz = (math.radians(a) for a in self.rotate)
        cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
        Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
        Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
        m = np.eye(4)
        m[:3, :3] = Rz @ Ry @ Rx @ np.diag(s)
        m[:3, 3] = self.translate
        return m


# --------------------------------------------------------------------------------------------------- objects


class ObjectBase(StrictModel):
    name: Optional[str] = None
    material: Optional[MaterialRef] = None
    transform: Optional[Transform] = None
    #: velocity: at time τ of the camera's shutter interval the object is moved by τ·motion (motion blur)
    motion: Vec3 = (0.0, 0.0, 0.0)


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

# ---------------------------------------------------------------------------------------------------- lights


class _LocalLight(StrictModel):
    """Id and Is of the classic model: `intensity` sets both; `diffuse` / `specular` override one."""

    intensity: Color = (1.0, 1.0, 1.0)
    diffuse: Optional[Color] = None
    specular: Optional[Color] = None

    @property
    def diffuse_intensity(self):
        return self.diffuse if self.diffuse is not None else self.intensity

    @property
    def specular_intensity(self):
        return self.specular if self.specular is not None else self.intensity


class _PositionedLight(_LocalLight):
    """A light at a point, dimmed by distance: `att(d) = c + l·d + q·d²` from `attenuation: [c, l, q]`."""

    position: Vec3
    attenuation: tuple[NonNegative, NonNegative, NonNegative] = (1.0, 0.0, 0.0)

    @field_validator("attenuation", mode="before")
    @classmethod
    def _att_tuple(cls, v):
        return tuple(v) if isinstance(v, list) else v

    @model_validator(mode="after")
    def _check(self):
        if sum(self.attenuation) <= 0:
            raise ValueError("attenuation [c, l, q] must not be all zero")
        return self


class PointLight(_PositionedLight):
    """Shines equally in every direction."""

    type: Literal["point"]


class SpotLight(_PositionedLight):
    """A point light limited to a cone about `direction`: full intensity within `inner_angle` of the axis, none
    beyond `angle`, and between them the factor s² with s = (cosθ − cos angle)/(cos inner_angle − cos angle)
    (glTF KHR_lights_punctual's recommended falloff; angles are half-angles in degrees)."""

    type: Literal["spot"]
    direction: Direction
    angle: Annotated[float, Field(gt=0, le=90, allow_inf_nan=False)] = 45.0
    inner_angle: Annotated[float, Field(ge=0, le=90, allow_inf_nan=False)] = 0.0

    @model_validator(mode="after")
    def _check_cone(self):
        if self.inner_angle > self.angle:
            raise ValueError(f"inner_angle ({self.inner_angle:g}) must not exceed angle ({self.angle:g})")
        return self


class DirectionalLight(_LocalLight):
    """A parallel light travelling along `direction` (so L = −direction)."""

    type: Literal["directional"]
    direction: Direction


class _AreaLight(StrictModel):
    type: Literal["area"]
    radiance: Color = (1.0, 1.0, 1.0)
    samples: Annotated[int, Field(ge=1, le=4096)] = 16


class RectLight(_AreaLight):
    """Emits on the side of cross(edge_u, edge_v) only."""

    shape: Literal["rect"]
    corner: Vec3
    edge_u: Vec3
    edge_v: Vec3

    @model_validator(mode="after")
    def _check(self):
        if norm(cross(self.edge_u, self.edge_v)) <= 1e-18:
            raise ValueError("edge_u and edge_v must be non-zero and not parallel")
        return self


class DiskLight(_AreaLight):
    """Emits on the side of `normal` only."""

    shape: Literal["disk"]
    center: Vec3
    normal: Direction
    radius: Positive


class SphereLight(_AreaLight):
    """Emits outward from its whole surface."""

    shape: Literal["sphere"]
    center: Vec3
    radius: Positive


def _light_tag(value: Any) -> Optional[str]:
    if not isinstance(value, dict):
        return None
    kind = value.get("type")
    if kind == "area":
        shape = value.get("shape")
        return f"area.{shape}" if shape in ("rect", "disk", "sphere") else "area.?"
    return kind if isinstance(kind, str) else None


Light = Annotated[
    Union[
        Annotated[PointLight, Tag("point")],
        Annotated[SpotLight, Tag("spot")],
        Annotated[DirectionalLight, Tag("directional")],
        Annotated[RectLight, Tag("area.rect")],
        Annotated[DiskLight, Tag("area.disk")],
        Annotated[SphereLight, Tag("area.sphere")],
    ],
    Discriminator(
        _light_tag,
        custom_error_type="light_type",
        custom_error_message=(
            "lights need type: point, spot, directional or area (area needs shape: rect, disk or sphere)"
        ),
    ),
]
LIGHT_TYPES = ("point", "spot", "directional", "area")

# ----------------------------------------------------------------------------------------------------- scene


class Scene(StrictModel):
    """A whole scene. Build one with `lumos.load_scene(path_or_dict)`."""

    camera: Camera = Field(default_factory=Camera)
    render: RenderSettings = Field(default_factory=RenderSettings)
    ambient: Color = (0.0, 0.0, 0.0)
    background: Color = (0.0, 0.0, 0.0)
    lights: list[Light] = Field(default_factory=list)
    materials: dict[str, Material] = Field(default_factory=dict)
    objects: list[Object] = Field(default_factory=list)
    _source: Optional[Path] = PrivateAttr(default=None)
    #: what the loader included from model files (`type: model`, a camera's `file`), one line each, for `lumos info`
    _included: list = PrivateAttr(default_factory=list)

    @model_validator(mode="after")
    def _check_material_names(self):
        for i, obj in enumerate(self.objects):
            if isinstance(obj.material, str) and obj.material not in self.materials:
                known = ", ".join(sorted(self.materials)) or "none are defined"
                raise UnknownMaterial(i, obj.material, known)
        return self

    def material_of(self, obj) -> Material:
        if obj.material is None:
            return DEFAULT_MATERIAL
        if isinstance(obj.material, str):
            return self.materials[obj.material]
        return obj.material

    @property
    def source(self) -> Optional[Path]:
        """The file the scene was loaded from (None for a dict)."""
        return self._source


class UnknownMaterial(ValueError):
    """Raised by Scene validation; the loader reports it at objects[i].material."""

    def __init__(self, index: int, name: str, known: str):
        super().__init__(f"unknown material '{name}' (defined: {known})")
        self.index = index
        self.name = name
