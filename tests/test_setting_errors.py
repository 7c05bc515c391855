"""Errors that name a setting (``core.errors.SettingError``): core names the field, the command
line words it as its option, and no module of core or the add-on words an error as a flag.

The panel's wording (each setting by its property's label) is tested through the operators'
poll machinery in ``test_panel_operators.py``.
"""
from __future__ import annotations

import argparse
import ast
import pickle
import re

import pytest
from test_cli_info import one_line_error

from conftest import ROOT
from xsl_render.core.errors import InputError, SettingError, setting_refused, verbatim
from xsl_render.operators.cli import build_parser
from xsl_render.operators.commands.setting_flags import FIELD_FLAGS, flag, in_flags

FLAGS = {"min_spp": "--min-spp", "max_spp": "--max-spp", "time_budget": "--time-budget"}
LABELS = {"min_spp": "Min Samples", "max_spp": "Max Samples", "time_budget": "Time Budget"}


@pytest.mark.parametrize("template, values, plain, flags, labels", [
    ("{min_spp} is larger than {max_spp}", {"min_spp": 8, "max_spp": 4},
     "min_spp 8 is larger than max_spp 4", "--min-spp 8 is larger than --max-spp 4",
     "Min Samples (8) is larger than Max Samples (4)"),
    ("{time_budget.name} must be a positive number of seconds (got {time_budget.value})",
     {"time_budget": 0.0}, "time_budget must be a positive number of seconds (got 0.0)",
     "--time-budget must be a positive number of seconds (got 0.0)",
     "Time Budget must be a positive number of seconds (got 0.0)"),
    ("{time_budget} is more than a week", {"time_budget": "1e+09 s"},
     "time_budget 1e+09 s is more than a week", "--time-budget 1e+09 s is more than a week",
     "Time Budget (1e+09 s) is more than a week"),
    ("{time_budget.name} is {time_budget.value:.1f} s", {"time_budget": 2.25},   # a value's format
     "time_budget is 2.2 s", "--time-budget is 2.2 s", "Time Budget is 2.2 s"),
    ("{tile_quantile.name} must be in (0, 1]", {"tile_quantile": 2.0},          # no name for it
     "tile_quantile must be in (0, 1]", "tile_quantile must be in (0, 1]",
     "tile_quantile must be in (0, 1]"),
    (f"{{min_spp}} of {verbatim('{odd} name')}", {"min_spp": "{x}"},            # braces the user typed
     "min_spp {x} of {odd} name", "--min-spp {x} of {odd} name", "Min Samples ({x}) of {odd} name"),
])
def test_a_setting_error_names_each_field_as_it_is_asked_to(template, values, plain, flags, labels):
    error = SettingError(template, **values)
    assert isinstance(error, InputError) and isinstance(error, ValueError)   # what front ends catch
    assert str(error) == plain and error.values == values and error.template == template
    assert error.worded(FLAGS) == flags
    assert error.worded(LABELS, pair="{name} ({value})") == labels
    copy = pickle.loads(pickle.dumps(error))            # the template survives, not just the text
    assert type(copy) is SettingError and copy.worded(FLAGS) == flags


@pytest.mark.parametrize("field, value, text, plain", [
    ("max_spp", 0, "must be a whole number from 1 to 16777216, not 0",
     "max_spp must be a whole number from 1 to 16777216, not 0"),
    ("resolution", "3x3", "3x3: each side must be 4 to 65536 pixels {Blender}",
     "resolution 3x3: each side must be 4 to 65536 pixels {Blender}"),
])
def test_a_general_check_names_the_setting_first(field, value, text, plain):
    error = setting_refused(field, value, text)
    assert str(error) == plain and error.values == {field: value}
    assert in_flags(error) == plain.replace(field, flag(field), 1)


def test_the_command_line_names_each_field_by_its_option():
    """``flag`` reads an option's dest back as argparse derives it, for every option of every
    command; the table holds only fields that are no option's dest, each naming a real option."""
    commands = next(action for action in build_parser()._actions
                    if isinstance(action, argparse._SubParsersAction)).choices
    options: dict[str, set[str]] = {}
    for parser in commands.values():
        for action in parser._actions:
            if action.option_strings:
                options.setdefault(action.dest, set()).update(action.option_strings)
    assert {dest for dest, strings in options.items() if flag(dest) not in strings} == set()
    assert set(FIELD_FLAGS) & set(options) == set()
    unset = {"--worker-python", "--worker-cache"}             # WorkerSetup's, at their defaults
    assert set(FIELD_FLAGS.values()) - set().union(*options.values()) == unset
    assert flag("min_spp") == "--min-spp" and flag("exponent") == "--guided-exponent"
    assert in_flags(InputError("no such file: x")) == "no such file: x"


@pytest.mark.parametrize("args, line", [
    (["--mode", "xsl", "--max-spp", "4", "--min-spp", "5"],
     "xsl-render: error: --min-spp 5 is larger than --max-spp 4"),
    (["--mode", "xsl", "--max-spp", "4", "--wx", "0", "--ws", "0"],
     "xsl-render: error: --wx and --ws cannot both be 0"),
    (["--mode", "xsl", "--max-spp", "4", "--estimator", "scene", "--step-rate", "2"],
     "xsl-render: error: a --step-rate is for the biased estimator (ray marching); --estimator "
     "'scene' does not march"),
    (["--mode", "xsl", "--max-spp", "4", "--frames", "3-1"],      # inside argparse's own error
     "xsl-render: error: render: argument --frames: --frames 3-1: the end frame 1 is before the "
     "start frame 3 (see xsl-render render --help)"),
])
@pytest.mark.blender          # the command line, as a user runs it (refused before Blender loads)
def test_the_command_line_words_core_errors_as_flags(cli, tmp_path, args, line):
    (tmp_path / "unused.blend").write_bytes(b"BLENDER-v500")
    result = cli("render", tmp_path / "unused.blend", *args, "--out", tmp_path / "o.exr", cwd=tmp_path)
    assert one_line_error(result) == line                 # exit code 2, one line, no traceback
    assert not (tmp_path / "o.exr").exists()


_FLAG = re.compile(r"(?<![\w-])--[a-z]")


def flag_worded_raises(path) -> list[str]:
    """``file:line`` of each ``raise`` in ``path`` whose text holds a flag (``--max-spp``);
    a command quoted in backticks (```xsl-render reference --frames```) is no flag."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Raise) and node.exc is not None:
            for part in ast.walk(node.exc):
                if (isinstance(part, ast.Constant) and isinstance(part.value, str)
                        and _FLAG.search(re.sub(r"`[^`]*`", "", part.value))):
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


def test_core_and_the_addon_name_settings_not_flags():
    """An error raised in core or the add-on reaches the panel too, where no flag exists: it
    names the setting's field (SettingError) and each front end words it."""
    paths = sorted(p for layer in ("core", "addon") for p in (ROOT / layer).rglob("*.py"))
    assert len(paths) > 50
    assert [hit for path in paths for hit in flag_worded_raises(path)] == []


def test_the_flag_check_catches_what_it_is_for(tmp_path, monkeypatch):
    monkeypatch.setattr("test_setting_errors.ROOT", tmp_path)
    bad = tmp_path / "bad.py"
    bad.write_text('def f(n):\n    raise InputError(f"the --max-spp {n} is wrong")\n'
                   'def g():\n    raise ValueError("a" "b --seed")\n'
                   'def h():\n    raise InputError("fill it (`xsl-render reference --frames`)")\n'
                   'def k():\n    raise InputError("a well-known thing--no flag")\n')
    assert flag_worded_raises(bad) == ["bad.py:2", "bad.py:4"]
