"""Benchmark: a render of fewer samples after one of more in one persistent Cycles session.

A persistent session only ever raises the count its integrator lays the blue noise out by, so
a later render of fewer samples takes the start of the longer sequence
(``core.sampling.sample_pattern.session_sequence``). Per scene, pattern and seed: the whole
frame at 16 and 8 spp fresh and right after a render of more in the same session, denoised
with the plain guides, against the cached converged reference (medians over the seeds); at
``bench_estimator.SIZES`` with auto's choice at 16 spp.

    .venv/bin/python bench/bench_session_sequence.py --scenes balls_a,balls_b --repeats 3"""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import cached_reference, error_line, errors, open_with_auto_choice, run_scenes  # noqa: E402
from bench_estimator import SIZES, chosen_scenes, scene_arguments  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
PATTERNS = ("BLUE_NOISE_ROUND", "TABULATED_SOBOL")
LABELS = {"BLUE_NOISE_ROUND": "round", "TABULATED_SOBOL": "legacy"}
#: label -> the counts one session renders, the last one kept.
CASES = {"16 spp fresh": (16,), "16 after 32": (32, 16), "16 after 64": (64, 16),
         "8 spp fresh": (8,), "8 after 16": (16, 8)}


def measure(scene_name: str, repeats: int, patterns: tuple[str, ...]) -> list[str]:
    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.sample_pattern import apply_sample_pattern
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene

    scene, blend = open_with_auto_choice(scene_name)
    width, height = SIZES[scene_name]
    reference = cached_reference(scene, blend, scene_name, "bench_session_sequence")
    rows: dict[tuple[str, str], list[dict]] = {}
    for pattern in patterns:
        for seed in range(repeats):
            for label, counts in CASES.items():
                forget_synced_session()
                with preserved_scene(scene):
                    apply_sample_pattern(scene, pattern)
                    with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
                        for spp in counts:
                            piece = renderer.render(None, spp)
                image = denoise(piece.pixels, piece.guides[..., :3], piece.guides[..., 3:6])
                rows.setdefault((pattern, label), []).append(errors(reference, image))
    lines = [f"\n{scene_name} ({width}x{height}), median of {repeats} seed(s)",
             f"{'run':28s} {'FLIP':>7s} {'p95':>7s} {'MSE':>9s}  FLIP per seed"]
    for (pattern, label), results in rows.items():
        lines.append(error_line(f"{LABELS.get(pattern, pattern)}: {label}", results))
    return lines


def main() -> int:
    parser = scene_arguments(__doc__, "bench-session-sequence", SCENES)
    parser.add_argument("--patterns", default=",".join(PATTERNS), help="Cycles sample patterns (default %(default)s)")
    args = parser.parse_args(sys.argv[1:])
    chosen = chosen_scenes(args, SCENES, "bench_session_sequence")
    if chosen is None:
        return 2
    patterns = tuple(p.strip() for p in args.patterns.split(",") if p.strip())
    return run_scenes("bench_session_sequence", chosen, args.out,
                      lambda scene: measure(scene, args.repeats, patterns))


if __name__ == "__main__":
    sys.exit(main())
