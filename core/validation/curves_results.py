"""curves.json: every run of ``xsl-render curves``, its repeats, the curves they make and each
run's equal-quality speedups, as the plot, the report and the command's table read it.

Top level: ``scene`` (file, sha256, frame, size; over frames the frames and fps),
``ceiling``, ``reference`` (path, key, source, inputs), ``repeats`` and ``seeds``, ``metrics``
(flip, flip_tile95, flip_share, mse, jod; flicker over frames), ``curves`` ({name: label,
baseline, points}) and ``runs`` ({name: the contestant, budget_s, every repeat, the medians of
seconds, mean_spp and each metric, taken separately, and ``speedups`` {baseline: {metric:
value, time_to_reach_s, extrapolated, faster, reason}}}). Over frames a repeat is one run of
every frame in one Cycles session, its errors the means over them, with per-frame figures.
A run is never read along its own curve."""
from __future__ import annotations

import statistics

from .contestants import Contestant
from .curves import speedups_against

#: flip_tile95: the 95th percentile of 32-px regions' mean FLIP (no region visibly worse);
#: flip_share: % of pixels with FLIP above 0.103 (the paper's Table II).
METRICS = ("flip", "flip_tile95", "flip_share", "mse", "jod")
#: Over frames: the same, each the mean over the frames (JOD: the sequence's as a video), and
#: the sequence's flicker.
SEQUENCE_METRICS = ("flip", "flip_tile95", "flip_share", "mse", "flicker", "jod")
#: Per-frame figures of a run over frames (``core.validation.sequence.FRAME_METRICS``).
FRAME_FIGURES = ("flip", "flip_tile95", "flip_share", "mse", "flicker")
#: Statistics of a render kept with each repeat in curves.json: what it cost and what it
#: decided (a guided run's pilot, its price of a sample, its final pass's counts, its guides'
#: prefilter), so that a curve's point can be explained without rendering it again. Not the
#: per-render ``tiles``, whose list grows with the plan.
STATS_KEPT = ("mode", "wall_s", "phases_s", "total_samples", "mean_spp", "renders", "max_spp",
              "noise_threshold", "time_budget_s", "stopped_by_time", "ideal_speedup",
              "director_map_mean", "path_guiding", "guided", "pilot_spp", "pilot_seconds",
              "pilot_resolution_divisor", "seconds_per_pixel_sample", "final_pass",
              "denoise_reserved_s", "denoise_guides", "estimator")


def metric_values(metrics: dict) -> dict[str, float | None]:
    """FLIP mean, MSE and JOD from the summaries ``compare_images`` made (None where a
    metric was skipped)."""
    def value(name: str, key: str):
        summary = metrics.get(name) or {}
        return None if summary.get("skipped") or summary.get(key) is None else float(summary[key])
    return {"flip": value("flip", "mean_flip"), "flip_tile95": value("flip", "tile95_flip"),
            "flip_share": value("flip", "error_pixel_percent"), "mse": value("mse", "mse"),
            "jod": value("vdp", "jod")}


def sequence_values(sequence: dict) -> dict[str, float | None]:
    """A run's figures from the summary of its frames (``compare_sequence``'s ``sequence``):
    the means over its frames, the flicker (and relative flicker) of the sequence, and the
    JOD of the sequence as a video (None where it did not run)."""
    flicker = sequence.get("flicker") or {}
    return {**{metric: sequence["mean"].get(metric) for metric in ("flip", "flip_tile95", "flip_share", "mse")},
            "flicker": flicker.get("flicker"), "relative_flicker": flicker.get("relative_flicker"),
            "jod": (sequence.get("vdp") or {}).get("jod")}


