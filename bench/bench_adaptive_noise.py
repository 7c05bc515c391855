"""Measurement: the noise Cycles' adaptive sampling leaves, as the uniform sample count that
leaves the same noise (what Auto Volumes takes its tolerance at for an adaptive render:
``core.sampling.shot_plan.estimator_samples``). Noise only, not time: any machine.

Per scene (its own settings, F12 without a denoiser, at ``--percentage`` of its size), a
render's noise is the median over pixels of |seed a - seed b| / sqrt(2), relative to the
pixel's luminance; uniform renders at ``COUNTS`` make the curve an adaptive render's threshold
is read along. Prints t x N and N over the minimum samples, which the estimator's constants
bound from above.

    .venv/bin/python bench/bench_adaptive_noise.py --scenes balls_b,road --percentage 25"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
COUNTS = (4, 8, 16, 32, 64, 128, 256)
THRESHOLDS = (0.1, 0.05, 0.02, 0.01)
FLOOR = 0.05
LUMINANCE = np.array([0.2126, 0.7152, 0.0722], np.float32)


def render(bpy, scene, folder: Path, seed: int, samples: int, threshold: float | None) -> np.ndarray:
    from xsl_render.core.imageio import read_image

    cycles = scene.cycles
    cycles.samples, cycles.seed, cycles.use_denoising = samples, seed, False
    cycles.use_adaptive_sampling = threshold is not None
    if threshold is not None:
        cycles.adaptive_threshold, cycles.adaptive_min_samples = threshold, 0
    scene.render.filepath = str(folder / "frame")
    bpy.ops.render.render(write_still=True, scene=scene.name)
    return read_image(folder / "frame.exr")[..., :3] @ LUMINANCE


def noise(bpy, scene, folder: Path, samples: int, threshold: float | None = None) -> float:
    a = render(bpy, scene, folder, 1, samples, threshold)
    b = render(bpy, scene, folder, 2, samples, threshold)
    level = np.maximum((a + b) / 2, FLOOR)
    return float(np.median(np.abs(a - b) / math.sqrt(2) / level))


def equivalent_count(curve: list[tuple[int, float]], value: float) -> float:
    """The uniform count whose noise is ``value``, log-log between the curve's points."""
    counts = np.log([c for c, _ in curve])
    noises = np.log([n for _, n in curve])
    order = np.argsort(noises)
    return float(np.exp(np.interp(np.log(value), noises[order], counts[order])))


def measure(bpy, name: str, percentage: int, ceiling: int) -> list[str]:
    bpy.ops.wm.open_mainfile(filepath=str(ROOT / "example_blends" / f"{name}.blend"), load_ui=False)
    scene = bpy.context.scene
    scene.render.resolution_percentage = percentage
    scene.render.image_settings.file_format = "OPEN_EXR"
    # A fresh session each render: a kept one would not see the new samples (untagged).
    scene.render.use_persistent_data = False
    lines = [f"\n{name} at {percentage} %: uniform noise"]
    with tempfile.TemporaryDirectory() as folder:
        curve = [(count, noise(bpy, scene, Path(folder), count)) for count in COUNTS]
        lines += [f"  {count:5d} spp  {value:.4f}  (x sqrt(spp) {value * math.sqrt(count):.3f})"
                  for count, value in curve]
        for threshold in THRESHOLDS:
            value = noise(bpy, scene, Path(folder), ceiling, threshold)
            count = equivalent_count(curve, value)
            minimum = math.ceil(16.0 / threshold ** 0.3)          # Cycles' automatic minimum
            lines.append(f"  adaptive t={threshold:<5g} noise {value:.4f} = uniform {count:7.1f} spp; "
                         f"t x spp = {threshold * count:.2f}, spp / minimum {count / minimum:.2f}")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="balls_b,road")
    parser.add_argument("--percentage", type=int, default=25)
    parser.add_argument("--ceiling", type=int, default=1024, help="adaptive renders' samples")
    args = parser.parse_args(argv)
    import bpy

    for name in args.scenes.split(","):
        print("\n".join(measure(bpy, name.strip(), args.percentage, args.ceiling)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
