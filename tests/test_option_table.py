"""Each option declared once (``core.option_table``): the command line's flags, the panel's
properties and a farm job's parameters are built from the one table (their names, ranges,
defaults, labels and words), and a command-line run checks its time budget once."""
from __future__ import annotations

import argparse
from pathlib import Path

import pytest
from test_farm_core import farm_job, guided_job

from xsl_render.core.farm.job_parameters import parameters
from xsl_render.core.maps.options import MapOptions
from xsl_render.core.option_table import OPTIONS
from xsl_render.core.sampling import volume_estimator
from xsl_render.core.sampling.guided_plan import GuidedOptions
from xsl_render.core.sampling.render_options import RenderOptions
from xsl_render.operators.cli import build_parser

#: The core records whose fields are settings a user sets.
SETTING_FIELDS = (set(RenderOptions.__dataclass_fields__) | set(GuidedOptions.__dataclass_fields__)
                  | set(MapOptions.__dataclass_fields__)) - {"resolution", "estimator_choice"}
#: Options a command declares otherwise, on purpose: farm-task guided's ceiling takes 0 for
#: "none" (an OpenJD INT parameter cannot be empty); the ceiling of curves and reference is
#: the contestants' (its reference, 16 x it, must stay within Cycles' samples).
OWN_DECLARATIONS = {("farm-task guided", "max_spp"), ("curves", "max_spp"), ("reference", "max_spp")}


def _parsers() -> dict[str, argparse.ArgumentParser]:
    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    found = {name: parser for name, parser in commands.items()}
    steps = next(a for a in commands["farm-task"]._actions if isinstance(a, argparse._SubParsersAction))
    found.update({f"farm-task {name}": parser for name, parser in steps.choices.items()})
    return found


def _refused(action, text: str) -> bool:
    try:
        action.type(text)
    except argparse.ArgumentTypeError:
        return True
    return False


def test_every_setting_flag_comes_from_the_table():
    seen = set()
    for command, parser in _parsers().items():
        for action in parser._actions:
            if action.dest not in SETTING_FIELDS or not action.option_strings:
                continue
            if (command, action.dest) in OWN_DECLARATIONS:
                continue
            option = OPTIONS.get(action.dest)
            assert option is not None, f"{command} {action.option_strings}: not in the option table"
            seen.add(action.dest)
            assert getattr(action, "option_table", None) == action.dest, (command, action.option_strings)
            assert option.option in action.option_strings, (command, action.dest)
            if option.kind == "choice":
                assert tuple(action.choices) == option.values
            elif option.kind == "bool":
                assert isinstance(action, argparse.BooleanOptionalAction)
            else:
                low = option.low if option.low is not None else option.above
                text = (lambda v: str(int(v))) if option.kind == "int" else repr
                assert not _refused(action, text(option.high)) and _refused(action, text(option.high * 2 + 1))
                assert _refused(action, text(low - 1))
                assert _refused(action, text(low)) == (option.low is None)        # exclusive or not
    assert {"max_spp", "min_spp", "seed", "denoise", "tile_size", "time_budget", "exponent",
            "light_n", "wx", "xs_op", "minbound"} <= seen


def test_a_flags_default_is_the_tables():
    render = _parsers()["render"]
    defaults = {action.dest: action.default for action in render._actions}
    for name in ("estimator", "min_spp", "seed", "tile_size", "exponent", "level_ratio", "light_n", "wx",
                 "minbound", "denoise", "pilot_fraction", "importance"):
        assert defaults[name] == OPTIONS[name].default, name
    assert OPTIONS["estimator"].default == "auto"          # auto everywhere, scene the opt-out


def test_core_records_take_their_defaults_from_the_table():
    for record in (RenderOptions(max_spp=4), GuidedOptions(time_budget=1.0), MapOptions()):
        for name, value in vars(record).items():
            if name in OPTIONS and name not in ("max_spp", "time_budget", "estimator"):
                assert value == OPTIONS[name].default, name


