"""Benchmark: every director map of a scene, the snapshot, and the light map alone.

The median of ``--runs`` runs of ``compute_maps`` (each map's seconds and the total; no ray
cache, so every run casts its rays), the snapshot alone, and the L map alone at n = 20,
sigma_base = 10 (eq. 6 at its widest) on the scene's lights. Default scene: road at 512x288.

    .venv/bin/python bench/bench_maps.py [SCENE.blend ...] [--runs 5] [--resolution WxH]"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def median_of(runs: int, call) -> tuple[float, object]:
    times, result = [], None
    for _ in range(runs):
        started = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - started)
    return statistics.median(times), result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=[str(ROOT / "example_blends" / "road.blend")])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--resolution", help="WxH (default: the scene's)")
    args = parser.parse_args(argv)

    import bpy
    import numpy as np

    from xsl_render.addon.maps.director_maps import compute_maps, light_transmittance
    from xsl_render.addon.maps.snapshot import render_snapshot
    from xsl_render.addon.maps.xmap import compute_x_map_detailed
    from xsl_render.addon.scene.blend_session import open_blend
    from xsl_render.addon.scene.probe import camera_model, find_lights
    from xsl_render.core.maps.light_map import light_map
    from xsl_render.core.maps.light_raster import (emission_footprints, lamp_footprints,
                                                   merge_footprints)
    from xsl_render.core.maps.options import MapOptions

    size = tuple(int(v) for v in args.resolution.lower().split("x")) if args.resolution else None
    for path in args.scenes:
        scene = open_blend(path)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        per_map: dict[str, list[float]] = {}
        for _ in range(args.runs):
            maps = compute_maps(scene, MapOptions(), size=size, depsgraph=depsgraph)
            for name, seconds in maps.info["seconds"].items():
                per_map.setdefault(name, []).append(seconds)
        width, height = maps.info["size"]
        print(f"{Path(path).name} {width}x{height}, median of {args.runs}:")
        for name, values in per_map.items():
            print(f"  {name:9s} {statistics.median(values):7.3f} s")

        snapshot_s, _ = median_of(args.runs, lambda: render_snapshot(scene, size=size))
        print(f"  snapshot alone (4 spp, denoised) {snapshot_s:.3f} s")

        camera = camera_model(scene, size=size)
        xres = compute_x_map_detailed(scene, depsgraph=depsgraph)
        snapshot = render_snapshot(scene, size=size)
        lights = [light for light in find_lights(scene, depsgraph, camera) if light.in_frame]
        footprints, _ = lamp_footprints(camera, lights, xres.z, light_transmittance(camera, xres))
        footprints = merge_footprints(footprints, emission_footprints(camera, snapshot.emission,
                                                                      xres.x_without_minbound))
        widest = {f.name: (20, 10.0) for f in footprints}
        l_s, l_map = median_of(args.runs, lambda: light_map(footprints, (camera.height, camera.width), widest))
        print(f"  L alone, n 20, sigma_base 10, {len(footprints)} lights: {l_s:.3f} s "
              f"(mean {float(np.mean(l_map[0])):.3f})")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
