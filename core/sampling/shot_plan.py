"""Auto Volumes' plan for a shot: which frames auto predicts, which of their choices the shot
renders with, and the sample count a frame's own settings give its tolerance.

A frame's choice must not depend on how the frames are split between processes (alone, a
chunk, the whole range) nor switch back and forth along the shot (the bias would flicker).
So a shot is the file's frame range (a frame outside it is a shot of its own); auto predicts
at ``SHOT_SAMPLES`` frames spread evenly over it, always the same ones, and the whole shot
renders with the most cautious of their choices (``most_cautious``). An unanimated file is
predicted once, at the range's first frame.
"""
from __future__ import annotations

import math

#: Frames of an animated shot auto predicts at (its first and last among them).
SHOT_SAMPLES = 5
#: Cycles' noise threshold where the file leaves it at 0 (automatic): 1 / samples, at least
#: this (``Integrator::get_adaptive_sampling``).
MIN_AUTOMATIC_THRESHOLD = 0.001
#: The noise an adaptive render leaves at noise threshold t (as samples everywhere would
#: leave it), measured on balls_b, road and statue (``bench/bench_adaptive_noise.py``,
#: docs/auto_volumes.md): about t x samples = 1.8-4.2 where the threshold stops the pixels,
#: and 1.2-1.6 x the minimum samples where that minimum does; the larger of the two at the
#: cautious end (more samples: a stricter tolerance).
ADAPTIVE_SAMPLES_TIMES_THRESHOLD = 4.2
ADAPTIVE_MINIMUM_SHARE = 1.6


def shot_of(frame: int, start: int, end: int) -> tuple[int, int]:
    """The shot ``frame`` belongs to: the range ``start``-``end`` when it is in it, else itself."""
    if start <= frame <= end:
        return start, end
    return frame, frame


def sampled_frames(shot: tuple[int, int], animated: bool, count: int = SHOT_SAMPLES) -> tuple[int, ...]:
    """The frames auto predicts for ``shot``: ``count`` spread evenly from its first to its
    last frame, or only the first where nothing in the file moves."""
    start, end = shot
    if not animated or end <= start or count < 2:
        return (start,)
    return tuple(sorted({math.floor(start + (end - start) * i / (count - 1) + 0.5) for i in range(count)}))


def caution(choice) -> tuple:
    """A sort key of an ``EstimatorChoice``: smaller is more cautious. The scene's own settings
    (auto unsure, or nothing to choose) first, then null scattering (unbiased), then ray
    marching from the finest scene step to the coarsest, a choice giving no medium a coarser
    step of its own before one that does."""
    if choice.biased is None:
        return (0,)
    if not choice.biased:
        return (1,)
    rate = math.inf if choice.step_rate is None else float(choice.step_rate)
    coarser = max((float(r) for r in (choice.medium_rates or {}).values()), default=0.0)
    return (2, rate, coarser)


def most_cautious(choices: list) -> int:
    """The index of the most cautious of ``choices`` (the first of equals: the earliest frame)."""
    if not choices:
        raise ValueError("no choice to pick from")
    return min(range(len(choices)), key=lambda index: caution(choices[index]))


def layer_samples(scene_samples: int, layer_samples: int, use_layer_samples: str) -> int:
    """The samples Cycles renders a view layer with: its own where the scene says so
    (``cycles.use_layer_samples`` 'USE', or 'BOUNDED' under the scene's), else the scene's."""
    if layer_samples > 0 and use_layer_samples == "USE":
        return layer_samples
    if layer_samples > 0 and use_layer_samples == "BOUNDED":
        return min(layer_samples, scene_samples)
    return scene_samples


def estimator_samples(samples: int, adaptive: bool = False, threshold: float = 0.0,
                      min_samples: int = 0) -> float:
    """The samples per pixel whose noise auto's tolerance is taken at, for a render of
    ``samples`` (with adaptive sampling: its ceiling) and the file's adaptive settings
    (``threshold`` and ``min_samples`` 0: Cycles' automatic ones). A time limit is not
    counted: it can only stop the render earlier, noisier, so the ceiling is the cautious
    count."""
    samples = max(1, int(samples))
    if not adaptive:
        return float(samples)
    if threshold <= 0.0:
        threshold = max(MIN_AUTOMATIC_THRESHOLD, 1.0 / samples)
    if min_samples <= 0:
        min_samples = math.ceil(16.0 / threshold ** 0.3)      # Cycles' automatic minimum
    equivalent = max(ADAPTIVE_MINIMUM_SHARE * min_samples, ADAPTIVE_SAMPLES_TIMES_THRESHOLD / threshold)
    return float(min(samples, equivalent))
