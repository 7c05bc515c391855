"""What a user hands a command, checked before any work: numbers, sizes Blender can make,
files to read and places to write.

Every check raises InputError with one line naming the problem and writes nothing that
outlasts it. ``name`` starts the message; a ``Field`` (a setting's field name) makes a number
or size check raise a SettingError naming that setting, which each front end words its own
way. Without a name the message starts with "must", for the command line's argument types,
which put ``argument --max-spp:`` in front. Blender's limits are copied here so the checks
run without Blender; ``tests/test_checks.py`` compares them with Blender's own ranges."""
from __future__ import annotations

import math
import operator
import os
import stat
from pathlib import Path

from . import temporaries
from .errors import Field, InputError, SettingError, setting_refused, verbatim

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


def _refused(name: str | None, value, text: str) -> InputError:
    """The error of a value refused with ``text``: naming the setting when ``name`` is a
    ``Field``, else as :func:`_say` words it."""
    if isinstance(name, Field):
        return setting_refused(name, value, text)
    return InputError(_say(name, text))


def _from_text(value, parse, name: str | None, what: str):
    """``value`` parsed when it is text (ASCII only: Python would read other scripts' digits,
    ``١``, as numbers no one else takes); a bool is refused (Python counts it as a number)."""
    if isinstance(value, bool):
        raise _refused(name, value, f"must be {what}, not {value}")
    if not isinstance(value, str):
        return value
    try:
        if not value.isascii():
            raise ValueError(value)
        return parse(value.strip())
    except ValueError:
        raise _refused(name, value, f"must be {what}, not '{value}'") from None


def whole_number(value, lo: int = INT32_MIN, hi: int = INT32_MAX, name: str | None = None,
                 limit: str = "") -> int:
    """``value`` (an int, or text) as an int in [lo, hi]. ``limit`` says whose range it is."""
    value = _from_text(value, int, name, "a whole number")
    try:
        value = operator.index(value)       # int, numpy integers
    except TypeError:
        raise _refused(name, value, f"must be a whole number, not {value!r}") from None
    if not lo <= value <= hi:
        raise _refused(name, value, f"must be a whole number from {lo} to {hi}{limit}, not {value}")
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
        raise _refused(name, value, f"must be a finite number, not {value!r}") from None
    if not math.isfinite(value):
        raise _refused(name, value, f"must be a finite number, not {value}")
    if lo is not None and value < lo:
        raise _refused(name, value, f"must be at least {lo:g}, not {value:g}")
    if hi is not None and value > hi:
        raise _refused(name, value, f"must be at most {hi:g}, not {value:g}")
    if above is not None and not value > above:
        raise _refused(name, value, f"must be greater than {above:g}, not {value:g}")
    if below is not None and not value < below:
        raise _refused(name, value, f"must be less than {below:g}, not {value:g}")
    return value


def physical_memory() -> int | None:
    """Bytes of RAM in this machine (None where the system does not say)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def available_memory() -> int | None:
    """Bytes of RAM free now (None where the system does not say)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def process_memory() -> int | None:
    """Bytes this process holds in RAM now (None where the system does not say: Linux's
    /proc only)."""
    try:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError, AttributeError):
        return None


def _bytes(count: float) -> str:
    for unit in ("bytes", "KB", "MB", "GB", "TB"):
        if count < 1000 or unit == "TB":
            return f"{count:.0f} {unit}" if unit == "bytes" else f"{count:.1f} {unit}"
        count /= 1000
    return ""


def frame_size(width: int, height: int, name: str | None = Field("resolution")) -> tuple[int, int]:
    """(width, height) if Blender can render a frame of that size here: each side 4 to 65536
    pixels (Blender's limits; it would silently render 1x1 as 4x4) and the frame small enough
    for this machine's memory (:data:`BYTES_PER_PIXEL`)."""
    for side in (width, height):
        if not MIN_SIDE <= side <= MAX_SIDE:
            raise _refused(name, f"{width}x{height}", f"{width}x{height}: each side must be "
                                                      f"{MIN_SIDE} to {MAX_SIDE} pixels (Blender's limits)")
    return fits_in_memory(width, height, name)


def fits_in_memory(width: int, height: int, name: str | None = Field("resolution")) -> tuple[int, int]:
    """(width, height) unless a frame that size cannot fit in this machine's memory."""
    memory = physical_memory()
    needed = width * height * BYTES_PER_PIXEL
    if memory is not None and needed > memory:
        raise _refused(name, f"{width}x{height}", f"{width}x{height} needs at least {_bytes(needed)} "
                                                  f"of memory; this machine has {_bytes(memory)}")
    return width, height


def parse_frame_size(text: str, name: str | None = Field("resolution")) -> tuple[int, int]:
    """'512x288' -> (512, 288), checked as :func:`frame_size`."""
    parts = str(text).strip().lower().split("x")
    try:
        width, height = (int(part) for part in parts)
    except ValueError:
        raise _refused(name, text, f"must look like 512x288, not '{text}'") from None
    return frame_size(width, height, name)


