"""Where a time-budgeted render spends its samples (``--mode guided``).

The guided render's pilot (the whole frame at a quarter of its resolution, a few samples,
denoised) scores every tile by the mean gradient of its display luminance, where a denoised
frame keeps its error; the budget then goes to the tiles in proportion to ``score **
exponent * importance ** IMPORTANCE_EXPONENT``, every pixel rendered from its first sample in
one Cycles session. The default exponent is 0 (every pixel alike, the pilot only timing the
render): after denoising, moving samples buys MSE far more than FLIP, and the scored
allocation lost to plain uniform sampling at equal time (docs/paper.md, "What it measured";
docs/performance.md, "Guided"). Counts are rounded to powers of ``level_ratio`` so neighbouring
tiles merge into few renders. Plain numbers only; the caller reads the clock."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SettingError
from ..option_table import DEFAULTS, OPTIONS
from .composite import Window
from .render_options import UNBOUNDED_SPP  # noqa: F401 (where guided's callers found it)
from .tile_plan import Rect, merge_rects, render_order, tile_windows

#: A tile's score never falls below this share of the frame's mean score, so that flat
#: tiles, whose pilot gradient is noise-free zero, still get their share.
SCORE_FLOOR = 0.05
#: The final pass is cut into at least this many renders, so that the ones at its end can
#: make up for a region that costs more per sample than the pilot said (a fog box on the
#: floor costs twice the sky).
FINAL_PASS_PIECES = 10
#: A flat final pass (every pixel planned alike) is cut into this many columns.
FLAT_PASS_PIECES = 3
#: The director map weighs a tile's samples as its mean to this power (the gentle exponent
#: the pilot's scores had when both were weighed together; linear, as the paper's XSL map
#: scales samples, loses FLIP badly).
IMPORTANCE_EXPONENT = 0.15


@dataclass(frozen=True)
class GuidedOptions:
    """How a guided render spends its time budget. (Its ceiling and tile size are the render
    options' ``max_spp`` and ``tile_size``, as for every mode.)

    Parameters
    ----------
    time_budget
        Seconds for the whole render: maps, scene sync, passes, denoising.
    pilot_fraction
        Most of the budget (after maps and scene sync) the low-resolution pilot may take.
    exponent
        Allocation exponent on the pilot's error scores. 0 (the default) scores nothing:
        the pilot only times the render and the samples are spread evenly, or by the
        importance map alone (see the module docstring for why).
    importance
        Director map weighting the allocation: "none", "x", "xs" or "xsl" (the tiles'
        weights go as its mean to ``IMPORTANCE_EXPONENT``).
    level_ratio
        Sample counts of the final pass are rounded to powers of this ratio.
    """

    time_budget: float
    pilot_fraction: float = DEFAULTS["pilot_fraction"]
    exponent: float = DEFAULTS["exponent"]
    importance: str = DEFAULTS["importance"]
    level_ratio: float = DEFAULTS["level_ratio"]

    def check(self) -> "GuidedOptions":
        """Raise InputError naming the first impossible option (each against its option,
        ``core.option_table``); return self."""
        if self.time_budget is None:
            raise SettingError("{time_budget.name} SECONDS is needed", time_budget=None)
        for name in ("time_budget", "pilot_fraction", "exponent", "importance", "level_ratio"):
            OPTIONS[name].check(getattr(self, name))
        return self

    def to_dict(self) -> dict:
        return asdict(self)


def tile_means(image: np.ndarray, windows: list[Window], scale: int = 1) -> np.ndarray:
    """Mean of ``image`` (h, w) over each window of the full frame; ``scale`` is how many
    full-resolution pixels one pixel of ``image`` spans (2 for a half-resolution image)."""
    height, width = image.shape[:2]
    means = np.empty(len(windows))
    for index, (row0, row1, col0, col1) in enumerate(windows):
        r0, c0 = min(row0 // scale, height - 1), min(col0 // scale, width - 1)
        r1, c1 = max(r0 + 1, -(-row1 // scale)), max(c0 + 1, -(-col1 // scale))
        means[index] = float(np.mean(image[r0:r1, c0:c1]))
    return means


def error_scores(display_luminance: np.ndarray, windows: list[Window], scale: int = 1) -> np.ndarray:
    """Each tile's score: the mean gradient magnitude of the denoised pilot's display
    luminance (values in [0, 1]) over the tile, floored at ``SCORE_FLOOR`` x the mean."""
    luminance = np.asarray(display_luminance, np.float64)
    if luminance.ndim != 2 or min(luminance.shape) < 2:
        raise ValueError(f"the pilot luminance must be an image of at least 2x2 pixels (got {luminance.shape})")
    gradient = np.hypot(*np.gradient(luminance))
    scores = tile_means(gradient, windows, scale)
    floor = SCORE_FLOOR * max(float(scores.mean()), 1e-12)
    return np.maximum(scores, floor)


def allocate(weights: np.ndarray, areas: np.ndarray, have: float, extra_samples: float,
             ceiling: int) -> np.ndarray:
    """Total samples per pixel of each tile after the final pass.

    Tiles get ``max(have, s * weight)``, capped at ``ceiling``, with ``s`` chosen so that
    the samples added, ``sum(area * (total - have))``, equal ``extra_samples`` (or as many
    as the ceiling lets in).

    Parameters
    ----------
    weights : (n,) non-negative tile weights (at least one positive).
    areas : (n,) pixels per tile.
    have : samples per pixel every tile already has (the pilot's).
    extra_samples : pixel-samples the final pass may add.
    ceiling : most samples per pixel a tile may reach.
    """
    weights = np.asarray(weights, np.float64)
    areas = np.asarray(areas, np.float64)
    if weights.shape != areas.shape or weights.ndim != 1 or not len(weights):
        raise ValueError("weights and areas must be matching non-empty vectors")
    if not (np.isfinite(weights).all() and (weights >= 0).all() and weights.max() > 0):
        raise ValueError("weights must be finite, non-negative and not all zero")
    have = float(have)
    if extra_samples <= 0 or have >= ceiling:
        return np.full(len(weights), min(have, float(ceiling)))

    def added(scale: float) -> float:
        return float((areas * (np.clip(scale * weights, have, ceiling) - have)).sum())

    if added(ceiling / weights[weights > 0].min()) <= extra_samples:
        return np.where(weights > 0, float(ceiling), have)
    low, high = 0.0, ceiling / weights[weights > 0].min()
    for _ in range(80):                      # bisection on a monotone function
        middle = 0.5 * (low + high)
        low, high = (middle, high) if added(middle) < extra_samples else (low, middle)
    return np.clip(low * weights, have, ceiling)


def round_to_levels(counts: np.ndarray, ratio: float, anchor: float = 1.0) -> np.ndarray:
    """Counts (>= 0) rounded, in log space, to the nearest level ``anchor * ratio**k`` (0
    stays 0, anything below half a sample becomes 0), as integers: nearby counts share a
    level, and a count equal to ``anchor`` stays exact."""
    counts = np.asarray(counts, np.float64)
    positive = counts >= 0.5
    anchor = max(float(anchor), 1.0)
    exponents = np.round(np.log(np.maximum(counts, 0.5) / anchor) / math.log(ratio))
    levels = np.maximum(1.0, np.round(anchor * ratio ** exponents))
    return np.where(positive, levels, 0).astype(np.int64)


@dataclass(frozen=True)
class FinalPass:
    """The rectangles of the final pass: each renders its pixels' ``spp`` samples from the
    first, in one Cycles session (see the module docstring)."""

    rects: list[Rect]
    totals: np.ndarray               # (n_tiles,) planned samples per pixel of each tile
    flat: bool = False               # every pixel planned alike

    @property
    def samples(self) -> int:
        return sum(rect.samples for rect in self.rects)

    def to_dict(self) -> dict:
        return {"renders": len(self.rects), "samples": self.samples, "flat": self.flat,
                "rects": [rect.to_dict() for rect in self.rects]}


def plan_final_pass(scores: np.ndarray, importance: np.ndarray | None, width: int, height: int,
                    options: GuidedOptions, pixel_samples: float, tile_size: int,
                    ceiling: int) -> FinalPass:
    """The final pass of a guided render: tiles of ``tile_size`` (the windows of
    ``tile_plan.tile_windows``, in that order, as ``scores`` and ``importance`` are) sharing
    ``pixel_samples`` pixel-samples, every pixel at least one and at most ``ceiling``."""
    windows = tile_windows(width, height, tile_size)
    if len(scores) != len(windows) or (importance is not None and len(importance) != len(windows)):
        raise ValueError("one score (and importance) per tile is needed")
    areas = np.array([(r1 - r0) * (c1 - c0) for r0, r1, c0, c1 in windows], np.float64)
    weights = np.maximum(np.asarray(scores, np.float64), 1e-12) ** options.exponent
    if importance is not None:
        weights = weights * np.maximum(np.asarray(importance, np.float64), 1e-12) ** IMPORTANCE_EXPONENT
    totals = allocate(weights, areas, 1, pixel_samples - areas.sum(), ceiling)
    # Levels anchored at the mean count: a flat allocation stays exact.
    mean = float((areas * totals).sum() / areas.sum())
    counts = np.clip(round_to_levels(totals, options.level_ratio, anchor=round(mean)), 1, ceiling)
    if len(set(counts.tolist())) == 1:
        # A flat plan: the frame in three columns, each next one paced by what those before
        # it cost at full resolution (the last one makes up for the second's timing noise;
        # more pieces are only more fixed costs). Side by side, not one above the other: a
        # frame's top and bottom differ most in cost (sky and fog on the floor: twice per
        # sample), its columns least.
        edges = [width * k // FLAT_PASS_PIECES for k in range(FLAT_PASS_PIECES + 1)]
        rects = [Rect(0, height, left, right, int(counts[0])) for left, right in zip(edges, edges[1:])
                 if right > left]
        return FinalPass(rects=rects, totals=totals, flat=True)
    rects = merge_rects([Rect(r0, r1, c0, c1, int(count))
                         for (r0, r1, c0, c1), count in zip(windows, counts)])
    return FinalPass(rects=render_order(split_rects(rects, FINAL_PASS_PIECES)), totals=totals)


def split_rects(rects: list[Rect], pieces: int) -> list[Rect]:
    """``rects`` with any holding more than 1/``pieces`` of all their samples cut into bands
    of whole rows that do not (a single row is not cut): a render's cost is only known once
    it is done, and the renders after it make up for it (``BudgetPacer``)."""
    most = max(1, -(-sum(rect.samples for rect in rects) // pieces))
    out = []
    for rect in rects:
        bands = min(rect.height, -(-rect.samples // most))
        edges = [rect.row0 + rect.height * k // bands for k in range(bands + 1)]
        out += [Rect(top, bottom, rect.col0, rect.col1, rect.spp)
                for top, bottom in zip(edges, edges[1:])]
    return out


#: A render of a plan weighted by scores or a map may take at most this many times its
#: planned samples (``BudgetPacer``): a region cheaper than the pilot said must not take the
#: time of one dearer than it said. So where the pilot priced a sample at more than this
#: many times what the final pass paid, such a plan ends early in proportion.
PACE_MAX_SCALE = 2.0


class BudgetPacer:
    """Keeps a sequence of renders inside a time budget.

    Render ``k`` was planned to take ``overhead`` seconds (a Cycles render's fixed cost) plus
    ``sample_seconds[k]`` (its samples). Before it starts, ``scale(time_left)`` says by how
    much to scale its samples so that the renders still to come fit in the time left (as
    the caller's clock reads it): slower than planned, fewer samples for the rest; faster,
    more, at most ``max_scale`` times the plan (a region cheaper than the pilot said must not
    take the time of one dearer than it said: a fog floor after the sky), or for renders
    ``side_by_side`` of like cost, the plan as the finished ones re-priced it.

    ``record(seconds, planned)`` after a render teaches it the real cost of a planned second
    (the plan's rate comes from a small pilot): the renders still to come are then planned
    at the rate the finished ones showed, so the last ones neither starve nor leave the
    budget unspent.
    """

    def __init__(self, sample_seconds: list[float], overhead: float, max_scale: float = PACE_MAX_SCALE,
                 side_by_side: bool = False):
        if any(seconds < 0 for seconds in sample_seconds) or overhead < 0:
            raise ValueError("planned seconds must not be negative")
        self._left = list(sample_seconds)
        self.overhead = overhead
        self.max_scale = max_scale
        self.side_by_side = side_by_side
        self._spent = self._expected = 0.0

    @property
    def cost_ratio(self) -> float:
        """Seconds a planned second has taken so far (1 before any render is recorded;
        kept within [1/4, 4] so one odd render cannot throw the plan away)."""
        if self._expected <= 0.0:
            return 1.0
        return float(min(4.0, max(0.25, self._spent / self._expected)))

    def record(self, seconds: float, planned: float) -> None:
        """A render took ``seconds`` (its fixed cost included) for samples the plan priced at
        ``planned`` seconds (the plan's rate times the samples it really rendered)."""
        if planned > 0.0 and seconds >= 0.0:
            self._spent += max(0.0, seconds - self.overhead)
            self._expected += planned

    def scale(self, time_left: float) -> float:
        """Scale for the next render's samples; call once per render, in order."""
        if not self._left:
            raise IndexError("every planned render has been paced")
        renders, planned = len(self._left), sum(self._left)
        self._left.pop(0)
        if planned <= 0.0:
            return 1.0
        usable = time_left - self.overhead * renders
        # ``side_by_side`` renders (a flat plan's halves) cost alike per sample, so the cap
        # holds against the plan as the finished ones re-priced it: a small pilot may
        # overstate the cost many times over (the timing noise of its short renders).
        cap = self.max_scale / self.cost_ratio if self.side_by_side else self.max_scale
        return float(min(cap, max(0.0, usable / (planned * self.cost_ratio))))
