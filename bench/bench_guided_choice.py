"""Benchmark: how a render should spend a time budget. Today's ``--mode guided`` against auto
stopped by Cycles' own time limit (the ``time_limit`` contestant: Blender's Time Limit) and
auto at the count the budget affords, priced by auto's own curve
(``core.sampling.budget_count``), at equal time on the example scenes and lit-suite seeds.

Per scene, a curves job in this process (finished runs reused): the file's curve (the
baseline; Blender 5's sample pattern unless ``--as-saved``), auto's curve, the contenders at
the file's 16 and 32 spp times; medians of ``--repeats``. Prints each contender's time over
its budget and its speedup over the file's and auto's curves (mean FLIP, p95-tile FLIP, MSE),
and writes docs/performance.md's section guided_choice (not with --tiny). Idle machine only.

    .venv/bin/python bench/bench_guided_choice.py --repeats 3 [--lit-seeds 3,8,12]
    .venv/bin/python bench/bench_guided_choice.py --tiny          # end to end, a few minutes"""
from __future__ import annotations

import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_estimator import ROOT, SIZES, SPEEDUP_NOTE, chosen_scenes, scene_arguments, speedup_cell  # noqa: E402
from performance_doc import write_bench_output  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
CONTENDERS = ("guided", "time_limit", "afforded")
#: The budgets: the file's time for these fractions of the ceiling (16 and 32 of 64).
BUDGET_FRACTIONS = (1 / 4, 1 / 2)
METRICS = ("flip", "flip_tile95", "mse")
CEILING = 64
#: --tiny: a tenth of the size, a ceiling of 8, a 16-spp reference, one repeat: the script end to end.
TINY = {"scale": 0.1, "ceiling": 8, "reference_spp": 16, "lit_size": (64, 36)}


def register(ceiling: int) -> tuple[str, ...]:
    """The file's curve (baseline), auto's curve, and guided and time_limit at the file's times."""
    from xsl_render.core.validation.contestants import Contestant, CurveSpec, register_curve, uniform_budgets

    def counts(ceiling):
        return uniform_budgets(ceiling)

    def budgets(ceiling):
        return [max(1, round(ceiling * f)) for f in BUDGET_FRACTIONS]

    def timed(kind: str, label: str, params: dict):
        def points(ceiling):
            return [Contestant(f"{kind}_at_file_{spp}spp", kind, kind, f"{label}, the file's {spp} spp time",
                               params, time_of=f"file_{spp}spp") for spp in budgets(ceiling)]
        return points

    register_curve(CurveSpec("file", "the file's own settings", lambda c: [
        Contestant(f"file_{spp}spp", "file", "uniform", f"file {spp} spp", {"spp": spp}) for spp in counts(c)],
        baseline=True))
    register_curve(CurveSpec("auto", "--estimator auto", lambda c: [
        Contestant(f"auto_{spp}spp", "auto", "uniform", f"auto {spp} spp", {"spp": spp, "estimator": "auto"})
        for spp in counts(c)]))
    register_curve(CurveSpec("guided", "guided", timed("guided", "guided", {"importance": "none",
                                                                            "estimator": "auto"})))
    register_curve(CurveSpec("time_limit", "auto, Cycles' time limit",
                             timed("time_limit", "auto, time limit", {"estimator": "auto"})))
    return ("file", "auto", "guided", "time_limit")


def register_afforded(data: dict, ceiling: int) -> str:
    """Auto at the count each budget affords, priced by a line through auto's curve."""
    from xsl_render.core.sampling.budget_count import affordable_count
    from xsl_render.core.validation.contestants import Contestant, CurveSpec, register_curve

    runs = data["runs"]
    timed = [(run["params"]["spp"], run["seconds"]) for run in runs.values() if run["curve"] == "auto"]
    points = []
    for fraction in BUDGET_FRACTIONS:
        spp = max(1, round(ceiling * fraction))
        budget = runs[f"file_{spp}spp"]["seconds"]
        count = affordable_count(budget, timed)
        points.append(Contestant(f"afforded_at_file_{spp}spp", "afforded", "uniform",
                                 f"auto at {count} spp, the file's {spp} spp time",
                                 {"spp": count, "estimator": "auto", "budget_s": budget}))
    register_curve(CurveSpec("afforded", "auto at the count the budget affords", lambda c: points))
    return "afforded"


def run_scene(blend: Path, size, ceiling: int, repeats: int, reference_spp, out: Path) -> dict:
    """The curves of one scene, the registry left as it was found."""
    from xsl_render.addon.validation.curves_runner import CurvesJob, CurvesSettings
    from xsl_render.core.validation.contestants import CURVES

    registered = list(CURVES)
    try:
        curves = register(ceiling)
        settings = dict(ceiling=ceiling, resolution=tuple(size), repeats=repeats, vdp=False,
                        reference_spp=reference_spp)
        data = CurvesJob(blend, CurvesSettings(curves=curves, **settings), out).run()
        curves = (*curves, register_afforded(data, ceiling))
        return CurvesJob(blend, CurvesSettings(curves=curves, **settings), out).run()
    finally:
        CURVES[:] = registered


