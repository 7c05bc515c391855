"""From a director map to the rectangles Cycles renders, each with its own sample count.

Section 5 of the paper weights a ceiling per pixel by the map: ``target = max(min_spp,
round(max_spp * map))``. Cycles renders one count per render, so the frame is cut into square
tiles, each rendered with a quantile of its pixels' targets (default the maximum: no pixel gets
fewer than asked), split into quadrants down to 8 px where that saves more than the extra
renders cost (``render_cost``), optionally rounded up to a few levels, and neighbours with the
same count merged. A ``TilePlan`` is plain data a farm can split between machines."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import InputError
from ..option_table import MIN_TILE_SIZE
from .render_options import RenderOptions

PLAN_FORMAT = 1


@dataclass(frozen=True)
class Rect:
    """A rectangle of pixels ``[row0, row1) x [col0, col1)`` (row 0 at the top) and its samples."""

    row0: int
    row1: int
    col0: int
    col1: int
    spp: int

    @property
    def height(self) -> int:
        return self.row1 - self.row0

    @property
    def width(self) -> int:
        return self.col1 - self.col0

    @property
    def area(self) -> int:
        return self.height * self.width

    @property
    def samples(self) -> int:
        return self.area * self.spp

    @property
    def window(self) -> tuple[int, int, int, int]:
        return self.row0, self.row1, self.col0, self.col1

    def to_dict(self) -> dict:
        return {"row0": self.row0, "row1": self.row1, "col0": self.col0, "col1": self.col1,
                "spp": self.spp}


@dataclass
class TilePlan:
    """The rectangles of one selective render and what they cost."""

    width: int
    height: int
    max_spp: int
    min_spp: int
    tile_size: int
    tile_quantile: float
    spp_levels: int
    rects: list[Rect]
    #: Sum of the per-pixel targets: the samples the paper's per-pixel renderer would shoot.
    target_samples: int = 0

    @property
    def pixels(self) -> int:
        return self.width * self.height

    @property
    def total_samples(self) -> int:
        return sum(rect.samples for rect in self.rects)

    @property
    def gold_samples(self) -> int:
        return self.pixels * self.max_spp

    @property
    def mean_spp(self) -> float:
        return self.total_samples / self.pixels

    @property
    def ideal_speedup(self) -> float:
        """Gold samples / plan samples: the speedup if time were proportional to samples."""
        return self.gold_samples / self.total_samples

    def spp_image(self) -> np.ndarray:
        """Samples per pixel as a float32 (H, W) image."""
        image = np.zeros((self.height, self.width), np.float32)
        for rect in self.rects:
            image[rect.row0:rect.row1, rect.col0:rect.col1] = rect.spp
        return image

    def check(self) -> "TilePlan":
        """Raise ValueError unless the rectangles cover the frame exactly once."""
        cover = np.zeros((self.height, self.width), np.int32)
        for rect in self.rects:
            if not (0 <= rect.row0 < rect.row1 <= self.height and 0 <= rect.col0 < rect.col1 <= self.width):
                raise ValueError(f"rectangle {rect} lies outside the {self.width}x{self.height} frame")
            if not 1 <= rect.spp <= self.max_spp:
                raise ValueError(f"rectangle {rect} has samples outside 1..{self.max_spp}")
            cover[rect.row0:rect.row1, rect.col0:rect.col1] += 1
        if not (cover == 1).all():
            raise ValueError("the plan's rectangles do not cover the frame exactly once")
        return self

    def to_dict(self) -> dict:
        return {
            "format": PLAN_FORMAT,
            "width": self.width, "height": self.height,
            "max_spp": self.max_spp, "min_spp": self.min_spp,
            "tile_size": self.tile_size, "tile_quantile": self.tile_quantile,
            "spp_levels": self.spp_levels,
            "renders": len(self.rects),
            "total_samples": self.total_samples, "gold_samples": self.gold_samples,
            "target_samples": self.target_samples,
            "mean_spp": self.mean_spp, "ideal_speedup": self.ideal_speedup,
            "rects": [rect.to_dict() for rect in self.rects],
        }

    @classmethod
    def from_dict(cls, data: dict) -> "TilePlan":
        """Rebuild a plan from its JSON; derived figures are recomputed, not trusted."""
        if data.get("format") != PLAN_FORMAT:
            raise InputError(f"unknown tile plan format {data.get('format')!r} (expected {PLAN_FORMAT})")
        try:
            rects = [Rect(int(r["row0"]), int(r["row1"]), int(r["col0"]), int(r["col1"]), int(r["spp"]))
                     for r in data["rects"]]
            plan = cls(width=int(data["width"]), height=int(data["height"]),
                       max_spp=int(data["max_spp"]), min_spp=int(data["min_spp"]),
                       tile_size=int(data["tile_size"]), tile_quantile=float(data["tile_quantile"]),
                       spp_levels=int(data["spp_levels"]), rects=rects,
                       target_samples=int(data.get("target_samples", 0)))
        except (KeyError, TypeError, ValueError) as error:
            raise InputError(f"malformed tile plan: {error}") from None
        try:
            return plan.check()
        except ValueError as error:
            raise InputError(f"malformed tile plan: {error}") from None


def check_director_map(director_map: np.ndarray, width: int, height: int) -> np.ndarray:
    """The map as float32 (H, W) in [0, 1]; InputError for a wrong size, NaN or out-of-range values.

    Accepts (H, W), (H, W, 1), or grey RGB(A) (all colour channels equal).
    """
    data = np.asarray(director_map, dtype=np.float32)
    if data.ndim == 3:
        if data.shape[2] == 1:
            data = data[:, :, 0]
        elif data.shape[2] in (3, 4) and np.array_equal(data[:, :, 0], data[:, :, 1]) \
                and np.array_equal(data[:, :, 0], data[:, :, 2]):
            data = data[:, :, 0]
        else:
            raise InputError(f"the director map must have one channel (it has {data.shape[2]})")
    if data.ndim != 2:
        raise InputError(f"the director map must be an image (got an array of shape {data.shape})")
    if data.shape != (height, width):
        raise InputError(f"the director map is {data.shape[1]}x{data.shape[0]} "
                         f"but the render is {width}x{height}")
    if not np.isfinite(data).all():
        raise InputError("the director map contains NaN or infinite values")
    low, high = float(data.min()), float(data.max())
    if low < -1e-6 or high > 1.0 + 1e-6:
        raise InputError(f"the director map must lie in [0, 1] (it spans {low:.4g}..{high:.4g})")
    return np.clip(data, 0.0, 1.0)


def target_spp(director_map: np.ndarray, max_spp: int, min_spp: int) -> np.ndarray:
    """Per-pixel samples the paper asks for: ``max(min_spp, round(max_spp * map))`` as int32."""
    return np.maximum(min_spp, np.rint(max_spp * np.asarray(director_map, np.float64))).astype(np.int32)


def spp_ladder(levels: int, min_spp: int, max_spp: int) -> np.ndarray:
    """``levels`` geometrically spaced sample counts from min_spp to max_spp (both included)."""
    ladder = np.rint(min_spp * (max_spp / min_spp) ** np.linspace(0.0, 1.0, levels))
    return np.unique(np.clip(ladder, min_spp, max_spp).astype(np.int32))


def quantise_up(spp: np.ndarray, ladder: np.ndarray) -> np.ndarray:
    """Round each count up to the next level of ``ladder`` (never fewer samples than asked)."""
    return ladder[np.searchsorted(ladder, spp, side="left")]


def tile_windows(width: int, height: int, tile_size: int) -> list[tuple[int, int, int, int]]:
    """(row0, row1, col0, col1) of the square tiles from the top left; edge tiles are cut."""
    return [(row, min(height, row + tile_size), col, min(width, col + tile_size))
            for row in range(0, height, tile_size) for col in range(0, width, tile_size)]


def split_tile(targets: np.ndarray, window: tuple[int, int, int, int], quantile: float,
               render_cost: int, ladder: np.ndarray | None = None) -> list[Rect]:
    """A tile, or its quadrants (recursively, down to ``MIN_TILE_SIZE``), whichever is cheaper.

    Cost of a rectangle = its pixels x its samples (the ``quantile`` of its targets) +
    ``render_cost`` (the fixed cost of one Cycles render, in pixel-samples). A quadrant whose
    pixels ask for fewer samples than the tile's most demanding pixel is rendered on its own
    when the samples saved outweigh the extra render. With a ``ladder`` (``spp_ladder``) the
    counts are rounded up to its levels before they are compared.
    """
    row0, row1, col0, col1 = window
    block = targets[row0:row1, col0:col1]
    spp = block.max() if quantile >= 1.0 else np.quantile(block, quantile, method="higher")
    spp = int(spp if ladder is None else quantise_up(np.array([spp]), ladder)[0])
    whole = Rect(row0, row1, col0, col1, spp)
    height, width = row1 - row0, col1 - col0
    if max(height, width) < 2 * MIN_TILE_SIZE:
        return [whole]
    rows = (row0, row0 + height // 2, row1) if height >= 2 * MIN_TILE_SIZE else (row0, row1)
    cols = (col0, col0 + width // 2, col1) if width >= 2 * MIN_TILE_SIZE else (col0, col1)
    parts = [rect for r in range(len(rows) - 1) for c in range(len(cols) - 1)
             for rect in split_tile(targets, (rows[r], rows[r + 1], cols[c], cols[c + 1]),
                                    quantile, render_cost, ladder)]
    if sum(rect.samples + render_cost for rect in parts) < whole.samples + render_cost:
        return parts
    return [whole]


def _merge_runs(rects: list[Rect], along_rows: bool) -> list[Rect]:
    """One sweep: join each rectangle to the previous one when they continue each other."""
    def key(rect: Rect):
        return (rect.row0, rect.row1, rect.spp, rect.col0) if along_rows else (rect.col0, rect.col1, rect.spp, rect.row0)

    merged: list[Rect] = []
    for rect in sorted(rects, key=key):
        last = merged[-1] if merged else None
        if last is None or last.spp != rect.spp:
            merged.append(rect)
        elif along_rows and (last.row0, last.row1, last.col1) == (rect.row0, rect.row1, rect.col0):
            merged[-1] = replace(last, col1=rect.col1)
        elif not along_rows and (last.col0, last.col1, last.row1) == (rect.col0, rect.col1, rect.row0):
            merged[-1] = replace(last, row1=rect.row1)
        else:
            merged.append(rect)
    return merged


def merge_rects(rects: list[Rect]) -> list[Rect]:
    """Merge rectangles with equal samples that share a whole edge, until none do.

    Greedy: runs along rows (same rows, touching columns), then runs along columns (same
    columns, touching rows), repeated while it helps. Returns rectangles sorted top to
    bottom, left to right.
    """
    count = None
    while count != len(rects):
        count = len(rects)
        rects = _merge_runs(_merge_runs(rects, along_rows=True), along_rows=False)
    return sorted(rects, key=lambda rect: (rect.row0, rect.col0))


def render_order(rects: list[Rect]) -> list[Rect]:
    """``rects`` in the order one Cycles session should render them: fewest samples first
    (then top to bottom, left to right). A kept session lays blue noise out by the largest
    count it has rendered, so a rectangle rendered after one of more samples would draw its
    samples from that longer sequence and render worse after denoising
    (``core.sampling.sample_pattern.session_sequence``); in rising order every rectangle
    gets the pixels a fresh session gives it."""
    return sorted(rects, key=lambda rect: (rect.spp, rect.row0, rect.col0))


def make_plan(director_map: np.ndarray, options: RenderOptions) -> TilePlan:
    """The tile plan for a director map (values in [0, 1] at render resolution).

    Raises InputError for a map with NaN or out of range values and for tiles larger than
    the frame. The map's shape sets the frame size.
    """
    options.check()
    height, width = np.shape(director_map)[:2]
    options.check_frame(width, height)
    data = check_director_map(director_map, width, height)
    targets = target_spp(data, options.max_spp, options.min_spp)
    ladder = spp_ladder(options.spp_levels, options.min_spp, options.max_spp) if options.spp_levels else None
    rects = [rect for window in tile_windows(width, height, options.tile_size)
             for rect in split_tile(targets, window, options.tile_quantile, options.render_cost, ladder)]
    rects = render_order(merge_rects(rects))
    plan = TilePlan(width=width, height=height, max_spp=options.max_spp, min_spp=options.min_spp,
                    tile_size=options.tile_size, tile_quantile=options.tile_quantile,
                    spp_levels=options.spp_levels, rects=rects,
                    target_samples=int(targets.sum(dtype=np.int64)))
    return plan.check()