@pytest.mark.parametrize("job", ["selective", "guided"])
def test_every_farm_parameter_of_a_setting_comes_from_the_table(tmp_path, job):
    made = farm_job(tmp_path) if job == "selective" else guided_job(tmp_path)
    by_farm_name = {option.farm: option for option in OPTIONS.values() if option.farm}
    found = {p["name"]: p for p in parameters(made)}
    settings = [p for name, p in found.items() if name in by_farm_name]
    assert len(settings) >= 12
    for parameter in settings:
        option = by_farm_name[parameter["name"]]
        assert parameter["userInterface"]["label"] == option.label
        assert parameter["description"].startswith(option.help)
        if option.kind == "choice":
            assert parameter["allowedValues"] == list(option.values)
        elif parameter["type"] in ("INT", "FLOAT") and not (job == "guided" and option.name in ("max_spp", "time_budget")):
            low = option.low if option.low is not None else option.above
            assert (parameter.get("minValue"), parameter.get("maxValue")) == (low, option.high)


def test_the_estimators_are_core_s():
    """volume_estimator declares them for its own checks; the table must offer the same."""
    assert set(OPTIONS["estimator"].values) == set(volume_estimator.ESTIMATORS)
    assert (OPTIONS["step_rate"].low, OPTIONS["step_rate"].high) == (volume_estimator.MIN_STEP_RATE,
                                                                     volume_estimator.MAX_STEP_RATE)


def test_a_command_line_run_checks_its_time_budget_once(tmp_path, monkeypatch):
    from xsl_render.operators.commands import render

    scene = tmp_path / "scene.blend"
    scene.write_bytes(b"BLENDER-v500" + bytes(64))
    calls = []
    check = GuidedOptions.check
    monkeypatch.setattr(GuidedOptions, "check", lambda self: calls.append(self) or check(self))
    args = build_parser().parse_args(["render", str(scene), "--mode", "guided", "--time-budget", "3",
                                      "--out", str(tmp_path / "o.exr")])
    render.check(args)
    assert len(calls) == 1 and args.request[0].guided.time_budget == 3.0


@pytest.mark.blender
def test_every_panel_property_comes_from_the_table(blender):
    import xsl_render
    from xsl_render.core.panel.settings import SETTINGS, panel_value

    xsl_render.register()
    try:
        group = blender.types.Scene.bl_rna.properties["xsl_render"].fixed_type
        for option in SETTINGS:
            prop = group.properties[option.prop or option.name]
            assert (prop.name, prop.description) == (option.label, option.help)
            if option.kind == "choice":
                assert [item.identifier for item in prop.enum_items] == [v.upper() for v in option.values]
                assert prop.default == panel_value(option, option.panel_value)
            elif option.kind in ("int", "float"):
                assert prop.default == pytest.approx(option.panel_value)
                if option.high is not None:
                    assert prop.hard_max == pytest.approx(option.high)
                if option.low is not None:
                    assert prop.hard_min == pytest.approx(option.low)
        assert group.properties["auto_volumes"].description == OPTIONS["auto_volumes"].help
    finally:
        xsl_render.unregister()


def test_no_module_declares_a_setting_s_range_again():
    """The bounds the table holds are not written again beside a flag (argparse) or in a farm
    parameter: those front ends ask the table."""
    root = Path(__file__).resolve().parent.parent
    for path in (root / "operators" / "commands").glob("*.py"):
        text = path.read_text(encoding="utf-8")
        for flag in ("--time-budget", "--pilot-fraction", "--level-ratio", "--tile-size", "--min-spp"):
            assert f'add_argument("{flag}"' not in text, (path.name, flag)
    farm = (root / "core" / "farm" / "job_parameters.py").read_text(encoding="utf-8")
    assert '"minValue": ' not in farm and "_number(" not in farm
