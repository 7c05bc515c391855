"""Benchmark: the equal-quality speedup of ``--mode guided`` on every example scene.

Per scene, a curves job in this process against the cached converged reference: uniform
4..64 spp, Cycles' adaptive at three thresholds, guided at the times uniform 16 and 32 spp
took (alone, and weighted by the XSL map) and, unless ``--quick``, path guiding, XS and XSL;
medians of ``--repeats``. Prints each guided run's speedup over uniform and over adaptive
(FLIP and MSE) beside issue 11's targets, then every other run's. Run it on an otherwise idle
machine.

    .venv/bin/python bench/bench_guided.py --out bench-guided --quick"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("road", "balls_a", "balls_b", "statue")
#: The uniform budgets the guided runs take their times from (of a 64-spp ceiling: 16, 32).
GUIDED_FRACTIONS = (1 / 4, 1 / 2)
FLIP_TARGET = {"road": 1.15}
MSE_TARGET = {"road": 1.25, "balls_b": 1.25}


def _register_bench_curves() -> None:
    """The guided curves at the two budgets the targets name (the registry has four)."""
    from xsl_render.core.validation.contestants import register_curve, time_matched_curve

    register_curve(time_matched_curve("guided", "guided", GUIDED_FRACTIONS, params={"importance": "none"}))
    register_curve(time_matched_curve("guided", "guided, XSL importance", GUIDED_FRACTIONS,
                                      curve="guided_xsl", params={"importance": "xsl"}))


def _speedup(run: dict, baseline: str, metric: str) -> str:
    entry = run["speedups"].get(baseline, {}).get(metric, {})
    value = entry.get("value")
    if value is None:
        return "   -  "
    return f"{value:5.2f}{'*' if entry.get('extrapolated') else ' '}"


def _verdict(value: float | None, target: float) -> str:
    return "" if value is None else ("meets" if value >= target else "MISSES")


def report_scene(scene: str, data: dict) -> list[str]:
    """The printed lines of one scene: the guided runs against the targets, then the rest."""
    lines = [f"\n{scene} ({data['scene']['size'][0]}x{data['scene']['size'][1]}, "
             f"{len(data['seeds'])} repeats, reference {data['reference']['inputs']['spp']} spp)",
             f"{'run':44s} {'s':>6s} {'FLIP':>7s} {'MSE':>9s} | over uniform FLIP  MSE | over adaptive FLIP  MSE"]
    order = ["guided", "guided_xsl", "uniform", "adaptive", "guiding", "xs", "xsl"]
    runs = sorted(data["runs"].values(), key=lambda r: (order.index(r["curve"]) if r["curve"] in order else 99,
                                                        r["seconds"]))
    for run in runs:
        lines.append(f"{run['label'][:44]:44s} {run['seconds']:6.2f} {run['flip']:7.4f} {run['mse']:9.3e} |"
                     f"       {_speedup(run, 'uniform', 'flip')} {_speedup(run, 'uniform', 'mse')} |"
                     f"        {_speedup(run, 'adaptive', 'flip')} {_speedup(run, 'adaptive', 'mse')}")
    for run in (r for r in runs if r["curve"] == "guided"):
        flip = run["speedups"].get("uniform", {}).get("flip", {}).get("value")
        mse = run["speedups"].get("uniform", {}).get("mse", {}).get("value")
        over_adaptive = run["speedups"].get("adaptive", {}).get("flip", {}).get("value")
        checks = [f"FLIP {flip if flip is None else round(flip, 2)} vs >= {FLIP_TARGET.get(scene, 1.0)}: "
                  f"{_verdict(flip, FLIP_TARGET.get(scene, 1.0))}"]
        if scene in MSE_TARGET:
            checks.append(f"MSE {mse if mse is None else round(mse, 2)} vs >= {MSE_TARGET[scene]}: "
                          f"{_verdict(mse, MSE_TARGET[scene])}")
        if scene == "road":
            checks.append(f"FLIP over adaptive {over_adaptive if over_adaptive is None else round(over_adaptive, 2)}"
                          f" vs >= 1.0: {_verdict(over_adaptive, 1.0)}")
        lines.append(f"  target, {run['label']}: " + "; ".join(checks))
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("bench-guided"), help="folder of the curves")
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated example scenes")
    parser.add_argument("--repeats", type=int, default=3, help="repeats per run; medians (default 3)")
    parser.add_argument("--resolution", default=None, help="render size WxH (default: each scene's own)")
    parser.add_argument("--quick", action="store_true", help="uniform, adaptive and guided only")
    args = parser.parse_args(argv)
    scenes = [s.strip() for s in args.scenes.split(",") if s.strip()]
    unknown = [s for s in scenes if s not in SCENES]
    if unknown:
        print(f"bench_guided: unknown scene '{unknown[0]}' (choose from {', '.join(SCENES)})", file=sys.stderr)
        return 2
    size = tuple(int(v) for v in args.resolution.lower().split("x")) if args.resolution else None

    from xsl_render.addon.validation.curves_runner import CurvesSettings, run_curves

    _register_bench_curves()
    curves = ("uniform", "adaptive", "guided", "guided_xsl") + (() if args.quick else ("guiding", "xs", "xsl"))
    lines = [f"bench_guided: {', '.join(scenes)} at {args.resolution or 'their own sizes'}, ceiling 64, "
             f"median of {args.repeats}"]
    for scene in scenes:
        settings = CurvesSettings(ceiling=64, resolution=size, repeats=args.repeats,
                                  curves=curves, vdp=False)
        data = run_curves(ROOT / "example_blends" / f"{scene}.blend", settings, args.out / scene)
        scene_lines = report_scene(scene, data)
        print("\n".join(scene_lines), flush=True)
        lines += scene_lines
    (args.out / "bench_guided.txt").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