def report_scene(name: str, data: dict) -> tuple[list[str], dict]:
    """The scene's lines, and each contender's speedups over auto's curve (mean FLIP)."""
    from xsl_render.core.validation.curves import speedups_against

    size = data["scene"]["size"]
    auto = {"auto": [(n, run["seconds"], run) for n, run in data["runs"].items() if run["curve"] == "auto"]}
    lines = [f"\n{name} ({size[0]}x{size[1]}, {len(data['seeds'])} repeat(s), reference "
             f"{data['reference']['inputs']['spp']} spp)",
             f"{'run':42s} {'s':>6s} {'budget':>6s} {'spp':>6s} {'FLIP':>7s} {'p95tile':>7s} {'MSE':>9s}"
             " | over the file: FLIP p95tile MSE | over auto: FLIP p95tile MSE"]
    over_auto: dict[str, list[float]] = {contender: [] for contender in CONTENDERS}
    for run_name, run in data["runs"].items():
        if run["curve"] not in CONTENDERS:
            continue
        budget = run.get("budget_s") or run["params"].get("budget_s")
        over_file = run["speedups"].get("file", {})
        against = speedups_against(auto, (run_name, run["seconds"], run), METRICS).get("auto", {})
        if (against.get("flip") or {}).get("value") is not None:
            over_auto[run["curve"]].append(against["flip"]["value"])
        lines.append(f"{run['label'][:42]:42s} {run['seconds']:6.2f} {run['seconds'] / budget:6.2f} "
                     f"{run.get('mean_spp') or 0:6.1f} {run['flip'] or 0:7.4f} {run.get('flip_tile95') or 0:7.4f} "
                     f"{run['mse'] or 0:9.2e} |  " + " ".join(speedup_cell(over_file, m) for m in METRICS)
                     + "  |  " + " ".join(speedup_cell(against, m) for m in METRICS))
    return lines, over_auto


def scene_files(args, bpy) -> list[tuple[str, Path, tuple[int, int]]]:
    """(name, .blend, size) of every scene asked for: the example scenes (as saved, or with
    Blender 5's sample pattern, saved once in --out: a reference is cached under the file's
    bytes) and the lit seeds."""
    from scene_copy import cycles_copy

    from xsl_render.core.sampling.sample_pattern import BLENDER_DEFAULT

    scale = TINY["scale"] if args.tiny else 1.0
    found = []
    for name in args.chosen:
        width, height = SIZES[name]
        size = (max(16, round(width * scale)), max(16, round(height * scale)))
        blend = ROOT / "example_blends" / f"{name}.blend"
        if not args.as_saved:
            folder = args.out / "blender5"
            blend = folder / f"{name}.blend"
            if not blend.is_file():
                folder.mkdir(parents=True, exist_ok=True)
                cycles_copy(name, folder, sampling_pattern=BLENDER_DEFAULT)
        found.append((name, blend, size))
    if args.lit_seeds:
        sys.path.insert(0, str(ROOT / "tests"))
        from support.lit_scenes import saved_lit_scene

        size = TINY["lit_size"] if args.tiny else (320, 180)
        for seed in (int(s) for s in args.lit_seeds.split(",") if s.strip()):
            blend, _ = saved_lit_scene(bpy, seed, args.out / "lit_scenes", *size)
            found.append((f"lit_{seed:03d}", blend, size))
    return found


def main(argv=None) -> int:
    parser = scene_arguments(__doc__, "bench-guided-choice", SCENES)
    parser.add_argument("--lit-seeds", default="", help="also these lit-suite seeds, e.g. 3,8,12 (320x180)")
    parser.add_argument("--as-saved", action="store_true",
                        help="the example files as saved (legacy sample pattern), not as Blender 5 makes them")
    parser.add_argument("--tiny", action="store_true", help="a tenth of the size, few samples: a check")
    args = parser.parse_args(argv)
    args.chosen = chosen_scenes(args, SCENES, "bench_guided_choice")
    if args.chosen is None:
        return 2
    ceiling = TINY["ceiling"] if args.tiny else CEILING
    repeats = 1 if args.tiny else args.repeats
    reference_spp = TINY["reference_spp"] if args.tiny else None

    import bpy

    lines = [f"bench_guided_choice: ceiling {ceiling}, budgets the file's "
             f"{', '.join(str(max(1, round(ceiling * f))) for f in BUDGET_FRACTIONS)} spp time, median of "
             f"{repeats}{' (tiny)' if args.tiny else ''}"]
    over_auto: dict[str, list[float]] = {contender: [] for contender in CONTENDERS}
    for name, blend, size in scene_files(args, bpy):
        data = run_scene(blend, size, ceiling, repeats, reference_spp, args.out / name)
        scene_lines, scene_over_auto = report_scene(name, data)
        for contender, values in scene_over_auto.items():
            over_auto[contender] += values
        print("\n".join(scene_lines), flush=True)
        lines += scene_lines
    lines += ["", SPEEDUP_NOTE, "Over auto's curve (mean FLIP), median over scenes and budgets: " + ", ".join(
        f"{contender} {statistics.median(values):.2f}x" if values else f"{contender} -"
        for contender, values in over_auto.items())]
    print("\n".join(lines[-3:]))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_guided_choice.txt").write_text("\n".join(lines) + "\n")
    if not args.tiny:
        write_bench_output("guided_choice", "How a time budget is spent (bench_guided_choice.py)",
                           "bench_guided_choice.py", argv, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