def name_list(text: str, name: str, choices=None, what: str = "name") -> tuple[str, ...]:
    """'a, b,' -> ('a', 'b'): the names of a comma-separated option (``--scenes``,
    ``--variants``, ``--curves``). Blanks around names and empty items go, so a trailing comma
    is harmless; nothing left is an InputError, and so is a name not among ``choices``.
    ``name``: the option's name, or its ``Field``."""
    items = tuple(item.strip() for item in str(text).split(",") if item.strip())
    if not items:
        raise _refused(name, text, "is empty")
    for item in items:
        if choices is not None and item not in choices:
            unknown = f"unknown {what} '{item}' (choose from {', '.join(choices)})"
            if isinstance(name, Field):
                raise SettingError(f"{{{name}.name}}: {verbatim(unknown)}", **{name: text})
            raise InputError(f"{name}: {unknown}")
    return items


# -- files ------------------------------------------------------------------------------------
#: Where the system does not say (``os.pathconf``): Linux's and macOS's limits.
DEFAULT_NAME_MAX, DEFAULT_PATH_MAX = 255, 4096


def _reason(error: OSError) -> str:
    return (error.strerror or str(error)).lower()


def _short(text: str) -> str:
    """A name shortened for a one-line message (a 300-byte name would fill the line)."""
    return text if len(text) <= 60 else f"{text[:28]}...{text[-28:]}"


def _limits(path: str) -> tuple[int, int]:
    """(NAME_MAX, PATH_MAX) of the file system ``path`` is on, asked of the nearest folder
    that exists (the one a new file lands in); ``os.pathconf`` says -1 for no limit."""
    folder = os.path.dirname(path)
    while True:
        try:
            name_max = os.pathconf(folder, "PC_NAME_MAX")
            path_max = os.pathconf(folder, "PC_PATH_MAX")
            break
        except (OSError, ValueError):
            parent = os.path.dirname(folder)
            if parent == folder:
                return DEFAULT_NAME_MAX, DEFAULT_PATH_MAX
            folder = parent
        except AttributeError:          # no pathconf (Windows)
            return DEFAULT_NAME_MAX, DEFAULT_PATH_MAX
    unlimited = 1 << 62
    return (name_max if name_max > 0 else unlimited), (path_max if path_max > 0 else unlimited)


def name_fits(path, name: str | None = None, written_as: str | os.PathLike | None = None) -> Path:
    """``path`` if the system can hold its name: no part longer than the file system's
    NAME_MAX bytes (usually 255), the whole absolute path shorter than PATH_MAX. Checked
    before anything else touches the path: past these limits every call fails with "File
    name too long". ``written_as``: the temporary name an output is written under first
    (``core.temporaries.temporary_name``), which must fit too."""
    path = Path(path)
    _name_within(path, name, _limits(os.path.abspath(path)), written_as)
    return path


def _name_within(path: Path, name: str | None, limits: tuple[int, int],
                 written_as: str | os.PathLike | None = None) -> None:
    name_max, path_max = limits
    absolute = os.fsencode(os.path.abspath(path))
    if len(absolute) >= path_max:
        raise InputError(_say(name, f"path too long: {_short(str(path))} ({len(absolute)} bytes; "
                                    f"the system takes paths shorter than {path_max})"))
    longest = max(absolute.split(os.fsencode(os.sep)), key=len)
    if len(longest) > name_max:
        raise InputError(_say(name, f"file name too long: {_short(os.fsdecode(longest))} "
                                    f"({len(longest)} bytes; at most {name_max} here)"))
    if written_as is not None:
        size = len(os.fsencode(Path(written_as).name))
        if size > name_max:
            extra = size - len(os.fsencode(path.name))
            raise InputError(_say(name, f"file name too long: {_short(path.name)} (written first "
                                        f"under a temporary name {extra} bytes longer, {size}; at "
                                        f"most {name_max} here)"))


def _not_regular(mode: int) -> str | None:
    """What a file that is not a regular file or a folder is ("a FIFO"); None if it is one."""
    for test, what in ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device")):
        if test(mode):
            return what
    return None if stat.S_ISREG(mode) or stat.S_ISDIR(mode) else "not a regular file"


def _stat(path: Path, name: str | None, what: str) -> os.stat_result:
    """``os.stat(path)`` (symlinks followed), its errors as one line."""
    try:
        return os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        raise InputError(_say(name, f"no such {what}: {path}")) from None
    except OSError as error:
        raise InputError(_say(name, f"cannot read {path}: {_reason(error)}")) from None


def readable_file(path, suffixes: tuple[str, ...] = (), name: str | None = None,
                  what: str = "file") -> Path:
    """``path`` if it is an existing regular file we may read (and has one of ``suffixes``);
    ``what`` names it in the message ("no such director map: m.exr"). A FIFO, device or
    socket is refused without being opened: opening a FIFO waits for a writer, forever."""
    path = name_fits(path, name)
    mode = _stat(path, name, what).st_mode
    if stat.S_ISDIR(mode):
        raise InputError(_say(name, f"{path} is a folder, not a file"))
    kind = _not_regular(mode)
    if kind is not None:
        raise InputError(_say(name, f"{path} is {kind}, not a regular file"))
    if suffixes and path.suffix.lower() not in suffixes:
        raise InputError(_say(name, f"{path} must be a {' or '.join(suffixes)} file"))
    try:
        # O_NONBLOCK: should the file have become a FIFO since, the open still returns.
        os.close(os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)))
    except OSError as error:
        raise InputError(_say(name, f"cannot read {path}: {_reason(error)}")) from None
    return path


