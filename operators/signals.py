"""Ctrl-C and SIGTERM on the command line, safe from the first instruction to the last.

Python turns Ctrl-C into KeyboardInterrupt wherever the main thread happens to be: inside
``import bpy`` that leaves Blender half set up (tracebacks, then a segmentation fault); and
once Blender is up, its own handler takes SIGINT over and only asks the render to stop,
which our code never hears. So the console script's first instruction (``entry.py``) blocks
both signals in the main thread, before any other thread exists: every thread started later
(Blender's, Cycles', numpy's) inherits the block, no handler ever runs, and the signal waits
for the one thread that asks for it with ``sigwait``, the :class:`Watcher`:

- while a command works, the watcher cancels it at once: every temporary file and folder
  goes (``core.temporaries.abort``, which waits for a set of renames under way to finish, so
  an output set is whole or absent), one line goes to stderr, and the process ends with 130
  (SIGINT) or 143 (SIGTERM) — from another thread, so it does not matter what the main
  thread is doing, in Python or in C;
- once the command's outputs are in place (``temporaries.seal``) a signal comes too late
  and is ignored: the command ends as it would have;
- a command that runs until stopped (``experiment-serve``) asks for
  :meth:`Watcher.interrupt_main_thread`: the signal becomes KeyboardInterrupt in its main
  thread, it shuts down cleanly, and the command line ends with 130 or 143 all the same
  (:attr:`Watcher.received`). Python's own SIGINT handler is put in place for that, whatever
  the process inherited: a background job of a shell script starts with SIGINT ignored, and
  ``_thread.interrupt_main`` does nothing then.

The watcher needs the GIL to act: while Blender holds it the cancel waits, but it always
comes, and nothing is written meanwhile. While Blender starts (``import bpy``, about half a
second) it waits for the start to end (``entry.py``): Blender makes its own temporary folder
then. The main thread goes on while the temporaries go: what it says from the decision on
goes nowhere, so the cancel's line is the only one.
"""
from __future__ import annotations

import _thread
import os
import signal
import sys
import threading

from ..core import temporaries

SIGNALS = (signal.SIGINT, signal.SIGTERM)
EXIT_CODES = {signal.SIGINT: 130, signal.SIGTERM: 143}


class Watcher:
    """The thread that takes SIGINT and SIGTERM (blocked everywhere else) and acts on them."""

    def __init__(self):
        self.interrupt_main = False
        self.received: int | None = None   # the signal that stopped an interruptible command
        self._stderr = os.dup(2)            # the terminal's, whatever fd 2 points at later
        self._thread = threading.Thread(target=self._run, name="xsl-render signals", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            signum = signal.sigwait(SIGNALS)
            if self.interrupt_main:
                self.received = signum
                _thread.interrupt_main()
                continue
            self.cancel(signum)

    def interrupt_main_thread(self) -> None:
        """From now on a signal raises KeyboardInterrupt in the main thread (call it there):
        Python's SIGINT handler goes in, whatever was inherited, since ``interrupt_main``
        acts only through it. The signals stay blocked in this thread: the handler runs
        only for ``interrupt_main``."""
        signal.signal(signal.SIGINT, signal.default_int_handler)
        self.interrupt_main = True

    def cancel(self, signum: int) -> None:
        """Remove every temporary and end the process, unless the outputs are in place."""
        if not temporaries.abort(decided=self._mute):
            return
        newline = "\n" if _is_terminal(self._stderr) else ""    # after a progress bar's \r
        os.write(self._stderr, f"{newline}xsl-render: cancelled\n".encode())
        os._exit(EXIT_CODES.get(signum, 130))

    def _mute(self) -> None:
        """The main thread goes on while the temporaries go, and may fail on one that vanished
        and say so: once the cancel is decided, the process's output goes nowhere (Python's
        streams and fds 1 and 2); the cancel's own line goes to the terminal's copy."""
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
        except OSError:
            return                          # never stop the cancel itself
        fds = {1, 2}
        for stream in (sys.stdout, sys.stderr):
            try:
                fds.add(stream.fileno())
            except (AttributeError, OSError, ValueError):
                pass
        for fd in fds - {self._stderr}:
            try:
                os.dup2(devnull, fd)
            except OSError:
                pass


def _is_terminal(fd: int) -> bool:
    try:
        return os.isatty(fd)
    except OSError:
        return False


def start() -> Watcher | None:
    """Start the watcher once the signals are blocked (``entry.py``); None where signals
    cannot be blocked (Windows: Ctrl-C stays Python's KeyboardInterrupt there)."""
    if not hasattr(signal, "pthread_sigmask"):
        return None
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    if not set(SIGNALS) <= blocked:
        raise RuntimeError("SIGINT and SIGTERM must be blocked before the watcher starts")
    return Watcher()
