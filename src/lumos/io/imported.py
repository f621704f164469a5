"""What every model importer returns (`ImportedModel`): a model file read into scene-format pieces.

A leaf module of its own, so that the importers (`io.obj`, `io.gltf`) and the dispatcher that calls them
(`io.models.import_model`) all import it and none imports another back.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

#: `<file>:<line>: ` (or `<file>:<line>:<column>: `) at the start of a warning: where, not what.
_WHERE = re.compile(r"^(?P<file>.*?):(?P<line>\d+)(?::\d+)?: ")


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

    def warnings_once(self) -> list[str]:
        """The warnings with each distinct problem said once: warnings that differ only in their line (a
        missing texture named by 26 map statements) become the first, with a count and the other lines."""
        order: list[str] = []
        seen: dict[str, list] = {}  # problem -> [first warning, file, other lines]
        for text in self.warnings:
            m = _WHERE.match(text)
            problem = f"{m['file']}: {text[m.end():]}" if m else text
            if problem not in seen:
                seen[problem] = [text, m["file"] if m else None, []]
                order.append(problem)
            elif m:
                seen[problem][2].append(m["line"])
            else:
                seen[problem][2].append("")
        out = []
        for problem in order:
            first, _, more = seen[problem]
            if more:
                lines = [x for x in more if x]
                shown = ", ".join(lines[:5]) + (", …" if len(lines) > 5 else "")
                first += f" ({len(more) + 1} times" + (f"; also line{'s' if len(lines) > 1 else ''} {shown}" if lines
                                                      else "") + ")"
            out.append(first)
        return out
