"""One render asked for: the mode, its options and what it renders for, checked once.

Every front end builds a ``RenderRequest`` (the command line's ``render``, the panel and
batch, the contestants of ``curves`` and ``experiment``, the farm's tasks) and hands it to
``addon.render_dispatch.request_frame_job``, the one place a mode becomes renders. What
only one front end knows (files, flags, panel labels) stays with it; everything a mode
needs travels here, typed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..errors import SettingError
from ..maps.options import MapOptions
from .guided_plan import GuidedOptions
from .render_options import UNBOUNDED_SPP, RenderOptions

@dataclass(frozen=True)
class ModeTraits:
    """What a render mode takes and does. The request's check, the command line, the panel
    and the farm ask ``MODE_TRAITS`` instead of switching on a mode's name; only the
    dispatcher (``addon.render_dispatch``) turns a mode into its renders.

    Parameters
    ----------
    director_map
        Driven by a director map (xs, xsl): its tiles must fit the frame, its map may be given
        as a file, the maps it computes may be saved.
    time_budget
        Renders within a time budget of its own (guided: ``GuidedOptions``), with an optional
        ceiling and an importance map computed inside.
    spp, seconds
        Takes a sample count (uniform), a wall time to render for (uniform, adaptive).
    budget_from
        What another run's stats give it as its budget: "spp" (its mean samples: uniform) or
        "seconds" (its wall time less its denoising: adaptive); None: nothing.
    """

    director_map: bool = False
    time_budget: bool = False
    spp: bool = False
    seconds: bool = False
    budget_from: str | None = None

    @property
    def computes_maps(self) -> bool:
        """Computes director maps in the run (xs, xsl unless given one; guided's importance)."""
        return self.director_map or self.time_budget


#: Every render mode: the gold standard, the paper's selective modes, the baselines and the
#: time-budgeted sampler.
MODE_TRAITS = {
    "gold": ModeTraits(),
    "xs": ModeTraits(director_map=True),
    "xsl": ModeTraits(director_map=True),
    "uniform": ModeTraits(spp=True, seconds=True, budget_from="spp"),
    "adaptive": ModeTraits(seconds=True, budget_from="seconds"),
    "guided": ModeTraits(time_budget=True),
}
MODES = tuple(MODE_TRAITS)
#: Modes driven by a director map.
SELECTIVE_MODES = tuple(mode for mode, traits in MODE_TRAITS.items() if traits.director_map)
#: The samples per pixel ``auto`` assumes for a guided render without a ceiling: its sample
#: count is only known after the pilot, which already renders with the estimator (changing
#: it afterwards would sync the scene again). 16 is what the measured budgets gave.
GUIDED_SPP = 16


@dataclass(frozen=True)
class RenderRequest:
    """A render of one mode, for a still or each frame of a range.

    Parameters
    ----------
    mode
        One of ``MODES``.
    options
        Seed, resolution, ceiling (``max_spp``), tiles, denoising, volume estimator.
    spp
        uniform: samples per pixel (or ``seconds`` instead).
    seconds
        uniform at equal time, adaptive: the wall time Cycles may render for (adaptive
        without it: up to the ceiling, until every pixel meets the noise threshold).
    noise_threshold
        adaptive: Cycles' noise threshold (None: Cycles' own default).
    guided
        guided: its time budget and allocation (only guided has one).
    map_options
        xs, xsl (maps computed on the fly) and guided (its importance map): the director
        maps' options.
    budget_from, budget_mean_spp
        The stats file an equal-samples or equal-time budget was read from, and the mean
        samples it recorded (both recorded in the run's stats).
    label
        xs, xsl: the name the run's stats give its mode (the paper's validation names its
        variants: ``x_only``, ``xsl_no_minbound``, ...); None: the mode.
    scene_samples
        The counts the front end left out are the scene's own samples, known once it is open
        (its ceiling, and uniform's count without a budget): ``at_scene_samples`` fills them
        in. Until then the request is checked, never rendered.
    """

    mode: str
    options: RenderOptions
    spp: int | None = None
    seconds: float | None = None
    noise_threshold: float | None = None
    guided: GuidedOptions | None = None
    map_options: MapOptions | None = None
    budget_from: str | None = None
    budget_mean_spp: float | None = None
    label: str | None = None
    scene_samples: bool = False

    @property
    def traits(self) -> ModeTraits:
        return MODE_TRAITS[self.mode]

    def check(self) -> "RenderRequest":
        """Raise a SettingError naming the first setting the mode cannot take; return self."""
        if self.mode not in MODE_TRAITS:
            raise SettingError(f"{{mode.name}} must be one of {', '.join(MODES)} (got '{{mode.value}}')",
                               mode=self.mode)
        traits = self.traits
        self.options.check()
        if traits.time_budget:
            if self.guided is None:
                raise SettingError("{mode} needs {time_budget.name} SECONDS", mode=self.mode,
                                   time_budget=None)
            self.guided.check()
            if self.options.max_spp > UNBOUNDED_SPP:
                raise SettingError(f"{{max_spp.name}} must be between 1 and {UNBOUNDED_SPP} "
                                   "(got {max_spp.value})", max_spp=self.options.max_spp)
        elif self.guided is not None:
            instead = " (use {seconds.name} with {mode})" if traits.seconds else " (got {mode})"
            raise SettingError("{time_budget.name} is for {mode.name} guided" + instead,
                               time_budget=self.guided.time_budget, mode=self.mode, seconds=None)
        if self.spp is not None:
            if not traits.spp:
                raise SettingError("{spp.name} is for {mode.name} uniform", spp=self.spp, mode=self.mode)
            if not 1 <= self.spp <= self.options.max_spp:
                raise SettingError("{spp} is above {max_spp}, the ceiling of every mode",
                                   spp=self.spp, max_spp=self.options.max_spp)
        if self.seconds is not None:
            if not (math.isfinite(self.seconds) and self.seconds > 0.0):
                raise SettingError("{seconds.name} must be positive (got {seconds.value:g})",
                                   seconds=self.seconds)
            if not traits.seconds:
                raise SettingError("{seconds.name} is for {mode.name} uniform and adaptive",
                                   seconds=self.seconds, mode=self.mode)
        if traits.spp and (self.spp is None) == (self.seconds is None) and not (
                self.scene_samples and self.spp is None):
            raise SettingError("{mode} needs either {spp.name} or {seconds.name}", mode=self.mode,
                               spp=self.spp, seconds=self.seconds)
        if self.noise_threshold is not None and not 0.0 < self.noise_threshold <= 1.0:
            raise SettingError("{noise_threshold.name} must be in (0, 1] (got {noise_threshold.value})",
                               noise_threshold=self.noise_threshold)
        return self

    def at_scene_samples(self, samples: int) -> "RenderRequest":
        """The request with the scene's ``samples`` where its counts were left to the scene:
        the ceiling (at least uniform's count from a budget file), and uniform's count where no
        budget gave one; checked. A request with its counts given is returned as it is."""
        if not self.scene_samples:
            return self
        spp = self.spp
        if self.traits.spp and spp is None and self.seconds is None:
            spp = samples
        options = replace(self.options, max_spp=max(samples, spp or 0))
        return replace(self, options=options, spp=spp, scene_samples=False).check()

    def to_dict(self) -> dict:
        """Everything the request asks for, as plain data (a rerun compares its digest)."""
        return {"mode": self.mode, "options": self.options.to_dict(), "spp": self.spp,
                "seconds": self.seconds, "noise_threshold": self.noise_threshold,
                "guided": None if self.guided is None else self.guided.to_dict(),
                "map_options": None if self.map_options is None else self.map_options.to_dict(),
                "budget_mean_spp": self.budget_mean_spp, "label": self.label}

    @property
    def estimator_spp(self) -> float:
        """The samples per pixel the run gives its pixels at most, which sets how much bias
        the estimator ``auto`` tolerates: its sample count when it has one (uniform), a time
        budget's ceiling (or ``GUIDED_SPP`` without one; a still's guided render chooses for
        at most ``GUIDED_SPP`` first, ``first_estimator_spp``), the ceiling otherwise (xs and
        xsl give some pixels that many)."""
        if self.spp:
            return float(self.spp)
        if self.traits.time_budget and not self.options.has_ceiling:
            return float(GUIDED_SPP)
        return float(self.options.max_spp)

    def first_estimator_spp(self, still: bool) -> float:
        """The count auto chooses for before the run starts. A still's time budget learns
        its count from its pilot and settles the choice for it (``volume_estimator.
        settled_for``: coarser from the predictions made, finer by predicting more), so it
        chooses for at most ``GUIDED_SPP`` first: a ceiling of 1024 made it predict every
        rate down to the finest (5.7 s of a 16 s budget on smoke in fog) for a count it never
        reached. A range keeps its first choice for every frame, so it chooses for the
        ceiling (``estimator_spp``)."""
        if still and self.traits.time_budget:
            return min(self.estimator_spp, float(GUIDED_SPP))
        return self.estimator_spp

    @property
    def unbounded(self) -> bool:
        """A guided render without a ceiling (its samples' preview scales to the most any
        pixel got)."""
        return self.traits.time_budget and not self.options.has_ceiling

    def record_budget(self, stats) -> None:
        """Record in the run's ``RenderStats`` where its budget came from."""
        stats.budget_from, stats.budget_mean_spp = self.budget_from, self.budget_mean_spp
