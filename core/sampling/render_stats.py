"""The statistics of one rendered frame, typed: what every mode records, then what only some
modes (or front ends) add. ``to_json`` is the ``--stats`` JSON and the panel's image
properties' source; nothing outside this module reads the statistics by string key.

Also here: ``RecordedBudget``, the part of a stats file an equal-samples or equal-time run
takes its budget from (``--budget-from``), and the equal-time rule itself.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields

from ..checks import MAX_SAMPLES, finite_number
from ..errors import InputError
from .guided_plan import GuidedOptions


@dataclass(frozen=True)
class FrameMaps:
    """What a frame's statistics record about its director maps."""

    frame: int
    seconds: dict                         # map name -> seconds, and "total"
    ray_cache_hit: bool                   # the camera rays came from an earlier frame
    ray_cache: str | None                 # the ray cache's file
    warnings: list[str]


@dataclass
class RenderStats:
    """What one run of one frame did.

    The first block is recorded by every mode; the rest are None (and left out of the JSON)
    where a mode or front end does not record them. ``wall_s`` is the sum of the phases.
    """

    mode: str
    scene: str
    resolution: tuple[int, int]
    max_spp: int
    seed: int
    phases_s: dict[str, float]            # phase name -> seconds (maps, renders, denoise, write, ...)
    total_samples: int
    mean_spp: float
    gold_samples: int                     # what the gold standard would have rendered
    renders: int                          # Cycles renders (rectangles, bands, passes)
    tiles: list[dict]                     # one record per render: window, spp, seconds
    options: dict                         # ``RenderOptions.to_dict()``
    estimator: dict                       # the volume estimator used and why
    warnings: list[str] = field(default_factory=list)
    cycles_sync_s: float | None = None    # Cycles' scene sync inside the renders
    denoise_guides: dict | None = None    # auto's guide prefilter: noise, noisy, prefiltered
    non_finite_pixels: int | None = None  # infinite or NaN pixels set to 0 (core.sampling.finite_pixels)
    # xs, xsl
    plan: dict | None = None
    ideal_speedup: float | None = None
    director_map_mean: float | None = None
    # gold rendered in bands (the panel)
    bands: dict | None = None
    # uniform, adaptive: by samples or by time, and where the budget came from
    budget: str | None = None
    budget_from: str | None = None
    budget_mean_spp: float | None = None
    noise_threshold: float | None = None
    time_budget_s: float | None = None
    time_limit_s: float | None = None
    stopped_by_time: bool | None = None
    # guided
    guided: GuidedOptions | None = None
    pilot_spp: int | None = None
    pilot_seconds: float | None = None
    pilot_resolution_divisor: int | None = None
    seconds_per_pixel_sample: float | None = None
    final_pass: dict | None = None
    denoise_reserved_s: float | None = None
    sync_outside_budget_s: float | None = None
    # a frame job: the frame, its maps, a guided range's shared time
    frame: int | None = None
    maps: FrameMaps | None = None
    sequence_budget: dict | None = None
    # the contestants of curves: Cycles' path guiding settings
    path_guiding: dict | None = None
    # the command line: the scene file and the image written
    file: str | None = None
    out: str | None = None
    # the paper's validation: the seconds its files took (not part of the run's time)
    write_s: float | None = None

    @property
    def wall_s(self) -> float:
        return float(sum(self.phases_s.values()))

    def phase(self, name: str) -> float:
        """Seconds of one phase (0 when the run had none)."""
        return float(self.phases_s.get(name, 0.0))

    @property
    def render_seconds(self) -> float:
        """The equal-time rule: the wall time an equal-time run may render for is this run's
        less its denoising (the other run denoises its own frame after Cycles stops)."""
        return self.wall_s - self.phase("denoise")

    def to_json(self, keep: tuple[str, ...] | None = None) -> dict:
        """The ``--stats`` JSON: every recorded field, ``wall_s`` after ``seed``; ``keep``:
        only these keys (a record that copies part of a run's stats)."""
        if keep is not None:
            return {key: value for key, value in self.to_json().items() if key in keep}
        out = {}
        for item in fields(self):
            value = getattr(self, item.name)
            if value is None and item.default is None:
                continue
            if item.name == "resolution":
                value = list(value)
            elif item.name == "guided":
                value = value.to_dict()
            elif item.name == "maps":
                value = asdict(value)
            out[item.name] = value
            if item.name == "seed":
                out["wall_s"] = self.wall_s
        return out

    @classmethod
    def from_json(cls, data: dict) -> "RenderStats":
        """A run's stats read back (``to_json``'s output; ``wall_s`` is recomputed)."""
        known = {item.name for item in fields(cls)}
        stats = cls(**{key: value for key, value in data.items() if key in known})
        stats.resolution = tuple(stats.resolution)
        if stats.guided is not None:
            stats.guided = GuidedOptions(**stats.guided)
        if stats.maps is not None:
            stats.maps = FrameMaps(**stats.maps)
        return stats


def sequence_stats(frames: list[RenderStats], mode: str, file: str, out: str, frame_range: str,
                   wall_s: float) -> dict:
    """The ``--stats`` JSON of a frame range: every frame's stats and their totals."""
    hits = [stats.maps.ray_cache_hit for stats in frames if stats.maps is not None]
    return {"mode": mode, "file": file, "out": out, "frames": [stats.to_json() for stats in frames],
            "frame_range": frame_range, "wall_s": wall_s,
            "total_samples": sum(stats.total_samples for stats in frames),
            "ray_cache_hits": sum(hits),
            "cycles_sync_s": sum(stats.cycles_sync_s or 0.0 for stats in frames)}


@dataclass(frozen=True)
class RecordedBudget:
    """What an equal-samples or equal-time run takes from another run's stats file."""

    mean_spp: float
    wall_s: float
    denoise_s: float

    @property
    def render_seconds(self) -> float:
        """``RenderStats.render_seconds`` of the recorded run."""
        return self.wall_s - self.denoise_s

    @classmethod
    def from_json(cls, data, path: str) -> "RecordedBudget":
        """Read from a stats file's JSON (a run's, or a farm frame's record); InputError
        naming ``path`` for anything a run would not have written."""
        if not isinstance(data, dict) or not {"mean_spp", "wall_s"} <= data.keys():
            raise InputError(f"{path} is not a stats file written by xsl-render render")
        phases = data.get("phases_s", {})
        if not isinstance(phases, dict):
            raise InputError(f"{path}: phases_s must be an object of seconds")
        values = {}
        # Numbers as a run writes them: finite, not negative, samples Cycles can take.
        for name, key, value, hi in (("wall_s", "wall_s", data["wall_s"], None),
                                     ("mean_spp", "mean_spp", data["mean_spp"], MAX_SAMPLES),
                                     ("denoise_s", "phases_s.denoise", phases.get("denoise", 0.0), None)):
            if isinstance(value, (bool, str)) or not isinstance(value, (int, float)):
                raise InputError(f"{path}: {key} must be a number, not {value!r}")
            values[name] = float(finite_number(value, lo=0.0, hi=hi, name=f"{path}: {key}"))
        return cls(**values)
