"""Ctrl-C while Blender renders, where Blender owns the process (``blender -b ... x.batch()``).

Blender runs a render in C and calls back into Python (Cycles' engine, status handlers);
a KeyboardInterrupt raised there is caught and printed by Blender and the render goes on,
and Python only runs signal handlers in the main thread once the render has returned. So the
commands watch SIGINT through Python's wakeup file descriptor, which the C-level handler
writes at once, from a helper thread: the first Ctrl-C asks the progress callback to cancel,
which stops the work at the next safe point (between two tile renders, or after a single
render) with nothing written and the scene restored; a second Ctrl-C exits at once.

The ``xsl-render`` console script goes further (``signals.py``): SIGINT is blocked in every
thread from its first instruction and its own watcher cancels at once, so there this context
never sees a signal.
"""
from __future__ import annotations

import os
import signal
import sys
import threading


class InterruptToCancel:
    """Context manager (main thread only): Ctrl-C sets ``requested``; twice: exit 130 now."""

    def __init__(self):
        self.requested = False
        self._saved = None
        self._watcher = None

    def _watch(self, read_fd: int) -> None:
        while True:
            try:
                data = os.read(read_fd, 64)
            except OSError:
                return
            if not data:
                return
            for signum in data:
                if signum != signal.SIGINT:
                    continue
                if self.requested:
                    os._exit(130)
                self.requested = True
                print("\nxsl-render: cancelling after the current render (Ctrl-C again to stop at once)",
                      file=sys.stderr, flush=True)

    def __enter__(self) -> "InterruptToCancel":
        read_fd, write_fd = os.pipe()
        os.set_blocking(write_fd, False)
        # A Python-level handler must be installed for the C handler to write the wakeup fd;
        # it does nothing itself (the watcher thread has already acted).
        previous_handler = signal.signal(signal.SIGINT, lambda signum, frame: None)
        previous_fd = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
        self._watcher = threading.Thread(target=self._watch, args=(read_fd,), daemon=True)
        self._watcher.start()
        self._saved = (previous_handler, previous_fd, read_fd, write_fd)
        return self

    def __exit__(self, *exc) -> None:
        previous_handler, previous_fd, read_fd, write_fd = self._saved
        signal.set_wakeup_fd(previous_fd)
        signal.signal(signal.SIGINT, previous_handler)
        os.close(write_fd)          # the watcher reads end-of-file and stops
        self._watcher.join(timeout=1.0)
        os.close(read_fd)

    def wrap(self, callback):
        """A progress callback that also answers "cancel" once Ctrl-C was pressed."""
        def progress(fraction: float, message: str) -> bool:
            answer = callback(fraction, message) if callback is not None else False
            return bool(answer) or self.requested
        return progress
