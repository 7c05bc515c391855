"""Benchmark (prediction only, no renders): would a coarser step per region of the frame pay?

Auto chooses one step per medium for the whole frame, the largest whose predicted visible
bias stays within the run's noise. This casts one camera ray per pixel at a quarter of each
scene's bench size, predicts the marching error along every ray at the given rates
(``core.media.ray_marching.MarchingPredictor``) and prints, per rate, the frame's measure and
the share of 32-pixel regions whose own stays within 16 spp's and 4 spp's tolerance.

    .venv/bin/python bench/bench_region_steps.py balls_b:0.5,1,2 statue:2,4,8 street:0.25,0.5,1"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_estimator import SIZES  # noqa: E402

#: Rays per region side at a quarter of the bench size: 32 pixels at full size.
REGION = 8
TOLERANCES = (0.0125, 0.025)


def measure(scene_name: str, rates: list[float]) -> list[str]:
    import bpy

    from xsl_render.addon.maps.zbuffer import cast_camera_rays
    from xsl_render.addon.scene.geometry import scan_scene
    from xsl_render.addon.scene.probe import camera_model
    from xsl_render.core.maps.transmittance import medium_segments
    from xsl_render.core.media.ray_marching import MarchingPredictor
    from xsl_render.core.sampling.volume_estimator import visible_bias

    blend = Path(__file__).resolve().parents[1] / "example_blends" / f"{scene_name}.blend"
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    width, height = SIZES.get(scene_name, (scene.render.resolution_x, scene.render.resolution_y))
    geometry, media = scan_scene(scene, bpy.context.evaluated_depsgraph_get())
    rays = cast_camera_rays(camera_model(scene, size=(width // 4, height // 4)), geometry)
    rows, cols = rays.shape
    predictor = MarchingPredictor(rays, media, [medium_segments(rays, m) for m in media],
                                  np.arange(rows * cols, dtype=np.int64))
    lines = [f"{scene_name} ({width}x{height}; {cols}x{rows} rays)"]
    for rate in rates:
        error = predictor.error(rate)     # (every ray: its pixels are the frame in order)
        t = error.luminance(error.transmittance).reshape(rows, cols)
        b = error.luminance(error.bias).reshape(rows, cols)
        regions = np.array([visible_bias(t[r:r + REGION, c:c + REGION], b[r:r + REGION, c:c + REGION])
                            for r in range(0, rows, REGION) for c in range(0, cols, REGION)])
        shares = ", ".join(f"<= {tol:.2%}: {np.mean(regions <= tol):.2f}" for tol in TOLERANCES)
        lines.append(f"  rate {rate:g}: frame {visible_bias(t, b):.4f}; regions 10/50/90 % "
                     f"{np.percentile(regions, 10):.4f} / {np.percentile(regions, 50):.4f} / "
                     f"{np.percentile(regions, 90):.4f}; share of regions {shares}")
    return lines


def main(argv: list[str]) -> int:
    if not argv:
        print(__doc__, file=sys.stderr)
        return 2
    for item in argv:
        name, _, rates = item.partition(":")
        if not rates:
            print(f"bench_region_steps: '{item}' names no rates (scene:rate,rate...)", file=sys.stderr)
            return 2
        print("\n".join(measure(name, [float(r) for r in rates.split(",")])), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
