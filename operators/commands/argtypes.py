"""The kinds of value a command-line option takes, each checked while the command line is parsed:
before Blender loads, before any work, before anything is written.

An option says what it accepts with ``type=`` (``SAMPLES``, ``number(above=0, hi=1)``,
``output_file(".exr")``, ``SCENE``...); a setting of ``core.option_table`` gets its type from
the table (``option_flags.add_option``). A bad value ends the command with exit code 2 and one
line (``argument --spp: must be a whole number from 1 to 16777216 (Cycles' limit), not 0``);
what relates several options is the command's ``check(args)``. Plain ``type=int`` and
``type=float`` are mapped to :func:`int32` and :func:`finite`, so no option takes NaN, infinity
or a number Blender's 32-bit properties cannot hold."""
from __future__ import annotations

import argparse

from ...core import checks
from ...core.errors import InputError
from .setting_flags import in_flags


def _converter(function, label: str, keep_text: bool = False, role: str | None = None):
    """An argparse type: ``function(text)`` (or, ``keep_text``, the text once ``function``
    accepted it), its InputError as argparse's one-line error. ``role``: "input" or
    "output" for a file the command reads or writes (:func:`declared_files`)."""
    def convert(text: str):
        try:
            value = function(text)
        except InputError as error:
            raise argparse.ArgumentTypeError(in_flags(error)) from None
        return text if keep_text else value
    convert.__name__ = label                # argparse names the type in some messages
    convert.role = role
    return convert


def checked_by(function, label: str):
    """An argparse type that is ``function(text)`` (a check of ``core.option_table``)."""
    return _converter(function, label)


def integer(lo: int = checks.INT32_MIN, hi: int = checks.INT32_MAX, limit: str = ""):
    """A whole number in [lo, hi]; ``limit`` says whose range it is ("(Cycles' limit)")."""
    return _converter(lambda text: checks.whole_number(text, lo, hi, limit=limit), "integer")


def number(lo: float | None = None, hi: float | None = None, *, above: float | None = None,
           below: float | None = None):
    """A finite number, bounded inclusively by lo/hi and exclusively by above/below."""
    return _converter(lambda text: checks.finite_number(text, lo, hi, above=above, below=below),
                      "number")


def auto_or(kind, word: str = "auto"):
    """``kind``, or ``word`` for None ("auto", "off")."""
    def convert(text: str):
        return None if text == word else kind(text)
    convert.__name__ = f"{kind.__name__} or {word}"
    return convert


int32 = integer()
finite = number()
_CYCLES = " (Cycles' limit)"
#: Samples per pixel: 1 to Cycles' 2^24.
SAMPLES = integer(1, checks.MAX_SAMPLES, _CYCLES)
#: Cycles' seed.
SEED = integer(0, checks.MAX_SEED, _CYCLES)
#: A frame Blender can go to.
FRAME = integer(checks.MIN_FRAME, checks.MAX_FRAME, " (Blender's limits)")
#: A size in pixels no frame can exceed.
PIXELS = integer(1, checks.MAX_SIDE)
#: WxH that Blender can render on this machine; comes back as the text given.
RESOLUTION = _converter(lambda text: checks.parse_frame_size(text, None), "WxH", keep_text=True)
POSITIVE = number(above=0.0)


def input_file(*suffixes: str, what: str = "file"):
    """An existing file we may read (with one of ``suffixes``, when given); ``what`` names it
    in messages ("no such director map: m.exr")."""
    return _converter(lambda text: checks.readable_file(text, suffixes, what=what), "file",
                      keep_text=True, role="input")


def input_folder(what: str = "folder"):
    """An existing folder we may list."""
    return _converter(lambda text: checks.readable_folder(text, what=what), "folder",
                      keep_text=True)


def image_or_frames(what: str = "image file"):
    """An image file we may read, or frames: a folder we may list, or a pattern such as
    ``out/frame_####.exr`` whose folder exists. The files read are named by the command's
    ``files(args)`` (every frame of a sequence), so the type declares none itself."""
    def check(text: str) -> None:
        from ...core.validation.frame_sequence import check_images_or_sequence

        check_images_or_sequence(text, what=what)
    return _converter(check, "file or frames", keep_text=True)


def output_file(*suffixes: str):
    """A file of one of ``suffixes`` that may be written (its folder is made if need be)."""
    return _converter(lambda text: checks.writable_file(text, suffixes), "file", keep_text=True,
                      role="output")


def output_folder():
    """A folder that may be written into (made if need be)."""
    return _converter(lambda text: checks.writable_folder(text), "folder", keep_text=True)


def _scene(text: str) -> None:
    from ...addon.scene.blend_session import check_blend_file   # reads the header; no bpy

    checks.readable_file(text)
    check_blend_file(text)


#: A .blend file we may read (never written).
SCENE = _converter(_scene, "SCENE.blend", keep_text=True, role="input")


def register_safe_numbers(parser: argparse.ArgumentParser) -> None:
    """Make plain ``type=int`` and ``type=float`` of ``parser`` (and its argument groups)
    :func:`int32` and :func:`finite`."""
    parser.register("type", int, int32)
    parser.register("type", float, finite)


# Frame lists live in core/frames.py (the farm's job template reads the same text).
from ...core.frames import frame_expression as _frame_expression  # noqa: E402

#: Frames: 12, 1-250, 1-250:2 or a list such as 1-3,8; comes back in canonical form.
FRAMES = _converter(_frame_expression, "FRAMES")


def file_options(parser: argparse.ArgumentParser) -> list[tuple[str, str, str]]:
    """(dest, label, role) of every option of ``parser`` that names a file it reads
    (``input_file``, ``SCENE``) or writes (``output_file``); the label is how the user
    knows it: the option ("--stats") or the positional's metavar ("SCENE.blend")."""
    found = []
    for action in parser._actions:
        role = getattr(action.type, "role", None)
        if role is not None:
            label = action.option_strings[-1] if action.option_strings else (action.metavar or action.dest)
            found.append((action.dest, label, role))
    return found


def declared_files(args) -> tuple[dict, dict]:
    """(inputs, outputs) of a parsed command line, label -> path: the options of
    :func:`file_options` (``args.file_options``) and what the command's optional
    ``files(args)`` adds, the files its options imply (a render's ``_spp.exr``, the maps of
    ``maps --out DIR``), named by the same functions that write them."""
    inputs, outputs = {}, {}
    for dest, label, role in getattr(args, "file_options", ()):
        value = getattr(args, dest, None)
        if value is not None:
            (inputs if role == "input" else outputs)[label] = value
    files = getattr(args.command, "files", None)
    if files is not None:
        more_inputs, more_outputs = files(args)
        inputs.update(more_inputs)
        outputs.update(more_outputs)
    return inputs, outputs
