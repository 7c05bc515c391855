"""Benchmark: Cycles' volume sampling per medium (distance, equiangular, both) under auto's
ray marching, against the prediction auto chooses it by (``core.media.scatter_sampling``).

Per scene (at ``bench_estimator.SIZES``) auto's choice at ``--spp`` is rendered with every
medium's ``volume_sampling`` set to each of Cycles' three methods in turn (the rest of auto's
choice as it is, its own switch of method left out), the whole frame in a fresh session,
seeds 0 .. repeats - 1 with the methods' order turned round from seed to seed, denoised as
auto denoises, against the cached converged reference. It prints each method's median
seconds, mean FLIP, p95 region FLIP and MSE, with the noise auto's prediction gives it and
what auto chose.

    .venv/bin/python bench/bench_scatter_sampling.py --repeats 3 [--spp 16]
"""
from __future__ import annotations

import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import cached_reference, errors, open_at_bench_size, main_at_spp  # noqa: E402
from bench_estimator import SIZES  # noqa: E402

SCENES = ("balls_b", "balls_a", "statue", "road", "street")
METHODS = ("MULTIPLE_IMPORTANCE", "DISTANCE", "EQUIANGULAR")


def measure(scene_name: str, repeats: int, spp: int) -> list[str]:
    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.selective_render import apply_estimator
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.addon.scene.geometry import step_setting
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.sampling.render_options import RenderOptions

    scene, blend = open_at_bench_size(scene_name)
    reference = cached_reference(scene, blend, scene_name, "bench_scatter_sampling")
    auto = choose_estimator(scene, RenderOptions(max_spp=64, estimator="auto").check(), spp)
    noise = auto.scatter_noise or {}
    results: dict[str, list[tuple[float, dict]]] = {method: [] for method in METHODS}
    for seed in range(repeats):
        for method in (METHODS if seed % 2 == 0 else tuple(reversed(METHODS))):
            forget_synced_session()
            with preserved_scene(scene):
                apply_estimator(scene, replace(auto, scatter_sampling=None))
                for key in noise:
                    step_setting(key)[0].volume_sampling = method
                started = time.perf_counter()
                with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
                    piece = renderer.render(None, spp)
                seconds = time.perf_counter() - started
            image = denoise(piece.pixels, piece.guides[..., :3], piece.guides[..., 3:6], prefilter_guides=True)
            results[method].append((seconds, errors(reference, image)))
    own = {key: step_setting(key)[0].volume_sampling for key in noise}
    lines = [f"\n{scene_name} ({SIZES[scene_name][0]}x{SIZES[scene_name][1]}), {spp} spp, {repeats} seed(s); "
             f"own methods {own}; auto chose {auto.scatter_sampling or 'the own'}",
             f"{'method':22s} {'s':>6s} {'FLIP':>7s} {'p95':>7s} {'MSE':>9s}  predicted noise  FLIP per seed"]
    for method, rows in results.items():
        med = {key: statistics.median(row[1][key] for row in rows) for key in ("flip", "p95", "mse")}
        predicted = " ".join(f"{values.get(method, float('nan')):.3f}" for values in noise.values())
        lines.append(f"{method:22s} {statistics.median(r[0] for r in rows):6.2f} {med['flip']:7.4f} "
                     f"{med['p95']:7.4f} {med['mse']:9.2e}  {predicted:>15s}  "
                     + " ".join(f"{row[1]['flip']:.4f}" for row in rows))
    return lines


if __name__ == "__main__":
    sys.exit(main_at_spp(__doc__, "bench_scatter_sampling", "bench-scatter-sampling", SCENES, 16, measure))
