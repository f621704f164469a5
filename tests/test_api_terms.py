"""The per-term AOVs (ambient, diffuse, specular, emitted, reflected, transmitted): the terms of
I = Ka·Ia + Σ(Kd·Id·(N·L) + Ks·Is·(R·V)^n) + emission + Kr·I_r + Kt·I_t as each method computes them.

They add up to the image for every method, shading and anti-aliasing, and each is zero where the model says so."""

import numpy as np
import pytest

import lumos
from lumos.errors import LumosError
from lumos.scene.model import TERM_AOVS

GLASS = {"ka": 0.0, "kd": 0.05, "ks": 0.6, "shininess": 80, "kt": 0.85, "ior": 1.5, "fresnel": True}
MIRROR = {"ka": 0.05, "kd": 0.1, "ks": 0.3, "shininess": 40, "kr": 0.7}
FLOOR = {"ka": 0.4, "kd": 0.7, "ks": 0.1, "shininess": 10,
         "texture": {"type": "checker", "scale": 0.5, "colors": [[0.9, 0.9, 0.85], [0.2, 0.25, 0.5]]}}


def scene(**materials):
    m = {"glass": GLASS, "mirror": MIRROR, "floor": FLOOR, "glow": {"emission": [1.5, 0.9, 0.3]}}
    m.update(materials)
    return {
        "camera": {"position": [0.0, 1.6, 5.0], "look_at": [0.0, 0.6, 0.0], "fov": 45.0},
        "ambient": 0.15, "background": [0.2, 0.3, 0.45],
        "lights": [{"type": "point", "position": [3.0, 4.0, 3.0], "intensity": 0.8},
                   {"type": "area", "shape": "rect", "corner": [-2.5, 3.5, 0.5], "edge_u": [0.0, 0.0, 1.0],
                    "edge_v": [1.0, 0.0, 0.0], "radiance": 0.6, "samples": 4}],
        "materials": m,
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": "floor"},
            {"type": "sphere", "center": [-0.9, 0.7, 0.0], "radius": 0.7, "material": "glass"},
            {"type": "sphere", "center": [0.9, 0.7, -0.4], "radius": 0.7, "material": "mirror"},
            {"type": "sphere", "center": [0.1, 0.25, 1.1], "radius": 0.25, "material": "glow"},
        ],
    }


CASES = [("raycast", {}), ("raycast", {"spp": 4}),
         ("whitted", {"antialias": "none"}), ("whitted", {"spp": 4}), ("whitted", {"antialias": "adaptive"}),
         ("raster", {"shading": "flat"}), ("raster", {"shading": "gouraud"}), ("raster", {"shading": "phong"}),
         ("raster", {"shading": "phong", "spp": 4, "shadows": True})]


@pytest.mark.parametrize("method, settings", CASES)
def test_terms_add_up_to_the_image(method, settings):
    img = lumos.render(scene(), method=method, width=64, height=48, aov=list(TERM_AOVS), **settings)
    total = sum(img.aovs[name].astype(np.float64) for name in TERM_AOVS)
    assert np.abs(total - img.array).max() < 1e-5
    for name in ("ambient", "diffuse", "emitted"):
        assert img.aovs[name].max() > 0.05, name  # every one of them shows somewhere
    if method == "whitted":
        assert img.aovs["reflected"].max() > 0.05 and img.aovs["transmitted"].max() > 0.05
    else:  # the local methods trace no secondary rays
        assert not img.aovs["reflected"].any() and not img.aovs["transmitted"].any()


@pytest.mark.parametrize("method, settings", [("raycast", {"mipmap": False}),  # point lookups: one colour each
                                              ("whitted", {"antialias": "none", "mipmap": False}),
                                              ("raster", {"shading": "gouraud"}), ("raster", {"shading": "phong"})])
def test_terms_vanish_where_the_model_says(method, settings):
    dull = {name: dict(m, ks=0.0) for name, m in (("glass", GLASS), ("mirror", MIRROR), ("floor", FLOOR))}
    img = lumos.render(scene(**dull), method=method, width=48, height=36, aov=list(TERM_AOVS), **settings)
    assert not img.aovs["specular"].any()
    flat = {"glass": dict(GLASS, kt=0.0), "mirror": dict(MIRROR, kr=0.0)}
    img = lumos.render(scene(**flat), method=method, width=48, height=36, aov=list(TERM_AOVS), **settings)
    assert not img.aovs["reflected"].any() and not img.aovs["transmitted"].any()
    # ambient is Ka·Ia, nothing else: where the eye sees the floor, ambient = texture colour × 0.15 (Ka replaced)
    ids = lumos.render(scene(**flat), method=method, width=48, height=36, aov=["object_id"], **settings)
    floor = ids.aovs["object_id"] == 0
    a = img.aovs["ambient"][floor]
    assert np.all((np.abs(a - 0.15 * np.array([0.9, 0.9, 0.85])).max(axis=1) < 1e-3)
                  | (np.abs(a - 0.15 * np.array([0.2, 0.25, 0.5])).max(axis=1) < 1e-3)) or method == "raster"


@pytest.mark.parametrize("method", ["path", "radiosity"])
def test_the_global_methods_refuse_the_classic_terms(method):
    with pytest.raises(LumosError, match="term of the classic model"):
        lumos.render(scene(), method=method, width=16, height=12, aov=["diffuse"])
