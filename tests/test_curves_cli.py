"""``xsl-render curves`` end to end on a tiny frame: every curve in curves.json, the plot and
the report written, runs reused by a second call, repeats and medians, and bad values exiting
with one line. The registry (core.validation.contestants) is tested without Blender."""
from __future__ import annotations

import json
import statistics

import numpy as np
import pytest
from support.cli_wording import refused_in_flags
from conftest import xsl_render_cli
from support.fog_scene import saved_fog_scene
from test_cli_info import one_line_error

from xsl_render.core.errors import InputError
from xsl_render.core.imageio import read_image, write_exr
from xsl_render.core.validation.contestants import (CURVES, parse_curves, plan_contestants,
                                                    register_curve, time_matched_curve,
                                                    uniform_budgets)

W, H = 48, 27
TINY = ("--resolution", f"{W}x{H}", "--max-spp", "8", "--reference-spp", "64", "--no-vdp", "--quiet")


# -- the registry ----------------------------------------------------------------------
@pytest.mark.parametrize("ceiling, budgets", [(64, [4, 8, 16, 32, 64]), (8, [1, 2, 4, 8]), (1, [1])])
def test_uniform_budgets(ceiling, budgets):
    assert uniform_budgets(ceiling) == budgets


def test_a_uniform_point_above_the_ceiling_renders_at_its_own_count(blender):
    """A biased curve's bias floor (256 spp) sits above the curves' ceiling (64): its run
    raises the ceiling for itself instead of being refused."""
    from xsl_render.addon.validation.contestants import contestant_request
    from xsl_render.core.sampling.render_options import RenderOptions
    from xsl_render.core.validation.contestants import Contestant

    floor = Contestant("biased_1_256spp", "biased_1", "uniform", "marching 1 256 spp",
                       {"spp": 256, "estimator": "biased", "step_rate": 1.0})
    request = contestant_request(floor, RenderOptions(max_spp=64))
    assert (request.spp, request.options.max_spp, request.options.step_rate) == (256, 256, 1.0)
    below = contestant_request(Contestant("uniform_16spp", "uniform", "uniform", "16", {"spp": 16}),
                               RenderOptions(max_spp=64))
    assert (below.spp, below.options.max_spp) == (16, 64)


def test_the_plan_at_a_ceiling_of_64():
    plan = plan_contestants(64)
    names = [c.name for c in plan]
    assert names[:5] == ["uniform_4spp", "uniform_8spp", "uniform_16spp", "uniform_32spp", "uniform_64spp"]
    assert [c.name for c in plan if c.gold] == ["uniform_64spp"]                 # gold: labelled, once
    adaptive = [c for c in plan if c.curve == "adaptive"]
    assert [c.params for c in adaptive] == [{"noise_threshold": t, "max_spp": 256} for t in (0.1, 0.05, 0.02)]
    assert [c.params["spp"] for c in plan if c.curve == "guiding"] == [16, 32, 64]
    for director in ("xs", "xsl"):
        assert [c.params["max_spp"] for c in plan if c.curve == director] == [16, 32, 64, 128]
    for curve, importance in (("guided", "none"), ("guided_xsl", "xsl")):
        points = [c for c in plan if c.curve == curve]
        assert [c.time_of for c in points] == [f"uniform_{n}spp" for n in (8, 16, 32, 64)]
        assert all(c.kind == "guided" and c.params == {"importance": importance} for c in points)
    assert all(c.time_of is None for c in plan if c.kind != "guided")


def test_a_time_matched_mode_is_one_registration(monkeypatch):
    """How a time-budgeted mode joins: one curve here (and one renderer on the Blender side)."""
    monkeypatch.setattr("xsl_render.core.validation.contestants.CURVES", list(CURVES))
    register_curve(time_matched_curve("guided", "guided sampler", (1 / 4, 1), curve="guided_quick"))
    plan = plan_contestants(64, parse_curves("guided_quick"))
    guided = [c for c in plan if c.curve == "guided_quick"]
    assert [c.time_of for c in guided] == ["uniform_16spp", "uniform_64spp"]
    assert all(c.kind == "guided" for c in guided)
    assert plan[-len(guided):] == guided                    # after the runs they take their time from
    assert {c.curve for c in plan} == {"uniform", "guided_quick"}   # uniform always comes along


