"""Benchmark: blue noise with its sequence rounded up to a power of two against the pure one,
at counts between powers of two, after OIDN.

Cycles lays its pure blue-noise sequence out by the render's count, so off a power of two a
pixel's samples no longer line up with its strata; "Blue-Noise (round)" rounds the sequence
up (``core.sampling.sample_pattern``). Per scene and count, one whole-frame render per seed
with each pattern (powers of two once: the same there), denoised as auto denoises, against
the cached converged reference: mean FLIP, p95 region FLIP, MSE and the guides' noise. At
``bench_estimator.SIZES`` with auto's choice at 16 spp.

    .venv/bin/python bench/bench_round_counts.py --repeats 2 [--counts 12,16,20,24,28,32]"""
from __future__ import annotations

import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import (cached_reference, error_line, errors, open_with_auto_choice,  # noqa: E402
                                  run_scenes)
from bench_estimator import SIZES, chosen_scenes, scene_arguments  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
COUNTS = (12, 16, 20, 24, 28, 32)


def measure(scene_name: str, repeats: int, counts: tuple[int, ...]) -> list[str]:
    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.sample_pattern import apply_sample_pattern
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.sampling.denoise_guides import NOISY_GUIDE_MEDIAN, guide_noise
    from xsl_render.core.sampling.sample_pattern import PURE, ROUND

    scene, blend = open_with_auto_choice(scene_name)
    width, height = SIZES[scene_name]
    reference = cached_reference(scene, blend, scene_name, "bench_round_counts")
    rows: dict[tuple[int, str], list[dict]] = {}
    for label, pattern in (("pure", PURE), ("round", ROUND)):
        wanted = [n for n in counts if pattern == PURE or n & (n - 1)]
        for seed in range(repeats):
            with preserved_scene(scene):
                apply_sample_pattern(scene, pattern)
                with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
                    for spp in wanted:
                        piece = renderer.render(None, spp)
                        noise = guide_noise(piece.guides[..., :3])
                        image = denoise(piece.pixels, piece.guides[..., :3], piece.guides[..., 3:6],
                                        prefilter_guides=noise > NOISY_GUIDE_MEDIAN)
                        rows.setdefault((spp, label), []).append(errors(reference, image) | {"noise": noise})
    lines = [f"\n{scene_name} ({width}x{height}), median of {repeats} seed(s); guides' noise in brackets",
             f"{'run':28s} {'FLIP':>7s} {'p95':>7s} {'MSE':>9s}  FLIP per seed"]
    for (spp, label), results in sorted(rows.items()):
        noise = statistics.median(row["noise"] for row in results)
        lines.append(error_line(f"{spp} spp, {label if spp & (spp - 1) else 'either'}", results,
                                f"[{noise:.4f}]"))
    return lines


def main() -> int:
    parser = scene_arguments(__doc__, "bench-round-counts", SCENES)
    parser.add_argument("--counts", default=",".join(map(str, COUNTS)),
                        help="samples per pixel, comma-separated (default %(default)s)")
    args = parser.parse_args(sys.argv[1:])
    chosen = chosen_scenes(args, SCENES, "bench_round_counts")
    if chosen is None:
        return 2
    counts = tuple(int(n) for n in args.counts.split(","))
    return run_scenes("bench_round_counts", chosen, args.out, lambda scene: measure(scene, args.repeats, counts))


if __name__ == "__main__":
    sys.exit(main())
