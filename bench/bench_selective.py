"""Benchmark: selective rendering against the gold standard, and a tile render's fixed cost.

Per scene (a built-in 512x288 fog scene, or .blend files), ceiling (64, 16) and director map
(a synthetic radial map of known mean, or ``--map`` EXRs): the median wall time of gold and of
the selective render, the ideal speedup (gold samples over selective samples), the achieved
one and their ratio; first the overhead of one tile render (the grid of tiles against one
frame, at 1 spp) and each tile's cost per sample, which gives a cost-weighted ideal.

    .venv/bin/python bench/bench_selective.py                         # built-in fog scene
    .venv/bin/python bench/bench_selective.py --scene balls_a.blend --map maps/xs.exr --max-spp 16"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))          # the synthetic fog scene lives with the tests


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", action="append", default=[], metavar="FILE.blend",
                        help="scene to render (repeatable; default: the built-in fog scene)")
    parser.add_argument("--map", action="append", default=[], metavar="FILE.exr",
                        help="director map at render size (repeatable; default: synthetic, --map-mean)")
    parser.add_argument("--map-mean", type=float, action="append", default=[],
                        help="mean of the synthetic radial map (repeatable; default 0.15)")
    parser.add_argument("--max-spp", type=int, action="append", default=[], help="default: 64 and 16")
    parser.add_argument("--resolution", default="512x288", help="render size (default 512x288)")
    parser.add_argument("--tile-size", type=int, default=32)
    parser.add_argument("--tile-quantile", type=float, default=1.0)
    parser.add_argument("--render-cost", type=int, default=1024, help="pixel-samples (see RenderOptions)")
    parser.add_argument("--runs", type=int, default=3, help="runs per measurement; the median is printed")
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    return parser.parse_args(argv)


def load_scene(bpy, path: str | None, resolution):
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.scene.blend_session import open_blend

    if path is None:
        return build_fog_scene(bpy, *resolution), f"fog {resolution[0]}x{resolution[1]}"
    return open_blend(path), Path(path).stem


def maps_for(args, width: int, height: int):
    import numpy as np
    from support.fog_scene import radial_map

    from xsl_render.core.imageio import read_image

    maps = [(Path(p).name, read_image(p)[:, :, 0]) for p in args.map]
    for mean in args.map_mean or ([] if maps else [0.15]):
        maps.append((f"radial mean {mean:g}", radial_map(width, height, mean)))
    for name, data in maps:
        if data.shape != (height, width):
            sys.exit(f"map {name} is {data.shape[1]}x{data.shape[0]}, the render {width}x{height}")
    return [(name, np.asarray(data, np.float32)) for name, data in maps]


def measure_tiles(scene, options, runs: int, cost_spp: int = 8) -> tuple[dict, "np.ndarray"]:
    """Per-render overhead and a map of what a sample costs where.

    Overhead: every tile of the grid at 1 spp, one by one, against the full frame at 1 spp.
    Cost map: each tile's time at ``cost_spp`` minus its time at 1 spp, per pixel-sample.
    Pixels differ a lot in cost (sky through fog vs lit surfaces in fog), so the ideal speedup
    ``gold samples / selective samples`` only predicts wall time when the map's samples fall
    on pixels of average cost; the cost-weighted ideal removes that and leaves the overhead.
    """
    import numpy as np

    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.sampling.tile_plan import tile_windows

    width, height = options.resolution
    windows = tile_windows(width, height, options.tile_size)
    with preserved_scene(scene):
        scene.render.resolution_x, scene.render.resolution_y = options.resolution
        scene.render.resolution_percentage = 100
        tiles_s, full_s, one, many = [], [], [], []
        with CyclesWindowRenderer(scene, seed=0) as renderer:
            renderer.render(None, 1)                                  # sync + BVH once
            for _ in range(runs):
                started = time.perf_counter()
                renderer.render(None, 1)
                full_s.append(time.perf_counter() - started)
                started = time.perf_counter()
                one.append([renderer.render(window, 1).seconds for window in windows])
                tiles_s.append(time.perf_counter() - started)
                many.append([renderer.render(window, cost_spp).seconds for window in windows])
    tiles, full = statistics.median(tiles_s), statistics.median(full_s)
    cost = np.zeros((height, width))
    for window, t1, tn in zip(windows, np.median(one, axis=0), np.median(many, axis=0)):
        r0, r1, c0, c1 = window
        cost[r0:r1, c0:c1] = max(tn - t1, 1e-9) / ((cost_spp - 1) * (r1 - r0) * (c1 - c0))
    overhead = {"tiles": len(windows), "tiles_s": tiles, "full_s": full,
                "overhead_ms_per_tile": 1000.0 * (tiles - full) / len(windows),
                "us_per_pixel_sample": {"min": 1e6 * cost.min(), "mean": 1e6 * cost.mean(),
                                        "max": 1e6 * cost.max()}}
    return overhead, cost


def main(argv=None) -> int:
    args = parse_args(argv)
    import bpy

    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.core.sampling.render_options import RenderOptions, parse_resolution
    from xsl_render.core.sampling.tile_plan import make_plan

    resolution = parse_resolution(args.resolution)
    results = []
    header = (f"{'scene':<16} {'spp':>4} {'map':<18} {'mean':>5} {'renders':>7} {'gold s':>7} "
              f"{'sel s':>6} {'ideal':>6} {'pixel':>6} {'costw':>6} {'achieved':>8} {'ach/ideal':>9} "
              f"{'ach/costw':>9}")
    for path in args.scene or [None]:
        scene, label = load_scene(bpy, path, resolution)
        width, height = resolution
        overhead, cost = measure_tiles(scene, RenderOptions(max_spp=1, tile_size=args.tile_size,
                                                            resolution=resolution), args.runs)
        overhead["scene"] = label
        results.append(overhead)
        print(f"{label}: {overhead['tiles']} tiles of {args.tile_size} px at 1 spp {overhead['tiles_s']:.3f} s, "
              f"full frame at 1 spp {overhead['full_s']:.3f} s -> "
              f"{overhead['overhead_ms_per_tile']:.1f} ms overhead per tile render; a pixel-sample costs "
              "{min:.1f}..{max:.1f} us (mean {mean:.1f})".format(**overhead["us_per_pixel_sample"]), flush=True)
        print(header)
        print("-" * len(header))
        for max_spp in args.max_spp or [64, 16]:
            options = RenderOptions(max_spp=max_spp, tile_size=args.tile_size, tile_quantile=args.tile_quantile,
                                    render_cost=args.render_cost, resolution=resolution)
            sr.render_selective(scene, maps_for(args, width, height)[0][1], options)   # warm-up
            for map_name, data in maps_for(args, width, height):
                plan = make_plan(data, options)
                gold_s, sel_s = [], []
                for _ in range(args.runs):          # interleaved: machine load hits both alike
                    gold_s.append(sr.render_gold(scene, options).stats["wall_s"])
                    sel_s.append(sr.render_selective(scene, data, options).stats["wall_s"])
                gold, sel = statistics.median(gold_s), statistics.median(sel_s)
                row = {"scene": label, "max_spp": max_spp, "map": map_name, "map_mean": float(data.mean()),
                       "renders": len(plan.rects), "gold_s": gold, "selective_s": sel,
                       "ideal_speedup": plan.ideal_speedup,
                       "pixel_ideal_speedup": plan.gold_samples / plan.target_samples,
                       "achieved_speedup": gold / sel, "gold_runs_s": gold_s, "selective_runs_s": sel_s}
                row["cost_weighted_ideal_speedup"] = float((cost * max_spp).sum() / (cost * plan.spp_image()).sum())
                row["achieved_over_ideal"] = row["achieved_speedup"] / row["ideal_speedup"]
                row["achieved_over_cost_weighted"] = row["achieved_speedup"] / row["cost_weighted_ideal_speedup"]
                results.append(row)
                print(f"{label:<16} {max_spp:>4} {map_name:<18} {row['map_mean']:>5.3f} {row['renders']:>7} "
                      f"{gold:>7.2f} {sel:>6.2f} {row['ideal_speedup']:>6.2f} "
                      f"{row['pixel_ideal_speedup']:>6.2f} {row['cost_weighted_ideal_speedup']:>6.2f} "
                      f"{row['achieved_speedup']:>8.2f} {row['achieved_over_ideal']:>9.2f} "
                      f"{row['achieved_over_cost_weighted']:>9.2f}", flush=True)
    print("ideal = gold samples / plan samples; pixel = gold samples / the per-pixel targets "
          "(what tiling costs); costw = the ideal with each sample weighted by what it costs "
          "where it lands (measured per tile); achieved = gold wall time / selective wall time "
          f"(medians of {args.runs} runs)")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
