"""Benchmark: what auto's sample pattern is worth, and auto's speed over a Blender 5 file.

The example scenes carry Cycles' legacy pattern (files saved before Blender 4.2 do); a file
made in Blender 5 has blue noise, and auto renders the legacy pattern with blue noise. Per
scene (at ``bench_estimator.SIZES``, one converged reference): the file's uniform curve, auto
and guided as ``bench_estimator.py --no-rates``, and the uniform curve of a copy whose only
change is Blender 5's pattern (so auto over it is the rest of auto's gain). Prints each run's
errors and its speedup over both uniform curves and over auto's. Idle machine only.

    .venv/bin/python bench/bench_sample_pattern.py --out bench-pattern --repeats 3"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_estimator import (METRICS, ROOT, SIZES, SPEEDUP_NOTE, _register, chosen_scenes,  # noqa: E402
                             error_cells, scene_arguments, speedup_cell)
from scene_copy import cycles_copy  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")

def report(scene: str, data: dict, blue: dict) -> list[str]:
    from xsl_render.core.validation.curves import speedups_against

    def members(source: dict, curve: str) -> list:
        return [(name, run["seconds"], run) for name, run in source["runs"].items() if run["curve"] == curve]

    baselines = {"legacy": members(data, "uniform"), "blue": members(blue, "uniform"),
                 "auto": members(data, "auto")}
    size = data["scene"]["size"]
    lines = [f"\n{scene} ({size[0]}x{size[1]}, {len(data['seeds'])} repeat(s))",
             f"{'run':34s} {'s':>6s} {'FLIP':>7s} {'p95tile':>7s} {'>0.103%':>7s} {'MSE':>9s} | "
             "vs uniform, file's pattern: FLIP p95 share MSE | vs uniform, blue noise: FLIP p95 share MSE"
             " | vs auto: FLIP p95 share MSE"]
    rows = [(f"blue noise: {run['label']}", run) for run in blue["runs"].values()]
    rows += [(run["label"], run) for run in data["runs"].values()]
    for label, run in rows:
        entry = (label, run["seconds"], run)
        over = speedups_against(baselines, entry, METRICS)
        lines.append(error_cells(run | {"label": label}, run["seconds"], width=34) + " | "
                     + " | ".join(" ".join(speedup_cell(over.get(name, {}), m) for m in METRICS)
                                  for name in ("legacy", "blue", "auto")))
    lines.append(SPEEDUP_NOTE)
    return lines


def main(argv=None) -> int:
    args = scene_arguments(__doc__, "bench-pattern", SCENES).parse_args(argv)
    scenes = chosen_scenes(args, SCENES, "bench_sample_pattern")
    if scenes is None:
        return 2

    from xsl_render.addon.validation.curves_runner import CurvesSettings, run_curves
    from xsl_render.core.sampling.sample_pattern import BLENDER_DEFAULT

    lines = [f"bench_sample_pattern: {', '.join(scenes)}, ceiling 64, median of {args.repeats}"]
    with tempfile.TemporaryDirectory(prefix="bench-pattern-") as folder:
        for scene in scenes:
            settings = CurvesSettings(ceiling=64, resolution=SIZES[scene], repeats=args.repeats,
                                      curves=_register(scene, False, rates=False), vdp=False)
            data = run_curves(ROOT / "example_blends" / f"{scene}.blend", settings, args.out / scene)
            copy = cycles_copy(scene, Path(folder), sampling_pattern=BLENDER_DEFAULT)
            blue = run_curves(copy, CurvesSettings(ceiling=64, resolution=SIZES[scene], repeats=args.repeats,
                                                   curves=("uniform",), vdp=False,
                                                   reference=Path(data["reference"]["path"])),
                              args.out / f"{scene}_blue_noise")
            scene_lines = report(scene, data, blue)
            print("\n".join(scene_lines), flush=True)
            lines += scene_lines
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_sample_pattern.txt").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
