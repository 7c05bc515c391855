"""A progress bar on stderr for the command line: a redrawn line on a terminal, plain
lines (at most one every few seconds) when stderr is a file or a pipe."""
from __future__ import annotations

import sys
import time


def format_duration(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class ProgressBar:
    """A ``core.progress`` callback: ``bar(fraction, message)``; never asks to cancel
    (Ctrl-C does that on the command line). Call ``close()`` when done."""

    WIDTH = 24

    def __init__(self, label: str, stream=None, interval: float | None = None):
        self.label = label
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.interval = interval if interval is not None else (0.1 if self.tty else 5.0)
        self.started = time.perf_counter()
        self.last = -1e9
        self.drawn = False

    def line(self, fraction: float, message: str) -> str:
        elapsed = time.perf_counter() - self.started
        eta = f"ETA {format_duration(elapsed * (1 - fraction) / fraction)}" if fraction > 0 else "ETA ?"
        done = int(round(self.WIDTH * fraction))
        bar = "#" * done + "-" * (self.WIDTH - done)
        return f"{self.label} [{bar}] {100 * fraction:3.0f}%  {message}  {eta}"

    def __call__(self, fraction: float, message: str) -> bool:
        now = time.perf_counter()
        if fraction < 1.0 and now - self.last < self.interval:
            return False
        self.last = now
        text = self.line(fraction, message)
        if self.tty:
            self.stream.write("\r" + text + "\x1b[K")
            self.drawn = True
        else:
            self.stream.write(text + "\n")
        self.stream.flush()
        return False

    def close(self) -> None:
        if self.tty and self.drawn:
            self.stream.write("\n")
            self.stream.flush()
            self.drawn = False
