"""What a user hands a command, checked before any work: numbers, sizes Blender can make,
files to read and places to write.

Every check raises InputError with one line that names the problem, and never writes
anything that outlasts it. ``name`` (an option such as ``--max-spp``) starts the message;
without it the message starts with "must" or names the path, for the command line's
argument converters (``operators/commands/argtypes.py``), which put ``argument --max-spp:``
in front themselves.

Blender's limits are copied here so that the checks run without loading Blender;
``tests/test_checks.py`` compares them with Blender's own property ranges.
"""
from __future__ import annotations

import math
import operator
import os
from pathlib import Path

from . import temporaries
from .errors import InputError

INT32_MIN, INT32_MAX = -2**31, 2**31 - 1
#: ``scene.cycles.samples``: at most 2^24 samples per pixel.
MAX_SAMPLES = 16_777_216
#: ``scene.cycles.seed``.
MAX_SEED = INT32_MAX
#: ``scene.frame_current`` (Blender's MINAFRAME and MAXFRAME).
MIN_FRAME, MAX_FRAME = -1_048_574, 1_048_574
#: ``scene.render.resolution_x`` and ``resolution_y``: Blender renders at least 4x4.
MIN_SIDE, MAX_SIDE = 4, 65_536
#: A frame costs at least this much memory per pixel: Cycles' render buffers (colour, albedo,
#: normal, samples), the composited image, the maps, the camera rays (float64) and the
#: saliency pyramids. Only a floor, for refusing sizes that cannot fit up front.
BYTES_PER_PIXEL = 256


def _say(name: str | None, text: str) -> str:
    return f"{name} {text}" if name else text


def _from_text(value, parse, name: str | None, what: str):
    """``value`` parsed when it is text; a bool is refused (Python counts it as a number)."""
    if isinstance(value, bool):
        raise InputError(_say(name, f"must be {what}, not {value}"))
    if not isinstance(value, str):
        return value
    try:
        return parse(value.strip())
    except ValueError:
        raise InputError(_say(name, f"must be {what}, not '{value}'")) from None


def whole_number(value, lo: int = INT32_MIN, hi: int = INT32_MAX, name: str | None = None,
                 limit: str = "") -> int:
    """``value`` (an int, or text) as an int in [lo, hi]. ``limit`` says whose range it is."""
    value = _from_text(value, int, name, "a whole number")
    try:
        value = operator.index(value)       # int, numpy integers
    except TypeError:
        raise InputError(_say(name, f"must be a whole number, not {value!r}")) from None
    if not lo <= value <= hi:
        raise InputError(_say(name, f"must be a whole number from {lo} to {hi}{limit}, not {value}"))
    return value


def finite_number(value, lo: float | None = None, hi: float | None = None, *,
                  above: float | None = None, below: float | None = None,
                  name: str | None = None) -> float:
    """``value`` (a number, or text) as a finite float; ``lo``/``hi`` bound it inclusively,
    ``above``/``below`` exclusively."""
    value = _from_text(value, float, name, "a number")
    try:
        value = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(_say(name, f"must be a finite number, not {value!r}")) from None
    if not math.isfinite(value):
        raise InputError(_say(name, f"must be a finite number, not {value}"))
    if lo is not None and value < lo:
        raise InputError(_say(name, f"must be at least {lo:g}, not {value:g}"))
    if hi is not None and value > hi:
        raise InputError(_say(name, f"must be at most {hi:g}, not {value:g}"))
    if above is not None and not value > above:
        raise InputError(_say(name, f"must be greater than {above:g}, not {value:g}"))
    if below is not None and not value < below:
        raise InputError(_say(name, f"must be less than {below:g}, not {value:g}"))
    return value


