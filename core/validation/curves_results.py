"""curves.json: every run of ``xsl-render curves``, its repeats, the curves they make and
each run's equal-quality speedups, as the plot, the report and the command's table read it.

Schema (one file per scene and resolution)::

    scene       {file, sha256, scene, frame, size: [w, h]}
    ceiling     the contestants' ceiling (the gold standard's samples per pixel)
    reference   {path, key, source: shipped|cache|rendered|given, inputs: {spp, seed, ...}}
    repeats     N; seeds: the contestants' seeds (each contestant renders once per seed)
    metrics     ["flip", "flip_tile95", "flip_share", "mse", "jod"]: HDR-FLIP mean, the 95th
                percentile of 32-px regions' mean FLIP, % of pixels above FLIP 0.103, MSE of
                the display-referred images, ColorVideoVDP JOD (None where it did not run;
                vdp.skipped says why)
    curves      {name: {label, baseline, points: [run names, budget growing]}}
    runs        {name: {curve, kind, label, params, time_of, gold, budget_s,
                        repeats: [{seed, seconds, mean_spp, flip, mse, jod, file, reused, stats}],
                        seconds, mean_spp, flip, mse, jod      (medians over the repeats),
                        speedups: {baseline: {metric: {value, time_to_reach_s, extrapolated,
                                                       faster, reason}}}}}

The median time and the median error of a run are taken separately. Speedups are read along
each baseline curve's lower envelope (``core.validation.curves``); a run is not read along
its own curve.
"""
from __future__ import annotations

import statistics

from .contestants import Contestant
from .curves import speedups_against

#: flip_tile95: the 95th percentile of 32-px regions' mean FLIP (no region visibly worse);
#: flip_share: % of pixels with FLIP above 0.103 (the paper's Table II).
METRICS = ("flip", "flip_tile95", "flip_share", "mse", "jod")
#: Statistics of a render kept with each repeat in curves.json.
STATS_KEPT = ("mode", "wall_s", "phases_s", "total_samples", "mean_spp", "renders", "max_spp",
              "noise_threshold", "time_budget_s", "stopped_by_time", "ideal_speedup",
              "director_map_mean", "path_guiding", "guided", "pilot_spp", "estimator")


def metric_values(metrics: dict) -> dict[str, float | None]:
    """FLIP mean, MSE and JOD from the summaries ``compare_images`` made (None where a
    metric was skipped)."""
    def value(name: str, key: str):
        summary = metrics.get(name) or {}
        return None if summary.get("skipped") or summary.get(key) is None else float(summary[key])
    return {"flip": value("flip", "mean_flip"), "flip_tile95": value("flip", "tile95_flip"),
            "flip_share": value("flip", "error_pixel_percent"), "mse": value("mse", "mse"),
            "jod": value("vdp", "jod")}


def _median(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(statistics.median(values)) if values else None


def summarise_run(contestant: Contestant, repeats: list[dict], budget_s: float | None = None) -> dict:
    """A run's entry: the contestant, every repeat, and the medians of time, samples and each
    metric (each median taken on its own)."""
    entry = {**contestant.to_dict(), "budget_s": budget_s, "repeats": repeats,
             "seconds": _median(r["seconds"] for r in repeats),
             "mean_spp": _median(r.get("mean_spp") for r in repeats)}
    entry.update({metric: _median(r.get(metric) for r in repeats) for metric in METRICS})
    return entry


def build_curves(header: dict, curve_specs: list, runs: dict[str, dict]) -> dict:
    """curves.json from the header (scene, ceiling, reference, repeats, seeds, vdp), the
    curve specs in registry order (``CurveSpec``) and the runs' entries (``summarise_run``),
    with each run's speedups over every baseline curve."""
    curves = {}
    for spec in curve_specs:
        members = [name for name, run in runs.items() if run["curve"] == spec.name]
        if members:
            curves[spec.name] = {"label": spec.label, "baseline": spec.baseline, "points": members}
    baselines = {name: [(member, runs[member]["seconds"], runs[member]) for member in curve["points"]]
                 for name, curve in curves.items() if curve["baseline"]}
    for name, run in runs.items():
        run["speedups"] = speedups_against(baselines, (name, run["seconds"], run), METRICS,
                                           own_curve=run["curve"])
    return {**header, "metrics": list(METRICS), "curves": curves, "runs": runs}


def speedup_text(speedup: dict | None) -> str:
    """'1.23x', '0.81x*' (extrapolated), or '-' (no value)."""
    if not speedup or speedup.get("value") is None:
        return "-"
    return f"{speedup['value']:.2f}x" + ("*" if speedup.get("extrapolated") else "")


def table_lines(data: dict) -> list[str]:
    """The command's table: one line per run, in curve order, with its speedups over each
    baseline on FLIP and MSE (and JOD where it ran)."""
    baselines = [name for name, curve in data["curves"].items() if curve["baseline"]]
    metrics = ["flip", "mse"] + (["jod"] if any(run.get("jod") is not None for run in data["runs"].values()) else [])
    group = " " * (34 + 1 + 7 + 1 + 7 + 1 + 7 + 1 + 9 + (7 if "jod" in metrics else 0))
    head = f"{'run':<34} {'time s':>7} {'spp':>7} {'FLIP':>7} {'MSE':>9}" + (f" {'JOD':>6}" if "jod" in metrics else "")
    for baseline in baselines:
        width = 2 + 9 * len(metrics) - 1
        group += f"  {'speedup vs ' + baseline:^{width - 2}}"
        head += "  " + " ".join(f"{m.upper():>8}" for m in metrics)
    lines = [group, head]
    for curve in data["curves"].values():
        for name in curve["points"]:
            run = data["runs"][name]
            line = (f"{run['label'][:34]:<34} {_num(run['seconds'], '7.2f')} {_num(run['mean_spp'], '7.1f')} "
                    f"{_num(run['flip'], '7.4f')} {_num(run['mse'], '9.2e')}")
            if "jod" in metrics:
                line += f" {_num(run['jod'], '6.3f')}"
            for baseline in baselines:
                speedups = run["speedups"].get(baseline)
                line += "  " + (" ".join(f"{speedup_text(speedups.get(m)):>8}" for m in metrics)
                                if speedups else f"{'(its own)':>{9 * len(metrics) - 1}}")
            lines.append(line)
    lines.append("speedup = time the baseline curve needs for the run's error / the run's time "
                 "(equal quality); * extrapolated beyond the curve's measured range")
    return lines


def _num(value, spec: str) -> str:
    width = int(spec.split(".")[0])
    return f"{'-':>{width}}" if value is None else format(value, spec)
