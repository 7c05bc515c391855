"""results.json: the numbers of a validation, per scene and variant, as the report reads them.

Times follow the paper's Fig. 8: a selective run's time includes making the maps it uses;
the gold standard's is its render. Every run (gold included) has its metrics against the
converged reference (``reference_metrics``) and, the paper's measure, every run but gold its
metrics against the gold standard (``metrics``). The equal-quality speedups
(``equal_quality``) are read along the uniform time-quality curve the scene's uniform runs
and gold make (``core.validation.curves``), on the errors against the reference; the time
ratio to gold (``speedup_over_gold``) is the paper's figure, not at equal quality. The
per-tile details stay in each run's own record (``<scene>/<variant>.json``).
"""
from __future__ import annotations

from ..sampling.render_stats import RenderStats
from .curves import speedups_against
from .curves_results import metric_values

#: Statistics of a render copied into results.json (the rest stays in the run's record).
_STATS_KEPT = ("mode", "resolution", "max_spp", "seed", "wall_s", "phases_s", "total_samples",
               "mean_spp", "gold_samples", "renders", "ideal_speedup", "director_map_mean",
               "time_budget_s", "time_limit_s", "stopped_by_time", "noise_threshold", "estimator",
               "warnings")


def run_summary(variant, record: dict, gold: dict, reused: bool) -> dict:
    """One variant's entry: files, timing, samples, speedups and metrics."""
    stats, gold_stats = RenderStats.from_json(record["stats"]), RenderStats.from_json(gold["stats"])
    comparison = record.get("comparison", {})
    wall, maps, gold_wall = stats.wall_s, stats.phase("maps"), gold_stats.wall_s
    return {
        **variant.to_dict(),
        "files": record["files"],
        "heatmaps": comparison.get("heatmaps", {}),
        "stats": stats.to_json(keep=_STATS_KEPT),
        "done_early": stats.stopped_by_time is False and bool(stats.time_budget_s),
        "mean_spp": stats.mean_spp,
        "time_s": wall,
        "maps_s": maps,
        "render_s": wall - maps,
        "speedup_over_gold": gold_wall / wall if wall > 0 else None,
        "sample_ratio_over_gold": (gold_stats.total_samples / stats.total_samples
                                   if stats.total_samples else None),
        "metrics": comparison.get("metrics", {}),
        "reference_metrics": record.get("reference_comparison", {}).get("metrics", {}),
        "reference_heatmaps": record.get("reference_comparison", {}).get("heatmaps", {}),
        "reused": reused,
    }


def uniform_curve(runs: dict) -> list[tuple[str, float, dict]]:
    """The scene's uniform time-quality curve: gold and every uniform run, as
    ``(name, seconds, {metric: value against the reference})``."""
    return [(name, run["time_s"], metric_values(run.get("reference_metrics", {})))
            for name, run in runs.items() if run["kind"] in ("gold", "uniform")]


def add_equal_quality(runs: dict) -> None:
    """Each run's equal-quality speedups over the uniform curve (``equal_quality``), when the
    scene has at least two points on it; the runs of the curve itself get none."""
    curve = uniform_curve(runs)
    for name, run in runs.items():
        own = run["kind"] in ("gold", "uniform")
        if len(curve) < 2 or own:
            run["equal_quality"] = None
            continue
        values = metric_values(run.get("reference_metrics", {}))
        run["equal_quality"] = speedups_against({"uniform": curve}, (name, run["time_s"], values))["uniform"]


def scene_summary(job, sha256: str, size, options, variants, records: dict, maps: dict,
                  warnings: list[str], reused: set[str], reference: dict | None = None) -> dict:
    """A scene's entry of results.json.

    ``maps`` is keyed by MinBound on/off (the info of each map set), ``reused`` names the
    variants whose render was found on disk rather than made now, ``reference`` describes
    the converged reference (``addon.validation.reference.Reference.to_dict``).
    """
    gold = records["gold"]
    runs = {v.name: run_summary(v, records[v.name], gold, v.name in reused) for v in variants}
    add_equal_quality(runs)
    return {
        "file": str(job.path),
        "sha256": sha256,
        "size": list(size),
        "max_spp": options.max_spp,
        "reference": reference,
        "maps": {("minbound" if minbound else "no_minbound"): info for minbound, info in maps.items()},
        "runs": runs,
        "warnings": list(dict.fromkeys(warnings)),
    }
