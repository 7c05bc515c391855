"""Auto Volumes' plan for a shot, bpy-free: the frames predicted, the most cautious choice,
the samples a frame's own settings give auto's tolerance."""
from __future__ import annotations

import pytest

from xsl_render.core.sampling.shot_plan import (caution, estimator_samples, layer_samples, most_cautious,
                                                sampled_frames, shot_of)
from xsl_render.core.sampling.volume_estimator import EstimatorChoice


def test_a_frame_in_the_range_belongs_to_it_and_one_outside_is_a_shot_of_its_own():
    assert shot_of(5, 1, 8) == (1, 8) == shot_of(1, 1, 8) == shot_of(8, 1, 8)
    assert shot_of(9, 1, 8) == (9, 9) and shot_of(0, 1, 8) == (0, 0)


def test_the_sampled_frames_depend_on_the_shot_only():
    assert sampled_frames((1, 8), animated=True) == (1, 3, 5, 6, 8)
    assert sampled_frames((1, 250), animated=True) == (1, 63, 126, 188, 250)
    assert sampled_frames((1, 3), animated=True) == (1, 2, 3)
    assert sampled_frames((1, 250), animated=False) == (1,)
    assert sampled_frames((7, 7), animated=True) == (7,)


def _marching(rate, media=None):
    return EstimatorChoice("auto", biased=True, step_rate=rate, medium_rates=media)


def test_the_most_cautious_choice_keeps_the_scene_then_null_scattering_then_the_finest_step():
    scene, null = EstimatorChoice("auto", reason="unsure"), EstimatorChoice("auto", biased=False)
    assert most_cautious([_marching(1.0), _marching(0.5), _marching(2.0)]) == 1
    assert most_cautious([_marching(0.25), null, _marching(0.5)]) == 1
    assert most_cautious([_marching(0.25), null, scene]) == 2
    assert most_cautious([_marching(0.5, {"material:smoke": 4.0}), _marching(0.5)]) == 1
    assert most_cautious([_marching(0.5), _marching(0.5)]) == 0           # the earliest of equals
    assert caution(_marching(None)) > caution(_marching(100.0))           # the scene's own rate: unknown
    with pytest.raises(ValueError):
        most_cautious([])


@pytest.mark.parametrize("scene, layer, mode, expected", [
    (64, 0, "USE", 64), (64, 16, "USE", 16), (64, 128, "BOUNDED", 64), (64, 16, "BOUNDED", 16),
    (64, 16, "IGNORE", 64)])
def test_a_view_layer_renders_its_own_samples_where_the_scene_says_so(scene, layer, mode, expected):
    assert layer_samples(scene, layer, mode) == expected


def test_adaptive_sampling_counts_the_noise_its_threshold_leaves_within_its_samples():
    assert estimator_samples(64) == 64.0
    assert estimator_samples(4096, adaptive=True, threshold=0.01) < 4096
    looser = estimator_samples(4096, adaptive=True, threshold=0.05)
    assert looser < estimator_samples(4096, adaptive=True, threshold=0.01)
    assert estimator_samples(16, adaptive=True, threshold=0.0001) == 16.0          # the ceiling
    # Measured (bench/bench_adaptive_noise.py): 48 / 51 / 47 spp at 0.1, 59 / 54 / 48 at 0.05,
    # 208 / 116 / 91 at 0.02: the count is never below what was measured.
    for threshold, measured in ((0.1, 51), (0.05, 59), (0.02, 208)):
        assert estimator_samples(4096, adaptive=True, threshold=threshold) >= measured
    # Past the minimum samples every pixel takes (given, or Cycles' automatic one).
    assert estimator_samples(4096, adaptive=True, threshold=0.5, min_samples=100) == 160.0
    assert estimator_samples(4096, adaptive=True, threshold=0.5) == 32.0          # ceil(16 / 0.5^0.3) x 1.6
    # Threshold 0: Cycles' automatic one, 1 / samples.
    assert estimator_samples(100, adaptive=True, threshold=0.0) == estimator_samples(100, adaptive=True,
                                                                                      threshold=0.01)
