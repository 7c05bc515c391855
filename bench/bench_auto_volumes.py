"""Benchmark: F12 with Auto Volumes against F12 without, on every example scene, at the scene's
own samples and at 16, 64 and 256 spp; the equal-quality speedup read along the file's own F12
curve. Writes docs/performance.md's section auto_volumes and its rows of the headline table.

Each render is Blender's own F12 of the file as saved at its bench size, its denoiser and
persistent data, seeds 0 .. repeats - 1, the two arms alternating; the time is the whole
operator call, Auto Volumes' prediction included; every error is against the scene's
converged reference. ``bench_estimator.py``'s auto row is the command line's (one choice,
two front ends: they should agree within noise).

    .venv/bin/python bench/bench_auto_volumes.py --scenes balls_b,street --repeats 3
    .venv/bin/python bench/bench_auto_volumes.py --tiny          # end to end in a minute or so"""
from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_denoise_guides import errors  # noqa: E402
from bench_estimator import ROOT, SIZES, chosen_scenes, scene_arguments  # noqa: E402
from performance_doc import (HEADLINE, HEADLINE_COUNTS, HEADLINE_HEADER, speedup_text,  # noqa: E402
                             write_bench_output, write_rows)

SCENES = ("road", "balls_a", "balls_b", "statue", "street")
COUNTS = (None, *HEADLINE_COUNTS)           # None: the scene's own samples
CURVE = (4, 8, 16, 32, 64, 128, 256, 512)
METRICS = ("flip", "p95", "mse")
#: --tiny: a tenth of the bench size, few samples, a 16-spp reference: the script end to end.
TINY = {"scale": 0.1, "counts": (None, 2), "curve": (1, 2, 4), "reference_spp": 16}
#: What the headline table's cells are.
HEADLINE_NOTE = ("Equal-quality speedup of Auto Volumes over the file as it is (F12, its own "
                 "settings), mean FLIP / p95-tile FLIP, read along the file's own time-quality curve; "
                 "\\* read beyond the curve's measured range.")


def open_scene(bpy, name: str, scale: float):
    blend = ROOT / "example_blends" / f"{name}.blend"
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    width, height = SIZES[name]
    scene.render.resolution_x, scene.render.resolution_y = max(8, int(width * scale)), max(8, int(height * scale))
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    return scene, blend


def reference_image(scene, blend, spp: int | None):
    from xsl_render.addon.validation.reference import ensure_reference, reference_inputs
    from xsl_render.core.validation.reference import read_reference

    size = (scene.render.resolution_x, scene.render.resolution_y)
    found = ensure_reference(scene, reference_inputs(scene, blend, spp=spp, max_spp=64, resolution=size))
    return read_reference(found.path, size).image


def f12(bpy, scene, folder: Path, samples: int, seed: int, auto: bool) -> tuple[float, object]:
    """One F12 of the scene at ``samples`` and ``seed``: (seconds, image)."""
    from xsl_render.core.imageio import read_image

    scene.cycles.samples, scene.cycles.seed = samples, seed
    scene.xsl_render.auto_volumes = auto
    scene.render.filepath = str(folder / "f12")
    started = time.perf_counter()
    bpy.ops.render.render(write_still=True, scene=scene.name)
    seconds = time.perf_counter() - started
    scene.xsl_render.auto_volumes = False
    return seconds, read_image(folder / "f12.exr")


def measure(bpy, name: str, repeats: int, settings: dict) -> tuple[list[str], dict]:
    """The scene's lines, and auto's speedups (metric -> Speedup dict) per count."""
    from xsl_render.core.validation.curves import Point, equal_quality_speedup

    scene, blend = open_scene(bpy, name, settings["scale"])
    reference = reference_image(scene, blend, settings["reference_spp"])
    own = int(scene.cycles.samples)
    lines = [f"\n{name} ({scene.render.resolution_x}x{scene.render.resolution_y}, its own {own} spp), "
             f"median of {repeats}",
             f"{'spp':>5s} {'arm':5s} {'s':>7s} {'FLIP':>7s} {'p95':>7s} {'MSE':>9s}  speedup FLIP / p95 / MSE"]
    found: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)

        def arm(samples: int, auto: bool) -> dict:
            runs = []
            for seed in range(repeats):
                seconds, image = f12(bpy, scene, folder, samples, seed, auto)
                runs.append({"s": seconds, **errors(reference, image)})
            return {key: statistics.median(run[key] for run in runs) for key in runs[0]}

        curve = {samples: arm(samples, False) for samples in settings["curve"]}
        for count in settings["counts"]:
            samples = own if count is None else count
            plain = curve.get(samples) or arm(samples, False)
            auto = arm(samples, True)
            speedups = []
            for metric in METRICS:
                points = [Point(run["s"], run[metric]) for run in curve.values()]
                speedup = equal_quality_speedup(points, auto[metric], auto["s"]).to_dict()
                found.setdefault(count, {})[metric] = speedup
                speedups.append(speedup_text(speedup))
            for label, run, extra in (("file", plain, ""), ("auto", auto, "  " + " / ".join(speedups))):
                lines.append(f"{samples:5d} {label:5s} {run['s']:7.2f} {run['flip']:7.4f} {run['p95']:7.4f} "
                             f"{run['mse']:9.3e}{extra}")
    return lines, found


def main(argv=None) -> int:
    parser = scene_arguments(__doc__, "bench-auto-volumes", SCENES)
    parser.add_argument("--tiny", action="store_true", help="a tenth of the size, few samples: a check")
    args = parser.parse_args(argv)
    scenes = chosen_scenes(args, SCENES, "bench_auto_volumes")
    if scenes is None:
        return 2
    settings = TINY if args.tiny else {"scale": 1.0, "counts": COUNTS, "curve": CURVE, "reference_spp": None}
    repeats = 1 if args.tiny else args.repeats

    import bpy

    import xsl_render

    xsl_render.register()
    lines = [f"bench_auto_volumes: {', '.join(scenes)}{' (tiny)' if args.tiny else ''}"]
    rows = []
    for name in scenes:
        scene_lines, speedups = measure(bpy, name, repeats, settings)
        print("\n".join(scene_lines), flush=True)
        lines += scene_lines
        rows.append([name] + [" / ".join(speedup_text(speedups.get(count, {}).get(metric)).replace("*", "\\*")
                                         for metric in ("flip", "p95")) for count in HEADLINE_COUNTS])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_auto_volumes.txt").write_text("\n".join(lines) + "\n")
    if not args.tiny:
        write_bench_output("auto_volumes", "Auto Volumes in F12 (bench_auto_volumes.py)",
                           "bench_auto_volumes.py", argv, lines)
        write_rows(HEADLINE, HEADLINE_HEADER, rows, note=HEADLINE_NOTE)
    return 0


if __name__ == "__main__":
    sys.exit(main())