@pytest.mark.parametrize("text, message", [("bogus", "unknown curve 'bogus'"), (",", "--curves is empty")])
def test_unknown_curves(text, message):
    with refused_in_flags(message):
        parse_curves(text)


# -- end to end --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def fog_blend(tmp_path_factory):
    return saved_fog_scene(tmp_path_factory.mktemp("scene"), W, H)


@pytest.fixture(scope="module")
def curves(fog_blend, tmp_path_factory):
    out = tmp_path_factory.mktemp("curves") / "out"
    result = xsl_render_cli("curves", fog_blend, "--out", out, *TINY)
    assert result.returncode == 0, result.stderr
    return out, result


def read(out) -> dict:
    return json.loads((out / "curves.json").read_text())


@pytest.mark.blender
@pytest.mark.render
def test_every_curve_and_speedup_in_curves_json(curves):
    out, result = curves
    data = read(out)
    assert list(data["curves"]) == ["uniform", "adaptive", "guiding", "xs", "xsl", "guided", "guided_xsl"]
    assert [data["curves"][c]["baseline"] for c in data["curves"]] == [True, True] + [False] * 5
    assert data["curves"]["uniform"]["points"] == ["uniform_1spp", "uniform_2spp", "uniform_4spp", "uniform_8spp"]
    assert data["reference"]["inputs"]["spp"] == 64 and data["reference"]["inputs"]["seed"] == 7
    assert data["ceiling"] == 8 and data["scene"]["size"] == [W, H] and data["seeds"] == [0]
    assert data["rendered"] == len(data["runs"]) == 4 + 3 + 3 + 4 + 4 + 4 + 4
    assert data["runs"]["uniform_8spp"]["gold"] and "(gold)" in data["runs"]["uniform_8spp"]["label"]
    for name, run in data["runs"].items():
        assert run["seconds"] > 0 and run["flip"] > 0 and run["mse"] > 0 and run["jod"] is None
        (repeat,) = run["repeats"]
        assert repeat["seed"] == 0 and (out / repeat["file"]).is_file()
        assert read_image(out / repeat["file"]).shape == (H, W, 4)
        if run["curve"] in ("uniform", "adaptive"):
            assert set(run["speedups"]) == {"uniform", "adaptive"} - {run["curve"]}
        else:
            assert set(run["speedups"]) == {"uniform", "adaptive"}
        for speedups in run["speedups"].values():
            for metric, speedup in speedups.items():
                if speedup["value"] is not None:
                    assert speedup["faster"] == (speedup["value"] > 1)
                    assert speedup["value"] == pytest.approx(speedup["time_to_reach_s"] / run["seconds"])
    assert data["runs"]["xsl_8"]["repeats"][0]["stats"]["phases_s"]["maps"] > 0      # maps in the time
    guided = data["runs"]["guided_xsl_at_uniform_8spp"]["repeats"][0]["stats"]
    assert guided["phases_s"]["maps"] > 0 and guided["guided"]["importance"] == "xsl"
    assert guided["time_budget_s"] == pytest.approx(data["runs"]["uniform_8spp"]["seconds"])
    # What the guided run decided is kept with its point: its price of a sample and its counts.
    assert guided["seconds_per_pixel_sample"] > 0 and guided["pilot_spp"] >= 1
    assert sum(rect["spp"] * (rect["row1"] - rect["row0"]) * (rect["col1"] - rect["col0"])
               for rect in guided["final_pass"]["rects"]) == guided["final_pass"]["samples"] \
        == guided["total_samples"]                  # the counts rendered, not the plan's
    assert "tiles" not in guided
    assert data["runs"]["adaptive_0.1"]["params"] == {"noise_threshold": 0.1, "max_spp": 32}
    effect = data["runs"]["guiding_8spp"]["repeats"][0]["stats"]["path_guiding"]["effect"]
    assert effect.startswith("used")          # Cycles really guided: the image differs from uniform
    assert data["vdp"] == {"ran": False, "skipped": "not requested (--no-vdp)"}
    png = read_image(out / "curves.png")
    assert png.shape[1] > 1000 and png[..., :3].std() > 0.05
    html = (out / "report.html").read_text()
    assert "data:image/png;base64," in html and "speedup over uniform" in html and "<script" not in html
    lines = result.stdout.splitlines()
    assert lines[0].startswith(f"fog.blend (scene 'Scene', frame 1) at {W}x{H}, ceiling 8 spp; "
                               "reference 64 spp, seed 7 (rendered)")
    assert any(line.startswith("XSL, ceiling 8 spp") for line in lines)
    assert lines[-1] == f"report: {(out / 'report.html').resolve()}"


