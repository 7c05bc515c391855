"""A render that spends a time budget where the denoised frame will keep its error
(``--mode guided``), every setting put back after success, error or cancel.

Inside the budget: the importance map asked for (computed by the caller), the scene's sync,
a pilot (the whole frame at a quarter of its resolution, 1 and a few samples: their times
price a sample and so the count the budget affords; auto's choice is settled for that count,
``settled_for``), then the final pass in three columns of the frame, each paced by what
those before it cost at full resolution, a count up to 1.5x a power of two rendered at it
(``sobol_friendly``), and one denoise of the whole frame as the file's denoiser would. A later
frame of a range knows what a sample costs and renders the whole frame once at the frame
before's count while it fits (``SequenceBudget``); the first frame of a range pilots at full
resolution and renders whole. What each choice measured: docs/performance.md, "Guided".
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ...core.progress import ProgressCallback, Steps, run_steps
from ...core.sampling.guided_plan import (BudgetPacer, FinalPass, GuidedOptions, error_scores,
                                          plan_final_pass, tile_means)
from ...core.sampling.sample_counts import (BUDGET_OVERRUN, column_count, sobol_friendly,
                                            still_count)
from ...core.sampling.sequence_budget import SequenceBudget
from ...core.sampling.pass_merge import PassAccumulator
from ...core.sampling.render_options import RenderOptions
from ...core.sampling.tile_plan import Rect, check_director_map, tile_windows
from ...core.sampling.volume_estimator import settled_for, provisional_choice
from ...core.tonemap import standard_view
from ..scene.state import preserved_scene
from .selective_render import (RenderOutcome, apply_estimator, finish_image, guide_prefilter, prepare_render, render_stats,
                               tile_entry)
from .denoise import PREFILTER_COST
from .tile_render import CyclesWindowRenderer

#: Pixels of the scene-sync render (as the equal-time baselines do it).
_SYNC_WINDOW = 8
#: Fixed cost assumed for one Cycles render of a rectangle (a render call, its EXR with the
#: guides written and read back; 2 cores).
_RENDER_OVERHEAD_S = 0.008
#: The final denoise is guessed from the frame's pixels (road: 0.25 s for 147456 pixels on
#: 2 cores), or, when that says more (small frames, a loaded machine), from the pilot's:
#: measured at 128x72, the full frame's took 3-3.5x its quarter-resolution pilot's. Auto's
#: prefiltered guides cost ``PREFILTER_COST`` times the plain denoise.
_DENOISE_SECONDS_PER_PIXEL = 1.7e-6
_DENOISE_RATIO = 3.5
#: The pilot's sample cap and resolution divisor: 4 spp at a quarter of the resolution scored
#: the tiles as well as more did on the road scene, for ~1/64 of a 16-spp render's samples.
_PILOT_MAX_SPP = 16
_PILOT_REDUCE = 4
#: The pilot keeps at least this many pixels on its short edge (tiny frames are reduced less).
_PILOT_MIN_EDGE = 16
#: Most of the budget a pilot that only times the render (exponent 0: nothing scored) takes.
_CLOCK_PILOT_FRACTION = 0.02
#: The first frame of a range prices its count (the one every frame of the range holds) with
#: a pilot at full resolution, of 1 and this many samples. A quarter-resolution pilot's two
#: renders of street at 256x144 (25 and 50 ms) put a sample's cost at 1.4-1.8x what a 16-32
#: spp frame paid, and moved the first count from 8 to 24 between repeats: the timing noise
#: of renders that short (repeated and averaged over 4-8 samples, windows from 8x8 pixels to
#: the whole frame cost the same per pixel-sample within their content's spread, no fixed
#: cost per sample pass showed). Full resolution's 1 and 4 samples came within 5 % (1 and 2:
#: 10-20 % under). It costs ~1.0-1.3 s there, once per range, which the range pays back.
_RANGE_PILOT_SPP = 4


def pilot_reduce(width: int, height: int) -> int:
    """The pilot's resolution divisor: ``_PILOT_REDUCE``, halved until the short edge keeps
    ``_PILOT_MIN_EDGE`` pixels (1 for tiny frames)."""
    reduce = _PILOT_REDUCE
    while reduce > 1 and min(width, height) // reduce < _PILOT_MIN_EDGE:
        reduce //= 2
    return reduce


class _Clock:
    """Seconds since the start (``already`` spent before it), without the time spent waiting
    between steps (a modal operator's timer ticks are not rendering time)."""

    def __init__(self, already: float = 0.0):
        self.start = time.perf_counter() - already
        self.waited = 0.0

    def now(self) -> float:
        return time.perf_counter() - self.start - self.waited

    def pause(self) -> float:
        return time.perf_counter()

    def resume(self, paused: float) -> None:
        self.waited += time.perf_counter() - paused


def render_guided(scene, options: RenderOptions, guided: GuidedOptions,
                  importance: np.ndarray | None = None, map_seconds: float = 0.0,
                  progress: ProgressCallback | None = None) -> RenderOutcome:
    """Render ``scene`` within ``guided.time_budget`` seconds (see the module docstring).

    Parameters
    ----------
    options
        Seed, resolution, denoising, the ceiling (``max_spp``; ``UNBOUNDED_SPP``: none) and
        the tiles the samples are allocated on (``tile_size``).
    guided
        The budget and how it is spent.
    importance
        (H, W) director map in [0, 1] at the render size weighing the error, or None.
    map_seconds
        Seconds already spent on ``importance``: part of the budget, recorded as "maps".
    """
    return run_steps(guided_steps(scene, options, guided, importance, map_seconds), progress)


def guided_steps(scene, options: RenderOptions, guided: GuidedOptions,
                 importance: np.ndarray | None = None, map_seconds: float = 0.0,
                 pace: SequenceBudget | None = None) -> Steps[RenderOutcome]:
    """``render_guided`` as steps (``core.progress``); closing it restores the scene.

    ``pace``: the frame is one of a range (``core.sampling.sequence_budget.SequenceBudget``): its
    scene sync's seconds are added to its budget instead of taken from it (the range charges
    them to the frames after it, which find the scene synced); what its final pass cost per
    sample is told to ``pace`` for the next frame, which renders without a pilot."""
    sync_outside = pace is not None
    budget = guided.time_budget
    # Auto's estimator prediction ran before, inside the budget like the importance map.
    chosen = options.volume_estimator()
    chosen_s = chosen.seconds
    # A still learns its count from its pilot, which renders with auto's choice made for the
    # ceiling (at most 16 spp), or ray marching where that was null scattering (``provisional_choice``), and
    # settles the choice for that count after it. A range keeps the ceiling's choice: it pays
    # null scattering's octree once for all its frames, and there ray marching's cost per
    # sample decides (street, frames 1-8 in one session: ray marching at rate 0.25 took 1.4x
    # null scattering's time at 16 spp, MSE 0.74x and flicker 0.77x at equal time).
    settles = pace is None
    later = pace is not None and bool(pace.rate) and not guided.exponent and importance is None
    # The first frame of a range of several (``later`` is false for it): see its final pass.
    range_start = pace is not None and pace.frames > 1 and not later
    # Its flat plan renders the whole frame once, at the count every frame will hold, priced
    # by a full-resolution pilot (``_RANGE_PILOT_SPP``).
    whole_start = range_start and not guided.exponent and importance is None
    used = provisional_choice(chosen) if settles else chosen
    if used is not chosen:
        options = replace(options, estimator_choice=used)
    clock = _Clock(already=map_seconds + chosen_s)
    phases: dict[str, float] = {"maps": map_seconds} | ({"estimator": chosen_s} if chosen_s else {})
    with preserved_scene(scene):
        width, height, warnings = prepare_render(scene, options)
        if importance is not None:
            importance = check_director_map(importance, width, height)
        yield 0.0, "guided: scene sync"
        windows = tile_windows(width, height, options.tile_size)
        image = PassAccumulator(width, height, 4)
        guides = PassAccumulator(width, height, 6)
        tiles: list[dict] = []

        def keep(window, piece, spp: int) -> float:
            """A final-pass render into the frame; its sample seconds (a scene sync Cycles
            did on the way is not what a sample costs)."""
            image.add(window, piece.pixels, spp)
            guides.add(window, piece.guides, spp)
            tiles.append(tile_entry(window, piece) | {"pass": "final"})
            return piece.seconds - piece.sync_seconds

        # The final denoise's time, set aside before the final pass: with the guides
        # prefiltered where the file's denoiser prefilters them (``guide_prefilter``), else
        # plain. A later frame of a range knows both from the frames before it.
        reserve = _DENOISE_SECONDS_PER_PIXEL * width * height if options.denoise else 0.0
        may_prefilter = options.denoise and guide_prefilter(scene)
        if pace is not None and pace.denoise_plain_s is not None:
            reserve = pace.denoise_plain_s
        prefilter_reserve = reserve * PREFILTER_COST
        if pace is not None and pace.denoise_prefiltered_s is not None:
            prefilter_reserve = pace.denoise_prefiltered_s
        allow_prefilter = False
        reduce = 1 if whole_start else pilot_reduce(width, height)

        def denoise_plan() -> tuple[float, bool]:
            """(seconds set aside for the final denoise, whether it prefilters the guides)."""
            return (prefilter_reserve, True) if may_prefilter else (reserve, False)

        def first_column_count(affordable: float, frame_sample_s: float, sequence: int) -> int:
            """A still's count (its first column's): raised to the power of two above it where
            ``BUDGET_OVERRUN`` of the budget reaches; ``sequence``: the session's
            (``CyclesWindowRenderer.sequence``)."""
            return still_count(affordable, BUDGET_OVERRUN * guided.time_budget / frame_sample_s,
                               options.max_spp, sequence)

        def sync(renderer) -> None:
            """A 1-sample render of a few pixels: Cycles syncs the scene."""
            nonlocal budget
            began = clock.now()
            side = min(_SYNC_WINDOW, width, height)
            row, col = (height - side) // 2, (width - side) // 2
            renderer.render((row, row + side, col, col + side), 1)
            seconds = clock.now() - began
            phases["sync"] = phases.get("sync", 0.0) + seconds
            if sync_outside:
                budget += seconds

        def pilot_pass(renderer):
            """The pilot: a quarter of the resolution, a first sample timing it, then as many
            as its share allows; (its render, samples, seconds per full-resolution
            pixel-sample). (No Cycles time limit: a limit set and unset at the same sample
            count makes the renderer re-sync the scene, 3.7 s on balls_b.) A pilot that only
            times the render (nothing scored) takes less."""
            fraction = guided.pilot_fraction if guided.exponent else min(guided.pilot_fraction,
                                                                         _CLOCK_PILOT_FRACTION)
            pilot_share = fraction * (budget - clock.now() - reserve)
            paused = clock.pause()
            yield 0.05, f"guided: pilot pass (1/{reduce} resolution, at most {pilot_share:.2f} s)"
            clock.resume(paused)
            began = clock.now()
            first = renderer.render(None, 1, reduce=reduce)
            fit = int((pilot_share - _RENDER_OVERHEAD_S) / max(first.seconds, 1e-6))
            # (Two samples at least where the rate is all it measures: its two renders' times.)
            least = _RANGE_PILOT_SPP if whole_start else 1 if guided.exponent else 2
            have = max(min(least, options.max_spp), min(options.max_spp, _PILOT_MAX_SPP, fit))
            pilot = renderer.render(None, have, reduce=reduce) if have > 1 else first
            phases["pilot"] = phases.get("pilot", 0.0) + clock.now() - began
            # No time limit: every pilot pixel has exactly ``have`` samples.
            pixels = float(pilot.pixels.shape[0] * pilot.pixels.shape[1])
            # Seconds per pixel-sample (a pilot pixel traces what a full one does per sample):
            # from the two renders' difference, which leaves out a render's fixed cost.
            rate = max(pilot.seconds - _RENDER_OVERHEAD_S, 0.5 * pilot.seconds) / (have * pixels)
            if have > 1 and pilot.seconds > first.seconds:
                rate = max((pilot.seconds - first.seconds) / ((have - 1) * pixels), 0.5 * rate)
            tiles.append(tile_entry((0, height, 0, width), pilot)
                         | {"pass": "pilot", "resolution_divisor": reduce})
            return pilot, have, rate

        with CyclesWindowRenderer(scene, options.seed, guides=True) as renderer:
            if later:
                # A later frame of a range: the frame before measured what a full-resolution
                # sample costs, so no pilot and no columns: one render of the whole frame, at
                # the frame before's count while it fits (``SequenceBudget.steady_count``).
                sync(renderer)
                rate, have, reduce, pilot_seconds = pace.rate, 0, 1, 0.0
                phases["pilot"] = phases["scoring"] = 0.0

                def steady(denoise_s: float) -> int:
                    left = budget - clock.now() - denoise_s - _RENDER_OVERHEAD_S
                    return pace.steady_count(max(0.0, left) / (rate * width * height), options.max_spp,
                                             rate * width * height, renderer.sequence())

                denoise_reserve, allow_prefilter = denoise_plan()
                spp = steady(denoise_reserve)
                final = FinalPass([Rect(0, height, 0, width, spp)], np.full(len(windows), float(spp)), flat=True)
                paused = clock.pause()
                yield 0.2, f"guided: the frame at {spp} spp"
                clock.resume(paused)
                began = clock.now()
                rendered_s = keep((0, height, 0, width), renderer.render(None, spp), spp)
                rendered_samples = spp * width * height
                phases["final"] = clock.now() - began
            else:
                sync(renderer)
                pilot, have, rate = yield from pilot_pass(renderer)
                # A still: auto's choice for the count the budget affords (the ceiling's
                # tolerance is stricter than a run that never reaches it needs: street at 64
                # spp's chose null scattering, whose octree took 3.5-7 s of a 9 s budget).
                count = max(1.0, (budget - clock.now() - reserve) / (rate * width * height))
                began = clock.now()
                settled = settled_for(chosen, min(count, options.max_spp)) if settles else chosen
                if clock.now() - began > 0.001:
                    # Finer rates, or the media's steps at another scene rate, predicted for the
                    # count: the estimator's time.
                    phases["estimator"] = phases.get("estimator", 0.0) + clock.now() - began
                    settled = replace(settled, seconds=chosen_s + clock.now() - began)
                if (settled.biased, settled.step_rate, settled.medium_settings) \
                        != (used.biased, used.step_rate, used.medium_settings):
                    paused = clock.pause()
                    yield 0.1, f"guided: {settled.describe()} for the budget's {count:.0f} spp"
                    clock.resume(paused)
                    apply_estimator(scene, settled)     # (the renderer tags the scene for it)
                    sync(renderer)
                    pilot, have, rate = yield from pilot_pass(renderer)
                used = settled
                pilot_seconds = pilot.seconds

                # Scores from the denoised pilot (none at exponent 0: every tile alike).
                paused = clock.pause()
                yield 0.15, f"guided: scoring the pilot ({have} spp)" if guided.exponent else "guided: planning"
                clock.resume(paused)
                began = clock.now()
                scoring_denoise, scores = 0.0, np.ones(len(windows))
                if guided.exponent:
                    # Denoised whatever the final image gets: the score is the error a denoised
                    # frame keeps, and a raw pilot's gradient is mostly its noise.
                    from .denoise import denoise

                    scored = denoise(pilot.pixels, pilot.guides[..., :3], pilot.guides[..., 3:6])
                    scoring_denoise = clock.now() - began
                    scores = error_scores(standard_view(scored[..., :3]).mean(axis=2), windows, reduce)
                weights = None if importance is None else np.maximum(tile_means(importance, windows), 1e-3)
                phases["scoring"] = clock.now() - began

                if whole_start:
                    # The first frame of a range: what it alone pays (auto's prediction, the
                    # pilot) goes outside its budget like its sync, for the frames after it to
                    # pay back, so that it renders the count they will hold (street at uniform
                    # 32 spp's time: its pilot left it 16 spp where they rendered 32).
                    budget += clock.now() - phases.get("sync", 0.0)
                # The final denoise set aside: its guides will be noisy where the pilot's are not
                # clean (fewer samples, so noisier than the frame's: road's scored 0.0000).
                frame_sample_s = rate * width * height

                def first_count(denoise_s: float) -> int:
                    affordable = max(0.0, budget - clock.now() - denoise_s) / frame_sample_s
                    if range_start:
                        return pace.steady_count(affordable, options.max_spp, frame_sample_s, renderer.sequence())
                    return first_column_count(affordable, frame_sample_s, renderer.sequence())

                denoise_reserve, allow_prefilter = denoise_plan()
                if options.denoise:
                    denoise_reserve = max(denoise_reserve, _DENOISE_RATIO * scoring_denoise)
                # The final pass: planned for the time left once the final denoise is set aside,
                # then planned again with each of its renders' fixed cost set aside too.
                left = budget - clock.now() - denoise_reserve
                final = plan_final_pass(scores, weights, width, height, guided, max(0.0, left) / rate,
                                        options.tile_size, options.max_spp)
                final = plan_final_pass(scores, weights, width, height, guided,
                                        max(0.0, left - _RENDER_OVERHEAD_S * len(final.rects)) / rate,
                                        options.tile_size, options.max_spp)
                if final.flat and range_start:
                    # The first frame of a range: the whole frame in one render, no columns.
                    # After a render of a window, a later frame of the session no longer got
                    # the pixels a fresh render gives (with blue noise, Blender 5.0's street
                    # frames 2-8 at 28 spp scored mean FLIP 0.0706-0.0723 against 0.068), and
                    # the range pays back whatever the pilot misjudged.
                    final = FinalPass([Rect(0, height, 0, width, final.rects[0].spp)], final.totals, flat=True)
                rects = final.rects
                pacer = BudgetPacer([rate * rect.samples for rect in rects], _RENDER_OVERHEAD_S,
                                    side_by_side=final.flat)
                began, rendered_s, rendered_samples = clock.now(), 0.0, 0
                rendered_rects = []
                held = None
                final_seconds = max(0.0, left)
                for index, rect in enumerate(rects):
                    paused = clock.pause()
                    yield 0.2 + 0.75 * index / max(1, len(rects)), f"guided: rectangle {index + 1}/{len(rects)}"
                    clock.resume(paused)
                    factor = pacer.scale(budget - clock.now() - denoise_reserve)
                    # Every pixel gets a sample, even when the clock is already out. A flat plan
                    # takes as many as fit, at a count Cycles' patterns stratify well.
                    wanted = int(rect.spp * factor) if final.flat else int(round(rect.spp * factor))
                    spp = max(1, min(wanted, options.max_spp))
                    if final.flat and range_start:
                        # A range's first frame (one render): the count its frames can hold
                        # (no frame before: a fresh count, raised as the allowance allows).
                        spp = pace.steady_count(spp, options.max_spp, rate * width * height, renderer.sequence())
                    elif final.flat:
                        # One count for the whole frame while the clock allows; the column
                        # after the first spends what a first column priced too dear left
                        # (``column_count``).
                        frame_affordable = final_seconds / (frame_sample_s * pacer.cost_ratio)
                        # (A count below one the session rendered is not rounded down:
                        # ``sobol_friendly``.)
                        spp = (first_column_count(spp, frame_sample_s, renderer.sequence()) if held is None
                               else column_count(held, spp, frame_affordable, renderer.sequence(),
                                                 priced_by_pilot=index == 1))
                        held = spp
                    seconds = keep(rect.window, renderer.render(rect.window, spp), spp)
                    pacer.record(seconds, rate * spp * rect.area)
                    rendered_s += seconds
                    rendered_samples += spp * rect.area
                    rendered_rects.append(replace(rect, spp=spp))
                # The stats record the counts rendered, not the plan's (the pacer moved them).
                final = replace(final, rects=rendered_rects)
                phases["final"] = clock.now() - began
            if pace is not None and rendered_samples:
                # (The count the next frame holds: a count kept whole below the session's
                # longest stays whole, ``sobol_friendly``.)
                pace.observe(rendered_s, rendered_samples,
                             sobol_friendly(rendered_samples // (width * height), renderer.sequence()))

        began = clock.now()
        merged, merged_guides = image.result(), guides.result()
        samples = image.samples.astype(np.float32)
        phases["composite"] = clock.now() - began
        merged, denoise_guides, non_finite = finish_image(merged, merged_guides if options.denoise else None,
                                                          options, phases, may_prefilter, allow_prefilter)
        if pace is not None and denoise_guides is not None:
            pace.observe_denoise(phases["denoise"], denoise_guides["prefiltered"], denoise_guides["noisy"])
        if used != options.volume_estimator():      # (a fixed choice is a new object each call)
            options = replace(options, estimator_choice=used)
        stats = render_stats("guided", scene, options, width, height, samples, phases, tiles, warnings,
                             denoise_guides=denoise_guides, non_finite_pixels=non_finite)
    # Phases add up to the wall time (progress reports and bookkeeping go to "other").
    phases["other"] = max(0.0, clock.now() - sum(phases.values()))
    if sync_outside:
        stats.sync_outside_budget_s = phases["sync"]
    stats.time_budget_s, stats.guided = guided.time_budget, guided
    stats.pilot_spp, stats.pilot_seconds, stats.pilot_resolution_divisor = have, pilot_seconds, reduce
    stats.seconds_per_pixel_sample, stats.final_pass = rate, final.to_dict()
    stats.denoise_reserved_s, stats.cycles_sync_s = denoise_reserve, renderer.sync_seconds
    if stats.wall_s > 1.1 * budget:
        warnings.append(f"the render took {stats.wall_s:.2f} s of a {budget:g} s budget "
                        f"(scene sync {phases['sync']:.2f} s, pilot {phases['pilot']:.2f} s at {have} spp)")
    yield 1.0, "guided: done"
    return RenderOutcome(merged, samples, stats, warnings)
