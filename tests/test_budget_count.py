"""The count a time budget affords (``core.sampling.budget_count``), priced by timed renders."""
from __future__ import annotations

import pytest

from xsl_render.core.sampling.budget_count import affordable_count, sample_cost


def test_a_line_through_the_timed_renders_prices_the_fixed_part_and_each_sample():
    timed = [(4, 1.0 + 4 * 0.25), (8, 1.0 + 8 * 0.25), (16, 1.0 + 16 * 0.25), (32, 1.0 + 32 * 0.25)]
    assert sample_cost(timed) == pytest.approx((1.0, 0.25))
    assert affordable_count(5.0, timed) == 16                 # (5 - 1) / 0.25
    assert affordable_count(5.1, timed) == 16                 # never over the budget
    assert affordable_count(1.1, timed) == 1                  # at least one sample


def test_noisy_or_flat_timings_charge_the_samples_everything():
    # A clock that cannot tell the counts apart: no positive slope, every second is the samples'.
    assert sample_cost([(4, 2.0), (8, 1.9)]) == pytest.approx((0.0, 0.5))
    assert affordable_count(4.0, [(4, 2.0), (8, 1.9)]) == 8
    with pytest.raises(ValueError, match="two counts"):
        sample_cost([(8, 1.0), (8, 1.1)])


@pytest.mark.blender
def test_the_time_limited_contender_is_auto_stopped_by_cycles_own_clock(blender):
    """bench_guided_choice's ``time_limit``: uniform sampling with auto's choice and Cycles'
    time limit (the budget), its ceiling far above what the clock lets it reach."""
    from xsl_render.addon.validation.contestants import TIME_LIMIT_CEILINGS, contestant_request
    from xsl_render.core.sampling.render_options import RenderOptions
    from xsl_render.core.validation.contestants import Contestant

    contender = Contestant("time_limit_at_file_16spp", "time_limit", "time_limit", "auto, time limit",
                           {"estimator": "auto"}, time_of="file_16spp")
    request = contestant_request(contender, RenderOptions(max_spp=64), 3.5)
    assert (request.mode, request.seconds, request.spp) == ("uniform", 3.5, None)
    assert (request.options.estimator, request.options.max_spp) == ("auto", TIME_LIMIT_CEILINGS * 64)
