"""Benchmark: auto's volume sampling on random lit scenes, against Cycles.

Per seed, the scene ``tests/support/random_scenes.py`` draws (48x27), lit by
``random_lights.py``: auto's prediction for every medium carrier whose own method is not
distance, what auto switches, and Cycles' noise (pixel variance over 6 seeds of 4 spp,
``tests/support/scatter_oracle.py``) with auto's methods and with every carrier at distance,
each over the own methods' noise. Sums up the switches' ratios and the misses (auto keeps
every method where distance renders under ``DISTANCE_MARGIN`` of the noise).

    .venv/bin/python bench/bench_scatter_random.py --seeds 0-29"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))          # the generator and the oracle live with the tests

from bench_xmap_oracle import seed_list  # noqa: E402

WIDTH, HEIGHT = 48, 27


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0-29", help="e.g. 0-29 or 3,7,10-12 (default 0-29)")
    args = parser.parse_args(argv)
    try:
        seeds = seed_list(args.seeds)
    except ValueError:
        print(f"bench_scatter_random: --seeds '{args.seeds}' is not a list of seeds", file=sys.stderr)
        return 2
    import bpy

    from support.random_lights import add_random_lights
    from support.random_scenes import build_random_scene
    from support.scatter_oracle import scene_verdict
    from xsl_render.core.media.scatter_sampling import DISTANCE_MARGIN

    switches, missed, judged = [], [], 0
    print(f"{'seed':>4s} {'s':>5s}  verdict")
    for seed in seeds:
        started = time.perf_counter()
        built = build_random_scene(bpy, seed, WIDTH, HEIGHT)
        lights = add_random_lights(bpy, built.scene, seed)
        verdict = scene_verdict(bpy, built.scene)
        seconds = time.perf_counter() - started
        print(f"{seed:4d} {seconds:5.1f}  {verdict.describe() if verdict else 'no carrier could switch'}"
              f"  [{built.describe()}; {', '.join(lights)}]", flush=True)
        if verdict is None:
            continue
        judged += 1
        if verdict.switched:
            switches.append((seed, verdict.auto_ratio))
        elif verdict.distance_ratio < DISTANCE_MARGIN:
            missed.append((seed, verdict.distance_ratio))
    ratios = ", ".join(f"seed {seed} {ratio:.2f}" for seed, ratio in switches)
    print(f"\n{judged} scene(s) judged; {len(switches)} switched, Cycles' noise with auto's methods over "
          f"the own: {ratios or '-'}; noisier: {sum(r >= 1.0 for _, r in switches)}, the most "
          f"{max((r for _, r in switches), default=float('nan')):.2f}")
    print(f"misses (kept, where Cycles renders every carrier at distance at under {DISTANCE_MARGIN} of "
          f"the own noise): {len(missed)}: " + ", ".join(f"seed {seed} {ratio:.2f}" for seed, ratio in missed))
    return 0


if __name__ == "__main__":
    sys.exit(main())