def readable_folder(path, name: str | None = None, what: str = "folder") -> Path:
    """``path`` if it is an existing folder whose contents we may list."""
    path = name_fits(path, name)
    mode = _stat(path, name, what).st_mode
    if not stat.S_ISDIR(mode):
        raise InputError(_say(name, f"{path} is {_not_regular(mode) or 'a file'}, not a folder"))
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
    """``path`` if a file of one of ``suffixes`` may be written there: a name the system can
    hold (with the temporary name it is written under first), not a folder or a device, in a
    folder that exists and takes new files, or can be made where one does."""
    path = name_fits(path, name, written_as=temporaries.temporary_name(path))
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
    path = name_fits(path, name)
    if os.path.lexists(path) and not path.is_dir():
        raise InputError(_say(name, f"{path} is a file, not a folder"))
    _writable_place(path, path, name)
    return path


class _Folder:
    """What :func:`separate_files` asks of a folder once, however many outputs it holds (an
    animation's frames): its absolute and real paths, its limits, the names in it (None where
    it cannot be listed) and how much longer than a file's name its temporary name is."""

    def __init__(self, folder: str, name: str):
        self.absolute = os.path.abspath(folder or os.curdir)
        self.real = os.path.normcase(os.path.realpath(self.absolute))
        self.absolute_size = len(os.fsencode(self.absolute))
        self.limits = _limits(os.path.join(self.absolute, name))
        try:
            with os.scandir(self.absolute) as entries:
                self.names = {entry.name for entry in entries}
        except OSError:
            self.names = None
        self.checked = False                # its own parts fit (the first file's whole check)
        # The same for every name (a fixed tag around it), measured on one.
        self.extra = len(os.fsencode(temporaries.temporary_name(os.path.join(folder, name)).name)) \
            - len(os.fsencode(name))

    def identities(self, path: str, name: str) -> tuple[list, os.stat_result | None]:
        """The keys under which ``path`` (a file in this folder) is the same file as another:
        its real path (folder and name) and, where it exists, its device and inode; and its
        ``os.stat``."""
        if self.names is not None and name not in self.names:
            return [("real", self.real, os.path.normcase(name))], None
        try:
            info = os.stat(path)
        except OSError:
            info = None
        folder, real_name = os.path.split(os.path.normcase(os.path.realpath(path)))
        keys = [("real", folder, real_name)]
        if info is not None:
            keys.append(("inode", info.st_dev, info.st_ino))
        return keys, info


def separate_files(inputs: dict[str, str | os.PathLike | None],
                   outputs: dict[str, str | os.PathLike | None]) -> None:
    """The one check of a command's files before any work (``operators/cli.py``), each given
    as label -> path (None: not used): every input that exists is a regular file (or a
    folder), never a FIFO, device or socket; every output has a name the system can hold, with
    the temporary name it is written under first, and is not a folder; and no output is the
    same file as an input or as another output. The same file: one real path (symlinks and
    ``..`` resolved) or, where both exist, one file on disk (hard links). Nothing is opened."""
    folders: dict[str, _Folder] = {}

    def look(path) -> tuple[str, str, _Folder]:
        text = os.fspath(path)
        folder, name = os.path.split(text)
        if folder not in folders:
            folders[folder] = _Folder(folder, name or "x")
        return text, name, folders[folder]

    known: dict[tuple, tuple[str, bool]] = {}       # identity -> (label, an input)
    for label, path in inputs.items():
        if path is None:
            continue
        name_fits(path, f"{label}:")
        text, name, place = look(path)
        keys, info = place.identities(text, name)
        kind = None if info is None else _not_regular(info.st_mode)
        if kind is not None:
            raise InputError(f"{label} {path} is {kind}, not a regular file")
        for key in keys:
            known.setdefault(key, (label, True))
    for label, path in outputs.items():
        if path is None:
            continue
        text, name, place = look(path)
        name_max, path_max = place.limits
        size = 4 * len(name)                # at most, in bytes (UTF-8)
        # The whole check only where a limit may be near: an animation names a million files.
        if (not place.checked or size + place.extra > name_max
                or place.absolute_size + 1 + size >= path_max):
            _name_within(Path(text), f"{label}:", place.limits, temporaries.temporary_name(text))
            place.checked = True
        keys, info = place.identities(text, name)
        if info is not None and stat.S_ISDIR(info.st_mode):
            raise InputError(f"{label} {path} is a folder, not a file")
        for key in keys:
            if key in known:
                other, an_input = known[key]
                if an_input:
                    raise InputError(f"{label} and {other} name the same file: {path} (an "
                                     "output never replaces an input)")
                raise InputError(f"{other} and {label} name the same file: {path}")
        for key in keys:
            known[key] = (label, False)
