"""Ctrl-C and SIGTERM on the command line, safe from the first instruction to the last.

Python's KeyboardInterrupt lands wherever the main thread is (inside ``import bpy`` it leaves
Blender half set up), and Blender's own handler only asks a render to stop. So the console
script's first instruction blocks both signals in the main thread before any other thread
exists; every later thread inherits the block, and one :class:`Watcher` thread takes them with
``sigwait``. While a command works it cancels at once: every temporary goes
(``core.temporaries.abort``), one line, exit 130 or 143; once the outputs are in place a signal
is ignored; a command that runs until stopped gets KeyboardInterrupt in its main thread instead
(:meth:`Watcher.interrupt_main_thread`)."""
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
