"""What each method can do, as data, and the one place that refuses what it cannot: `lumos.render`, the CLI,
`lumos sheet`, `lumos explain` and each `render_<method>` called directly all refuse in the same words.
"""

from __future__ import annotations

from ..errors import LumosError
from ..scene.model import PATH_AOVS, TERM_AOVS

#: The anti-aliasing each method takes, and what it means there ("" where the name says it).
ANTIALIAS: dict[str, dict[str, str]] = {
    "raycast": {"none": "", "supersample": "spp jittered samples"},
    "raster": {"none": "", "supersample": "spp passes"},
    "whitted": {"none": "", "supersample": "", "adaptive": ""},
    "path": {"none": "pixel centres", "supersample": "spp samples spread over each pixel by the filter"},
    "radiosity": {"none": "", "supersample": ""},
}

#: Settings only the path tracer reads: (key, given?, the flag that sets it).
PATH_ONLY = (
    ("time_limit", lambda s: s.time_limit is not None, "--time-limit"),
    ("denoise", lambda s: s.denoise, "--denoise"),
    ("sampling", lambda s: s.sampling != "mis", "--sampling"),
    ("sampler", lambda s: s.sampler != "sobol", "--sampler"),
    ("light_selection", lambda s: s.light_selection != "tree", "--light-selection"),
)

#: The methods that compute the classic model's terms (the term AOVs); the others compute global illumination.
MAKE_TERMS = ("raycast", "raster", "whitted")


def check_settings(settings) -> None:
    """Refuse, with a one-line error naming the key, a setting `settings.method` cannot honour."""
    method = settings.method
    modes = ANTIALIAS.get(method, {settings.antialias: ""})  # a method registered from outside: its own checks
    if settings.antialias not in modes:
        takes = " or ".join(f"{mode} ({meaning})" if meaning else mode for mode, meaning in modes.items())
        raise LumosError(f"render.antialias: {settings.antialias} anti-aliasing is a whitted feature; {method} "
                         f"takes {takes}")
    if settings.filter != "box" and settings.antialias == "adaptive":
        raise LumosError(f"render.filter: {settings.filter} filtering needs supersample anti-aliasing; adaptive "
                         "anti-aliasing subdivides the pixel's square (a box filter)")
    if method != "path":
        for key, given, flag in PATH_ONLY:
            if given(settings):
                raise LumosError(f"render.{key}: {flag} is a path feature; method {method} does not take it")
        for name in PATH_AOVS:
            if name in settings.aov:
                raise LumosError(f"render.aov: the {name!r} AOV is made by method path only")
    if method not in MAKE_TERMS:
        for name in TERM_AOVS:
            if name in settings.aov:
                raise LumosError(f"render.aov: the {name!r} AOV is a term of the classic model, made by "
                                 f"{', '.join(MAKE_TERMS[:-1])} and {MAKE_TERMS[-1]}; method {method} computes "
                                 "global illumination")
    if "noisy" in settings.aov and not settings.denoise:
        raise LumosError("render.aov: the 'noisy' AOV is the image before denoising; it needs denoise (--denoise)")
