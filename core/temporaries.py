"""The temporary files and folders of this process, so that nothing is left behind whatever
stops the work.

Every output is written under a temporary name next to its real one and renamed into place
(``core.files``); each temporary, and each folder made for one, is recorded here. On an error
the writer removes its own; on Ctrl-C or SIGTERM the signal watcher calls :func:`abort` from
its thread, wherever the main thread is, which removes them all; a kill cannot be answered,
so temporary names carry their process id and a later run sweeps those of processes that are
gone (:func:`sweep`). Renames run under :func:`gate`, whose lock :func:`abort` takes too: a
cancel never lands between two renames of a set."""
from __future__ import annotations

import os
import re
import secrets
import shutil
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path

from .errors import Cancelled

#: What every temporary name holds: ``.<name>.<pid>-<token>.partial[<suffix>]``.
_TAG = re.compile(r"^\..*\.(?P<pid>\d+)-[0-9a-f]{8}\.partial(\.[^.]+)?\Z")
#: Prefix of this process's folder in the system's temporary folder (:func:`open_session`).
SESSION_PREFIX = "xsl-render-"
_SESSION = re.compile(rf"^{re.escape(SESSION_PREFIX)}(?P<pid>\d+)-[A-Za-z0-9_]+\Z")

_lock = threading.RLock()
_temporaries: dict[str, None] = {}     # paths (files or folders), in the order made
_made_folders: list[Path] = []
_swept: set[str] = set()
_state = {"aborted": False, "sealed": False, "cancel_requested": False, "session": None,
          "saved_tempdir": None}


#: The pid in a temporary's name is padded to this many digits (Linux's largest pid_max has
#: 7), so the name is as long in every process: whether an output's name leaves room for its
#: temporary, which the up-front checks ask, does not change with the pid. (Unpadded, a pid
#: of 3 digits after the counter wrapped let a name through that a 5-digit one refused.)
PID_DIGITS = 7


def temporary_name(path: str | os.PathLike) -> Path:
    """A hidden name next to ``path`` that says whose it is: ``.NAME.<pid>-<token>.partial`` plus
    ``path``'s extension (writers such as OpenImageIO pick the format from it)."""
    path = Path(path)
    return path.with_name(f".{path.stem}.{os.getpid():0{PID_DIGITS}d}-{secrets.token_hex(4)}"
                          f".partial{path.suffix}")


@contextmanager
def gate():
    """Held while outputs are renamed into place; raises Cancelled once :func:`abort` began
    or a cancel was asked for (:func:`request_cancel`)."""
    with _lock:
        if _state["aborted"] or _state["cancel_requested"]:
            raise Cancelled("cancelled")
        yield


def new_file(path: str | os.PathLike) -> Path:
    """Create an empty temporary file for ``path`` (whose folder exists) and record it."""
    with gate():
        tmp = temporary_name(path)
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        _temporaries[str(tmp)] = None
    return tmp


def new_folder(path: str | os.PathLike) -> Path:
    """Create an empty temporary folder for ``path`` (whose parent exists) and record it."""
    with gate():
        tmp = temporary_name(path)
        os.mkdir(tmp)
        _temporaries[str(tmp)] = None
    return tmp


def forget(path: str | os.PathLike) -> None:
    """``path`` is no longer a temporary (renamed into place, or removed)."""
    with _lock:
        _temporaries.pop(str(path), None)


def discard(path: str | os.PathLike) -> None:
    """Remove a temporary file or folder and forget it."""
    _remove(Path(path))
    forget(path)


def make_folders(folder: str | os.PathLike) -> list[Path]:
    """Create ``folder`` and its missing parents; returns the folders made, outermost first.

    They are recorded: :func:`abort` removes them again when they are still empty, and so
    should a writer that fails (:func:`remove_empty`)."""
    folder = Path(folder).absolute()
    missing = []
    while not folder.exists():
        missing.append(folder)
        if folder.parent == folder:
            break
        folder = folder.parent
    made = []
    with gate():
        for path in reversed(missing):
            try:
                os.mkdir(path)
            except FileExistsError:
                continue
            made.append(path)
            _made_folders.append(path)
    return made


def remove_empty(folders: list[Path]) -> None:
    """Remove the folders made by :func:`make_folders` that hold nothing, innermost first."""
    for folder in reversed(folders):
        try:
            os.rmdir(folder)
        except OSError:
            pass


def probe(folder: str | os.PathLike) -> None:
    """Raise OSError unless a file can be created in the existing ``folder`` (made and removed
    at once: permissions, read-only mounts, /proc and the like say no here, root or not)."""
    tmp = new_file(Path(folder) / "xsl-probe")
    discard(tmp)


def seal() -> None:
    """The command's outputs are all in place: a cancel from now on comes too late to undo them
    (:func:`abort` then answers False and the command ends as it would have)."""
    with _lock:
        _state["sealed"] = True


