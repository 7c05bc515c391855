"""Frame ranges and lists, and numbered output names for animations, as Blender names its
own frames.

A frame list is what Open Job Description's range expressions accept (``1-3,8``,
``1-250:2,300``), so the command line and the farm's job template read the same text. An
output path's last run of ``#`` in the file name becomes the frame number, zero-padded to the
run's length (Blender's ``BLI_path_frame``); without one, four digits are appended. One
deliberate difference: a name ending in ``.exr`` keeps it at the end (``render0001.exr``)."""
from __future__ import annotations

import re

from .checks import MAX_FRAME, MIN_FRAME
from .errors import SettingError, verbatim

EXTENSION = ".exr"
#: Digits Blender pads an appended frame number to.
DEFAULT_DIGITS = 4
#: (ASCII digits only: Python's \d and int() would take other scripts' digits, ``١-٣``.)
_RANGE = re.compile(r"^\s*(-?\d+)\s*(?:(?:-|\.\.)\s*(-?\d+)\s*(?::\s*(\d+)\s*)?)?\Z", re.ASCII)


def parse_frame_range(text: str) -> range:
    """``"1-48"``, ``"1..48"``, ``"1-48:2"`` (every 2nd frame) or ``"7"`` -> a range of frames.

    Raises InputError for anything else, an end before the start, a step below 1 or a frame
    Blender cannot go to.
    """
    match = _RANGE.match(str(text))
    if not match:
        raise SettingError("{frames.name} must look like START-END or START-END:STEP, or a list "
                           "of them such as 1-3,8 (got '{frames.value}')", frames=text)
    start = int(match.group(1))
    end = int(match.group(2)) if match.group(2) is not None else start
    step = int(match.group(3)) if match.group(3) is not None else 1
    if end < start:
        raise SettingError(f"{{frames}}: the end frame {end} is before the start frame {start}",
                           frames=text)
    if step < 1:
        raise SettingError("{frames}: the step must be at least 1", frames=text)
    if not (MIN_FRAME <= start and end <= MAX_FRAME and step <= MAX_FRAME - MIN_FRAME):
        raise SettingError(f"{{frames}}: frames must lie between {MIN_FRAME} and {MAX_FRAME} "
                           "(Blender's limits)", frames=text)
    return range(start, end + 1, step)


def parse_frame_list(text: str) -> tuple[int, ...]:
    """``"1-3,8"``, ``"1-250:2,300"``, ``"7"`` (``parse_frame_range`` items joined by commas)
    -> the frames in ascending order.

    Raises InputError (naming the ``frames`` setting) for a bad item, or for two items whose spans
    overlap (``1-3,2``; also ``1-9:2,2-8:2``, which share no frame): Open Job Description
    refuses overlapping ranges, so the command line refuses them first.
    """
    return tuple(frame for _, frames in _items(text) for frame in frames)


def frame_expression(text: str) -> str:
    """The canonical text of a frame list: each item as ``A``, ``A-B`` or ``A-B:S``, items in
    ascending order (``"8, 1-3:1"`` -> ``"1-3,8"``). Checked as ``parse_frame_list`` does."""
    canonical = []
    for _, frames in _items(text):
        start, end, step = frames.start, frames.stop - 1, frames.step
        canonical.append(str(start) if start == end else
                         f"{start}-{end}" + (f":{step}" if step != 1 else ""))
    return ",".join(canonical)


def _items(text: str) -> list[tuple[str, range]]:
    """(item text, its range) of each comma-separated item, by start frame; spans disjoint."""
    texts = str(text).split(",")
    if len(texts) > 1 and any(not item.strip() for item in texts):
        raise SettingError("{frames}: an empty item between commas", frames=text)
    items = sorted(((item, parse_frame_range(item)) for item in texts), key=lambda i: i[1].start)
    for (before, first), (after, second) in zip(items, items[1:]):
        if second.start <= first.stop - 1:
            raise SettingError(f"{{frames}}: {verbatim(before.strip())} and "
                               f"{verbatim(after.strip())} overlap", frames=text)
    return items


def frame_runs(frames) -> list[range]:
    """``frames`` (ascending) as runs of evenly spaced frames, each what one ``START-END:STEP``
    animation renders, each run as long as the frames keep its spacing: (1, 2, 3, 5, 7, 8)
    -> 1-3, 5-7:2, 8."""
    runs: list[range] = []
    for frame in frames:
        last = runs[-1] if runs else None
        if last is not None and len(last) == 1:
            runs[-1] = range(last.start, frame + 1, frame - last.start)
        elif last is not None and frame - last[-1] == last.step:
            runs[-1] = range(last.start, frame + 1, last.step)
        else:
            runs.append(range(frame, frame + 1))
    return runs


def has_frame_marker(pattern: str) -> bool:
    """True when the file name (not a folder) of ``pattern`` holds a ``#``."""
    return "#" in _split(pattern)[1]


def frame_path(pattern: str, frame: int) -> str:
    """The output path of ``frame``: the last ``#`` run of the file name replaced by the
    zero-padded frame number, else the number appended (before a trailing ``.exr``);
    ``.exr`` added when missing. Folders are kept as they are (``#`` in them too)."""
    folder, name = _split(pattern)
    runs = list(re.finditer(r"#+", name))
    if runs:
        run = runs[-1]
        number = f"{frame:0{len(run.group())}d}"
        name = name[:run.start()] + number + name[run.end():]
    else:
        number = f"{frame:0{DEFAULT_DIGITS}d}"
        if name.lower().endswith(EXTENSION):
            name = name[:-len(EXTENSION)] + number + name[-len(EXTENSION):]
        else:
            name = name + number
    if not name.lower().endswith(EXTENSION):
        name += EXTENSION
    return folder + name


def _split(pattern: str) -> tuple[str, str]:
    """(folder including its last separator, file name); either separator counts."""
    cut = max(pattern.rfind("/"), pattern.rfind("\\"))
    return pattern[:cut + 1], pattern[cut + 1:]
