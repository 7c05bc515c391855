"""The render request every front end builds (``core.sampling.render_request``): checked once,
its errors naming settings (the command line words them as its flags)."""
from __future__ import annotations

from types import SimpleNamespace

import pytest
from support.cli_wording import refused_in_flags

from xsl_render.core.checks import MAX_SAMPLES
from xsl_render.core.errors import SettingError
from xsl_render.core.maps.options import MapOptions
from xsl_render.core.sampling.guided_plan import GuidedOptions
from xsl_render.core.sampling.render_options import UNBOUNDED_SPP, RenderOptions
from xsl_render.core.sampling.render_request import (GUIDED_SPP, MODE_TRAITS, MODES, SELECTIVE_MODES,
                                                     RenderRequest)

OPTIONS = RenderOptions(max_spp=64)
UNBOUNDED = RenderOptions(max_spp=UNBOUNDED_SPP)
GUIDED = GuidedOptions(time_budget=5.0)


@pytest.mark.parametrize("request_, spp", [
    (RenderRequest("gold", OPTIONS), 64.0),
    (RenderRequest("uniform", OPTIONS, spp=16), 16.0),
    (RenderRequest("uniform", OPTIONS, seconds=3.0), 64.0),
    (RenderRequest("adaptive", OPTIONS, seconds=3.0, noise_threshold=0.05), 64.0),
    (RenderRequest("adaptive", OPTIONS, noise_threshold=0.05), 64.0),      # up to the ceiling
    (RenderRequest("xs", OPTIONS, map_options=MapOptions()), 64.0),
    (RenderRequest("xsl", OPTIONS), 64.0),                                  # its map from a file
    (RenderRequest("guided", UNBOUNDED, guided=GUIDED), float(GUIDED_SPP)),         # no ceiling
    (RenderRequest("guided", RenderOptions(max_spp=8), guided=GUIDED), 8.0),
])
def test_requests_each_mode_takes(request_, spp):
    assert request_.check() is request_
    assert request_.mode in MODES
    assert request_.estimator_spp == spp             # what auto's bias tolerance is set for
    assert request_.unbounded == (request_.options is UNBOUNDED)


@pytest.mark.parametrize("request_, still, spp", [
    (RenderRequest("guided", OPTIONS, guided=GUIDED), True, float(GUIDED_SPP)),   # settles later
    (RenderRequest("guided", OPTIONS, guided=GUIDED), False, 64.0),              # a range keeps it
    (RenderRequest("guided", RenderOptions(max_spp=8), guided=GUIDED), True, 8.0),
    (RenderRequest("uniform", OPTIONS, spp=32), True, 32.0),
    (RenderRequest("xs", OPTIONS, map_options=MapOptions()), True, 64.0),
])
def test_a_stills_time_budget_chooses_for_a_modest_count_first(request_, still, spp):
    assert request_.check().first_estimator_spp(still) == spp


@pytest.mark.parametrize("request_, message", [
    (RenderRequest("fast", OPTIONS), "--mode must be one of gold, xs"),
    (RenderRequest("guided", OPTIONS), "--mode guided needs --time-budget SECONDS"),
    (RenderRequest("uniform", OPTIONS, spp=8, guided=GUIDED),
     r"--time-budget is for --mode guided \(use --equal-time with --mode uniform\)"),
    (RenderRequest("gold", OPTIONS, spp=8), "--spp is for --mode uniform"),
    (RenderRequest("uniform", OPTIONS, spp=128), "--spp 128 is above --max-spp 64, the ceiling of every mode"),
    (RenderRequest("uniform", OPTIONS), "--mode uniform needs either --spp or --equal-time"),
    (RenderRequest("uniform", OPTIONS, spp=8, seconds=2.0), "--mode uniform needs either --spp or --equal-time"),
    (RenderRequest("uniform", OPTIONS, seconds=float("nan")), "--equal-time must be positive"),
    (RenderRequest("adaptive", OPTIONS, seconds=-1.0), "--equal-time must be positive"),
    (RenderRequest("xsl", OPTIONS, seconds=2.0), "--equal-time is for --mode uniform and adaptive"),
    (RenderRequest("guided", RenderOptions(max_spp=70000), guided=GUIDED), "--max-spp must be between 1 and 65536"),
    (RenderRequest("adaptive", OPTIONS, noise_threshold=0.0), r"--noise-threshold must be in \(0, 1\]"),
    (RenderRequest("uniform", RenderOptions(max_spp=4, min_spp=8), spp=2), "--min-spp 8 is larger than --max-spp 4"),
    (RenderRequest("guided", OPTIONS, guided=GuidedOptions(time_budget=0.0)), "--time-budget must be greater than 0"),
])
def test_impossible_requests_are_refused_naming_the_setting(request_, message):
    """(Every rule reads the mode's ``MODE_TRAITS``, not its name.)"""
    with refused_in_flags(message) as refused:
        request_.check()
    assert isinstance(refused.value, SettingError)
    assert "--" not in str(refused.value)            # core names fields; the front end words them


def test_the_budget_source_is_recorded():
    request = RenderRequest("uniform", OPTIONS, spp=12, budget_from="run.json", budget_mean_spp=11.6)
    stats = SimpleNamespace(budget_from=None, budget_mean_spp=None)
    request.record_budget(stats)
    assert (stats.budget_from, stats.budget_mean_spp) == ("run.json", 11.6)
    RenderRequest("gold", OPTIONS).record_budget(stats)
    assert (stats.budget_from, stats.budget_mean_spp) == (None, None)


def test_every_mode_has_its_traits():
    assert set(MODE_TRAITS) == set(MODES) and SELECTIVE_MODES == ("xs", "xsl")
    assert {MODE_TRAITS[mode].budget_from for mode in MODES} == {None, "spp", "seconds"}


def test_counts_left_to_the_scene_are_its_samples_once_it_is_open():
    """The command line's counts default to the scene's samples: a request checked before the
    scene opens, with a stand-in ceiling, gets them (and is checked again) once it is open."""
    stand_in = RenderOptions(max_spp=MAX_SAMPLES)
    uniform = RenderRequest("uniform", stand_in, scene_samples=True).check().at_scene_samples(24)
    assert (uniform.spp, uniform.options.max_spp, uniform.scene_samples) == (24, 24, False)
    budgeted = RenderRequest("uniform", stand_in, spp=40, scene_samples=True).check().at_scene_samples(24)
    assert (budgeted.spp, budgeted.options.max_spp) == (40, 40)       # a budget file's count stays
    timed = RenderRequest("uniform", stand_in, seconds=2.0, scene_samples=True).at_scene_samples(24)
    assert (timed.spp, timed.options.max_spp) == (None, 24)
    gold = RenderRequest("gold", RenderOptions(max_spp=MAX_SAMPLES, min_spp=8), scene_samples=True).check()
    with refused_in_flags("--min-spp 8 is larger than --max-spp 4"):
        gold.at_scene_samples(4)
    given = RenderRequest("gold", OPTIONS)
    assert given.at_scene_samples(24) is given
    with pytest.raises(SettingError, match="needs either"):          # only a stand-in may lack both
        RenderRequest("uniform", OPTIONS).check()
