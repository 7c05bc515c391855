"""Benchmark: how well a short reduced-resolution pilot prices a full frame's sample.

A guided still prices a sample from its pilot (``addon/cycles/guided_render.py``). Per scene
and seed, in one Cycles session after the sync: the pilot at a quarter and half resolution
with 1, 2 and 4 samples, then the whole frame at 16 spp; prints each estimate's ratio to what
the frame paid per pixel-sample (the difference of two renders, shipped; a render less its
fixed cost; one full-resolution sample) and the frame's own seconds, whose spread is the floor
under any pilot. At ``bench_estimator.SIZES`` with auto's choice at 16 spp and blue noise.

    .venv/bin/python bench/bench_pilot_rate.py --repeats 4"""
from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import open_with_auto_choice, run_scenes  # noqa: E402
from bench_estimator import SIZES, chosen_scenes, scene_arguments  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
SPP = 16
REDUCTIONS = (4, 2)


def measure(scene_name: str, repeats: int) -> list[str]:
    from xsl_render.addon.cycles.guided_render import _RENDER_OVERHEAD_S
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer

    scene, _ = open_with_auto_choice(scene_name)
    width, height = SIZES[scene_name]

    def timed(renderer, *args, **kwargs) -> float:
        began = time.perf_counter()
        renderer.render(*args, **kwargs)
        return time.perf_counter() - began

    lines = [f"\n{scene_name} ({width}x{height}): estimate / full frame's seconds per pixel-sample",
             f"{'seed':>4s} {'full s':>7s} " + " ".join(f"{f'1/{r}: diff 1-2':>13s} {'diff 1-4':>8s} {'whole 2':>7s}"
                                                      for r in REDUCTIONS) + f" {'full: whole 1':>12s}"]
    ratios: dict[str, list[float]] = {}
    fulls = []
    for seed in range(repeats):
        with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
            timed(renderer, (height // 2 - 4, height // 2 + 4, width // 2 - 4, width // 2 + 4), 1)  # sync
            estimates = {}
            for reduce in REDUCTIONS:
                one, two, four = (timed(renderer, None, spp, reduce=reduce) for spp in (1, 2, 4))
                pixels = (width // reduce) * (height // reduce)
                estimates[reduce] = ((two - one) / pixels, (four - one) / (3 * pixels),
                                     (two - _RENDER_OVERHEAD_S) / (2 * pixels))
            one = timed(renderer, None, 1)
            full = timed(renderer, None, SPP)
        rate = (full - _RENDER_OVERHEAD_S) / (SPP * width * height)
        fulls.append(full)
        cells = []
        for reduce, values in estimates.items():
            for name, value in zip(("diff 1-2", "diff 1-4", "whole 2"), values):
                ratios.setdefault(f"1/{reduce} {name}", []).append(value / rate)
            cells.append(f"{values[0] / rate:13.2f} {values[1] / rate:8.2f} {values[2] / rate:7.2f}")
        whole_one = (one - _RENDER_OVERHEAD_S) / (width * height) / rate
        ratios.setdefault("full whole 1", []).append(whole_one)
        lines.append(f"{seed:4d} {full:7.2f} " + " ".join(cells) + f" {whole_one:12.2f}")
    lines.append(f"full frame {min(fulls):.2f}-{max(fulls):.2f} s; per estimate, median [min, max]: "
                 + "; ".join(f"{name} {statistics.median(v):.2f} [{min(v):.2f}, {max(v):.2f}]"
                             for name, v in ratios.items()))
    return lines


def main(argv=None) -> int:
    args = scene_arguments(__doc__, "bench-pilot-rate", SCENES).parse_args(argv)
    scenes = chosen_scenes(args, SCENES, "bench_pilot_rate")
    if scenes is None:
        return 2
    return run_scenes("bench_pilot_rate", scenes, args.out, lambda scene: measure(scene, args.repeats))


if __name__ == "__main__":
    sys.exit(main())
