"""Counts a guided frame renders at: powers of two kept, one count per frame, and the
denoising guides' prefilter not bought with a power of two."""
from __future__ import annotations

import pytest

from xsl_render.core.sampling.sample_counts import (column_count, power_of_two_within,
                                                    sobol_friendly, still_count)


@pytest.mark.parametrize("count, friendly", [(0, 1), (1, 1), (2, 2), (3, 3), (5, 4), (6, 6), (9, 8), (11, 8),
                                             (12, 12), (16, 16), (19, 16), (23, 16), (24, 24), (39, 32),
                                             (47, 32), (48, 48), (70, 70), (600, 600)])
def test_a_whole_frame_count_just_above_a_power_of_two_is_rounded_down_to_it(count, friendly):
    assert sobol_friendly(count) == friendly


@pytest.mark.parametrize("count, reach, ceiling, expected", [
    (29, 32.3, 4096, 32), (29, 31.9, 4096, 29), (16, 22.0, 4096, 16), (40, 70.0, 4096, 64),
    (29, 40.0, 30, 29), (7, 15.5, 4096, 8), (1, 0.5, 4096, 1)])
def test_a_range_raises_its_count_to_the_power_of_two_its_allowance_reaches(count, reach, ceiling, expected):
    assert power_of_two_within(count, reach, ceiling) == expected


@pytest.mark.parametrize("held, affordable, frame, count", [
    (16, 16, 16, 16), (16, 14, 16, 16), (16, 13, 16, 13),   # held down to 85 % of the count before
    (16, 32, 21, 16), (16, 47, 23.5, 16), (16, 40, 23, 16),  # the slack of a rounding down: held
    (16, 31, 31, 31), (16, 32, 32, 32), (16, 47, 40, 32),   # the frame affords more: priced too
    (4, 29, 18, 29), (4, 20, 20, 16), (16, 40, 25, 32),     # dear, the later columns spend the
    (55, 95, 80, 95), (55, 60, 56, 60), (55, 95, 55, 55),   # time the first left
    (8, 5, 8, 4), (12, 12, 12, 12), (12, 30, 30, 30), (1, 1, 1, 1), (1, 3, 3, 3), (16, 11, 16, 8),
])
def test_later_columns_of_a_flat_pass_hold_one_count_unless_the_first_was_priced_too_dear(
        held, affordable, frame, count):
    assert column_count(held, affordable, frame) == count


@pytest.mark.parametrize("affordable, allowance, ceiling, count", [
    (30.4, 1.6, 4096, 32), (29.9, 1.6, 4096, 29), (28.0, 1.0, 4096, 28),   # raised where 5 % reaches 32
    (20.0, 1.6, 4096, 16), (35.0, 1.6, 4096, 32),                          # rounded down (sobol_friendly)
    (15.2, 1.0, 4096, 16), (15.2, 1.0, 12, 12), (0.3, 0.1, 4096, 1)])
def test_a_still_is_raised_to_the_power_of_two_its_overrun_reaches(affordable, allowance, ceiling, count):
    assert still_count(affordable, allowance, ceiling) == count


