"""The guided render's plan as plain numbers: tile scores, the allocation of the samples left,
rounding to levels, the final pass's rectangles, the pacer, the options; and the merge of
passes by sample count."""
from __future__ import annotations

import math

import numpy as np
import pytest
from support.cli_wording import refused_in_flags

from xsl_render.core.errors import InputError
from xsl_render.core.sampling.guided_plan import (FINAL_PASS_PIECES, SCORE_FLOOR, UNBOUNDED_SPP,
                                                  BudgetPacer, GuidedOptions, IMPORTANCE_EXPONENT,
                                                  allocate, error_scores, plan_final_pass,
                                                  round_to_levels, tile_means)
from xsl_render.core.sampling.pass_merge import PassAccumulator
from xsl_render.core.sampling.tile_plan import tile_windows


def test_allocation_adds_exactly_the_samples_given():
    weights = np.array([1.0, 2.0, 4.0, 8.0])
    areas = np.array([100.0, 100.0, 50.0, 25.0])
    totals = allocate(weights, areas, have=2, extra_samples=3000, ceiling=1000)
    assert np.isclose((areas * (totals - 2)).sum(), 3000, rtol=1e-6)
    assert (np.diff(totals) > 0).all()                  # more weight, more samples
    assert np.allclose(totals / weights, totals[-1] / weights[-1])   # proportional above the floor


def test_allocation_keeps_the_pilot_and_the_ceiling():
    weights = np.array([0.01, 1.0, 100.0])
    areas = np.ones(3)
    totals = allocate(weights, areas, have=5, extra_samples=30, ceiling=20)
    assert totals.min() >= 5 and totals.max() <= 20
    assert totals[0] == 5                               # too little weight: only the pilot
    assert totals[2] == 20                              # capped
    assert np.isclose((totals - 5).sum(), 30)


def test_allocation_stops_at_the_ceiling_everywhere():
    totals = allocate(np.ones(3), np.ones(3), have=2, extra_samples=1e9, ceiling=8)
    np.testing.assert_array_equal(totals, 8)


@pytest.mark.parametrize("weights", [[0.0, 0.0], [1.0, np.nan], [-1.0, 1.0]])
def test_allocation_refuses_meaningless_weights(weights):
    with pytest.raises(ValueError):
        allocate(np.array(weights), np.ones(2), have=1, extra_samples=10, ceiling=10)


def test_levels_round_in_log_space_and_keep_zero():
    counts = np.array([0.0, 0.4, 0.6, 1.0, 1.4, 2.0, 3.2, 9.0, 100.0])
    levels = round_to_levels(counts, 2.0)
    np.testing.assert_array_equal(levels, [0, 0, 1, 1, 1, 2, 4, 8, 128])


def test_scores_follow_the_edges_and_never_vanish():
    luminance = np.zeros((64, 64))
    luminance[:, 40:] = 1.0                              # one vertical edge at column 40
    windows = tile_windows(64, 64, 32)
    scores = error_scores(luminance, windows)
    assert scores[1] > 10 * scores[0]                   # the tiles the edge runs through
    assert scores.min() == pytest.approx(SCORE_FLOOR * np.mean(tile_means(np.hypot(*np.gradient(luminance)), windows)))


def test_half_resolution_scores_map_onto_full_resolution_tiles():
    luminance = np.zeros((16, 24))
    luminance[:8, 12:] = 1.0                             # bright top-right quarter (half resolution)
    windows = tile_windows(48, 32, 16)                   # the full frame is 48x32
    means = tile_means(luminance, windows, scale=2)
    assert means[windows.index((0, 16, 32, 48))] == 1.0 and means[windows.index((16, 32, 0, 16))] == 0.0


