"""Benchmark: which denoising guides leave OIDN the least error in fog?

In fog Cycles writes the albedo and normal guides at the first scattering event, as noisy as
the image. At equal samples of the image: the guides as rendered (every mode's denoise),
prefiltered (denoised first, quality Balanced, auto's, and High), another seed's, a
surface-only render's (the media taken out), none. Each scene at ``bench_estimator.SIZES``
with auto's choice at ``--spp``, seeds 0 .. repeats - 1, against the cached converged
reference; prints medians and the denoise's seconds.

    .venv/bin/python bench/bench_denoise_guides.py --repeats 3 [--spp 32]"""
from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_estimator import ROOT, SIZES, chosen_scenes, scene_arguments  # noqa: E402

SCENES = ("road", "balls_a", "balls_b", "statue")
#: Auto's step rate at 16 spp (None: the scene's own), from the estimator tables.
AUTO_RATE = {"road": None, "balls_a": None, "balls_b": 0.5, "statue": 4.0}
SPP = 16
SURFACE_SPP = (1, 4)


def _hide_media(scene) -> None:
    """Take the media out of ``scene``: the world's volume unlinked, volume objects and meshes
    whose every material is volume-only hidden from the render."""
    world = scene.world
    if world is not None and world.node_tree is not None:
        for link in list(world.node_tree.links):
            if link.to_socket.name == "Volume":
                world.node_tree.links.remove(link)
    for obj in scene.objects:
        if obj.type == "VOLUME":
            obj.hide_render = True
        elif obj.type == "MESH" and obj.material_slots:
            surfaces = [node.inputs["Surface"].is_linked
                        for slot in obj.material_slots if slot.material and slot.material.node_tree
                        for node in slot.material.node_tree.nodes if node.type == "OUTPUT_MATERIAL"]
            if surfaces and not any(surfaces):
                obj.hide_render = True


def open_at_bench_size(scene_name: str):
    """The example scene opened at its bench size (``SIZES``); (scene, blend path)."""
    import bpy

    blend = ROOT / "example_blends" / f"{scene_name}.blend"
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = SIZES[scene_name]
    scene.render.resolution_percentage = 100
    return scene, blend


def open_with_auto_choice(scene_name: str):
    """The example scene opened at its bench size with auto's choice at 16 spp set by hand
    (``AUTO_RATE``, blue noise); (scene, blend path)."""
    scene, blend = open_at_bench_size(scene_name)
    scene.cycles.volume_biased = True
    if AUTO_RATE[scene_name] is not None:
        scene.cycles.volume_step_rate = AUTO_RATE[scene_name]
    scene.cycles.sampling_pattern = "AUTOMATIC"
    return scene, blend


def run_scenes(bench: str, scenes: list[str], out: Path, measure) -> int:
    """``measure(scene)`` for each scene, printed as it comes and written to out/<bench>.txt."""
    lines = [f"{bench}: {', '.join(scenes)}"]
    for scene in scenes:
        scene_lines = measure(scene)
        print("\n".join(scene_lines), flush=True)
        lines += scene_lines
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{bench}.txt").write_text("\n".join(lines) + "\n")
    return 0


def cached_reference(scene, blend, scene_name: str, bench: str):
    """The converged reference the estimator benches render and cache (ceiling 64: 1024 spp,
    seed 7), (H, W, 4); exits naming the bench that renders it where it is not cached."""
    from xsl_render.addon.validation.reference import reference_inputs
    from xsl_render.core.validation.reference import find_reference, read_reference

    size = (scene.render.resolution_x, scene.render.resolution_y)
    cached = find_reference(reference_inputs(scene, blend, max_spp=64, resolution=size).key)
    if cached is None:
        raise SystemExit(f"{bench}: no cached reference of {scene_name}; "
                         f"run bench/bench_estimator.py --scenes {scene_name} first")
    return read_reference(cached.path, size).image


def errors(reference, image) -> dict:
    from xsl_render.core.validation.image_pair import ImagePair, as_rgb
    from xsl_render.core.validation.metrics import compare_images

    results = compare_images(ImagePair(as_rgb(reference), as_rgb(image[..., :3]), True), vdp=False)
    return {"flip": results["flip"].extra["mean_flip"], "p95": results["flip"].extra["tile95_flip"],
            "mse": results["mse"].extra.get("mse", results["mse"].average_error_percent)}


