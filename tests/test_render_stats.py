"""``core.sampling.render_stats``: the typed statistics of a run and the budget another run
takes from them, read back from JSON as they were written."""
from __future__ import annotations

import json
import math

import pytest

from xsl_render.core.errors import InputError
from xsl_render.core.sampling.guided_plan import GuidedOptions
from xsl_render.core.sampling.render_stats import FrameMaps, RecordedBudget, RenderStats, sequence_stats


def make_stats(**extra) -> RenderStats:
    return RenderStats(mode="xsl", scene="Scene", resolution=(4, 2), max_spp=8, seed=0,
                       phases_s={"maps": 0.5, "renders": 1.0, "denoise": 0.25}, total_samples=40,
                       mean_spp=5.0, gold_samples=64, renders=2, tiles=[{"spp": 8}], options={},
                       estimator={"estimator": "scene"}, **extra)


def test_wall_time_is_the_sum_of_the_phases_and_equal_time_leaves_out_denoising():
    stats = make_stats()
    assert stats.wall_s == 1.75 and stats.render_seconds == 1.5
    stats.phases_s["write"] = 0.25                   # a phase added later counts at once
    assert stats.wall_s == 2.0 and stats.phase("write") == 0.25 and stats.phase("sync") == 0.0


def test_json_leaves_out_what_was_not_recorded_and_reads_back_the_same():
    stats = make_stats(guided=GuidedOptions(time_budget=3.0), cycles_sync_s=0.1,
                       maps=FrameMaps(1, {"total": 0.5}, True, "rays.npz", []))
    data = json.loads(json.dumps(stats.to_json()))
    assert data["wall_s"] == 1.75 and data["resolution"] == [4, 2]
    assert data["guided"]["time_budget"] == 3.0 and data["maps"]["ray_cache_hit"] is True
    assert "plan" not in data and "budget_from" not in data and "frame" not in data
    again = RenderStats.from_json(data)
    assert again == stats and again.guided.time_budget == 3.0 and again.maps.ray_cache_hit
    assert stats.to_json(keep=("mode", "wall_s")) == {"mode": "xsl", "wall_s": 1.75}


def test_a_frame_range_sums_its_frames():
    first = make_stats(maps=FrameMaps(1, {}, False, None, []), cycles_sync_s=2.0)
    second = make_stats(maps=FrameMaps(2, {}, True, None, []))
    data = sequence_stats([first, second], "xsl", "a.blend", "f_#.exr", "1-2", 9.0)
    assert data["total_samples"] == 80 and data["ray_cache_hits"] == 1 and data["cycles_sync_s"] == 2.0
    assert [frame["maps"]["frame"] for frame in data["frames"]] == [1, 2]


def test_a_budget_read_from_a_stats_file():
    budget = RecordedBudget.from_json(make_stats().to_json(), "s.json")
    assert (budget.mean_spp, budget.wall_s, budget.denoise_s) == (5.0, 1.75, 0.25)
    assert budget.render_seconds == 1.5


@pytest.mark.parametrize("data, message", [
    ([], "s.json is not a stats file written by xsl-render render"),
    ({"wall_s": 1.0}, "not a stats file written by xsl-render render"),
    ({"wall_s": 1.0, "mean_spp": 4, "phases_s": []}, "phases_s must be an object of seconds"),
    ({"wall_s": "1", "mean_spp": 4}, "wall_s must be a number"),
    ({"wall_s": True, "mean_spp": 4}, "wall_s must be a number"),
    ({"wall_s": math.inf, "mean_spp": 4}, "wall_s"),
    ({"wall_s": 1.0, "mean_spp": -1}, "mean_spp"),
    ({"wall_s": 1.0, "mean_spp": 4, "phases_s": {"denoise": None}}, "phases_s.denoise must be a number"),
])
def test_a_budget_refuses_what_no_run_writes(data, message):
    with pytest.raises(InputError, match=message):
        RecordedBudget.from_json(data, "s.json")
