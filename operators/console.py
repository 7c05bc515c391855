"""Keep Blender's own console chatter out of the command line's output.

Blender's C code prints to file descriptors 1 and 2 ("Read blend: ...", render progress,
"Saved: ..."). The command line promises clean stdout (``--json``) and exactly one line on
stderr for bad input, so while a command runs those descriptors point at a log file and
Python's ``sys.stdout``/``sys.stderr`` keep the real terminal.
"""
from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager

from ..core import temporaries


@contextmanager
def blender_chatter_to_log(keep: bool = False):
    """Redirect fd 1 and 2 to a log file for the duration; yields the log's path.

    ``keep`` leaves the log on disk afterwards (``--verbose``), in the system's temporary
    folder rather than the command's own, which goes at its end; otherwise it is deleted.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    saved_out, saved_err = os.dup(1), os.dup(2)
    folder = temporaries.system_tempdir() if keep else None
    fd, log_path = tempfile.mkstemp(prefix="xsl-render-", suffix=".log", dir=folder)
    old_stdout, old_stderr = sys.stdout, sys.stderr
    try:
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        sys.stdout = os.fdopen(os.dup(saved_out), "w", buffering=1, encoding="utf-8")
        sys.stderr = os.fdopen(os.dup(saved_err), "w", buffering=1, encoding="utf-8")
        yield log_path
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
                stream.close()
            except OSError:
                pass
        sys.stdout, sys.stderr = old_stdout, old_stderr
        os.dup2(saved_out, 1)
        os.dup2(saved_err, 2)
        os.close(saved_out)
        os.close(saved_err)
        os.close(fd)
        if not keep:
            try:
                os.unlink(log_path)
            except OSError:
                pass
