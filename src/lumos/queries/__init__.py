"""Ray queries from Python: `lumos.RayCaster` (`raycaster.py`) and its interference estimate (`interference.py`).

See docs/queries.md.
"""

from .interference import Interference
from .raycaster import Crossings, Hits, RayCaster, Segments

__all__ = ["RayCaster", "Hits", "Crossings", "Segments", "Interference"]
