"""``core.checks`` and the command line's argument types: what a command accepts, checked
before any work, and Blender's limits as Blender itself states them."""
from __future__ import annotations

import argparse
import os

import pytest

from xsl_render.core import checks, temporaries
from xsl_render.core.errors import InputError
from xsl_render.core.sampling.render_files import render_output_paths
from xsl_render.operators.cli import build_parser
from xsl_render.operators.commands import argtypes


@pytest.mark.parametrize("value, lo, hi, words", [
    ("2147483648", 1, checks.MAX_SAMPLES, "from 1 to 16777216"),
    ("0", 1, 10, "from 1 to 10"),
    ("1.5", 0, 10, "whole number, not '1.5'"),
    ("nan", 0, 10, "whole number, not 'nan'"),
    (True, 0, 10, "whole number, not True"),
    (2.0, 0, 10, "whole number, not 2.0"),
])
def test_whole_numbers_outside_their_range_are_refused(value, lo, hi, words):
    with pytest.raises(InputError, match=words):
        checks.whole_number(value, lo, hi, name="--n")


def test_whole_numbers_take_numpy_integers():
    import numpy as np

    assert checks.whole_number(np.int64(7), 0, 10) == 7


@pytest.mark.parametrize("value, bounds, words", [
    ("nan", {}, "finite"), ("inf", {}, "finite"), ("-inf", {}, "finite"), (10 ** 400, {}, "finite"),
    ("x", {}, "not 'x'"), ("0", {"above": 0.0}, "greater than 0"), ("-1", {"lo": 0.0}, "at least 0"),
    ("2", {"hi": 1.0}, "at most 1"), ("1", {"below": 1.0}, "less than 1"),
])
def test_numbers_must_be_finite_and_in_range(value, bounds, words):
    with pytest.raises(InputError, match=words):
        checks.finite_number(value, **bounds)


@pytest.mark.parametrize("text, words", [
    ("1x1", "4 to 65536"), ("3x100", "4 to 65536"), ("65537x4", "4 to 65536"),
    ("65536x65536", "memory"), ("12by4", "look like"), ("4x", "look like"), ("-4x4", "4 to 65536"),
])
def test_frame_sizes_blender_cannot_render_here_are_refused(text, words):
    with pytest.raises(InputError, match=words):
        checks.parse_frame_size(text)


def test_a_frame_size_that_fits_is_kept():
    assert checks.parse_frame_size(" 4x65536 ") == (4, 65536)


def test_outputs_of_one_command_must_be_distinct_files(tmp_path):
    with pytest.raises(InputError, match="--a and --b name the same file"):
        checks.separate_files({}, {"--a": tmp_path / "x.json", "--b": tmp_path / "." / "x.json"})
    with pytest.raises(InputError, match="is a folder"):
        checks.separate_files({}, {"--a": tmp_path})
    checks.separate_files({}, {"--a": tmp_path / "x.json", "--b": None, "--c": tmp_path / "y.json"})


def test_no_output_is_an_input_by_any_name(tmp_path):
    """Issue 23: the same file by its own name, through a symlink, a hard link or ``..``."""
    scene = tmp_path / "scene.blend"
    scene.write_bytes(b"BLENDER")
    (tmp_path / "link.json").symlink_to(scene)
    os.link(scene, tmp_path / "hard.json")
    (tmp_path / "sub").mkdir()
    for output in (scene, tmp_path / "link.json", tmp_path / "hard.json", tmp_path / "sub" / ".." / "scene.blend"):
        with pytest.raises(InputError, match=r"--stats and SCENE.blend name the same file: .*never replaces an input"):
            checks.separate_files({"SCENE.blend": scene}, {"--out": tmp_path / "o.exr", "--stats": output})
    checks.separate_files({"SCENE.blend": scene, "REF": scene}, {"--out": tmp_path / "o.exr"})   # read twice: fine


def test_inputs_that_are_not_regular_files_are_refused_without_opening_them(tmp_path):
    fifo = tmp_path / "f.exr"
    os.mkfifo(fifo)
    for check in (lambda: checks.readable_file(fifo), lambda: checks.separate_files({"--map": fifo}, {})):
        with pytest.raises(InputError, match="is a FIFO"):
            check()                     # an open() would block here for ever
    with pytest.raises(InputError, match="is a character device, not a regular file"):
        checks.readable_file("/dev/null")
    with pytest.raises(InputError, match="is a FIFO"):
        checks.readable_folder(fifo)


