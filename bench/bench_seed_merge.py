"""Benchmark: are 2N samples per pixel from two seeds worth 2N from one, after OIDN?

A pass that rendered too few samples could be topped up by a second render of the same pixels
with another seed, merged by sample count (``PassAccumulator``): it would cost exactly the
missing samples. Per scene and seed pair, denoised as every run is: one seed's 2N, two seeds'
N + N merged, and one seed's N; at ``bench_estimator.SIZES`` with auto's choice and blue
noise, against the cached converged reference.

    .venv/bin/python bench/bench_seed_merge.py --repeats 3 [--spp 8]"""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import (cached_reference, error_line, errors, main_at_spp,  # noqa: E402
                                  open_with_auto_choice)
from bench_estimator import SIZES  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
SPP = 8


def measure(scene_name: str, repeats: int, spp: int) -> list[str]:
    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.core.sampling.pass_merge import PassAccumulator

    scene, blend = open_with_auto_choice(scene_name)
    width, height = SIZES[scene_name]
    reference = cached_reference(scene, blend, scene_name, "bench_seed_merge")

    def denoised(pixels, guides):
        return denoise(pixels, guides[..., :3], guides[..., 3:6])

    rows: dict[str, list[dict]] = {}
    for pair in range(repeats):
        with CyclesWindowRenderer(scene, 2 * pair, guides=True) as renderer:
            whole = renderer.render(None, 2 * spp)
            half = renderer.render(None, spp)
        with CyclesWindowRenderer(scene, 2 * pair + 1, guides=True) as renderer:
            other = renderer.render(None, spp)
        image, guides = PassAccumulator(width, height, 4), PassAccumulator(width, height, 6)
        for part in (half, other):
            image.add(None, part.pixels, spp)
            guides.add(None, part.guides, spp)
        for label, result in ((f"one seed, {2 * spp}", denoised(whole.pixels, whole.guides)),
                              (f"two seeds, {spp} + {spp}", denoised(image.result(), guides.result())),
                              (f"one seed, {spp}", denoised(half.pixels, half.guides))):
            rows.setdefault(label, []).append(errors(reference, result))
    lines = [f"\n{scene_name} ({width}x{height}), median of {repeats} seed pairs",
             f"{'run':28s} {'FLIP':>7s} {'p95':>7s} {'MSE':>9s}  FLIP per pair"]
    lines += [error_line(label, results) for label, results in rows.items()]
    return lines


if __name__ == "__main__":
    sys.exit(main_at_spp(__doc__, "bench_seed_merge", "bench-seed-merge", SCENES, SPP, measure))