def _spp_map(final, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Samples per pixel of a final pass, and how many of its rectangles cover each pixel."""
    spp, covered = np.zeros((height, width), int), np.zeros((height, width), int)
    for rect in final.rects:
        spp[rect.row0:rect.row1, rect.col0:rect.col1] = rect.spp
        covered[rect.row0:rect.row1, rect.col0:rect.col1] += 1
    return spp, covered


def test_final_pass_spends_its_samples_where_the_error_is():
    width, height, tile = 96, 64, 32
    windows = tile_windows(width, height, tile)
    scores = np.ones(len(windows))
    scores[0] = 50.0                                     # one tile with much more error
    options = GuidedOptions(time_budget=1.0, exponent=1.0, level_ratio=1.5)
    final = plan_final_pass(scores, None, width, height, options, pixel_samples=20 * width * height,
                            tile_size=tile, ceiling=UNBOUNDED_SPP)
    spp, covered = _spp_map(final, width, height)
    assert covered.min() == covered.max() == 1           # every pixel once
    row0, row1, col0, col1 = windows[0]
    assert spp[row0:row1, col0:col1].min() > np.delete(spp, np.s_[col0:col1], axis=1).max()
    assert abs(final.samples - 20 * width * height) < 0.3 * 20 * width * height   # levels round


def test_exponent_zero_is_uniform():
    options = GuidedOptions(time_budget=1.0, exponent=0.0)
    scores = np.random.default_rng(0).uniform(0.1, 10, size=len(tile_windows(64, 48, 16)))
    final = plan_final_pass(scores, None, 64, 48, options, pixel_samples=6 * 64 * 48,
                            tile_size=16, ceiling=UNBOUNDED_SPP)
    assert {rect.spp for rect in final.rects} == {6} and final.flat


@pytest.mark.parametrize("exponent", [0.0, 1.0])
def test_importance_weighs_the_samples_whatever_the_scores_exponent(exponent):
    options = GuidedOptions(time_budget=1.0, exponent=exponent, level_ratio=1.01)
    importance = np.array([0.05, 1.0])
    final = plan_final_pass(np.ones(2), importance, 64, 32, options, pixel_samples=100 * 64 * 32,
                            tile_size=32, ceiling=UNBOUNDED_SPP)
    spp, _ = _spp_map(final, 64, 32)
    ratio = spp[:, 32:].mean() / spp[:, :32].mean()
    assert ratio == pytest.approx(20 ** IMPORTANCE_EXPONENT, rel=0.05)     # gently: 1.57x


@pytest.mark.parametrize("pixel_samples", [0.0, 10.0, 64 * 48 * 0.5])
def test_every_pixel_gets_a_sample_however_small_the_budget(pixel_samples):
    options = GuidedOptions(time_budget=1.0, exponent=1.0)
    scores = np.random.default_rng(1).uniform(0.1, 10, size=len(tile_windows(64, 48, 16)))
    final = plan_final_pass(scores, None, 64, 48, options, pixel_samples=pixel_samples,
                            tile_size=16, ceiling=UNBOUNDED_SPP)
    covered = np.zeros((48, 64), int)
    for rect in final.rects:
        assert rect.spp >= 1
        covered[rect.row0:rect.row1, rect.col0:rect.col1] += 1
    assert covered.min() == covered.max() == 1


def test_a_flat_plan_is_three_columns():
    options = GuidedOptions(time_budget=1.0, exponent=0.0)
    final = plan_final_pass(np.ones(len(tile_windows(96, 54, 16))), None, 96, 54, options,
                            pixel_samples=32 * 96 * 54, tile_size=16, ceiling=UNBOUNDED_SPP)
    assert final.flat
    assert [rect.window for rect in final.rects] == [(0, 54, 0, 32), (0, 54, 32, 64), (0, 54, 64, 96)]
    assert {rect.spp for rect in final.rects} == {32}


def test_final_pass_comes_in_pieces_the_pacer_can_correct():
    options = GuidedOptions(time_budget=1.0, exponent=1.0, level_ratio=1.5)
    scores = np.ones(len(tile_windows(96, 54, 16)))
    scores[0] = 3.0                                      # not flat: pieces to pace
    final = plan_final_pass(scores, None, 96, 54, options, pixel_samples=32 * 96 * 54,
                            tile_size=16, ceiling=UNBOUNDED_SPP)
    assert len(final.rects) >= FINAL_PASS_PIECES
    assert max(rect.samples for rect in final.rects) <= final.samples / FINAL_PASS_PIECES + 96 * 32
    covered = np.zeros((54, 96), int)
    for rect in final.rects:
        covered[rect.row0:rect.row1, rect.col0:rect.col1] += 1
    assert covered.min() == covered.max() == 1


def test_final_pass_obeys_the_ceiling():
    options = GuidedOptions(time_budget=1.0, exponent=1.0)
    scores = np.random.default_rng(2).uniform(0.1, 10, size=len(tile_windows(64, 48, 16)))
    final = plan_final_pass(scores, None, 64, 48, options, pixel_samples=1e9, tile_size=16, ceiling=5)
    assert {rect.spp for rect in final.rects} == {5}


def test_pacer_rescales_the_renders_still_to_come():
    pacer = BudgetPacer([1.0, 1.0, 2.0], overhead=0.1)
    assert pacer.scale(4.3) == pytest.approx(1.0)       # on schedule
    assert pacer.scale(1.7) == pytest.approx(0.5)       # behind: half the samples for the rest
    assert pacer.scale(100.0) == 2.0                    # far ahead: at most twice the plan
    with pytest.raises(IndexError):
        pacer.scale(1.0)
    assert BudgetPacer([1.0], overhead=0.0).scale(-1.0) == 0.0


@pytest.mark.parametrize("took, ratio", [(2.1, 2.0), (0.6, 0.5), (100.0, 4.0), (0.1, 0.25)])
def test_pacer_plans_the_rest_at_the_rate_the_finished_renders_showed(took, ratio):
    pacer = BudgetPacer([1.0, 1.0, 1.0], overhead=0.1)
    assert pacer.cost_ratio == 1.0
    assert pacer.scale(3.3) == pytest.approx(1.0)
    pacer.record(took, 1.0)                              # the pilot's rate was off by ``ratio``
    assert pacer.cost_ratio == pytest.approx(ratio)      # (clamped to [1/4, 4])
    assert pacer.scale(2.2) == pytest.approx(min(2.0, 1.0 / ratio))   # the rest at the real rate
    assert pacer.scale(1e6) == 2.0                                    # never past twice the plan
    pacer.record(1.0, 0.0)                               # nothing planned: nothing learnt
    assert pacer.cost_ratio == pytest.approx(ratio)


def test_side_by_side_renders_are_capped_against_the_repriced_plan():
    pacer = BudgetPacer([1.0, 1.0], overhead=0.0, side_by_side=True)
    pacer.scale(2.0)
    pacer.record(0.25, 1.0)                              # the pilot overstated the cost 4x
    assert pacer.scale(100.0) == pytest.approx(8.0)      # twice the re-priced plan


@pytest.mark.parametrize("field, value, message", [
    ("time_budget", 0.0, "--time-budget"), ("time_budget", -1.0, "--time-budget"),
    ("time_budget", math.nan, "--time-budget"), ("time_budget", math.inf, "--time-budget"),
    ("pilot_fraction", 0.0, "--pilot-fraction"), ("pilot_fraction", 1.5, "--pilot-fraction"),
    ("exponent", -0.1, "--guided-exponent"), ("exponent", math.nan, "--guided-exponent"),
    ("importance", "s", "--importance"),
    ("level_ratio", 1.0, "--level-ratio"),
])
def test_bad_guided_options_are_refused(field, value, message):
    options = GuidedOptions(time_budget=2.0)
    with refused_in_flags(message):
        GuidedOptions(**{**options.to_dict(), field: value}).check()


def test_merge_weights_passes_by_their_samples():
    merged = PassAccumulator(4, 2, channels=1)
    merged.add(None, np.full((2, 4, 1), 1.0), 4)
    merged.add((0, 1, 0, 2), np.full((1, 2, 1), 3.0), 12)
    counts = np.array([[2.0, 6.0]])
    merged.add((1, 2, 2, 4), np.full((1, 2, 1), 5.0), counts)
    result = merged.result()[..., 0]
    assert result[0, 0] == pytest.approx((4 * 1 + 12 * 3) / 16)
    assert result[1, 2] == pytest.approx((4 * 1 + 2 * 5) / 6) and result[1, 3] == pytest.approx((4 + 30) / 10)
    assert result[1, 0] == 1.0
    np.testing.assert_array_equal(merged.samples, [[16, 16, 4, 4], [4, 4, 6, 10]])


def test_merge_refuses_gaps_and_bad_passes():
    merged = PassAccumulator(4, 2, channels=1)
    merged.add((0, 1, 0, 4), np.ones((1, 4, 1)), 1)
    with pytest.raises(ValueError, match="no sample"):
        merged.result()
    with pytest.raises(ValueError):
        merged.add((0, 3, 0, 4), np.ones((3, 4, 1)), 1)
    with pytest.raises(ValueError):
        merged.add((0, 1, 0, 4), np.ones((1, 4, 1)), -1)
