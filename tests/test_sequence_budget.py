"""The time of a guided range as plain numbers: the first frame's sync paid back, counts
held from frame to frame, a sample priced over the last frames, the denoise's cost carried."""
from __future__ import annotations

import pytest

from xsl_render.core.sampling.sample_counts import BUDGET_OVERRUN, HOLD_RANGE
from xsl_render.core.sampling.sequence_budget import (LAST_FRAMES_UNRAISED, MIN_FRAME_SHARE, PILOT_MISPRICED,
                                                      RATE_WINDOW, SequenceBudget)


def test_a_sequence_pays_its_first_frames_sync_back_over_the_rest():
    sequence = SequenceBudget(per_frame=2.0, frames=5)
    assert sequence.next_budget() == 2.0                 # the first frame: its sync comes on top
    sequence.record(2.0 + 4.0)                           # ... 4 s of octree
    assert sequence.next_budget() == pytest.approx(1.0)  # (10 - 6) / 4
    for _ in range(4):
        sequence.record(sequence.next_budget())
    assert sequence.spent == pytest.approx(10.0)         # the range kept its 5 x 2 s


def test_a_sequence_never_starves_a_frame():
    sequence = SequenceBudget(per_frame=2.0, frames=2)
    sequence.record(9.0)
    assert sequence.next_budget() == MIN_FRAME_SHARE * 2.0


def test_a_later_frame_keeps_the_count_of_the_frame_before_while_it_fits():
    sequence = SequenceBudget(per_frame=2.0, frames=4)
    # One sample per pixel of the frame costs 0.1 s: the range's allowance (5 % of 8 s)
    # shared by the 4 frames left is 1 sample per pixel each.
    cost = 0.1
    allowance = BUDGET_OVERRUN * 2.0 * 4 / 4 / cost
    assert sequence.steady_count(18.0, 4096, cost) == 16        # no frame before: a fresh count
    sequence.observe(1.0, 1e6, 16)
    assert (sequence.rate, sequence.spp) == (1e-6, 16)
    high = HOLD_RANGE[1]
    for affordable in (16 - allowance, 16.0, 19.0, high * 16):  # within the range: held
        assert sequence.steady_count(affordable, 4096, cost) == 16
    assert sequence.steady_count(16 - allowance - 0.5, 4096, cost) == 14   # too dear now: fewer
    assert sequence.steady_count(2 * 16, 4096, cost) == 32      # much more time: more
    assert sequence.steady_count(16.0, 8, cost) == 8            # never above the ceiling
    sequence.observe(0.0, 1e6, 4)                               # nothing measured: kept
    assert sequence.spp == 16
    for _ in range(3):
        sequence.record(2.0)
    # The last frame: the whole allowance is its own (4 spp), so a frame that affords 12 holds 16.
    assert sequence.steady_count(12.0, 4096, cost) == 16
    # Too dear for 16: a fresh count (7), raised to the power of two the allowance reaches.
    assert sequence.steady_count(7.5, 4096, cost) == 8


@pytest.mark.parametrize("done, affordable, count", [
    (4, 40.0, 32), (4, 30.5, 32), (4, 21.0, 16),    # 4 frames left: a fresh count past 1.3x
    (5, 40.0, 16), (5, 30.5, 16), (7, 60.0, 16),    # the last 3: held as it is
    (5, 13.5, 16), (5, 12.0, 12), (5, 10.0, 8)])    # and let go of when too dear
def test_a_range_does_not_raise_its_count_in_its_last_frames(done, affordable, count):
    assert LAST_FRAMES_UNRAISED == 3
    # 8 frames of 4 s, a sample per pixel of the frame 0.2 s: the allowance is 2 spp a frame
    # with 4 frames left, 2.7 with 3.
    sequence = SequenceBudget(per_frame=4.0, frames=8)
    sequence.observe(3.2, 1.6e7, 16)
    for _ in range(done):
        sequence.record(4.0)
    assert sequence.steady_count(affordable, 4096, 0.2) == count


@pytest.mark.parametrize("frames, done, affordable, count", [
    (2, 1, 33.0, 32), (2, 1, 64.0, 64), (2, 1, 31.0, 16),   # the second frame: the pilot's price
    (3, 1, 50.0, 50), (3, 2, 50.0, 16), (4, 2, 60.0, 16)])  # undone at twice it, not later
def test_a_ranges_second_frame_undoes_a_first_frame_its_pilot_priced_too_dear(frames, done, affordable,
                                                                              count):
    assert PILOT_MISPRICED == 2.0
    # Frames of 4 s, a sample per pixel of the frame 0.2 s; the first frame rendered 16.
    sequence = SequenceBudget(per_frame=4.0, frames=frames)
    sequence.observe(3.2, 1.6e7, 16)
    for _ in range(done):
        sequence.record(2.0)
    assert sequence.steady_count(affordable, 4096, 0.2) == count


def test_the_first_frame_of_a_range_takes_the_count_its_frames_can_hold():
    # 8 frames of 8 s, a sample per pixel 0.25 s: the allowance is 1.6 spp a frame.
    sequence = SequenceBudget(per_frame=8.0, frames=8)
    assert sequence.steady_count(30.5, 4096, 0.25) == 32      # 30 + 1.6 reaches 32
    assert sequence.steady_count(29.5, 4096, 0.25) == 29      # it does not
    assert sequence.steady_count(20.0, 4096, 0.25) == 16      # rounded down (sobol_friendly)
    assert sequence.steady_count(29.5, 24, 0.25) == 24        # the ceiling


def test_a_later_frame_prices_a_sample_over_the_last_frames():
    sequence = SequenceBudget(per_frame=2.0, frames=8)
    sequence.observe(1.0, 1e6, 16)
    sequence.observe(3.0, 1e6, 16)                              # a dearer view: priced together
    assert sequence.rate == pytest.approx(2e-6)
    for _ in range(RATE_WINDOW):
        sequence.observe(1.0, 2e6, 16)                          # the dear frame leaves the window
    assert sequence.rate == pytest.approx(0.5e-6)
    assert "recent" not in sequence.to_dict() and sequence.to_dict()["rate"] == sequence.rate


def test_a_range_carries_its_frames_denoise_seconds_and_guide_noise():
    sequence = SequenceBudget(per_frame=2.0, frames=4)
    assert (sequence.denoise_plain_s, sequence.denoise_prefiltered_s, sequence.guides_noisy) == (None, None, None)
    sequence.observe_denoise(0.35, prefiltered=True, noisy=True)
    sequence.observe_denoise(0.08, prefiltered=False, noisy=True)     # noisy, but not afforded
    assert (sequence.denoise_plain_s, sequence.denoise_prefiltered_s) == (0.08, 0.35)
    sequence.observe_denoise(0.07, prefiltered=False, noisy=False)
    assert (sequence.denoise_plain_s, sequence.guides_noisy) == (0.07, False)
    assert sequence.to_dict()["denoise_prefiltered_s"] == 0.35
