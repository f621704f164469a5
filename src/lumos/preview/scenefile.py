"""The page's Save: the edited scene written to a new file in the scene's own folder, never over a file.

The folder is the scene's so that its relative paths (mesh files, textures, included models) still work; a name
with a folder in it, one that resolves elsewhere (`..`, an absolute path, a link) and one that exists are refused.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import LumosError

SCENE_SUFFIXES = (".yaml", ".yml", ".json")


def save_new_scene(data: dict, folder: Path, name, origin: str) -> Path:
    """Write `data` to the new file `name` in `folder` (YAML, or JSON for a `.json` name; `.yaml` is added to a
    name without one of `SCENE_SUFFIXES`); returns its path. `origin` (the scene file's name) goes in the YAML's
    first line."""
    if not isinstance(name, str) or not name.strip() or "\x00" in name or len(name) > 255:
        raise LumosError("save: give a file name, such as showcase-edited.yaml")
    name = name.strip()
    target = folder / name
    if target.suffix.lower() not in SCENE_SUFFIXES:
        target = target.with_name(target.name + ".yaml")
    resolved = target.resolve()
    if resolved.parent != folder.resolve() or Path(name).name != name:
        raise LumosError(f"save: {name!r} is not a file in the scene's folder {folder}; give a name only")
    if resolved.exists():
        raise LumosError(f"save: {resolved.name} exists in {folder}; choose another name")
    text = (json.dumps(data, indent=2) + "\n" if resolved.suffix.lower() == ".json"
            else f"# {resolved.name}: {origin} edited in the lumos preview\n" + _yaml(data))
    try:
        with open(resolved, "x", encoding="utf-8") as f:  # "x": never over a file made meanwhile
            f.write(text)
    except FileExistsError:
        raise LumosError(f"save: {resolved.name} exists in {folder}; choose another name") from None
    except OSError as exc:
        raise LumosError(f"save: cannot write {resolved}: {exc.strerror or exc}") from None
    return resolved


def _yaml(data: dict) -> str:
    import yaml

    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, allow_unicode=True, width=120)
