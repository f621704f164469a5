"""The scene model (pure Python, validated) and its loader. Never imports Numba."""

from .model import (
    AOV_NAMES,
    DEFAULT_MATERIAL,
    LIGHT_TYPES,
    OBJECT_TYPES,
    Box,
    Camera,
    Cone,
    Cylinder,
    DirectionalLight,
    Disk,
    DiskLight,
    Material,
    Mesh,
    Plane,
    PointLight,
    Rect,
    RectLight,
    RenderSettings,
    Scene,
    Sphere,
    SphereLight,
    SpotLight,
    Transform,
    Triangle,
)
from .loader import format_validation_error, load_scene
