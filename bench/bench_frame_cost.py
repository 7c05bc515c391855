"""Benchmark: does a frame of a range pay a fixed part beside its samples?

A guided range prices the next frame's count at what the frames before paid per sample
(``core/sampling/sequence_budget.py``), which is right only if a frame has no fixed part. In
one Cycles session after the scene sync, each frame asked for is rendered whole at 1, 4, 8
and 16 spp (the order reversed every other frame), and seconds = fixed + per sample x spp is
fitted per frame. Street at 256x144, null scattering and blue noise. Run it on an otherwise
idle machine.

    .venv/bin/python bench/bench_frame_cost.py --frames 2-5 --repeats 2"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_estimator import ROOT, SIZES  # noqa: E402

COUNTS = (1, 4, 8, 16)
SIZE = SIZES["street"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", default="2-5", help="first-last frame (default 2-5)")
    parser.add_argument("--repeats", type=int, default=2, help="sessions, each with its own seed (default 2)")
    parser.add_argument("--out", type=Path, default=Path("bench-frame-cost"), help="folder of the output")
    args = parser.parse_args(argv)
    first, _, last = args.frames.partition("-")
    frames = range(int(first), int(last or first) + 1)

    import bpy

    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer

    bpy.ops.wm.open_mainfile(filepath=str(ROOT / "example_blends" / "street.blend"), load_ui=False)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    scene.cycles.sampling_pattern = "AUTOMATIC"
    lines = [f"bench_frame_cost: street {SIZE[0]}x{SIZE[1]}, frames {args.frames}, {args.repeats} sessions, "
             f"whole-frame renders at {'/'.join(map(str, COUNTS))} spp after each frame change",
             f"{'seed':>4s} {'frame':>5s} " + " ".join(f"{f'{spp} spp s':>9s}" for spp in COUNTS)
             + f" {'fixed s':>8s} {'s/sample':>8s}"]
    fixed_parts = []
    for seed in range(args.repeats):
        with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
            began = time.perf_counter()
            renderer.render((SIZE[1] // 2 - 4, SIZE[1] // 2 + 4, SIZE[0] // 2 - 4, SIZE[0] // 2 + 4), 1)
            lines.append(f"{seed:4d} sync {time.perf_counter() - began:.2f} s")
            for frame in frames:
                scene.frame_set(frame)
                seconds = {}
                for spp in (COUNTS if frame % 2 else tuple(reversed(COUNTS))):
                    seconds[spp] = renderer.render(None, spp).seconds
                per_sample, fixed = statistics.linear_regression(list(seconds), list(seconds.values()))
                fixed_parts.append(fixed)
                lines.append(f"{seed:4d} {frame:5d} " + " ".join(f"{seconds[spp]:9.3f}" for spp in COUNTS)
                             + f" {fixed:8.3f} {per_sample:8.3f}")
                print(lines[-1], flush=True)
    lines.append(f"fixed part per render: median {statistics.median(fixed_parts):.3f} s "
                 f"[{min(fixed_parts):.3f}, {max(fixed_parts):.3f}]")
    print(lines[-1])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_frame_cost.txt").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
