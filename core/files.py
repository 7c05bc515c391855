"""Atomic file writes: a temporary name in the same folder, renamed into place; and sets of
files that appear together or not at all."""
from __future__ import annotations

import hashlib
import json
import os
from contextlib import ExitStack, contextmanager
from pathlib import Path

from . import temporaries
from .errors import InputError


def write_error(path: str | os.PathLike, error: OSError) -> InputError:
    """A failed write (disk full, no permission, a name too long) as one line naming the file
    and the reason: the user's to fix, exit code 2, not a bug of ours."""
    reason = (error.strerror or str(error)).lower()
    return InputError(f"cannot write {path}: {reason}")


class _OutputSet:
    """Files written (``atomic_path``) while the set is open: renamed into place together."""

    def __init__(self):
        self.staged: dict[Path, Path] = {}      # real path -> its temporary
        self.made: list[Path] = []              # folders made for them

    def stage(self, tmp: Path, path: Path) -> None:
        earlier = self.staged.pop(path, None)
        if earlier is not None:                 # written twice: the last one counts
            temporaries.discard(earlier)
        self.staged[path] = tmp

    def commit(self, seal: bool) -> None:
        with temporaries.gate():
            for path in self.staged:
                if path.is_dir():       # checked before any rename: the set stays whole
                    raise InputError(f"cannot write {path}: a folder has that name")
            for path, tmp in self.staged.items():
                try:
                    os.replace(tmp, path)
                except OSError as error:
                    raise write_error(path, error) from None
                temporaries.forget(tmp)
            if seal:
                temporaries.seal()

    def discard(self) -> None:
        for tmp in self.staged.values():
            temporaries.discard(tmp)
        temporaries.remove_empty(self.made)


_open_sets: list[_OutputSet] = []


@contextmanager
def output_set(seal: bool = False, own: bool = False):
    """Every file written through :func:`atomic_path` inside the block appears when the block
    ends without an error, all at once (one rename each, under ``temporaries.gate``), or not
    at all. A block inside another one joins it, unless ``own``: then its files appear at its
    own end (finished work that outlives the command, such as a cache entry). ``seal``: these
    are the command's last outputs, so a cancel after them is too late (``temporaries.seal``)."""
    if _open_sets and not own:
        yield
        return
    current = _OutputSet()
    _open_sets.append(current)
    try:
        yield
    except BaseException:
        _open_sets.pop()
        current.discard()
        raise
    _open_sets.pop()
    try:
        current.commit(seal)
    except BaseException:
        current.discard()
        raise


@contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path next to ``path`` (same extension); rename it into place on
    success (at the end of the enclosing :func:`output_set`, if any), delete it on failure or
    cancel, so no half-written file ever has the real name. An OSError while the file is
    made, written or renamed (disk full, no permission) becomes an InputError naming ``path``
    and the reason (:func:`write_error`)."""
    path = Path(path)
    try:
        made = temporaries.make_folders(path.parent)
        temporaries.sweep(path.parent)
        tmp = temporaries.new_file(path)  # mode 0o666 under the umask, as open() makes it
    except OSError as error:
        raise write_error(path, error) from None
    try:
        yield tmp
    except BaseException as error:
        temporaries.discard(tmp)
        if _open_sets:
            _open_sets[-1].made += made
        else:
            temporaries.remove_empty(made)
        if isinstance(error, OSError):
            raise write_error(path, error) from None
        raise
    if _open_sets:
        _open_sets[-1].made += made
        _open_sets[-1].stage(tmp, path)
        return
    try:
        with temporaries.gate():
            os.replace(tmp, path)
            temporaries.forget(tmp)
    except BaseException as error:
        temporaries.discard(tmp)
        temporaries.remove_empty(made)
        if isinstance(error, OSError):
            raise write_error(path, error) from None
        raise


@contextmanager
def atomic_paths(*paths: str | os.PathLike):
    """``atomic_path`` for a set of files that belong together: yield one temporary path per
    file, each written in place (``atomic=False``); once every one is written they are renamed
    into place as a set of their own (:func:`output_set`), the last path named last (so a
    record naming the others goes last); on failure or cancel none is. Their own, even inside
    a command's set: what uses this (a cache entry, a farm frame) is read back by the same
    command, and a later run reuses it."""
    with output_set(own=True), ExitStack() as stack:
        # Exits run in reverse order of entry: entering the last path first stages it last,
        # and a set renames in the order its files were staged.
        names = [stack.enter_context(atomic_path(path)) for path in reversed(paths)]
        yield names[::-1]


def write_text(path: str | os.PathLike, text: str, atomic: bool = True) -> Path:
    """Write ``text`` as UTF-8, atomically unless ``path`` is already a temporary
    (``atomic_paths``)."""
    if not atomic:
        Path(path).write_text(text, encoding="utf-8")
        return Path(path)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path: str | os.PathLike, data, atomic: bool = True) -> Path:
    return write_text(path, json.dumps(data, indent=2) + "\n", atomic)


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def json_digest(data) -> str:
    """SHA-256 of ``data`` as canonical JSON (sorted keys, no spaces, no NaN)."""
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def file_identity(path: str | os.PathLike) -> list:
    """[path, size, modification time in ns] of a file, what a rerun compares to tell whether
    an input changed (a file put back by a move keeps all three); [path, None, None] for one
    that does not exist."""
    try:
        status = os.stat(path)
    except OSError:
        return [str(path), None, None]
    return [str(path), status.st_size, status.st_mtime_ns]
