"""Benchmark: how far each example scene's director maps let the speedup go, before any render.

The selective samples follow the map (``max(min_spp, round(max_spp * map))``), so the map
alone fixes the ideal speedup (gold samples / selective samples). Per scene and ceiling it
prints the maps' means, the ideal per pixel and of the tile plan actually rendered, and the
same with S = 0: the highest any saliency map could give with the paper's weights, since
XS(0.5, 0.5, +) >= 0.5 X. Only the snapshot renders; a few seconds per scene.

    .venv/bin/python bench/bench_bounds.py [SCENE ...] [--max-spp 64 16]"""
from __future__ import annotations

import argparse
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "example_blends"
#: The map issue 6 judges on each scene, and its target speedup over gold.
TARGETS = {"balls_a": ("xs", 5.0), "balls_b": ("xs", 5.0), "statue": ("xs", 5.0), "road": ("xsl", 3.0)}


def bounds(maps, which: str, options, max_spp: int) -> dict[str, float]:
    """Means and ideal speedups of one scene's maps at one ceiling (no bpy)."""
    import numpy as np

    from xsl_render.core.maps.director import xs_map, xsl_map
    from xsl_render.core.sampling.render_options import RenderOptions
    from xsl_render.core.sampling.tile_plan import make_plan, target_spp

    render = RenderOptions(max_spp=max_spp).check()
    director = maps.xs if which == "xs" else maps.xsl
    no_s = xs_map(maps.x, np.zeros_like(maps.s), options.wx, options.ws, options.xs_op)
    if which == "xsl":
        no_s = xsl_map(no_s, maps.l, options.wxs, options.wl, options.xsl_op)
    gold = max_spp * director.size

    def pixel_ideal(image) -> float:
        return gold / float(target_spp(image, max_spp, render.min_spp).sum())

    return {"x": float(maps.x.mean()), "s": float(maps.s.mean()), "l": float(maps.l.mean()),
            "map": float(director.mean()), "pixel": pixel_ideal(director),
            "plan": make_plan(director, render).ideal_speedup, "no_s": pixel_ideal(no_s)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=list(TARGETS), metavar="SCENE")
    parser.add_argument("--max-spp", type=int, nargs="+", default=[64, 16])
    args = parser.parse_args(argv)

    import warnings

    import bpy

    from xsl_render.addon.maps.director_maps import compute_maps
    from xsl_render.addon.scene.blend_session import open_blend
    from xsl_render.core.maps.options import MapOptions

    options = MapOptions()
    header = (f"{'scene':8} {'map':>4} {'spp':>4} {'X':>6} {'S':>6} {'L':>6} {'map':>6} "
              f"{'pixel':>6} {'plan':>6} {'no S':>6} {'target':>7}  reachable")
    print(header)
    print("-" * len(header))
    for name in args.scenes:
        which, target = TARGETS.get(name, ("xsl", float("nan")))
        scene = open_blend(str(EXAMPLES / f"{name}.blend"))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")      # "no light source shows": expected on the balls
            maps = compute_maps(scene, options)
        for max_spp in args.max_spp:
            b = bounds(maps, which, options, max_spp)
            verdict = ("no: not even with S = 0" if b["no_s"] < target else
                       "no: not by this map's samples" if b["pixel"] < target else
                       "not after tiling" if b["plan"] < target else "yes, by the plan's samples")
            print(f"{name:8} {which:>4} {max_spp:4d} {b['x']:6.3f} {b['s']:6.3f} {b['l']:6.3f} "
                  f"{b['map']:6.3f} {b['pixel']:5.2f}x {b['plan']:5.2f}x {b['no_s']:5.2f}x "
                  f"{target:6.1f}x  {verdict}")
        bpy.ops.wm.read_factory_settings(use_empty=True)
    print("pixel = gold samples / per-pixel targets; plan = gold samples / tile-plan samples; "
          "no S = pixel ideal of the same map with S = 0 (the ceiling for any saliency map)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