def request_cancel() -> bool:
    """Ctrl-C where the process must not end at once (Blender's batch entry): from now on no
    output goes into place (:func:`gate` raises Cancelled), so a cancel once announced is the
    command's end whatever it was doing; False, and nothing changed, once :func:`seal` was
    called (the outputs are in place already)."""
    with _lock:
        if _state["sealed"]:
            return False
        _state["cancel_requested"] = True
        return True


def cancel_requested() -> bool:
    """Whether :func:`request_cancel` was called for the current command."""
    return _state["cancel_requested"]


def new_command() -> None:
    """A command starts in a process that runs several (Blender's batch entry): nothing of it
    is sealed or cancelled yet."""
    with _lock:
        _state["sealed"] = _state["cancel_requested"] = False


def abort(decided=None) -> bool:
    """Remove every temporary of this process, and every folder made for one that is empty;
    False (and nothing done) once :func:`seal` was called. ``decided``, if given, is called
    once the cancel is certain, before anything is removed.

    Called by the signal watcher just before the process ends: the gate's lock is kept, so
    neither a rename into place nor a new temporary can follow."""
    _lock.acquire()
    if _state["sealed"]:
        _lock.release()
        return False
    _state["aborted"] = True
    if decided is not None:
        decided()
    for name in reversed(list(_temporaries)):
        _remove_while_written(Path(name))
    _temporaries.clear()
    remove_empty(_made_folders)
    return True


def _remove_while_written(path: Path, passes: int = 20) -> None:
    """Remove ``path`` while the rest of the process may still write in it: the main thread
    and Blender's C code do not stop for the watcher (each of its system calls lets them run),
    and they make folders of their own outside the gate, in the session folder (Blender's
    ``blender_*`` at the end of ``import bpy``, the renders' ``tempfile.mkdtemp``). What
    appears after ``rmtree`` listed a folder makes that folder's removal fail, silently: again
    until it is gone (once it is, what they make by a path inside it fails)."""
    for _ in range(passes):
        _remove(path)
        if not os.path.lexists(path):
            return


def _remove(path: Path) -> None:
    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink()
    except FileNotFoundError:
        pass
    except OSError:
        pass


# -- what earlier runs left behind ------------------------------------------------------------
def process_alive(pid: int) -> bool:
    """True unless process ``pid`` is certainly gone (where we cannot tell: True)."""
    if os.name != "posix":
        return True                     # os.kill(pid, 0) would send Ctrl-C on Windows
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True                     # another user's process: alive
    return True


def sweep(folder: str | os.PathLike) -> list[Path]:
    """Remove the temporaries that killed runs left in ``folder`` (names of :func:`temporary_name`
    whose process is gone); each folder is looked at once per process. Returns what went."""
    key = str(Path(folder).absolute())
    with _lock:
        if key in _swept:
            return []
        _swept.add(key)
    return _sweep(Path(folder), _TAG)


def _sweep(folder: Path, pattern: re.Pattern) -> list[Path]:
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        match = pattern.match(entry.name)
        if match and not process_alive(int(match.group("pid"))):
            _remove(Path(entry.path))
            removed.append(Path(entry.path))
    return removed


# -- the command line's own temporary folder --------------------------------------------------
def open_session() -> Path:
    """Make this process's folder in the system's temporary folder and send every temporary
    file there: Python's ``tempfile`` and, through TMPDIR, Blender (its session folder), so
    that one removal clears everything. Folders of earlier runs that were killed are removed
    first. For the command line only: it changes the process's environment."""
    # The signal watcher already runs: under the lock that :func:`abort` takes, a cancel waits
    # until the folder is recorded (and then removes it); so does gettempdir's probe file, the
    # first thing made, on the first call.
    with _lock:
        base = Path(tempfile.gettempdir())
    _sweep(base, _SESSION)
    with _lock:
        folder = Path(tempfile.mkdtemp(prefix=f"{SESSION_PREFIX}{os.getpid()}-", dir=base))
        _temporaries[str(folder)] = None
        _state["session"] = folder
        _state["saved_tempdir"] = (tempfile.tempdir, {name: os.environ.get(name)
                                                      for name in ("TMPDIR", "TEMP", "TMP")})
    tempfile.tempdir = str(folder)
    for name in ("TMPDIR", "TEMP", "TMP"):
        os.environ[name] = str(folder)
    return folder


def system_tempdir() -> Path:
    """The system's temporary folder, outside this process's session folder."""
    session = _state["session"]
    return Path(session).parent if session is not None else Path(tempfile.gettempdir())


def close_session() -> None:
    """Remove the session folder and give the environment back (end of the command line)."""
    folder = _state["session"]
    if folder is None:
        return
    tempdir, environ = _state["saved_tempdir"]
    tempfile.tempdir = tempdir
    for name, value in environ.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value
    discard(folder)
    _state["session"] = None
