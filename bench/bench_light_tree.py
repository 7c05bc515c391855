"""Benchmark: auto without Cycles' light tree where the scene has one light.

With one light the tree has nothing to choose and only costs (``core.sampling.light_tree``).
Per scene (at ``bench_estimator.SIZES``) auto's own choice against the same choice with the
file's light tree, the whole frame in a fresh Cycles session each, arms alternating, seeds
0 .. repeats - 1, against the cached converged reference: median and fastest seconds, their
ratio, and the medians of mean FLIP, p95 region FLIP and MSE. On scenes with several lights
(``--scenes road,statue``) it shows what the tree buys there.

    .venv/bin/python bench/bench_light_tree.py --scenes balls_a,balls_b --repeats 5"""
from __future__ import annotations

import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import cached_reference, errors, open_at_bench_size, run_scenes  # noqa: E402
from bench_estimator import SIZES, chosen_scenes, scene_arguments  # noqa: E402

SCENES = ("balls_a", "balls_b", "statue", "road")
COUNTS = (4, 16, 32)


def measure(scene_name: str, repeats: int) -> list[str]:
    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.selective_render import apply_estimator
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.sampling.render_options import RenderOptions

    scene, blend = open_at_bench_size(scene_name)
    reference = cached_reference(scene, blend, scene_name, "bench_light_tree")
    options = RenderOptions(max_spp=64, estimator="auto").check()
    lines = [f"\n{scene_name} ({SIZES[scene_name][0]}x{SIZES[scene_name][1]}), {repeats} seed(s), "
             "a fresh session per render",
             f"{'run':34s} {'median s':>8s} {'min s':>6s} {'FLIP':>7s} {'p95':>7s} {'MSE':>9s}"]
    for spp in COUNTS:
        auto = choose_estimator(scene, options, spp)
        arms = {"auto": auto, "auto, the file's light tree": replace(auto, light_tree=None)}
        if auto.light_tree is None:
            arms = {"auto (keeps the tree)": auto, "auto, light tree off": replace(auto, light_tree=False)}
        results: dict[str, list[tuple[float, dict]]] = {label: [] for label in arms}
        for seed in range(repeats):
            order = list(arms.items()) if seed % 2 == 0 else list(reversed(arms.items()))
            for label, choice in order:
                forget_synced_session()
                with preserved_scene(scene):
                    apply_estimator(scene, choice)
                    started = time.perf_counter()
                    with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
                        piece = renderer.render(None, spp)
                    seconds = time.perf_counter() - started
                image = denoise(piece.pixels, piece.guides[..., :3], piece.guides[..., 3:6],
                                prefilter_guides=True)
                results[label].append((seconds, errors(reference, image)))
        medians = {}
        for label, rows in results.items():
            seconds = [row[0] for row in rows]
            med = {key: statistics.median(row[1][key] for row in rows) for key in ("flip", "p95", "mse")}
            medians[label] = statistics.median(seconds)
            lines.append(f"{label + f' {spp} spp':34s} {medians[label]:8.2f} {min(seconds):6.2f} "
                         f"{med['flip']:7.4f} {med['p95']:7.4f} {med['mse']:9.2e}")
        first, second = medians.values()
        lines.append(f"{'':34s} time ratio (second / first) {second / first:.2f}")
    return lines


def main() -> int:
    args = scene_arguments(__doc__, "bench-light-tree", SCENES).parse_args(sys.argv[1:])
    scenes = chosen_scenes(args, SCENES, "bench_light_tree")
    if scenes is None:
        return 2
    return run_scenes("bench_light_tree", scenes, args.out, lambda scene: measure(scene, args.repeats))


if __name__ == "__main__":
    sys.exit(main())
