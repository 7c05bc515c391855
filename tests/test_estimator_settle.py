"""A time-budgeted run settles auto's estimator for the count its budget affords.

Auto chooses before rendering, for a count of samples per pixel; a guided render learns its
count only from its pilot. The choice made for its ceiling is stricter than a run that never
reaches the ceiling needs (street at 64 spp's tolerance chose null scattering, whose octree
took most of a 16-spp budget), so the pilot renders with a provisional choice and the render
settles it afterwards, from the predictions already made.
"""
from __future__ import annotations

import json

import pytest

from xsl_render.core.sampling.volume_estimator import (EstimatorChoice, settled_for,
                                                       choose_step_rate, chosen_spp, fixed_choice,
                                                       provisional_choice, tolerated_bias)

#: Visible-error measures of a scene, coarse to fine (the two-media test scene's, rounded).
MEASURES = {4.0: 0.16, 2.0: 0.11, 1.0: 0.04, 0.5: 0.008, 0.25: 0.0018}


#: The measures here are written against a tolerance of 0.05 / sqrt(spp) (conftest).
pytestmark = pytest.mark.usefixtures("tolerance_units")


def _auto(spp: float) -> EstimatorChoice:
    return choose_step_rate(MEASURES.__getitem__, spp)


@pytest.mark.parametrize("ceiling, count, rate", [
    (4096, 512, 0.25),       # null at the ceiling; 0.25 passes at 512 spp
    (4096, 16, 0.5),
    (64, 4, 0.5),            # 0.25 at the ceiling, 0.5 at 4 spp
    (64, 1, 1.0),
    (16, 64, 0.5),           # more than the choice's count: its own count
])
def test_a_smaller_count_settles_on_the_rate_auto_chooses_for_it(ceiling, count, rate):
    settled = settled_for(_auto(ceiling), count)
    assert settled.biased and settled.step_rate == rate
    assert settled == _auto(min(count, ceiling)) or settled.tried != _auto(min(count, ceiling)).tried
    assert settled.step_rate == _auto(min(count, ceiling)).step_rate
    assert settled.tolerance == pytest.approx(tolerated_bias(min(count, ceiling)))


@pytest.mark.parametrize("first, count, rate, predicted", [
    (16, 512, 0.25, (0.5, 0.25)),      # 0.5 at 16 spp; 512 needs 0.25, predicted now
    (16, 32, 0.5, ()),                 # 0.5 passes at 32 spp's tolerance too (0.8 % <= 0.88 %)
    (16, 64, 0.25, (0.25,)),           # not at 64's (0.63 %): 0.25 predicted
    (64, 4, 0.5, ()),                  # fewer: from the trials made
])
def test_a_choice_that_keeps_its_prediction_settles_finer_too(first, count, rate, predicted):
    """A still's time budget chooses for at most 16 spp first; where its pilot affords more,
    the settle predicts the finer rates it needs (only those not tried yet)."""
    from dataclasses import replace

    calls = []

    def measure(rate):
        calls.append(rate)
        return MEASURES[rate]
    chosen = replace(choose_step_rate(measure, first), remeasure=measure)
    calls.clear()
    settled = settled_for(chosen, count)
    assert settled.step_rate == rate and tuple(calls) == tuple(r for r in predicted if r not in chosen.tried)
    assert settled.tolerance == pytest.approx(tolerated_bias(count))
    assert set(chosen.tried) <= set(settled.tried)
    # Without the prediction a larger count is taken as the choice's own.
    assert settled_for(replace(chosen, remeasure=None), 1024).tolerance == pytest.approx(chosen.tolerance)


def test_settling_needs_no_new_prediction():
    calls = []

    def measure(rate):
        calls.append(rate)
        return MEASURES[rate]

    at_ceiling = choose_step_rate(measure, 4096)
    asked = len(calls)
    assert settled_for(at_ceiling, 4).step_rate == 0.5
    assert len(calls) == asked
    assert settled_for(at_ceiling, 4).tried == at_ceiling.tried


def test_the_provisional_choice_marches_where_auto_chose_null_scattering():
    null = _auto(1e6)
    assert null.biased is False
    provisional = provisional_choice(null)
    assert provisional.biased and provisional.step_rate == 0.25
    assert chosen_spp(provisional) == pytest.approx(1e6)
    marching = _auto(64)
    assert provisional_choice(marching) is marching
    hopeless = choose_step_rate(lambda rate: 0.5, 64)          # 50 %: null at any count
    assert hopeless.biased is False and provisional_choice(hopeless) is hopeless


@pytest.mark.parametrize("choice", [
    fixed_choice("scene", None), fixed_choice("unbiased", None), fixed_choice("biased", 2.0),
    EstimatorChoice("auto", biased=True, step_rate=None, predicted_bias=0.0,
                    reason="homogeneous media only"),
    EstimatorChoice("auto", biased=False, reason="a medium only Cycles evaluates"),
])
def test_choices_without_predictions_stay_as_they_are(choice):
    assert provisional_choice(choice) is choice
    assert settled_for(choice, 4) is choice


