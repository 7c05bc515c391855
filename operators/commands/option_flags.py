"""Command-line options built from core's option table (``core.option_table``): the flag, its
type and range, its default and help come from the one declaration the panel and the farm use
too. A value is checked while the command line is parsed, by the option's own check."""
from __future__ import annotations

import argparse

from ...core.option_table import OPTIONS
from . import argtypes


def option_type(option):
    """The argparse type of ``option``: text checked by ``option.check`` (``none_word`` ->
    None), its error as argparse's one line."""
    def parse(text: str):
        return option.check(text, field=False)
    kind = {"int": "integer", "float": "number"}.get(option.kind, option.kind)
    return argtypes.checked_by(parse, kind if option.none_word is None else f"{kind} or {option.none_word}")


def default_note(option, default) -> str:
    """' (default X)' as --help says it."""
    if default is None:
        return f" (default {option.none_means})" if option.none_means else ""
    if option.kind == "bool":
        return f" (default {'on' if default else 'off'})"
    return f" (default {default:g})" if isinstance(default, float) else f" (default {default})"


def _sentence(text: str) -> str:
    """The table's help as argparse's: lower case first, but for a name (Cycles, Blender)."""
    first = text.split(" ", 1)[0]
    acronym = len(first) > 1 and first.isupper()
    return text if acronym or first.startswith(_NAMES) else text[0].lower() + text[1:]


_NAMES = ("Cycles", "Blender", "Open", "OIDN")


def add_option(parser, name: str, help: str | None = None, note: bool = True,
               **overrides) -> argparse.Action:
    """Add option ``name`` of the table to ``parser`` (or an argument group); ``help`` replaces
    the table's words where a command uses the setting differently (``note`` False: they say
    the default themselves), ``overrides`` any other keyword of ``add_argument`` (``default``,
    ``required``, ``metavar``)."""
    option = OPTIONS[name]
    default = overrides.pop("default", option.default)
    kwargs = {"dest": option.name, "default": default}
    if option.kind == "bool":
        kwargs["action"] = argparse.BooleanOptionalAction
    elif option.kind == "choice":
        kwargs["choices"] = option.values
    else:
        kwargs["type"] = option_type(option)
    if help == argparse.SUPPRESS:
        words = help
    else:
        words = ((help or _sentence(option.help)) + (default_note(option, default) if note else "")).replace("%", "%%")
    kwargs.update(help=words, **overrides)
    action = parser.add_argument(option.option, **kwargs)
    action.option_table = option.name          # where it came from (tests/test_option_table.py)
    return action