@pytest.mark.blender
@pytest.mark.render
def test_repeats_reuse_finished_runs_and_report_medians(curves, fog_blend):
    out, _ = curves
    result = xsl_render_cli("curves", fog_blend, "--out", out, "--repeats", "2", "--curves", "adaptive", *TINY)
    assert result.returncode == 0, result.stderr
    data = read(out)
    assert list(data["runs"]) == ["uniform_1spp", "uniform_2spp", "uniform_4spp", "uniform_8spp",
                                  "adaptive_0.1", "adaptive_0.05", "adaptive_0.02"]
    assert (data["rendered"], data["reused"]) == (7, 7)                # seed 0 reused, seed 1 new
    for run in data["runs"].values():
        assert [r["seed"] for r in run["repeats"]] == [0, 1]
        assert [r["reused"] for r in run["repeats"]] == [True, False]
        assert run["seconds"] == pytest.approx(statistics.median(r["seconds"] for r in run["repeats"]))
        assert run["flip"] == pytest.approx(statistics.median(r["flip"] for r in run["repeats"]))
    seeds = [read_image(out / r["file"]) for r in data["runs"]["uniform_1spp"]["repeats"]]
    assert not np.array_equal(*seeds)                                # another seed, another image


@pytest.mark.blender
@pytest.mark.render
def test_a_given_reference_is_checked(fog_blend, tmp_path, curves):
    out, _ = curves
    small = write_exr(tmp_path / "small.exr", np.ones((9, 16, 4), np.float32))
    assert f"is 16x9, the runs render at {W}x{H}" in one_line_error(
        xsl_render_cli("curves", fog_blend, "--out", tmp_path / "o", "--reference", small, *TINY))
    same_seed = write_exr(tmp_path / "seed0.exr", np.ones((H, W, 4), np.float32),
                          attributes={"xsl_render:reference_seed": 0})
    assert "contestant seed 0 is the converged reference's seed" in one_line_error(
        xsl_render_cli("curves", fog_blend, "--out", tmp_path / "o", "--reference", same_seed, *TINY))
    assert not (tmp_path / "o" / "runs").exists()


@pytest.mark.parametrize("extra, message", [
    (("--repeats", "0"), "--repeats: must be a whole number from 1 to 50"),
    (("--repeats", "two"), "--repeats: must be a whole number, not 'two'"),
    (("--repeats", "8"), "contestant seed 7 is the converged reference's seed"),
    (("--seed", "7"), "contestant seed 7 is the converged reference's seed"),
    (("--seed", "-1"), "--seed: must be a whole number from 0 to 2147483647"),
    (("--max-spp", "0"), "--max-spp: must be a whole number from 1 to 1048576"),
    (("--reference-spp", "0"), "--reference-spp: must be a whole number from 1 to 16777216"),
    (("--curves", "bogus"), "unknown curve 'bogus'"),
    (("--reference", "missing.exr"), "--reference: no such reference file"),
])
@pytest.mark.blender          # the command line, as a user runs it
def test_bad_values_exit_2_with_one_line(extra, message, tmp_path):
    from conftest import EXAMPLES

    result = xsl_render_cli("curves", EXAMPLES / "road.blend", "--out", tmp_path / "o", *extra)
    assert message in one_line_error(result)
    assert not (tmp_path / "o").exists()