def _median(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(statistics.median(values)) if values else None


def summarise_run(contestant: Contestant, repeats: list[dict], budget_s: float | None = None,
                  metrics: tuple[str, ...] = METRICS) -> dict:
    """A run's entry: the contestant, every repeat, and the medians of time, samples and each
    metric (each median taken on its own)."""
    entry = {**contestant.to_dict(), "budget_s": budget_s, "repeats": repeats,
             "seconds": _median(r["seconds"] for r in repeats),
             "mean_spp": _median(r.get("mean_spp") for r in repeats)}
    entry.update({metric: _median(r.get(metric) for r in repeats) for metric in metrics})
    return entry


def build_curves(header: dict, curve_specs: list, runs: dict[str, dict],
                 metrics: tuple[str, ...] = METRICS) -> dict:
    """curves.json from the header (scene, ceiling, reference, repeats, seeds, vdp), the
    curve specs in registry order (``CurveSpec``) and the runs' entries (``summarise_run``),
    with each run's speedups over every baseline curve on each of ``metrics``
    (``SEQUENCE_METRICS`` for runs over frames)."""
    curves = {}
    for spec in curve_specs:
        members = [name for name, run in runs.items() if run["curve"] == spec.name]
        if members:
            curves[spec.name] = {"label": spec.label, "baseline": spec.baseline, "points": members}
    baselines = {name: [(member, runs[member]["seconds"], runs[member]) for member in curve["points"]]
                 for name, curve in curves.items() if curve["baseline"]}
    for name, run in runs.items():
        run["speedups"] = speedups_against(baselines, (name, run["seconds"], run), metrics,
                                           own_curve=run["curve"])
    return {**header, "metrics": list(metrics), "curves": curves, "runs": runs}


def speedup_text(speedup: dict | None) -> str:
    """'1.23x', '0.81x*' (extrapolated), or '-' (no value)."""
    if not speedup or speedup.get("value") is None:
        return "-"
    return f"{speedup['value']:.2f}x" + ("*" if speedup.get("extrapolated") else "")


#: The table's columns of values: (metric, heading, format).
_COLUMNS = {"flip": ("FLIP", "7.4f"), "mse": ("MSE", "9.2e"), "flicker": ("flicker", "8.4f"),
            "jod": ("JOD", "6.3f")}


def frame_count(data: dict) -> int | None:
    """How many frames each run renders (None: one frame, ``curves`` without --frames)."""
    frames = data["scene"].get("frames")
    return len(frames) if frames else None


def table_lines(data: dict) -> list[str]:
    """The command's table: one line per run, in curve order, with its speedups over each
    baseline on FLIP and MSE (the flicker too over frames, JOD where it ran)."""
    baselines = [name for name, curve in data["curves"].items() if curve["baseline"]]
    metrics = ["flip", "mse"]
    metrics += [m for m in ("flicker", "jod") if m in data.get("metrics", METRICS)
                and any(run.get(m) is not None for run in data["runs"].values())]
    widths = [int(_COLUMNS[m][1].split(".")[0]) for m in metrics]
    head = f"{'run':<34} {'time s':>7} {'spp':>7}" + "".join(f" {_COLUMNS[m][0]:>{w}}"
                                                             for m, w in zip(metrics, widths))
    group = " " * len(head)
    for baseline in baselines:
        width = 2 + 9 * len(metrics) - 1
        group += f"  {'speedup vs ' + baseline:^{width - 2}}"
        head += "  " + " ".join(f"{_COLUMNS[m][0].upper():>8}" for m in metrics)
    lines = [group, head]
    for curve in data["curves"].values():
        for name in curve["points"]:
            run = data["runs"][name]
            line = (f"{run['label'][:34]:<34} {_num(run['seconds'], '7.2f')} {_num(run['mean_spp'], '7.1f')}"
                    + "".join(f" {_num(run.get(m), _COLUMNS[m][1])}" for m in metrics))
            for baseline in baselines:
                speedups = run["speedups"].get(baseline)
                line += "  " + (" ".join(f"{speedup_text(speedups.get(m)):>8}" for m in metrics)
                                if speedups else f"{'(its own)':>{9 * len(metrics) - 1}}")
            lines.append(line)
    count = frame_count(data)
    if count:
        lines.append(f"over {count} frames: time = the whole run (one scene sync), errors = the mean over "
                     "the frames, flicker = the sequence's, JOD = the sequence's as a video")
    lines.append("speedup = time the baseline curve needs for the run's error / the run's time "
                 "(equal quality); * extrapolated beyond the curve's measured range")
    return lines


def _num(value, spec: str) -> str:
    width = int(spec.split(".")[0])
    return f"{'-':>{width}}" if value is None else format(value, spec)
