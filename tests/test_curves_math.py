"""The equal-quality speedup (core.validation.curves): the monotone envelope, log-log
interpolation, extrapolation flags, JOD read as its drop, and the speedup itself."""
from __future__ import annotations

import math

import pytest

from xsl_render.core.validation.curves import (JOD_MAX, Point, as_error, equal_quality_speedup,
                                               monotone_envelope, speedups_against, time_to_reach)

# A power law: error = 0.1 * seconds^-0.25 (FLIP after denoising falls about so with spp).
LAW = [Point(s, 0.1 * s ** -0.25) for s in (1.0, 2.0, 4.0, 8.0, 16.0)]


def law_time(error: float) -> float:
    return (error / 0.1) ** -4


@pytest.mark.parametrize("points, kept", [
    ([(1, .05), (2, .04), (4, .03)], [1, 2, 4]),                 # already monotone
    ([(4, .03), (1, .05), (2, .04)], [1, 2, 4]),                 # any order
    ([(1, .05), (2, .06), (4, .03)], [1, 4]),                    # a slower, worse point goes
    ([(1, .05), (2, .05), (4, .03)], [1, 4]),                    # equal error: the faster stays
    ([(2, .05), (2, .04), (4, .03)], [2, 4]),                    # equal time: the better stays
    ([(1, .05), (0, .01), (2, math.nan), (3, 0.0), (4, .03)], [1, 4]),   # unusable points
    ([], []),
])
def test_envelope_is_strictly_decreasing(points, kept):
    envelope = monotone_envelope([Point(s, e) for s, e in points])
    assert [p.seconds for p in envelope] == kept
    assert all(a.error > b.error for a, b in zip(envelope, envelope[1:]))


@pytest.mark.parametrize("error", [0.1, 0.09, 0.08, 0.07, 0.06, 0.1 * 16 ** -0.25])
def test_interpolation_is_exact_on_a_power_law(error):
    reach = time_to_reach(LAW, error)
    assert reach.seconds == pytest.approx(law_time(error), rel=1e-9)
    assert not reach.extrapolated and reach.reason is None


@pytest.mark.parametrize("error, extrapolated", [
    (0.12, True),           # worse than the fastest point: along the first segment
    (0.03, True),           # better than the slowest point: along the last segment
    (0.1 * 3 ** -0.25, False),
])
def test_extrapolation_follows_the_end_slope_and_is_flagged(error, extrapolated):
    reach = time_to_reach(LAW, error)
    assert reach.extrapolated is extrapolated
    assert reach.seconds == pytest.approx(law_time(error), rel=1e-9)


def test_interpolation_is_piecewise_in_log_log():
    curve = [Point(1.0, 0.1), Point(4.0, 0.05), Point(8.0, 0.04)]
    # Halfway between 0.1 and 0.05 in log(error) is halfway between 1 s and 4 s in log(time).
    assert time_to_reach(curve, math.sqrt(0.1 * 0.05)).seconds == pytest.approx(2.0)
    assert time_to_reach(curve, 0.05).seconds == pytest.approx(4.0)
    assert time_to_reach(curve, 0.04).seconds == pytest.approx(8.0)


def test_a_non_monotone_curve_is_read_along_its_envelope():
    noisy = [Point(1.0, 0.1), Point(2.0, 0.11), Point(4.0, 0.05)]   # the 2 s point is noise
    assert time_to_reach(noisy, 0.1 * 0.5 ** 0.5).seconds == pytest.approx(2.0)
    assert time_to_reach(noisy, 0.1 * 0.5 ** 0.5).seconds == time_to_reach(
        [Point(1.0, 0.1), Point(4.0, 0.05)], 0.1 * 0.5 ** 0.5).seconds


@pytest.mark.parametrize("curve, error, reason", [
    ([], 0.05, "no usable point"),
    ([Point(2.0, 0.05)], 0.04, "one point"),
    (LAW, 0.0, "only positive errors"),
    (LAW, -1.0, "only positive errors"),
    (LAW, math.nan, "only positive errors"),
])
def test_no_time_without_a_curve_to_read(curve, error, reason):
    reach = time_to_reach(curve, error)
    assert reach.seconds is None and reason in reach.reason


def test_a_single_point_is_read_at_its_own_error():
    assert time_to_reach([Point(2.0, 0.05)], 0.05).seconds == 2.0


@pytest.mark.parametrize("run_seconds, error, value, faster", [
    (2.0, 0.1 * 4 ** -0.25, 2.0, True),        # the curve needs 4 s for what the run did in 2
    (4.0, 0.1 * 4 ** -0.25, 1.0, False),       # a tie is not faster
    (8.0, 0.1 * 4 ** -0.25, 0.5, False),
])
def test_speedup_is_time_to_reach_over_run_time(run_seconds, error, value, faster):
    speedup = equal_quality_speedup(LAW, error, run_seconds)
    assert speedup.value == pytest.approx(value)
    assert speedup.faster is faster
    assert speedup.to_dict()["faster"] is faster


@pytest.mark.parametrize("seconds, error", [(0.0, 0.05), (-1.0, 0.05), (math.inf, 0.05), (1.0, None)])
def test_speedup_without_a_valid_run(seconds, error):
    speedup = equal_quality_speedup(LAW, error, seconds)
    assert speedup.value is None and not speedup.faster and speedup.reason


