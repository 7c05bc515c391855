"""Progress reports and cancellation for long renders, without any user interface.

The work calls ``Progress.update(fraction, message)``; the callback given by the caller
(the command line's progress bar, the Blender panel) shows it and may return True to cancel,
which raises ``Cancelled`` at the next safe point (between renders).

Long jobs are also written as *steps*: a generator that yields ``(fraction, message)`` at
every safe point and returns its result. The command line drives it in one go
(``run_steps``); the Blender panel advances it one step per timer tick (``StepRunner``) so
the interface stays responsive, and cancels by closing it, which runs the generator's
``finally`` and ``with`` blocks (the scene is restored) at the point where it stopped.
"""
from __future__ import annotations

import time
from typing import Callable, Generator, Optional, TypeVar

from .errors import Cancelled

#: (fraction done in [0, 1], one-line message) -> True to cancel.
ProgressCallback = Callable[[float, str], Optional[bool]]
T = TypeVar("T")
#: Work split at its safe points: yields (fraction, message), returns the result.
Steps = Generator[tuple[float, str], None, T]


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

    def start(self, spp: int) -> tuple[float, str]:
        """Report the next render; returns what was reported (a step of ``Steps``)."""
        step = (self.done / self.total, f"tile {self.count + 1}/{len(self.costs)} ({spp} spp)")
        self.progress.update(*step)
        return step

    def finish(self) -> tuple[float, str]:
        self.done += self.costs[self.count]
        self.count += 1
        step = (self.done / self.total, f"tile {self.count}/{len(self.costs)} done")
        self.progress.update(*step)
        return step


class WeightedSteps:
    """Overall progress of a job made of steps of unequal weight, run one after another.

    ``begin(label)`` reports the start of the next step (a True answer from the callback,
    Ctrl-C, raises ``Cancelled`` there, between steps); ``sub(label)`` is a callback for the
    step's own progress, mapped onto its share of the whole (a render reached through it
    stops at its next safe point); ``finish()`` moves on. ``reweight`` changes a step's
    weight once its cost is known (a cached reference costs nothing).
    """

    def __init__(self, callback: ProgressCallback | None, weights: list[float]):
        self.callback = callback
        self.weights = list(weights)
        self.total = sum(self.weights) or 1.0
        self.done = 0.0
        self.index = 0

    def reweight(self, weight: float) -> None:
        """Give the current step another weight (before it reports anything)."""
        self.weights[self.index] = weight
        self.total = sum(self.weights) or 1.0

    def sub(self, label: str, echo: str = "") -> ProgressCallback:
        """A callback for the current step; ``echo`` is a prefix of the step's own messages
        that the label already says (the render functions start theirs with the mode)."""
        start, weight = self.done, self.weights[self.index]

        def report(fraction: float, message: str):
            if self.callback is None:
                return False
            if echo and message.startswith(echo):
                message = message[len(echo):]
            return self.callback((start + weight * min(1.0, max(0.0, fraction))) / self.total,
                                 f"{label}: {message}")
        return report

    def begin(self, label: str) -> None:
        if self.callback is not None and self.callback(self.done / self.total, label):
            raise Cancelled("cancelled")

    def finish(self) -> None:
        self.done += self.weights[self.index]
        self.index += 1


def run_steps(steps: Steps[T], callback: ProgressCallback | None = None) -> T:
    """Drive ``steps`` to the end, reporting each step to ``callback``; return its result.

    A callback answering True raises ``Cancelled`` after the generator has been closed
    (its clean-up has run). An exception inside the steps closes it the same way.
    """
    report = Progress(callback)
    try:
        while True:
            try:
                fraction, message = next(steps)
            except StopIteration as done:
                return done.value
            report.update(fraction, message)
    finally:
        steps.close()


def scaled_steps(steps: Steps[T], start: float, end: float, prefix: str = "") -> Steps[T]:
    """``steps`` with its fractions mapped onto [start, end] and its messages prefixed; for
    ``result = yield from scaled_steps(part, 0.2, 0.6)`` inside a larger job. Closing the
    outer job closes ``steps`` too."""
    try:
        while True:
            try:
                fraction, message = next(steps)
            except StopIteration as done:
                return done.value
            yield start + (end - start) * min(1.0, max(0.0, fraction)), prefix + message
    finally:
        steps.close()


def timed_steps(steps: Steps[T]) -> Steps[tuple[T, float]]:
    """``steps`` passed on unchanged, returning ``(result, seconds)``: the seconds spent
    inside ``steps`` only, not the time whoever drives them waits between two steps (a
    modal operator's timer ticks), so that work done inside a time budget is counted as
    the budget counts it."""
    seconds = 0.0
    try:
        while True:
            started = time.perf_counter()
            try:
                step = next(steps)
            except StopIteration as done:
                return done.value, seconds + time.perf_counter() - started
            seconds += time.perf_counter() - started
            yield step
    finally:
        steps.close()


class StepRunner:
    """Advance ``steps`` one step at a time (one step per timer tick of a modal operator).

    After each ``advance()``: ``fraction`` and ``message`` hold the last step, ``done`` says
    whether the generator returned, ``result`` holds what it returned. ``cancel()`` closes
    the generator (its clean-up runs now). An exception inside a step propagates from
    ``advance()`` with the generator already finished.
    """

    def __init__(self, steps: Steps):
        self.steps = steps
        self.fraction = 0.0
        self.message = ""
        self.done = False
        self.result = None
        self.started = time.perf_counter()

    def advance(self) -> bool:
        """Run the work up to its next safe point; True once it has finished."""
        if self.done:
            return True
        try:
            self.fraction, self.message = next(self.steps)
        except StopIteration as finished:
            self.done, self.result, self.fraction = True, finished.value, 1.0
        except BaseException:
            self.done = True
            raise
        return self.done

    def cancel(self) -> None:
        if not self.done:
            self.done = True
            self.steps.close()

    @property
    def elapsed(self) -> float:
        return time.perf_counter() - self.started