def measure(scene_name: str, repeats: int, spp_count: int = 16) -> list[str]:
    import numpy as np

    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.oidn_library import QUALITY_HIGH
    from xsl_render.addon.cycles.oidn_library import load as load_oidn
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer

    scene, blend = open_with_auto_choice(scene_name)
    width, height = SIZES[scene_name]
    reference = cached_reference(scene, blend, scene_name, "bench_denoise_guides")

    renders = []
    for seed in range(repeats + 1):           # one more: the last seed's guides are "other seed"'s
        with CyclesWindowRenderer(scene, seed, guides=True) as renderer:
            renders.append(renderer.render(None, spp_count))
    _hide_media(scene)
    surface, surface_s = {}, {}
    for spp in SURFACE_SPP:
        with CyclesWindowRenderer(scene, 7, guides=True) as renderer:
            began = time.perf_counter()
            surface[spp] = renderer.render(None, spp).guides
            surface_s[spp] = time.perf_counter() - began

    library = load_oidn()

    def prefiltered_high(k: int) -> np.ndarray:
        """The render's own guides denoised first at quality High (auto's use Balanced)."""
        guides = renders[k].guides[::-1]
        albedo = library.prefilter(guides[..., :3], "albedo", QUALITY_HIGH)
        normal = library.prefilter(guides[..., 3:6], "normal", QUALITY_HIGH)
        out = library.denoise(renders[k].pixels[::-1], albedo, normal, hdr=True, clean_aux=True,
                              quality=QUALITY_HIGH)[::-1]
        return np.concatenate([np.maximum(out, 0.0), renders[k].pixels[..., 3:]], axis=2)

    def with_guides(guides_of, prefilter: bool = False):
        def run(k: int) -> np.ndarray:
            guides = guides_of(k)
            return denoise(renders[k].pixels, guides[..., :3], guides[..., 3:6], prefilter_guides=prefilter)
        return run

    variants = {"as rendered (every mode)": with_guides(lambda k: renders[k].guides),
                "prefiltered, Balanced (auto)": with_guides(lambda k: renders[k].guides, prefilter=True),
                "prefiltered, High": prefiltered_high,
                "another seed's": with_guides(lambda k: renders[k + 1].guides),
                **{f"surface-only, {spp} spp": with_guides(lambda k, spp=spp: surface[spp]) for spp in SURFACE_SPP},
                "none": lambda k: denoise(renders[k].pixels)}
    lines = [f"\n{scene_name} ({width}x{height}, {spp_count} spp, seeds 0-{repeats - 1}; surface guide renders "
             + ", ".join(f"{spp} spp {surface_s[spp]:.2f} s" for spp in SURFACE_SPP)
             + f" with their scene sync; a {spp_count}-spp render {renders[0].seconds:.2f} s)",
             f"{'guides':28s} {'FLIP':>7s} {'p95tile':>7s} {'MSE':>9s} {'den s':>5s}  (medians; FLIP per seed)"]
    for label, denoised in variants.items():
        rows, seconds = [], []
        for k in range(repeats):
            began = time.perf_counter()
            image = denoised(k)
            seconds.append(time.perf_counter() - began)
            rows.append(errors(reference, image))
        lines.append(error_line(label, rows, f"{statistics.median(seconds):5.2f}"))
    return lines


def error_line(label: str, rows: list[dict], extra: str = "") -> str:
    """One run's medians of ``errors`` over its repeats, then its mean FLIP per repeat."""
    med = {key: statistics.median(row[key] for row in rows) for key in ("flip", "p95", "mse")}
    return (f"{label:28s} {med['flip']:7.4f} {med['p95']:7.4f} {med['mse']:9.2e} {extra} "
            + " ".join(f"{row['flip']:.4f}" for row in rows))


def main_at_spp(doc: str, bench: str, out: str, scenes: tuple[str, ...], spp: int, measure) -> int:
    """A bench over example scenes at one sample count: --out, --scenes, --repeats, --spp;
    ``measure(scene, repeats, spp)`` per scene."""
    parser = scene_arguments(doc, out, scenes)
    parser.add_argument("--spp", type=int, default=spp, help=f"samples per pixel (default {spp})")
    args = parser.parse_args(sys.argv[1:])
    chosen = chosen_scenes(args, scenes, bench)
    if chosen is None:
        return 2
    return run_scenes(bench, chosen, args.out, lambda scene: measure(scene, args.repeats, args.spp))


def main() -> int:
    return main_at_spp(__doc__, "bench_denoise_guides", "bench-guides", SCENES, SPP, measure)


if __name__ == "__main__":
    sys.exit(main())
