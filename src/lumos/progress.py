"""A progress bar on stderr (rich) that appears only for renders that last longer than about a second."""

from __future__ import annotations

import contextlib
import sys
import time
from typing import Callable, Iterator, Optional

#: Seconds a render must have run, with work left, before the bar appears.
SHOW_AFTER_S = 0.8


@contextlib.contextmanager
def make_progress(progress) -> Iterator[Optional[Callable[[float], None]]]:
    """Yield a `report(fraction)` callable (or None).

    `progress` is False (no reports), a callable (receives each fraction), or True (a rich bar on stderr, shown
    once the render has taken SHOW_AFTER_S and is not done yet). The bar's `report.note(text)` sets a line of
    figures shown beside it (a cluster's pieces and samples per second); other reporters have no `note`.
    """
    if not progress:
        yield None
        return
    if callable(progress):
        yield progress
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn, TimeRemainingColumn

    start = time.perf_counter()
    state = {"bar": None, "task": None, "note": ""}
    console = Console(file=sys.stderr)

    def report(fraction: float) -> None:
        bar = state["bar"]
        if bar is None:
            if time.perf_counter() - start < SHOW_AFTER_S or fraction >= 1.0:
                return
            bar = Progress(TextColumn("rendering"), BarColumn(), TaskProgressColumn(), TimeRemainingColumn(),
                           TextColumn("{task.fields[note]}"), console=console, transient=True)
            bar.start()
            state["bar"], state["task"] = bar, bar.add_task("render", total=1.0, note=state["note"])
        bar.update(state["task"], completed=fraction, note=state["note"])

    def note(text: str) -> None:
        state["note"] = text

    report.note = note
    try:
        yield report
    finally:
        if state["bar"] is not None:
            state["bar"].stop()
