"""Benchmark: Cycles' volume estimators on the example scenes, and what ``--estimator auto`` gets.

Per scene (at ``SIZES``), a curves job in this process against the cached converged
reference: the file's uniform curve (4..64 spp), ray marching at step rates 0.25 .. 8 (one
curve on homogeneous media; ``--floor``: each rate at 256 spp, its bias floor), auto, and
guided at the times uniform 16 and 32 took. Prints each run's equal-quality speedup over the
file, over the best fixed rate in hindsight (the biased curves' envelope) and over auto, on
mean FLIP, p95 region FLIP, the share over 0.103, MSE (and JOD where installed). Run it on an
otherwise idle machine.

    .venv/bin/python bench/bench_estimator.py --out bench-estimator --repeats 3
    .venv/bin/python bench/bench_estimator.py --scenes balls_b --repeats 1"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("road", "balls_a", "balls_b", "statue", "street")
HETEROGENEOUS = {"balls_b", "statue", "street"}
#: Half the scenes' own sizes where their converged references would take 10+ minutes on two
#: cores (the sizes the issue's first measurements used); road at its own (its reference ships).
#: street (the moving example) at its own size, its first frame.
SIZES = {"road": (512, 288), "balls_a": (256, 192), "balls_b": (256, 192), "statue": (192, 256),
         "street": (256, 144)}
RATES = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
METRICS = ("flip", "flip_tile95", "flip_share", "mse")
FLOOR_SPP = 256


def _register(scene: str, floor: bool, rates: bool = True, scored: bool = False) -> tuple[str, ...]:
    from xsl_render.core.validation.contestants import (Contestant, CurveSpec, register_curve,
                                                        time_matched_curve, uniform_budgets)

    def curve(name: str, label: str, params: dict, extra: tuple[int, ...] = ()):
        def points(ceiling: int):
            return [Contestant(f"{name}_{spp}spp", name, "uniform", f"{label} {spp} spp",
                               {"spp": spp, **params})
                    for spp in sorted(set(uniform_budgets(ceiling)) | set(extra))]
        return register_curve(CurveSpec(name, label, points)).name

    swept = (RATES if scene in HETEROGENEOUS else (1.0,)) if rates else ()
    names = [curve(f"biased_{rate:g}", f"marching {rate:g}",
                   {"estimator": "biased", "step_rate": rate}, (FLOOR_SPP,) if floor else ())
             for rate in swept]
    names.append(curve("auto", "auto", {"estimator": "auto"}))
    register_curve(time_matched_curve("guided", "guided, auto", (1 / 4, 1 / 2), curve="guided_auto",
                                      params={"importance": "none", "estimator": "auto"}))
    guided = ["guided_auto"]
    if scored:
        # The allocation by the pilot's error scores (the default before it was measured
        # against plain uniform sampling at equal time).
        register_curve(time_matched_curve("guided", "guided, auto, scored 0.15", (1 / 4, 1 / 2),
                                          curve="guided_auto_scored",
                                          params={"importance": "none", "estimator": "auto",
                                                  "exponent": 0.15}))
        guided.append("guided_auto_scored")
    return ("uniform", *names, *guided)


def _best_fixed(data: dict) -> list[tuple[str, float, dict]]:
    """Every biased curve's points: their lower envelope is the best fixed rate in hindsight."""
    return [(name, run["seconds"], run) for name, run in data["runs"].items()
            if run["curve"].startswith("biased_") and not name.endswith(f"_{FLOOR_SPP}spp")]


#: The last line of every bench table here.
SPEEDUP_NOTE = ("speedup = time the curve needs for the run's error / the run's time; "
                "* extrapolated beyond the curve's measured range")


def error_cells(run: dict, seconds: float, width: int = 28) -> str:
    """A run's label, seconds and errors (mean FLIP, p95 region FLIP, share > 0.103, MSE):
    the first columns of every bench table here."""
    return (f"{run['label'][:width]:{width}s} {seconds:6.2f} {run['flip'] or 0:7.4f} "
            f"{run.get('flip_tile95') or 0:7.4f} {run.get('flip_share') or 0:7.3f} {run['mse'] or 0:9.2e}")


def speedup_cell(speedups: dict, metric: str) -> str:
    """A fixed-width table cell: the speedup on ``metric``, '*' when read beyond the curve."""
    entry = speedups.get(metric) or {}
    value = entry.get("value")
    return "   -  " if value is None else f"{value:5.2f}{'*' if entry.get('extrapolated') else ' '}"