def physical_memory() -> int | None:
    """Bytes of RAM in this machine (None where the system does not say)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def _bytes(count: float) -> str:
    for unit in ("bytes", "KB", "MB", "GB", "TB"):
        if count < 1000 or unit == "TB":
            return f"{count:.0f} {unit}" if unit == "bytes" else f"{count:.1f} {unit}"
        count /= 1000
    return ""


def frame_size(width: int, height: int, name: str | None = "--resolution") -> tuple[int, int]:
    """(width, height) if Blender can render a frame of that size here: each side 4 to 65536
    pixels (Blender's limits; it would silently render 1x1 as 4x4) and the frame small enough
    for this machine's memory (:data:`BYTES_PER_PIXEL`)."""
    for side in (width, height):
        if not MIN_SIDE <= side <= MAX_SIDE:
            raise InputError(_say(name, f"{width}x{height}: each side must be {MIN_SIDE} to "
                                        f"{MAX_SIDE} pixels (Blender's limits)"))
    return fits_in_memory(width, height, name)


def fits_in_memory(width: int, height: int, name: str | None = "--resolution") -> tuple[int, int]:
    """(width, height) unless a frame that size cannot fit in this machine's memory."""
    memory = physical_memory()
    needed = width * height * BYTES_PER_PIXEL
    if memory is not None and needed > memory:
        raise InputError(_say(name, f"{width}x{height} needs at least {_bytes(needed)} of memory; "
                                    f"this machine has {_bytes(memory)}"))
    return width, height


def parse_frame_size(text: str, name: str | None = "--resolution") -> tuple[int, int]:
    """'512x288' -> (512, 288), checked as :func:`frame_size`."""
    parts = str(text).strip().lower().split("x")
    try:
        width, height = (int(part) for part in parts)
    except ValueError:
        raise InputError(_say(name, f"must look like 512x288, not '{text}'")) from None
    return frame_size(width, height, name)


def name_list(text: str, name: str, choices=None, what: str = "name") -> tuple[str, ...]:
    """'a, b,' -> ('a', 'b'): the names of a comma-separated option (``--scenes``,
    ``--variants``, ``--curves``). Blanks around names and empty items go, so a trailing comma
    is harmless; nothing left is an InputError, and so is a name not among ``choices``."""
    items = tuple(item.strip() for item in str(text).split(",") if item.strip())
    if not items:
        raise InputError(f"{name} is empty")
    for item in items:
        if choices is not None and item not in choices:
            raise InputError(f"{name}: unknown {what} '{item}' (choose from {', '.join(choices)})")
    return items


# -- files ------------------------------------------------------------------------------------
def _reason(error: OSError) -> str:
    return (error.strerror or str(error)).lower()


def readable_file(path, suffixes: tuple[str, ...] = (), name: str | None = None,
                  what: str = "file") -> Path:
    """``path`` if it is an existing file we may read (and has one of ``suffixes``); ``what``
    names it in the message ("no such director map: m.exr")."""
    path = Path(path)
    if not path.exists():
        raise InputError(_say(name, f"no such {what}: {path}"))
    if path.is_dir():
        raise InputError(_say(name, f"{path} is a folder, not a file"))
    if suffixes and path.suffix.lower() not in suffixes:
        raise InputError(_say(name, f"{path} must be a {' or '.join(suffixes)} file"))
    try:
        with open(path, "rb"):
            pass
    except OSError as error:
        raise InputError(_say(name, f"cannot read {path}: {_reason(error)}")) from None
    return path


def readable_folder(path, name: str | None = None, what: str = "folder") -> Path:
    """``path`` if it is an existing folder whose contents we may list."""
    path = Path(path)
    if not path.exists():
        raise InputError(_say(name, f"no such {what}: {path}"))
    if not path.is_dir():
        raise InputError(_say(name, f"{path} is a file, not a folder"))
    try:
        with os.scandir(path) as entries:
            next(entries, None)
    except OSError as error:
        raise InputError(_say(name, f"cannot read {path}: {_reason(error)}")) from None
    return path


def _writable_place(folder: Path, target: Path, name: str | None) -> None:
    """InputError unless ``folder`` exists as a writable folder or can be made in one."""
    existing = folder.absolute()
    while not os.path.lexists(existing) and existing.parent != existing:
        existing = existing.parent
    if not existing.is_dir():
        raise InputError(_say(name, f"cannot write {target}: {existing} is not a folder"))
    try:
        temporaries.probe(existing)
    except OSError as error:
        raise InputError(_say(name, f"cannot write {target}: {existing}: {_reason(error)}")) from None


def writable_file(path, suffixes: tuple[str, ...] = (), name: str | None = None) -> Path:
    """``path`` if a file of one of ``suffixes`` may be written there: not a folder or a
    device, in a folder that exists and takes new files, or can be made where one does."""
    path = Path(path)
    if path.is_dir():
        raise InputError(_say(name, f"{path} is a folder, not a file"))
    if suffixes and path.suffix.lower() not in suffixes:
        raise InputError(_say(name, f"{path} must be a {' or '.join(suffixes)} file"))
    if path.exists() and not path.is_file():
        raise InputError(_say(name, f"{path} exists and is not a regular file"))
    _writable_place(path.parent, path, name)
    return path


def writable_folder(path, name: str | None = None) -> Path:
    """``path`` if it is a folder that takes new files, or can be made where one is."""
    path = Path(path)
    if os.path.lexists(path) and not path.is_dir():
        raise InputError(_say(name, f"{path} is a file, not a folder"))
    _writable_place(path, path, name)
    return path


def distinct_outputs(paths: dict[str, str | os.PathLike | None]) -> None:
    """InputError when two of a command's outputs (label -> path; None: not written) are one
    file, or when one of them is an existing folder: a set of files must be written whole."""
    seen: dict[str, str] = {}
    for label, path in paths.items():
        if path is None:
            continue
        if Path(path).is_dir():
            raise InputError(f"{label} {path} is a folder, not a file")
        key = os.path.normcase(os.path.realpath(path))
        if key in seen:
            raise InputError(f"{seen[key]} and {label} name the same file: {path}")
        seen[key] = label
