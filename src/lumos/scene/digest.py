"""A fingerprint of a scene's geometry, lights and materials: what a radiosity solution depends on.

A pure hash of the scene model (and of which sides of which objects were meshed into patches), so a saved
solution can be matched to the scene it was solved for.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np


def scene_digest(scene, sides=None) -> str:
    """A fingerprint of what a solution depends on: the objects, lights and materials (not the camera, the
    image size, the display settings, the background, the ambient term or the animation block, so a saved
    solution renders any view), and `sides`: which sides of which objects are patches (the inside of a solid is
    one only when the camera or a light is in it, so a solution solved from outside a box cannot draw the view
    from inside)."""
    data = scene.model_dump(exclude={"camera", "render", "background", "ambient", "animation"}, warnings=False)
    for light in data.get("lights", []):  # lights without a name hash as before lights could have one
        if light.get("name") is None:
            light.pop("name", None)
    if sides is not None:
        data["_sides"] = np.asarray(sides)

    def encode(value):  # mesh arrays (from files or inline) by their bytes; paths and the rest as text
        if isinstance(value, np.ndarray):
            return hashlib.sha1(np.ascontiguousarray(value).tobytes()).hexdigest() + str(value.shape)
        return str(value)

    return hashlib.sha1(json.dumps(data, sort_keys=True, default=encode).encode()).hexdigest()
