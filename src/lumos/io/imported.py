"""What every model importer returns (`ImportedModel`): a model file read into scene-format pieces.

A leaf module of its own, so that the importers (`io.obj`, `io.gltf`) and the dispatcher that calls them
(`io.models.import_model`) all import it and none imports another back.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class ImportedModel:
    """A model file read into scene-format pieces (see `lumos.io.models`): materials by name, objects, the file's
    own cameras and lights, and one-line warnings."""

    source: Path
    materials: dict[str, dict] = field(default_factory=dict)
    objects: list[dict] = field(default_factory=list)
    cameras: list[dict] = field(default_factory=list)
    lights: list[dict] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