@pytest.mark.blender
@pytest.mark.render
def test_guided_switches_to_the_settled_estimator_and_restores_the_scene(blender, monkeypatch):
    """The pilot renders with the provisional choice; a settled choice that differs is what
    Cycles renders the final pass with (after a new sync and pilot) and what the stats
    record; the scene's own settings come back."""
    from test_ray_marching import _two_media_scene

    from xsl_render.addon.cycles import guided_render
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.addon.scene.state import settings_dump
    from xsl_render.core.sampling.guided_plan import GuidedOptions
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = 48, 27
    scene.cycles.volume_biased, scene.cycles.volume_step_rate = False, 1.7
    before = settings_dump(scene)
    options = with_estimator_choice(scene, RenderOptions(max_spp=4096, estimator="auto").check(), 4096)
    assert options.estimator_choice.biased is False             # null scattering at the ceiling
    seen, settled = [], EstimatorChoice("auto", True, 2.0, 0.11, 0.1, dict(MEASURES), "forced")
    real_render = CyclesWindowRenderer.render

    def spying(self, *args, **kwargs):
        seen.append((self.scene.cycles.volume_biased, round(self.scene.cycles.volume_step_rate, 3)))
        return real_render(self, *args, **kwargs)

    monkeypatch.setattr(CyclesWindowRenderer, "render", spying)
    monkeypatch.setattr(guided_render, "settled_for", lambda choice, spp: settled)
    outcome = guided_render.render_guided(scene, options, GuidedOptions(time_budget=3.0))
    # sync and pilot (1 + more samples) provisional, then sync, pilot and the final pass settled
    assert seen[0] == (True, 0.25) and seen[-1] == (True, 2.0)
    assert seen.index((True, 2.0)) >= 2 and set(seen) == {(True, 0.25), (True, 2.0)}
    assert outcome.stats.estimator["step_rate"] == 2.0 and outcome.stats.estimator["reason"] == "forced"
    assert outcome.stats.phases_s["estimator"] == pytest.approx(options.estimator_choice.seconds)
    assert settings_dump(scene) == before


@pytest.mark.blender
@pytest.mark.render
def test_a_guided_range_keeps_the_choice_made_for_its_ceiling(cli, blender, tmp_path):
    """A range pays null scattering's octree once for all its frames, so its frames keep
    auto's choice for the ceiling, one for the shot (ray marching's cost per sample decides
    there); a still settles its choice for its budget's count."""
    from test_ray_marching import _two_media_scene

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = 48, 27
    path = tmp_path / "two.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    common = ("--mode", "guided", "--time-budget", "2", "--max-spp", "4096", "--quiet")
    result = cli("render", path, *common, "--frames", "1-2", "--out", tmp_path / "f_#.exr",
                 "--stats", tmp_path / "f.json")
    assert result.returncode == 0, result.stderr
    frames = json.loads((tmp_path / "f.json").read_text())["frames"]
    assert [f["estimator"]["tolerance"] for f in frames] == pytest.approx([tolerated_bias(4096)] * 2)
    assert [f["estimator"]["biased"] for f in frames] == [False, False]
    assert frames[0]["estimator"]["tried"]
    assert {**frames[1]["estimator"], "seconds": 0.0} == {**frames[0]["estimator"], "seconds": 0.0}   # one per shot
    assert frames[1]["estimator"]["seconds"] == 0.0 < frames[0]["estimator"]["seconds"]    # predicted once
    assert frames[1]["cycles_sync_s"] < 0.5 * frames[0]["cycles_sync_s"] + 0.05
    still = cli("render", path, *common, "--out", tmp_path / "s.exr", "--stats", tmp_path / "s.json")
    assert still.returncode == 0, still.stderr
    chosen = json.loads((tmp_path / "s.json").read_text())["estimator"]
    assert chosen["tolerance"] > tolerated_bias(4096)              # settled for the count it afforded


@pytest.mark.blender
@pytest.mark.render
def test_guided_with_a_fixed_estimator_records_its_options_as_given(blender):
    """Only auto's choice is settled: a fixed estimator's options reach the stats unchanged."""
    from test_ray_marching import _two_media_scene

    from xsl_render.addon.cycles.guided_render import render_guided
    from xsl_render.core.sampling.guided_plan import GuidedOptions
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = 32, 18
    options = RenderOptions(max_spp=8, estimator="scene").check()
    outcome = render_guided(scene, options, GuidedOptions(time_budget=1.0))
    assert outcome.stats.options == options.to_dict()
    assert outcome.stats.estimator["estimator"] == "scene"
