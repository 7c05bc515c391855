"""Render time of the example scenes at their full 512 px size, as saved (Cycles, CPU).

    .venv/bin/python bench/example_scenes.py [--runs 3] [--spp 16 64] [SCENE ...]

Prints, per scene and sample count, the median wall-clock seconds of a full render and the
median CPU seconds the process used (all render threads together; on a busy machine the
wall time grows, the CPU time much less). ``fixed`` is a 1-sample render of a 1/10 size
frame: what every render pays before the first sample (scene sync, BVH, and in Blender 5
the volume octree Cycles builds by evaluating each heterogeneous volume's shader).
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "example_blends"
SCENES = ("balls_a", "balls_b", "statue", "road")


def render_once(bpy, path: Path, spp: int, percentage: int = 100) -> tuple[float, float]:
    """(wall s, CPU s) of one render of the saved scene with ``spp`` samples."""
    bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
    scene = bpy.context.scene
    scene.cycles.samples = spp
    scene.render.resolution_percentage = percentage
    wall, cpu = time.perf_counter(), time.process_time()
    bpy.ops.render.render(write_still=False)
    return time.perf_counter() - wall, time.process_time() - cpu


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=list(SCENES), metavar="SCENE")
    parser.add_argument("--runs", type=int, default=3, help="renders per measurement (median)")
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 64])
    args = parser.parse_args(argv)

    import bpy

    print(f"{'scene':8} {'size':>8} {'what':>7} {'wall s':>8} {'cpu s':>8}")
    for name in args.scenes:
        path = EXAMPLES / f"{name}.blend"
        bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
        r = bpy.context.scene.render
        size = f"{r.resolution_x}x{r.resolution_y}"
        rows = [("fixed", 1, 10)] + [(f"{spp} spp", spp, 100) for spp in args.spp]
        for label, spp, percentage in rows:
            times = [render_once(bpy, path, spp, percentage) for _ in range(args.runs)]
            wall = statistics.median(t[0] for t in times)
            cpu = statistics.median(t[1] for t in times)
            print(f"{name:8} {size:>8} {label:>7} {wall:8.1f} {cpu:8.1f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
