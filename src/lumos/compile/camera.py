"""The camera as two small arrays for the kernels (DESIGN.md §3: basis, pixel centres, thin lens)."""

from __future__ import annotations

import math

import numpy as np

from ..kernels import layout as L


def camera_arrays(camera, pixel_filter: str = "box") -> tuple[np.ndarray, np.ndarray]:
    """(cam_vecs float64 (4, 3) = position, u, v, w; cam_params float64 (CAM_SIZE,)); `pixel_filter` ("box" or
    "gaussian") places raycast's and whitted's supersamples (`kernels.camera`)."""
    from ..kernels.camera import FILTER_BOX, FILTER_GAUSSIAN

    u, v, w = camera.basis()
    vecs = np.array([camera.position, u, v, w], dtype=np.float64)
    params = np.zeros(L.CAM_SIZE)
    params[L.CAM_ORTHO] = 1.0 if camera.type == "orthographic" else 0.0
    params[L.CAM_TAN_HALF_FOV] = math.tan(math.radians(camera.fov) / 2.0)
    params[L.CAM_HALF_SIZE] = camera.size / 2.0
    params[L.CAM_APERTURE] = camera.aperture
    params[L.CAM_FOCUS] = camera.resolved_focus_distance()
    params[L.CAM_FILTER] = FILTER_GAUSSIAN if pixel_filter == "gaussian" else FILTER_BOX
    return vecs, params
