"""The `render:` block: method, image size, samples, depth, AOVs, and each method's own settings.

Part of the scene model (`lumos.scene.model`, which re-exports every public name).
"""

from __future__ import annotations

from typing import Annotated, Literal, Optional

from pydantic import Field, model_validator

from .types import Positive, StrictModel


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
    #: with an environment: rays per patch that gather its light (drawn in proportion to its radiance)
    sky_samples: Annotated[int, Field(ge=1, le=65536)] = 64
    #: largest patch edge in world units (default: 1/24 of the scene's bounds' diagonal)
    patch_size: Optional[Positive] = None
    #: adaptive refinement: split patches whose radiance differs from a neighbour's by more than the threshold
    #: (relative), down to `subdivide_levels` levels
    subdivide: bool = False
    subdivide_threshold: Positive = 0.25
    subdivide_levels: Annotated[int, Field(ge=1, le=8)] = 2
    #: stop when the unshot power relative to the power sent (progressive, stochastic), or the distance left to
    #: the solution relative to the mean radiance (gauss_seidel, jacobi), falls below this
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
    #: raster, raycast, whitted: filter textures, bump and normal maps over each pixel's footprint (mip-mapped
    #: images, box-filtered checker and stripes; the ray methods by ray cones)
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
    #: how light sampling picks an emitter: by its estimated contribution at the shading point (a light tree,
    #: pbrt-v4's), or by its power alone (one table for the whole scene)
    light_selection: Literal["tree", "power"] = "tree"
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
