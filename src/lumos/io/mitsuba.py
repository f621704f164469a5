"""Mitsuba 3 scene files (`.xml`) read into lumos's scene format, so that `lumos render scene.xml` and
`lumos.load_scene("scene.xml")` take the scenes Mitsuba users have.

    data, lines = read_mitsuba(Path("scene.xml"))     # a scene dict as a YAML file gives it, {key path: line}
    lumos.load_scene("scene.xml")                     # the loader calls read_mitsuba (scene/loader.py)

Three steps, one module each:
- `mitsuba_xml`: the XML itself — `<default>`/`$param`, `<include>`, ids and `<ref>`s, typed values,
  `<transform>`s composed as Mitsuba composes them — into a tree of plugin nodes.
- `mitsuba_scene` (with `mitsuba_shapes`): sensor, film, sampler, integrator, emitters and shapes → `camera`,
  `render`, `lights`, `objects`, `background`, converting Mitsuba's units to lumos's.
- `mitsuba_bsdfs` (with `mitsuba_data`: spectra, named IORs, conductor presets): BSDFs and textures → materials.

Mesh and image paths are written relative to the XML file's folder (lumos's loader resolves them from there).
Bad input raises LumosError `<file>:<line>: <what>`; a plugin lumos does not have, or reads approximately, gives
one LumosWarning per plugin naming what stands in for it. docs/formats.md ("Mitsuba 3 scenes") has the mapping.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from .mitsuba_bsdfs import Context
from .mitsuba_scene import SceneBuilder
from .mitsuba_xml import parse_scene


def read_mitsuba(path: Path, params: Optional[dict] = None) -> tuple[dict, dict]:
    """Read the Mitsuba 3 scene `path` into (lumos scene dict, {key path tuple: line in the XML file}).

    params: values for the scene's `$name` parameters (as `mitsuba -D name=value`); without them the file's
    `<default>`s apply. Raises LumosError with a one-line `<file>:<line>: <what>` for bad input."""
    path = Path(path)
    root = parse_scene(path, params)
    ctx = Context(path, root.folders)
    data = SceneBuilder(ctx).build(root)
    return data, ctx.lines
