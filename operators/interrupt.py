"""Ctrl-C where Blender owns the process (``blender -b ... x.batch()``).

Blender renders in C and catches a KeyboardInterrupt raised in its Python callbacks, so the
batch entry watches SIGINT through Python's wakeup file descriptor from a helper thread: before
the command's work begins, Ctrl-C ends it with 130 and "cancelled"; while it works, the first
says "cancelling after the current render" and the work stops at the next safe point with
nothing more written and the scene restored (unless its outputs were already in place); a
second exits at once. The ``xsl-render`` console script blocks SIGINT from its first
instruction instead (``signals.py``), so there this context never sees a signal."""
from __future__ import annotations

import os
import signal
import sys
import threading

from ..core import temporaries


class InterruptToCancel:
    """Context manager (main thread only): Ctrl-C sets ``requested``; twice: exit 130 now.

    ``before_work``: the work has not begun (the batch entry): a Ctrl-C is a cancel without
    an announcement until ``begin_work``, which answers whether the work may begin."""

    _active: "InterruptToCancel | None" = None          # the open one, for nested commands

    def __init__(self, before_work: bool = False):
        self.requested = False
        self._working = not before_work
        self._lock = threading.Lock()
        self._saved = None
        self._watcher = None
        self._nested = False

    def _watch(self, read_fd: int) -> None:
        while True:
            try:
                data = os.read(read_fd, 64)
            except OSError:
                return
            if not data:
                return
            for signum in data:
                if signum == signal.SIGINT:
                    self._interrupted()

    def _interrupted(self) -> None:
        with self._lock:
            if not self._working:
                self.requested = True       # ``begin_work`` answers it: nothing was done
                return
            if self.requested:
                os._exit(130)
            if not temporaries.request_cancel():
                return                      # the outputs are in place: too late to undo them
            self.requested = True
            print("\nxsl-render: cancelling after the current render (Ctrl-C again to stop at once)",
                  file=sys.stderr, flush=True)

    def begin_work(self) -> bool:
        """The work begins (announced cancels from now on); False: a Ctrl-C came before."""
        with self._lock:
            self._working = not self.requested
            return self._working

    def __enter__(self) -> "InterruptToCancel":
        if InterruptToCancel._active is not None:
            self._nested = True
            return InterruptToCancel._active
        temporaries.new_command()
        read_fd, write_fd = os.pipe()
        os.set_blocking(write_fd, False)
        self._watcher = threading.Thread(target=self._watch, args=(read_fd,), daemon=True)
        self._watcher.start()
        # The descriptor first: a signal that comes while the handler changes is written to
        # it either way. A Python-level handler must be installed for the C handler to write
        # the descriptor; it does nothing itself (the watcher thread has already acted).
        previous_fd = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
        previous_handler = signal.signal(signal.SIGINT, lambda signum, frame: None)
        self._saved = (previous_handler, previous_fd, read_fd, write_fd)
        InterruptToCancel._active = self
        return self

    def __exit__(self, *exc) -> None:
        if self._nested:
            return
        InterruptToCancel._active = None
        previous_handler, previous_fd, read_fd, write_fd = self._saved
        # (None: a handler not set from Python, which cannot be put back: Python's own.)
        signal.signal(signal.SIGINT, previous_handler if previous_handler is not None
                      else signal.default_int_handler)
        signal.set_wakeup_fd(previous_fd)
        os.close(write_fd)          # the watcher reads end-of-file and stops
        self._watcher.join(timeout=1.0)
        os.close(read_fd)
        temporaries.new_command()

    def wrap(self, callback):
        """A progress callback that also answers "cancel" once Ctrl-C was pressed."""
        def progress(fraction: float, message: str) -> bool:
            answer = callback(fraction, message) if callback is not None else False
            return bool(answer) or self.requested
        return progress
