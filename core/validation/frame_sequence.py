"""The frames of a test and a reference animation for ``xsl-render compare``: which files they
are, matched by frame number, and checked from their headers before any pixel is read.

A sequence is a pattern (a run of ``#`` is the frame number, Blender's naming: its frames are
the files it names for the frames asked for, or every file of its folder it names) or a folder
(every ``.exr`` whose name ends in a number; hidden files and ``_spp`` maps are not frames, two
files of one frame are refused). Both sides must hold the same frames, of one size and kind
and each pair one channel layout, so a comparison never stops half-way."""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

from ..checks import readable_file, readable_folder
from ..errors import InputError, SettingError, verbatim
from ..frames import frame_path, has_frame_marker
from ..imageio import image_header

FRAME_SUFFIX = ".exr"
_TRAILING_NUMBER = re.compile(r"(\d+)\Z")


@dataclass(frozen=True)
class Sequence:
    """One side's frames: ``frames`` maps frame number -> file, in ascending order.

    ``label`` is how the command line names the side ("REF", "TEST"), ``given`` the text
    given for it (a pattern or a folder).
    """

    label: str
    given: str
    frames: dict[int, Path]

    @property
    def is_pattern(self) -> bool:
        return has_frame_marker(self.given)

    def where(self, frame: int) -> str:
        """Where frame ``frame`` of this side is (or would be), for a message."""
        if self.is_pattern:
            return frame_path(self.given, frame)
        return f"a .exr file numbered {frame} in {self.given}"


@dataclass(frozen=True)
class FramePair:
    """Frame ``frame``'s reference and test files."""

    frame: int
    reference: Path
    test: Path


@dataclass(frozen=True)
class FrameSize:
    """What every frame of a checked pair of sequences has: its size and its kind."""

    width: int
    height: int
    hdr: bool


def is_sequence(text: str | os.PathLike) -> bool:
    """True when ``text`` names frames rather than one image: an existing folder, or a path
    (not an existing file) whose file name holds a ``#`` run."""
    text = os.fspath(text)
    if os.path.isfile(text):
        return False
    return os.path.isdir(text) or has_frame_marker(text)


def pattern_folder(pattern: str) -> str:
    """The folder part of a pattern, with its last separator ("" for the current folder)."""
    cut = max(pattern.rfind("/"), pattern.rfind("\\"))
    return pattern[:cut + 1]


def check_images_or_sequence(text: str, what: str = "image file") -> str:
    """``text`` if it names an image file we may read, a folder of frames we may list, or a
    pattern whose folder exists; InputError (one line) otherwise. Nothing is read."""
    text = os.fspath(text)
    if os.path.isdir(text):
        readable_folder(text)
    elif has_frame_marker(text) and not os.path.isfile(text):
        readable_folder(pattern_folder(text) or os.curdir, what="folder")
    else:
        readable_file(text, what=what)
    return text


def find_frames(text: str, label: str, frames: tuple[int, ...] | None = None) -> Sequence:
    """The frames of one side: of a pattern or a folder (module notes), only ``frames`` when
    given (a frame asked for but missing is left out here and named by :func:`match_frames`).

    Raises InputError when the side holds no frame at all, or when a folder holds two files
    of one frame.
    """
    text = os.fspath(text)
    found = _pattern_frames(text, frames) if has_frame_marker(text) and not os.path.isdir(text) \
        else _folder_frames(text, label)
    if frames is not None:
        found = {frame: found[frame] for frame in frames if frame in found}
    if not found:
        if frames is not None:
            where = Sequence(label, text, {}).where(frames[0])
            raise SettingError(f"{verbatim(label)} {verbatim(text)} holds none of the frames of "
                               f"{{frames.name}} (frame {frames[0]} would be {verbatim(where)})",
                               frames=frames)
        what = "names no existing frame" if has_frame_marker(text) else "holds no .exr frames"
        raise InputError(f"{label} {text} {what}")
    return Sequence(label, text, dict(sorted(found.items())))


