"""The sample count a time budget affords, priced by timed renders of the same frame (an
earlier run, or a pilot): a line through their (samples, seconds) gives what a render costs
whatever its count (scene sync, auto's prediction, denoising) and what each sample adds.
``bench/bench_guided_choice.py`` compares auto at that count with guided and with Cycles' own
time limit."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np


def sample_cost(timed: Sequence[tuple[float, float]]) -> tuple[float, float]:
    """(fixed seconds, seconds per sample) of the least-squares line through ``timed``, each
    ``(samples, seconds)``, two counts at least. Where the line has no positive slope (counts
    too close for the clock), every second is charged to the samples."""
    samples = np.array([float(s) for s, _ in timed])
    seconds = np.array([float(t) for _, t in timed])
    if len(set(samples.tolist())) < 2:
        raise ValueError("pricing a sample needs renders of two counts at least")
    slope, fixed = np.polyfit(samples, seconds, 1)
    if not slope > 0.0:
        return 0.0, float(np.max(seconds / samples))
    return max(0.0, float(fixed)), float(slope)


def affordable_count(budget_s: float, timed: Sequence[tuple[float, float]]) -> int:
    """The most samples whose priced time stays within ``budget_s`` (at least 1)."""
    fixed, per_sample = sample_cost(timed)
    return max(1, int(math.floor((budget_s - fixed) / per_sample)))
