"""The `rect` object (a parallelogram, Mitsuba's `rectangle`): the same surface as its two triangles in every
method, sampled by area when it emits, and clear errors for degenerate edges."""

import numpy as np
import pytest

import lumos
from lumos.errors import LumosError

CORNER, EDGE_U, EDGE_V = [-1.0, -0.7, -0.5], [1.8, 0.3, 0.2], [0.2, 1.4, -0.6]


def _scene(obj):
    return {"camera": {"position": [0.3, 0.2, 4], "look_at": [0, 0, 0], "fov": 45},
            "lights": [{"type": "point", "position": [1, 2, 3], "intensity": 0.8},
                       {"type": "directional", "direction": [0.2, -0.5, -1], "intensity": 0.4}],
            "objects": [dict(obj, material={"kd": [0.7, 0.5, 0.3], "ks": 0.3, "shininess": 20})]}


def _quad_mesh():
    c, u, v = map(np.asarray, (CORNER, EDGE_U, EDGE_V))
    return {"type": "mesh", "vertices": [c.tolist(), (c + u).tolist(), (c + u + v).tolist(), (c + v).tolist()],
            "faces": [[0, 1, 2], [0, 2, 3]], "smooth": False}


@pytest.mark.parametrize("method", ["raycast", "whitted", "raster"])
def test_rect_is_its_two_triangles(method):
    rect = lumos.render(_scene({"type": "rect", "corner": CORNER, "edge_u": EDGE_U, "edge_v": EDGE_V}),
                        method=method, width=48, height=40, antialias="none", aov=["object_id"])
    mesh = lumos.render(_scene(_quad_mesh()), method=method, width=48, height=40, antialias="none",
                        aov=["object_id"])
    inside = (rect.aovs["object_id"] == 0) & (mesh.aovs["object_id"] == 0)
    assert inside.sum() > 200
    assert np.mean(rect.aovs["object_id"] == mesh.aovs["object_id"]) > 0.99  # the same coverage, up to edges
    np.testing.assert_allclose(rect.array[inside], mesh.array[inside], atol=2e-4)


def test_rect_uv_runs_along_its_edges():
    from conftest import compile_dict, surfaces

    compiled = compile_dict({"objects": [{"type": "rect", "corner": CORNER, "edge_u": EDGE_U, "edge_v": EDGE_V}]})
    s, t = 0.3, 0.8
    target = np.asarray(CORNER) + s * np.asarray(EDGE_U) + t * np.asarray(EDGE_V)
    n = np.cross(EDGE_U, EDGE_V)
    origin = target + n / np.linalg.norm(n)
    hit = surfaces(compiled.arrays, [origin], [-n / np.linalg.norm(n)])[0]
    assert hit["u"] == pytest.approx(s, abs=1e-9) and hit["v"] == pytest.approx(t, abs=1e-9)
    np.testing.assert_allclose(hit["p"], target, atol=1e-9)


def test_degenerate_rect_is_a_one_line_error():
    with pytest.raises(LumosError, match=r"objects\[0\].*edge_u and edge_v must be non-zero and not parallel"):
        lumos.load_scene({"objects": [{"type": "rect", "edge_u": [1, 0, 0], "edge_v": [2, 0, 0]}]})
