"""The validated scene model: camera, render settings, lights, materials and objects, one module each
(`camera`, `settings`, `materials`, `transform`, `objects`, `lights`), re-exported here with the `Scene` itself.

Plain pydantic models, pure Python (NumPy only for mesh arrays; never Numba). Field names are the scene-file
keys of `docs/scene-format.md`; the conventions (camera basis, light units, shading normal) are those of
DESIGN.md. The compile step (`lumos.compile`) turns a `Scene` into flat arrays for the kernels.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from pydantic import Field, PrivateAttr, model_validator

from .types import Color, StrictModel
from .camera import (
    Camera,
)
from .settings import (
    AOV_NAMES,
    DEFAULT_MAX_DEPTH,
    PATH_AOVS,
    RadiositySettings,
    RenderSettings,
    TERM_AOVS,
)
from .materials import (
    Bump,
    DEFAULT_MATERIAL,
    Material,
    MaterialRef,
    TEXTURE_TARGETS,
    Texture,
)
from .transform import (
    Row4,
    Transform,
)
from .objects import (
    Box,
    Cone,
    Csg,
    Cylinder,
    Disk,
    Mesh,
    ModelInclude,
    OBJECT_TYPES,
    Object,
    ObjectBase,
    Plane,
    Rect,
    Solid,
    Sphere,
    Triangle,
)
from .keyframes import (
    Animation,
)
from .lights import (
    DirectionalLight,
    DiskLight,
    Environment,
    LIGHT_TYPES,
    Light,
    PointLight,
    RectLight,
    Sky,
    SphereLight,
    SpotLight,
)


__all__ = [
    "AOV_NAMES",
    "Animation",
    "Box",
    "Bump",
    "Camera",
    "Cone",
    "Csg",
    "Cylinder",
    "DEFAULT_MATERIAL",
    "DEFAULT_MAX_DEPTH",
    "DirectionalLight",
    "Disk",
    "DiskLight",
    "Environment",
    "LIGHT_TYPES",
    "Light",
    "Material",
    "MaterialRef",
    "Mesh",
    "ModelInclude",
    "OBJECT_TYPES",
    "Object",
    "ObjectBase",
    "PATH_AOVS",
    "Plane",
    "PointLight",
    "RadiositySettings",
    "Rect",
    "RectLight",
    "RenderSettings",
    "Row4",
    "Scene",
    "Solid",
    "Sphere",
    "Sky",
    "SphereLight",
    "SpotLight",
    "TERM_AOVS",
    "TEXTURE_TARGETS",
    "Texture",
    "Transform",
    "Triangle",
    "MaterialError",
    "UnknownMaterial",
]


class Scene(StrictModel):
    """A whole scene. Build one with `lumos.load_scene(path_or_dict)`."""

    camera: Camera = Field(default_factory=Camera)
    render: RenderSettings = Field(default_factory=RenderSettings)
    ambient: Color = (0.0, 0.0, 0.0)
    background: Color = (0.0, 0.0, 0.0)
    lights: list[Light] = Field(default_factory=list)
    #: light from every direction (an image or a constant): what rays that miss see, and, in `path`, a light
    environment: Optional[Environment] = None
    materials: dict[str, Material] = Field(default_factory=dict)
    objects: list[Object] = Field(default_factory=list)
    #: keyframed tracks over time (`lumos.scene.animation`); the rest of the scene is its state where no track says
    animation: Optional[Animation] = None
    _source: Optional[Path] = PrivateAttr(default=None)
    #: what the loader included from model files (`type: model`, a camera's `file`), one line each, for `lumos info`
    _included: list = PrivateAttr(default_factory=list)
    #: the scene was made up for a bare model file (`lumos render model.obj`): its camera, lights and method
    _made_for_model: bool = PrivateAttr(default=False)

    @model_validator(mode="after")
    def _check_environment(self):
        if self.environment is not None and "background" in self.model_fields_set:
            raise ValueError("give background (one colour) or environment, not both: the environment is what rays "
                             "that miss see")
        return self

    @model_validator(mode="after")
    def _check_material_names(self):
        known = ", ".join(sorted(self.materials)) or "none are defined"
        for i, obj in enumerate(self.objects):
            if isinstance(obj.material, str) and obj.material not in self.materials:
                raise UnknownMaterial(("objects", i, "material"), obj.material, known)
        for i, light in enumerate(self.lights):
            if getattr(light, "material", None) is None:
                continue
            if isinstance(light.material, str) and light.material not in self.materials:
                raise UnknownMaterial(("lights", i, "material"), light.material, known)
            if any(c > 0 for c in self.material_of(light).emission):
                raise MaterialError(("lights", i, "material"), "an area light's material must not emit (the "
                                    "light's emission is its radiance); give the material emission 0")
        return self

    def material_of(self, obj) -> Material:
        """The material of an object (the default one where it has none), or of an area light (None where it
        has none: a light without a material reflects nothing)."""
        if obj.material is None:
            return None if obj.type == "area" else DEFAULT_MATERIAL
        if isinstance(obj.material, str):
            return self.materials[obj.material]
        return obj.material

    @property
    def source(self) -> Optional[Path]:
        """The file the scene was loaded from (None for a dict)."""
        return self._source

    @property
    def made_for_model(self) -> bool:
        """Whether the scene was made up for a bare model file (its camera, lights and method chosen by lumos)."""
        return self._made_for_model


class MaterialError(ValueError):
    """Raised by Scene validation about a material reference; the loader reports it at `where` (a key path such as
    ("objects", 3, "material"))."""

    def __init__(self, where: tuple, message: str):
        super().__init__(message)
        self.where = where


class UnknownMaterial(MaterialError):
    """A material name that `materials:` does not define."""

    def __init__(self, where: tuple, name: str, known: str):
        super().__init__(where, f"unknown material '{name}' (defined: {known})")
        self.name = name