@pytest.mark.parametrize("metric, value, error", [
    ("flip", 0.04, 0.04), ("mse", 2e-5, 2e-5), ("jod", 9.6, 0.4), ("jod", JOD_MAX, 0.0), ("flip", None, None),
])
def test_as_error_turns_jod_into_its_drop(metric, value, error):
    assert as_error(metric, value) == (pytest.approx(error) if error is not None else None)


def test_jod_direction_higher_quality_is_faster():
    # Uniform: JOD 9.0 in 1 s, 9.5 in 4 s. A run reaching 9.5 in 2 s is 2x faster; one
    # reaching only 9.0 in 2 s is 0.5x.
    uniform = [("u1", 1.0, {"jod": 9.0}), ("u4", 4.0, {"jod": 9.5})]
    better = speedups_against({"uniform": uniform}, ("run", 2.0, {"jod": 9.5}), metrics=("jod",))
    worse = speedups_against({"uniform": uniform}, ("run", 2.0, {"jod": 9.0}), metrics=("jod",))
    assert better["uniform"]["jod"]["value"] == pytest.approx(2.0) and better["uniform"]["jod"]["faster"]
    assert worse["uniform"]["jod"]["value"] == pytest.approx(0.5) and not worse["uniform"]["jod"]["faster"]


def test_speedups_against_every_baseline_but_its_own():
    uniform = [(p.name or f"u{p.seconds}", p.seconds, {"flip": p.error, "mse": p.error ** 2}) for p in LAW]
    adaptive = [("a1", 2.0, {"flip": 0.09, "mse": None}), ("a2", 8.0, {"flip": 0.06})]
    run = ("xsl", 3.0, {"flip": 0.07, "mse": 0.07 ** 2, "jod": None})
    table = speedups_against({"uniform": uniform, "adaptive": adaptive}, run)
    assert set(table) == {"uniform", "adaptive"}
    assert table["uniform"]["flip"]["value"] == pytest.approx(law_time(0.07) / 3.0)
    assert table["uniform"]["mse"]["value"] == pytest.approx(law_time(0.07) / 3.0)
    assert table["uniform"]["jod"]["value"] is None                       # not measured
    assert table["adaptive"]["mse"]["reason"] == "the curve has no usable point"
    assert table["adaptive"]["flip"]["extrapolated"] is False
    own = speedups_against({"uniform": uniform, "adaptive": adaptive}, run, own_curve="uniform")
    assert set(own) == {"adaptive"}


# -- curves.json, its table, plot and report from synthetic runs (no Blender) -----------
def synthetic_curves(jod: bool):
    from xsl_render.core.validation.contestants import CURVES, plan_contestants
    from xsl_render.core.validation.curves_results import build_curves, summarise_run

    runs = {}
    for contestant in plan_contestants(8, ("uniform", "adaptive", "xsl")):
        spp = contestant.params.get("spp") or contestant.params["max_spp"] / 2
        seconds = 0.5 + spp / 4 if contestant.curve != "xsl" else 1.0 + spp / 8
        flip = 0.1 * (spp / 8) ** -0.25
        repeats = [{"seed": seed, "seconds": seconds * (1 + 0.1 * seed), "mean_spp": spp, "flip": flip,
                    "mse": flip ** 2, "jod": (10 - flip * 5) if jod else None, "file": f"{contestant.name}.exr",
                    "reused": False, "stats": {}} for seed in (0, 1)]
        runs[contestant.name] = summarise_run(contestant, repeats)
    header = {"scene": {"file": "x/fog.blend", "sha256": "0", "scene": "Scene", "frame": 1, "size": [48, 27]},
              "ceiling": 8, "reference": {"source": "cache", "inputs": {"spp": 128, "seed": 7}},
              "repeats": 2, "seeds": [0, 1], "vdp": {"ran": jod, "skipped": None if jod else "not installed"},
              "warnings": []}
    return build_curves(header, CURVES, runs)


@pytest.mark.parametrize("jod", [False, True])
def test_curves_json_table_plot_and_report(jod, tmp_path):
    from xsl_render.core.validation.curves_plot import write_curves_png
    from xsl_render.core.validation.curves_report import write_curves_report
    from xsl_render.core.validation.curves_results import table_lines

    data = synthetic_curves(jod)
    assert list(data["curves"]) == ["uniform", "adaptive", "xsl"]
    assert data["runs"]["uniform_4spp"]["seconds"] == pytest.approx(1.5 * 1.05)    # median of 1.5, 1.65
    assert set(data["runs"]["xsl_4"]["speedups"]) == {"uniform", "adaptive"}
    assert set(data["runs"]["uniform_4spp"]["speedups"]) == {"adaptive"}
    assert (data["runs"]["xsl_4"]["speedups"]["uniform"]["jod"]["value"] is not None) is jod
    lines = table_lines(data)
    assert ("JOD" in lines[1]) is jod and "speedup vs uniform" in lines[0]
    assert len(lines) == 2 + len(data["runs"]) + 1
    png = write_curves_png(data, tmp_path / "curves.png")
    report = write_curves_report(data, tmp_path, png).read_text()
    assert report.count("<tr") == 2 + len(data["runs"]) and (">JOD<" in report) is jod
