"""Benchmark: how responsive the panel stays, and what stepping costs.

The panel's operators run their jobs one step per timer tick; the interface can only
redraw and read ESC between two steps, so the longest step is how long Blender may look
frozen. For the built-in fog scene (512x288 by default) this prints, per job (maps, XSL
render, gold render in bands), the median over several runs of: the whole job driven in one
go (as scripts and ``blender -b`` run it), the same job stepped as the modal operator steps
it, the number of steps and the longest and median step. The gold standard is also timed as
one ordinary render, the cost of making it cancellable.

    .venv/bin/python bench/bench_panel_steps.py [--runs 3] [--resolution 512x288] [--max-spp 64]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))          # the synthetic fog scene lives with the tests


def stepped(make_steps) -> tuple[float, list[float]]:
    """Wall time of the job and the duration of each step, as a modal operator runs it."""
    from xsl_render.core.progress import StepRunner

    runner = StepRunner(make_steps())
    steps, started = [], time.perf_counter()
    while True:
        tick = time.perf_counter()
        done = runner.advance()
        steps.append(time.perf_counter() - tick)
        if done:
            return time.perf_counter() - started, steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--resolution", default="512x288")
    parser.add_argument("--max-spp", type=int, default=64)
    args = parser.parse_args()
    width, height = (int(v) for v in args.resolution.split("x"))

    import bpy
    from support.fog_scene import build_fog_scene

    import xsl_render
    from xsl_render.addon.cycles.banded_gold import gold_band_steps
    from xsl_render.addon.cycles.selective_render import render_gold
    from xsl_render.addon.maps.director_maps import map_steps
    from xsl_render.core.panel.settings import map_options, render_options
    from xsl_render.core.progress import run_steps
    from xsl_render.operators.jobs import ray_cache_dir, selective_job

    xsl_render.register()
    scene = build_fog_scene(bpy, width, height)
    scene.xsl_render.max_spp = args.max_spp
    settings = scene.xsl_render
    cache = ray_cache_dir(scene)
    jobs = {
        "maps (rays cached)": lambda: map_steps(scene, map_options(settings), cache_dir=cache),
        "XSL render (with maps)": lambda: selective_job(scene).steps,
        "gold in bands": lambda: gold_band_steps(scene, render_options(settings)),
    }
    run_steps(jobs["maps (rays cached)"]())           # warm up: Cycles start-up, the ray cache
    print(f"fog scene {width}x{height}, max {args.max_spp} spp, median of {args.runs} runs")
    print(f"{'job':<24} {'in one go':>10} {'stepped':>9} {'steps':>6} {'longest':>9} {'median':>8}")
    for name, make in jobs.items():
        whole = statistics.median(timed(lambda: run_steps(make())) for _ in range(args.runs))
        runs = [stepped(make) for _ in range(args.runs)]
        wall = statistics.median(run[0] for run in runs)
        longest = statistics.median(max(run[1]) for run in runs)
        typical = statistics.median(statistics.median(run[1]) for run in runs)
        print(f"{name:<24} {whole:9.2f}s {wall:8.2f}s {len(runs[0][1]):6d} {longest:8.3f}s {typical:7.3f}s")
    one = statistics.median(timed(lambda: render_gold(scene, render_options(settings))) for _ in range(args.runs))
    print(f"{'gold as one render':<24} {one:9.2f}s")
    xsl_render.unregister()


def timed(job) -> float:
    started = time.perf_counter()
    job()
    return time.perf_counter() - started


if __name__ == "__main__":
    main()
