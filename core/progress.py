"""Progress reports and cancellation for long renders, without any user interface.

The work calls ``Progress.update(fraction, message)``; the callback given by the caller
(the command line's progress bar, the Blender panel) shows it and may return True to cancel,
which raises ``Cancelled`` at the next safe point (between renders).
"""
from __future__ import annotations

import time
from typing import Callable, Optional

from .errors import Cancelled

#: (fraction done in [0, 1], one-line message) -> True to cancel.
ProgressCallback = Callable[[float, str], Optional[bool]]


class Progress:
    """Forward progress to an optional callback and turn a True answer into ``Cancelled``."""

    def __init__(self, callback: ProgressCallback | None = None):
        self.callback = callback
        self.started = time.perf_counter()
        self.cancel_requested = False

    def update(self, fraction: float, message: str) -> None:
        """Report progress; raise Cancelled if the callback asks for it (now or earlier)."""
        if self.callback is not None and self.callback(min(1.0, max(0.0, fraction)), message):
            self.cancel_requested = True
        self.check()

    def note(self, fraction: float, message: str) -> None:
        """Report progress from a place that cannot stop (inside a Cycles render); a cancel
        request is remembered and raised by the next ``update`` or ``check``."""
        if self.callback is not None and self.callback(min(1.0, max(0.0, fraction)), message):
            self.cancel_requested = True

    def check(self) -> None:
        if self.cancel_requested:
            raise Cancelled("cancelled")

    @property
    def elapsed(self) -> float:
        return time.perf_counter() - self.started


class TileProgress:
    """Fraction done over a list of renders of unequal cost.

    A render costs its pixel-samples plus a fixed overhead (scene update, session reset,
    image write), expressed in pixel-samples so both add up (``RenderOptions.render_cost``).
    """

    def __init__(self, progress: Progress, costs: list[int], overhead: int = 1024):
        self.progress = progress
        self.costs = [cost + overhead for cost in costs]
        self.total = sum(self.costs) or 1
        self.done = 0
        self.count = 0

    def start(self, spp: int) -> None:
        self.progress.update(self.done / self.total,
                            f"tile {self.count + 1}/{len(self.costs)} ({spp} spp)")

    def finish(self) -> None:
        self.done += self.costs[self.count]
        self.count += 1
        self.progress.update(self.done / self.total, f"tile {self.count}/{len(self.costs)} done")
