"""Benchmark: what Cycles' other render settings buy on top of auto's choice.

Auto leaves bounces, clamping and (with several lights) the light tree as the artist set them.
Per scene (at ``bench_estimator.SIZES``): auto's own curve at a few counts and, at ``--spp``,
the same choice with one ``scene.cycles`` setting changed per arm (``--arms``, each
``name=value[;name=value]``), a fresh Cycles session each, arms alternating, against the
cached converged reference. Prints each arm's seconds, errors and equal-quality speedup along
auto's curve (above 1: the setting pays).

    .venv/bin/python bench/bench_render_settings.py --scenes road --repeats 3"""
from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import cached_reference, errors, open_at_bench_size, run_scenes  # noqa: E402
from bench_estimator import SIZES, chosen_scenes, scene_arguments  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
CURVE = (8, 16, 32)
#: Settings an artist leaves at what the file has and auto does not choose: the paths'
#: length, Cycles' clamps, the light tree (kept by auto where several lights share the frame).
ARMS = ("max_bounces=1", "max_bounces=0", "sample_clamp_direct=10", "sample_clamp_indirect=1",
        "use_light_tree=False")


def parse_arm(text: str) -> dict:
    """``"name=value;name=value"`` as {name: value}, each value as Python reads it."""
    import ast

    settings = {}
    for item in filter(None, text.split(";")):
        name, _, value = item.partition("=")
        settings[name.strip()] = ast.literal_eval(value.strip())
    return settings


def measure(scene_name: str, repeats: int, spp: int, arms: tuple[str, ...]) -> list[str]:
    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.selective_render import apply_estimator
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.sampling.denoise_guides import guides_are_noisy
    from xsl_render.core.sampling.render_options import RenderOptions
    from xsl_render.core.validation.curves import Point, equal_quality_speedup

    scene, blend = open_at_bench_size(scene_name)
    reference = cached_reference(scene, blend, scene_name, "bench_render_settings")
    options = RenderOptions(max_spp=64, estimator="auto").check()
    runs = [(f"auto {count} spp", count, {}) for count in CURVE]
    runs += [(f"auto {spp} spp, {arm}", spp, parse_arm(arm)) for arm in arms]
    results: dict[str, list[tuple[float, dict]]] = {label: [] for label, _, _ in runs}
    for seed in range(repeats):
        for label, count, settings in (runs if seed % 2 == 0 else runs[::-1]):
            choice = choose_estimator(scene, options, count)
            forget_synced_session()
            with preserved_scene(scene):
                apply_estimator(scene, choice)
                for name, value in settings.items():
                    setattr(scene.cycles, name, value)
                started = time.perf_counter()
                with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
                    piece = renderer.render(None, count)
                seconds = time.perf_counter() - started
            prefilter = choice.prefilter_guides and guides_are_noisy(piece.guides[..., :3])
            image = denoise(piece.pixels, piece.guides[..., :3], piece.guides[..., 3:6],
                            prefilter_guides=prefilter)
            results[label].append((seconds, errors(reference, image)))
    medians = {label: (statistics.median(r[0] for r in rows),
                       {key: statistics.median(r[1][key] for r in rows) for key in ("flip", "p95", "mse")})
               for label, rows in results.items()}
    curve = {metric: [Point(medians[f"auto {count} spp"][0], medians[f"auto {count} spp"][1][metric])
                      for count in CURVE] for metric in ("flip", "mse")}
    lines = [f"\n{scene_name} ({SIZES[scene_name][0]}x{SIZES[scene_name][1]}), {repeats} seed(s), "
             "a fresh session per render",
             f"{'run':44s} {'median s':>8s} {'min s':>6s} {'FLIP':>7s} {'p95':>7s} {'MSE':>9s} "
             "| over auto's curve: FLIP MSE"]
    for label, rows in results.items():
        seconds, med = medians[label]
        gains = [equal_quality_speedup(curve[metric], med[metric], seconds) for metric in ("flip", "mse")]
        shown = " ".join(f"{g.value:5.2f}{'*' if g.extrapolated else ' '}" if g.value else "   - "
                         for g in gains)
        lines.append(f"{label:44s} {seconds:8.2f} {min(r[0] for r in rows):6.2f} {med['flip']:7.4f} "
                     f"{med['p95']:7.4f} {med['mse']:9.2e} | {shown}")
    return lines


def main() -> int:
    parser = scene_arguments(__doc__, "bench-render-settings", SCENES)
    parser.add_argument("--spp", type=int, default=16, help="the arms' samples per pixel (default 16)")
    parser.add_argument("--arms", default=",".join(ARMS),
                        help="comma-separated arms, each name=value[;name=value] of scene.cycles")
    args = parser.parse_args(sys.argv[1:])
    scenes = chosen_scenes(args, SCENES, "bench_render_settings")
    if scenes is None:
        return 2
    arms = tuple(a.strip() for a in args.arms.split(",") if a.strip())
    return run_scenes("bench_render_settings", scenes, args.out,
                      lambda scene: measure(scene, args.repeats, args.spp, arms))


if __name__ == "__main__":
    sys.exit(main())
