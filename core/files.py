"""Atomic file writes: a temporary name in the same folder, renamed into place (one file, or
a set of files that belong together)."""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from contextlib import ExitStack, contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path next to ``path`` (same extension); rename it into place on
    success, delete it on failure or cancel, so no half-written file ever has the real name."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix}",
                               dir=path.parent)
    os.close(fd)
    # mkstemp makes the file private (0600); give it the permissions a plain open() would.
    os.chmod(tmp, 0o666 & ~_umask())
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


@contextmanager
def atomic_paths(*paths: str | os.PathLike):
    """``atomic_path`` for a set of files that belong together: yield one temporary path per
    file; only once every one is written are they renamed into place, the last path named
    last (so a record naming the others goes last); on failure or cancel none is."""
    with ExitStack() as stack:
        # Exit order is the reverse of entry: enter the last path first, rename it last.
        temporaries = [stack.enter_context(atomic_path(path)) for path in reversed(paths)]
        yield temporaries[::-1]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


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


def check_output_path(path: str | os.PathLike, suffix: str) -> Path:
    """Check, before any work is done, that ``path`` can be written as a ``suffix`` file.

    Raises InputError (one line) when the name has another extension, names a folder, or
    its folder cannot be created or written. The folder itself is created at write time
    (:func:`atomic_path`), so nothing is left behind by a command that fails later.
    """
    from .errors import InputError

    path = Path(path)
    if path.is_dir():
        raise InputError(f"output {path} is a folder, not a file")
    if path.suffix.lower() != suffix.lower():
        raise InputError(f"output {path} must be a {suffix} file")
    folder = path.parent.absolute()
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise InputError(f"cannot write {path}: {folder} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {path}: folder {folder} is not writable")
    return path


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
