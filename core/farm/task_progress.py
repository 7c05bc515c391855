"""How far a farm task is, told to the farm: Open Job Description's stdout lines.

A worker agent reads ``openjd_progress: <percent>`` and ``openjd_status: <text>`` from an
action's standard output and shows them in the farm's monitor. A task prints one progress
line per whole percent (a tile task may render thousands of rectangles) and a status line
whenever its work changes; both are flushed at once, since a task may be cancelled any time.
"""
from __future__ import annotations

import sys
from typing import TextIO


class TaskProgress:
    """The progress and status lines of one farm task, written to ``stream`` (stdout)."""

    def __init__(self, stream: TextIO | None = None):
        self.stream = stream
        self.percent: int | None = None
        self.text: str | None = None

    def _write(self, line: str) -> None:
        stream = self.stream or sys.stdout
        stream.write(line + "\n")
        stream.flush()

    def status(self, text: str) -> None:
        """One status line, unless it is the one shown already."""
        text = " ".join(str(text).split())          # one line, whatever the message held
        if text and text != self.text:
            self.text = text
            self._write(f"openjd_status: {text}")

    def progress(self, fraction: float) -> None:
        """The fraction done (0..1) as a whole percent, when it changed."""
        percent = int(min(max(float(fraction), 0.0), 1.0) * 100)
        if percent != self.percent:
            self.percent = percent
            self._write(f"openjd_progress: {percent}")

    def callback(self, prefix: str = ""):
        """A ``core.progress`` callback (fraction, message) that reports both; never cancels
        (a farm cancels a task with SIGTERM)."""
        def report(fraction: float, message: str) -> bool:
            self.progress(fraction)
            self.status(prefix + message)
            return False
        return report
