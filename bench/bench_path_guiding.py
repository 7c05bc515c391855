"""Benchmark: is Cycles' path guiding an estimator lever auto should pull?

Cycles on the CPU can guide paths with Intel Open Path Guiding (``use_guiding``, with surface
and volume guiding), learning the light field as it renders: a lever made for scenes lit
through media, and one auto does not use. Per scene (at ``bench_estimator.SIZES``, against
the same converged reference) this runs auto's uniform curve (its volume estimator and blue
noise) on the example scene as it is and on a copy whose only change is path guiding on
(surface and volume, Cycles' default 128 training samples), and prints every run's errors
and its equal-quality speedup over auto's curve without guiding. Run it on an otherwise
idle machine (the times are the measure).

    .venv/bin/python bench/bench_path_guiding.py --out bench-guiding --repeats 3
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_estimator import (METRICS, ROOT, SIZES, SPEEDUP_NOTE, _register, chosen_scenes,  # noqa: E402
                             error_cells, scene_arguments, speedup_cell)
from scene_copy import cycles_copy  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
#: The curve's ceiling: 4 / 8 / 16 / 32 spp, where issue 20's budgets lie.
CEILING = 32

def report(scene: str, plain: dict, guided: dict) -> list[str]:
    from xsl_render.core.validation.curves import speedups_against

    auto = {"auto": [(name, run["seconds"], run) for name, run in plain["runs"].items()
                     if run["curve"] == "auto"]}
    size = plain["scene"]["size"]
    lines = [f"\n{scene} ({size[0]}x{size[1]}, {len(plain['seeds'])} repeat(s))",
             f"{'run':34s} {'s':>6s} {'FLIP':>7s} {'p95tile':>7s} {'>0.103%':>7s} {'MSE':>9s} | "
             "vs auto without guiding: FLIP p95 share MSE"]
    rows = [(run["label"], run) for run in plain["runs"].values() if run["curve"] == "auto"]
    rows += [(f"path guiding: {run['label']}", run) for run in guided["runs"].values()]
    for label, run in rows:
        over = speedups_against(auto, (label, run["seconds"], run), METRICS).get("auto", {})
        lines.append(error_cells(run | {"label": label}, run["seconds"], width=34) + " | "
                     + " ".join(speedup_cell(over, m) for m in METRICS))
    lines.append(SPEEDUP_NOTE)
    return lines


def main(argv=None) -> int:
    args = scene_arguments(__doc__, "bench-guiding", SCENES).parse_args(argv)
    scenes = chosen_scenes(args, SCENES, "bench_path_guiding")
    if scenes is None:
        return 2

    from xsl_render.addon.validation.curves_runner import CurvesSettings, run_curves

    lines = [f"bench_path_guiding: {', '.join(scenes)}, auto's curve to {CEILING} spp, median of {args.repeats}"]
    with tempfile.TemporaryDirectory(prefix="bench-guiding-") as folder:
        for scene in scenes:
            _register(scene, False, rates=False)     # (defines the auto curve)
            settings = CurvesSettings(ceiling=CEILING, resolution=SIZES[scene], repeats=args.repeats,
                                      curves=("auto",), vdp=False)
            plain = run_curves(ROOT / "example_blends" / f"{scene}.blend", settings, args.out / scene)
            copy = cycles_copy(scene, Path(folder), use_guiding=True, use_surface_guiding=True,
                               use_volume_guiding=True)
            guided = run_curves(copy, CurvesSettings(ceiling=CEILING, resolution=SIZES[scene],
                                                     repeats=args.repeats, curves=("auto",), vdp=False,
                                                     reference=Path(plain["reference"]["path"])),
                                args.out / f"{scene}_path_guiding")
            scene_lines = report(scene, plain, guided)
            print("\n".join(scene_lines), flush=True)
            lines += scene_lines
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_path_guiding.txt").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