def test_names_past_the_systems_limits_are_refused(tmp_path):
    long = "a" * 300
    with pytest.raises(InputError, match="file name too long: a+\\.\\.\\.a+ \\(300 bytes; at most 255"):
        checks.readable_file(tmp_path / long)
    with pytest.raises(InputError, match="file name too long"):
        checks.writable_folder(tmp_path / long)
    with pytest.raises(InputError, match="path too long"):
        checks.writable_file(tmp_path.joinpath(*["b" * 200] * 25, "o.exr"))
    # A name that fits, whose temporary name (written first) does not.
    with pytest.raises(InputError, match="written first under a temporary name"):
        checks.writable_file(tmp_path / ("c" * 250 + ".exr"))
    # A derived output over the limit: the one check names it.
    extra = len(temporaries.temporary_name(tmp_path / "d.exr").name) - len("d.exr")   # pid's digits
    fits = tmp_path / ("d" * (255 - extra - 2 - len(".exr")) + ".exr")                 # _spp: 4 more
    checks.writable_file(fits)
    with pytest.raises(InputError, match="its samples: file name too long"):
        checks.separate_files({}, render_output_paths(fits))
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_places_to_write_are_probed_without_leaving_anything(tmp_path):
    (tmp_path / "file").write_text("x")
    assert checks.writable_file(tmp_path / "new" / "deeper" / "o.exr", (".exr",))
    assert checks.writable_folder(tmp_path / "new")
    with pytest.raises(InputError, match="not a folder"):
        checks.writable_file(tmp_path / "file" / "o.exr")
    with pytest.raises(InputError, match="is a file, not a folder"):
        checks.writable_folder(tmp_path / "file")
    with pytest.raises(InputError, match="is a folder, not a file"):
        checks.writable_file(tmp_path)
    with pytest.raises(InputError, match=r"must be a \.png file"):
        checks.writable_file(tmp_path / "o.exr", (".png",))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]       # nothing made


@pytest.mark.skipif(not checks.Path("/proc/self").exists(), reason="needs /proc")
def test_a_place_nothing_can_be_written_to_is_refused_even_for_root():
    with pytest.raises(InputError, match="cannot write /proc/x"):
        checks.writable_folder("/proc/x")


def _value_options():
    """(command, option, action) of every option of every command that takes a number."""
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in commands.choices.items():
        for action in sub._actions:
            if isinstance(action, argparse._SubParsersAction):     # farm-task's steps
                for step, leaf in action.choices.items():
                    for inner in leaf._actions:
                        yield f"{name} {step}", inner, leaf
            else:
                yield name, action, sub


def _converter(parser, action):
    """What argparse calls on the option's text (plain int and float map to safe ones)."""
    return parser._registry_get("type", action.type, action.type)


NUMERIC = [(command, action.option_strings[0], _converter(parser, action))
           for command, action, parser in _value_options()
           if action.option_strings and getattr(_converter(parser, action), "__name__", "") in
           ("integer", "number", "integer or auto", "number or auto", "number or off")]


def test_the_table_of_numeric_options_is_complete():
    names = {(command, option) for command, option, _ in NUMERIC}
    assert len(NUMERIC) > 60
    assert {("render", "--max-spp"), ("hotspots", "--distance-cm"), ("compare", "--exposure"),
            ("experiment-analyse", "--timing-tolerance-ms"), ("farm-task maps", "--frame"),
            ("render", "--equal-time"), ("maps", "--light-n")} <= names


def _taken(value, kinds) -> list[str]:
    taken = []
    for command, option, converter in NUMERIC:
        if not converter.__name__.startswith(kinds):
            continue
        try:
            converter(value)
        except argparse.ArgumentTypeError:
            continue
        taken.append(f"{command} {option}")
    return taken


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e999", "NaN"])
def test_no_numeric_option_takes_nan_or_infinity(value):
    """Every option of every command that takes a number, not just those anyone thought of."""
    assert _taken(value, ("integer", "number")) == []


@pytest.mark.parametrize("value", ["2147483648", "-2147483649", "99999999999"])
def test_no_whole_number_option_takes_numbers_past_32_bits(value):
    # --render-cost counts pixel-samples, no Blender property: a huge one keeps whole tiles.
    assert [option for option in _taken(value, ("integer",)) if not option.endswith("--render-cost")] == []


def test_plain_int_and_float_options_are_made_safe():
    parser = argparse.ArgumentParser()
    argtypes.register_safe_numbers(parser)
    group = parser.add_argument_group("g")
    group.add_argument("--f", type=float)
    parser.add_argument("--i", type=int)
    assert parser.parse_args(["--f", "1.5", "--i", "-3"]) == argparse.Namespace(f=1.5, i=-3)
    for argv in (["--f", "nan"], ["--i", "2147483648"]):
        with pytest.raises(SystemExit):
            parser.parse_args(argv)


@pytest.mark.blender
def test_blender_limits_are_blenders_own(blender):
    scene = blender.context.scene

    def limits(struct, name):
        prop = struct.bl_rna.properties[name]
        return prop.hard_min, prop.hard_max

    assert limits(scene.cycles, "samples") == (1, checks.MAX_SAMPLES)
    assert limits(scene.cycles, "seed") == (0, checks.MAX_SEED)
    assert limits(scene, "frame_current") == (checks.MIN_FRAME, checks.MAX_FRAME)
    assert limits(scene.render, "resolution_x") == (checks.MIN_SIDE, checks.MAX_SIDE)
    assert limits(scene.render, "resolution_y") == (checks.MIN_SIDE, checks.MAX_SIDE)
