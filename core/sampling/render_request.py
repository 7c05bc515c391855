"""One render asked for: the mode, its options and what it renders for, checked once.

Every front end builds a ``RenderRequest`` (the command line's ``render``, the panel and
batch, the contestants of ``curves`` and ``experiment``, the farm's tasks) and hands it to
``addon.render_dispatch.request_frame_job``, the one place a mode becomes renders. What
only one front end knows (files, flags, panel labels) stays with it; everything a mode
needs travels here, typed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import SettingError
from ..maps.options import MapOptions
from .guided_plan import GuidedOptions
from .render_options import UNBOUNDED_SPP, RenderOptions

#: Every render mode: the gold standard, the paper's selective modes, the baselines and the
#: time-budgeted sampler.
MODES = ("gold", "xs", "xsl", "uniform", "adaptive", "guided")
#: Modes driven by a director map.
SELECTIVE_MODES = ("xs", "xsl")
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

    def check(self) -> "RenderRequest":
        """Raise a SettingError naming the first setting the mode cannot take; return self."""
        if self.mode not in MODES:
            raise SettingError(f"{{mode.name}} must be one of {', '.join(MODES)} (got '{{mode.value}}')",
                               mode=self.mode)
        self.options.check()
        if self.mode == "guided":
            if self.guided is None:
                raise SettingError("{mode} needs {time_budget.name} SECONDS", mode=self.mode,
                                   time_budget=None)
            self.guided.check()
            if self.options.max_spp > UNBOUNDED_SPP:
                raise SettingError(f"{{max_spp.name}} must be between 1 and {UNBOUNDED_SPP} "
                                   "(got {max_spp.value})", max_spp=self.options.max_spp)
        elif self.guided is not None:
            raise SettingError("{time_budget.name} is for {mode.name} guided "
                               "(use {seconds.name} with {mode})",
                               time_budget=self.guided.time_budget, mode=self.mode, seconds=None)
        if self.spp is not None:
            if self.mode != "uniform":
                raise SettingError("{spp.name} is for {mode.name} uniform", spp=self.spp, mode=self.mode)
            if not 1 <= self.spp <= self.options.max_spp:
                raise SettingError("{spp} is above {max_spp}, the ceiling of every mode",
                                   spp=self.spp, max_spp=self.options.max_spp)
        if self.seconds is not None and not (math.isfinite(self.seconds) and self.seconds > 0.0):
            raise SettingError("{seconds.name} must be positive (got {seconds.value:g})", seconds=self.seconds)
        if self.mode == "uniform" and (self.spp is None) == (self.seconds is None):
            raise SettingError("{mode} needs either {spp.name} or {seconds.name}", mode=self.mode,
                               spp=self.spp, seconds=self.seconds)
        if self.noise_threshold is not None and not 0.0 < self.noise_threshold <= 1.0:
            raise SettingError("{noise_threshold.name} must be in (0, 1] (got {noise_threshold.value})",
                               noise_threshold=self.noise_threshold)
        return self

    @property
    def estimator_spp(self) -> float:
        """The samples per pixel the run gives its pixels at most, which sets how much bias
        the estimator ``auto`` tolerates: uniform's count when it has one, guided's ceiling
        (or ``GUIDED_SPP``), the ceiling otherwise (xs and xsl give some pixels that many)."""
        if self.mode == "uniform" and self.spp:
            return float(self.spp)
        if self.mode == "guided":
            return float(self.options.max_spp if self.options.has_ceiling else GUIDED_SPP)
        return float(self.options.max_spp)

    @property
    def unbounded(self) -> bool:
        """A guided render without a ceiling (its samples' preview scales to the most any
        pixel got)."""
        return self.mode == "guided" and not self.options.has_ceiling

    def record_budget(self, stats) -> None:
        """Record in the run's ``RenderStats`` where its budget came from."""
        stats.budget_from, stats.budget_mean_spp = self.budget_from, self.budget_mean_spp