def report_scene(scene: str, data: dict) -> list[str]:
    from xsl_render.core.validation.curves import speedups_against

    size = data["scene"]["size"]
    metrics = METRICS + (("jod",) if any(run.get("jod") is not None for run in data["runs"].values()) else ())
    lines = [f"\n{scene} ({size[0]}x{size[1]}, {len(data['seeds'])} repeat(s), reference "
             f"{data['reference']['inputs']['spp']} spp)",
             f"{'run':28s} {'s':>6s} {'FLIP':>7s} {'p95tile':>7s} {'>0.103%':>7s} {'MSE':>9s} "
             f"{'chosen':>10s} | vs uniform: FLIP p95tile share MSE | vs best fixed: FLIP p95tile share MSE"
             " | vs auto: FLIP p95tile share MSE" + (" | JOD, vs uniform, vs auto" if "jod" in metrics else "")]
    best = {"best_fixed": _best_fixed(data)} if _best_fixed(data) else {}
    # The auto curve as a baseline: what a guided run adds to plain uniform sampling with
    # the same estimator choice.
    auto = {"auto": [(name, run["seconds"], run) for name, run in data["runs"].items()
                     if run["curve"] == "auto"]}
    for name, run in data["runs"].items():
        chosen = ((run["repeats"][0].get("stats") or {}).get("estimator") or {}) if run["repeats"] else {}
        rate = {None: "scene", True: f"march {chosen.get('step_rate') or 'sc'}",
                False: "null sc."}[chosen.get("biased")]
        over = run["speedups"].get("uniform", {})
        against = speedups_against(best, (name, run["seconds"], run), METRICS).get("best_fixed", {})
        over_auto = ({} if run["curve"] == "auto" else
                     speedups_against(auto, (name, run["seconds"], run), metrics).get("auto", {}))

        lines.append(error_cells(run, run["seconds"]) + f" {rate:>10s} | "
                     + " ".join(speedup_cell(over, m) for m in METRICS) + " | "
                     + " ".join(speedup_cell(against, m) for m in METRICS) + " | "
                     + " ".join(speedup_cell(over_auto, m) for m in METRICS)
                     + (f" | {run.get('jod') or 0:6.3f} {speedup_cell(over, 'jod')} {speedup_cell(over_auto, 'jod')}"
                        if "jod" in metrics else ""))
    lines.append(SPEEDUP_NOTE)
    return lines


def scene_arguments(doc: str, out: str, scenes: tuple[str, ...]) -> argparse.ArgumentParser:
    """A bench's parser with what every example-scene bench takes: --out, --scenes, --repeats."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path(out), help="folder of the curves")
    parser.add_argument("--scenes", default=",".join(scenes), help="comma-separated example scenes")
    parser.add_argument("--repeats", type=int, default=3, help="repeats per run; medians (default 3)")
    return parser


def chosen_scenes(args, scenes: tuple[str, ...], bench: str) -> list[str] | None:
    """The scenes ``--scenes`` asked for, or None once the first unknown one is reported."""
    chosen = [s.strip() for s in args.scenes.split(",") if s.strip()]
    unknown = [s for s in chosen if s not in scenes]
    if unknown:
        print(f"{bench}: unknown scene '{unknown[0]}' (choose from {', '.join(scenes)})", file=sys.stderr)
        return None
    return chosen


def main(argv=None) -> int:
    parser = scene_arguments(__doc__, "bench-estimator", SCENES)
    parser.add_argument("--resolution", default=None, help="render size WxH (default: SIZES)")
    parser.add_argument("--floor", action="store_true", help=f"also each step rate at {FLOOR_SPP} spp")
    parser.add_argument("--no-guided", action="store_true", help="leave out the guided runs")
    parser.add_argument("--no-rates", action="store_true",
                        help="leave out the step-rate sweep (no 'best fixed' column)")
    parser.add_argument("--scored", action="store_true",
                        help="also guided with the pilot's error scores (--guided-exponent 0.15)")
    args = parser.parse_args(argv)
    scenes = chosen_scenes(args, SCENES, "bench_estimator")
    if scenes is None:
        return 2
    size = tuple(int(v) for v in args.resolution.lower().split("x")) if args.resolution else None

    from xsl_render.addon.validation.curves_runner import CurvesSettings, run_curves
    from xsl_render.core.validation.vdp import vdp_unavailable_reason

    lines = [f"bench_estimator: {', '.join(scenes)} at {args.resolution or 'SIZES'}, "
             f"ceiling 64, median of {args.repeats}"]
    for scene in scenes:
        curves = _register(scene, args.floor, rates=not args.no_rates, scored=args.scored)
        if args.no_guided:
            curves = tuple(c for c in curves if not c.startswith("guided_"))
        settings = CurvesSettings(ceiling=64, resolution=size or SIZES[scene], repeats=args.repeats, curves=curves,
                                  vdp=vdp_unavailable_reason() is None)     # JOD where installed
        data = run_curves(ROOT / "example_blends" / f"{scene}.blend", settings, args.out / scene)
        scene_lines = report_scene(scene, data)
        print("\n".join(scene_lines), flush=True)
        lines += scene_lines
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_estimator.txt").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
