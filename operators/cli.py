"""The ``xsl-render`` command: parse, check, call, report.

A subcommand (``operators/commands/<name>.py``) has ``add_arguments(parser)`` and
``run(args) -> int`` and may have ``files(args)`` (the files its options imply, checked with
the options' own by ``core.checks.separate_files`` before anything else), ``check(args)`` (what
relates several options, before Blender loads), ``OUTPUTS_AS_A_SET`` / ``outputs_as_a_set(args)``
(every file appears at the end or none; False where finished work is kept as it goes) and
``INTERRUPTIBLE`` (Ctrl-C raises KeyboardInterrupt in it). Exit codes: 0 success, 2 bad input
(one line, a setting named by its option), 130 / 143 cancelled, 1 an unexpected failure (one
line; the traceback with ``XSL_DEBUG=1``)."""
from __future__ import annotations

import argparse
import os
import re
import sys
import textwrap
import traceback
from contextlib import nullcontext
from typing import Callable

from ..core import temporaries
from ..core.checks import separate_files
from ..core.errors import Cancelled, InputError
from ..core.files import output_set
from .commands.argtypes import declared_files, file_options, register_safe_numbers
from .commands.setting_flags import in_flags
from .console import blender_chatter_to_log
from .signals import EXIT_CODES


class OneLineParser(argparse.ArgumentParser):
    """argparse that reports a usage error as one line and exit code 2, and whose plain
    ``type=int`` / ``type=float`` refuse what Blender cannot hold (NaN, inf, past 32 bits).

    A value that starts with a minus and a digit is a value, never an option: argparse takes
    only plain negative numbers as values, so ``--frames -3--1`` (frames -3 to -1) had ended
    in "expected one argument"."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        register_safe_numbers(self)
        self._negative_number_matcher = re.compile(r"^-\d|^-\.\d")

    def error(self, message: str):  # noqa: D401 - argparse API
        command = self.prog.removeprefix("xsl-render").strip()
        raise InputError(f"{command + ': ' if command else ''}{message} (see {self.prog} --help)")


def build_parser(in_blender: bool = False) -> argparse.ArgumentParser:
    """The command line. ``in_blender``: the parser of the batch entry (``operators/batch.py``),
    the same commands and options, with SCENE.blend left out (Blender has the file open)."""
    from .commands import COMMANDS, GROUPS

    parser = OneLineParser(prog="xsl-render", usage="%(prog)s [-h] [--verbose] COMMAND ...",
                           formatter_class=argparse.RawDescriptionHelpFormatter,
                           description=textwrap.fill(
                               "Render fog, smoke and clouds in Blender Cycles faster at the same "
                               "look (Auto Volumes), and the paper's perceptual selective rendering "
                               "of participating media.", 78),
                           epilog=command_list(GROUPS))
    parser.add_argument("--verbose", action="store_true",
                        help="keep Blender's console output in a log file and print its path")
    # The commands are listed by group in the epilog, not as one list.
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser,
                                help=argparse.SUPPRESS, prog="xsl-render")
    sub.required = True
    for command in COMMANDS:
        child = sub.add_parser(command.NAME, help=command.HELP, description=command.HELP)
        child.in_blender = in_blender          # read by commands.common.add_scene_positional
        command.add_arguments(child)
        child.set_defaults(run=command.run, command=command, file_options=file_options(child))
    return parser


def command_list(groups: dict) -> str:
    """The commands by group, each with its help, as the top-level --help ends."""
    width = max(len(command.NAME) for commands in groups.values() for command in commands) + 2
    lines = []
    for title, commands in groups.items():
        lines.append(f"{title}:")
        for command in commands:
            wrapped = textwrap.wrap(command.HELP, 78 - width - 2)
            lines.append(f"  {command.NAME:<{width}}{wrapped[0]}")
            lines += [" " * (width + 2) + line for line in wrapped[1:]]
        lines.append("")
    return "\n".join(lines) + "'xsl-render COMMAND --help' says more about each."


class _Failed(Exception):
    """``run`` returned a non-zero code: its outputs are discarded like an error's."""

    def __init__(self, code: int):
        super().__init__(code)
        self.code = code


def _outputs_as_a_set(command, args) -> bool:
    if hasattr(command, "outputs_as_a_set"):
        return bool(command.outputs_as_a_set(args))
    return bool(getattr(command, "OUTPUTS_AS_A_SET", True))


def check_files(args, in_blender: bool = False) -> None:
    """The command's files (``argtypes.declared_files``) through ``separate_files``; inside
    Blender the open .blend is an input too."""
    inputs, outputs = declared_files(args)
    if in_blender:
        import bpy

        if bpy.data.filepath:
            inputs.setdefault("the open file", bpy.data.filepath)
    separate_files(inputs, outputs)


def main(argv: list[str] | None = None, in_blender: bool = False, watcher=None,
         begin_work: Callable[[], bool] | None = None) -> int:
    """Run one command; ``watcher``: the command line's signal watcher (``signals.py``);
    ``begin_work``: called once the command line is checked, False if the command was
    cancelled before its work began (the batch entry's ``interrupt.InterruptToCancel``)."""
    argv = sys.argv[1:] if argv is None else argv
    try:
        args = build_parser(in_blender).parse_args(argv)
    except InputError as error:
        print(f"xsl-render: error: {in_flags(error)}", file=sys.stderr)
        return 2
    except SystemExit as done:          # --help
        return int(done.code or 0)
    command = args.command
    try:
        check_files(args, in_blender)
        if hasattr(command, "check"):
            command.check(args)
    except InputError as error:
        print(f"xsl-render: error: {in_flags(error)}", file=sys.stderr)
        return 2
    if begin_work is not None and not begin_work():
        print("xsl-render: cancelled", file=sys.stderr)
        return 130
    interruptible = watcher is not None and getattr(command, "INTERRUPTIBLE", False)
    if interruptible:
        watcher.interrupt_main_thread()
    outputs = output_set(seal=True) if _outputs_as_a_set(command, args) else nullcontext()
    with blender_chatter_to_log(keep=args.verbose) as log_path:
        try:
            with outputs:
                code = args.run(args)
                if temporaries.cancel_requested():
                    raise Cancelled("cancelled")    # announced while it ran: honoured
                if code:
                    raise _Failed(code)
        except _Failed as failed:
            code = failed.code
        except InputError as error:
            print(f"xsl-render: error: {in_flags(error)}", file=sys.stderr)
            code = 2
        except KeyboardInterrupt:
            if not temporaries.cancel_requested():      # else announced (``interrupt.py``)
                print("xsl-render: cancelled", file=sys.stderr)
            code = 130
        except Exception as error:     # our bug, not the user's: say so in one line
            if os.environ.get("XSL_DEBUG"):
                traceback.print_exc()
            message = str(error).strip().splitlines()[0] if str(error).strip() else ""
            print(f"xsl-render: internal error: {type(error).__name__}: {message} "
                  "(set XSL_DEBUG=1 for the traceback)", file=sys.stderr)
            code = 1
        if interruptible and watcher.received is not None and code in (0, 130):
            code = EXIT_CODES[watcher.received]     # stopped by a signal: 130 or 143 as ever
        if args.verbose:
            print(f"xsl-render: Blender's console output is in {log_path}", file=sys.stderr)
    return code