def _pattern_frames(pattern: str, frames: tuple[int, ...] | None) -> dict[int, Path]:
    """Frames of a pattern: those of ``frames`` whose file exists, else every file of the
    pattern's folder that the pattern names for some frame."""
    if frames is not None:
        return {frame: Path(frame_path(pattern, frame)) for frame in frames
                if os.path.lexists(frame_path(pattern, frame))}
    folder = pattern_folder(pattern)
    name = pattern[len(folder):]
    run = list(re.finditer(r"#+", name))[-1]
    rest = name[run.end():]
    if not (name[:run.start()] + "0" + rest).lower().endswith(FRAME_SUFFIX):
        rest += FRAME_SUFFIX
    shape = re.compile(re.escape(name[:run.start()]) + r"(-?\d+)" + re.escape(rest) + r"\Z")
    found = {}
    for entry in _entries(folder or os.curdir):
        match = shape.match(entry)
        if match is None:
            continue
        frame = int(match.group(1))
        if frame_path(pattern, frame) == folder + entry:     # the padding the pattern gives
            found[frame] = Path(folder + entry)
    return found


def _folder_frames(folder: str, label: str) -> dict[int, Path]:
    """Frames of a folder: its ``.exr`` files by the number their names end in (others are
    not frames)."""
    found: dict[int, Path] = {}
    for entry in _entries(folder):
        stem, suffix = os.path.splitext(entry)
        if entry.startswith(".") or suffix.lower() != FRAME_SUFFIX or os.path.isdir(os.path.join(folder, entry)):
            continue
        number = _TRAILING_NUMBER.search(stem)
        if number is None:          # not a frame (frame_0007_spp.exr)
            continue
        frame = int(number.group(1))
        if frame in found:
            first, second = sorted((found[frame].name, entry))
            raise InputError(f"{label} {folder} holds two files of frame {frame}, {first} and {second}; "
                             "name one sequence with a pattern such as "
                             f"{os.path.join(folder, 'frame_####.exr')}")
        found[frame] = Path(folder) / entry
    return found


def _entries(folder: str) -> list[str]:
    try:
        with os.scandir(folder) as entries:
            return sorted(entry.name for entry in entries)
    except OSError as error:
        raise InputError(f"cannot list {folder}: {(error.strerror or str(error)).lower()}") from None


def match_frames(reference: Sequence, test: Sequence,
                 frames: tuple[int, ...] | None = None) -> list[FramePair]:
    """The frames both sides hold, ascending: every frame of ``frames`` when given, else
    every frame found. Raises InputError naming the first frame one side lacks."""
    wanted = frames if frames is not None else sorted(set(reference.frames) | set(test.frames))
    pairs = []
    for frame in wanted:
        for side, other in ((reference, test), (test, reference)):
            if frame not in side.frames:
                if frames is not None:
                    raise SettingError(f"{verbatim(side.label)} has no frame {frame} of "
                                       f"{{frames.name}}: {verbatim(side.where(frame))} does not "
                                       "exist", frames=frames)
                raise SettingError(f"frame {frame} is in {verbatim(other.label)} but not in "
                                   f"{verbatim(side.label)} ({verbatim(side.where(frame))} does "
                                   "not exist); {frames.name} chooses the frames to compare",
                                   frames=frames)
        pairs.append(FramePair(frame, reference.frames[frame], test.frames[frame]))
    return pairs


def check_frames(pairs: list[FramePair]) -> FrameSize:
    """Every frame file readable, every frame of one size and kind (HDR or LDR), each pair of
    one channel layout, from the files' headers; InputError naming the first that is not."""
    first: tuple[int, int, int, bool] | None = None
    kinds = {True: "HDR (floating-point pixels)", False: "LDR (integer pixels)"}
    for pair in pairs:
        headers = []
        for label, path in (("REF", pair.reference), ("TEST", pair.test)):
            readable_file(path, what=f"frame {pair.frame} of {label}")
            width, height, channels, hdr = header = image_header(path)
            if first is None:
                first = (width, height, pair.frame, hdr)
            if (width, height) != first[:2]:
                raise InputError(f"frame {pair.frame} of {label}, {path}, is {width}x{height}; "
                                 f"frame {first[2]} of REF is {first[0]}x{first[1]}: every frame "
                                 "must have one size")
            if hdr != first[3]:
                raise InputError(f"frame {pair.frame} of {label}, {path}, is {kinds[hdr]}, frame "
                                 f"{first[2]} of REF {kinds[first[3]]}: every frame must be of the same kind")
            if channels not in (1, 2, 3, 4):
                raise InputError(f"frame {pair.frame} of {label}, {path}, has {channels} channels; "
                                 "expected grey, grey+alpha, RGB or RGBA")
            headers.append(header)
        if headers[0][2] != headers[1][2]:
            raise InputError(f"frame {pair.frame}: REF has {headers[0][2]} channels, TEST "
                             f"{headers[1][2]}; images differ in channel count")
    return FrameSize(first[0], first[1], first[3])
