"""Which volume estimator Cycles uses for a run, and at what step: the choice of ``--estimator``.

- ``scene``: the scene's own settings (``volume_biased``, ``volume_step_rate``), untouched.
- ``unbiased``: null scattering (Blender 5's default).
- ``biased``: ray marching at the scene's step rate, or at ``step_rate`` when given.
- ``auto``: ray marching at the largest candidate step rate whose predicted picture error
  (``core.media.light_paths``) stays within the noise the run's samples leave,
  ``NOISE_AT_ONE_SPP / sqrt(spp)``; else null scattering. A run that learns its count only
  while it renders (a time budget) chooses for a count first, renders its pilot with
  ``provisional_choice`` and settles with ``settled_for`` once the count is known.

Ray marching pays where Blender 5 would build its majorant octree (seconds at every sync) and
where its estimate is less noisy; its bias grows fast with the step. The constant's
calibration on the lit suite is ``bench/bench_auto_rates.py`` (docs/light_paths.md).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import Callable

import numpy as np

from ..errors import SettingError

ESTIMATORS = ("scene", "unbiased", "biased", "auto")
#: Scene step rates ``auto`` tries, largest first. Rates above 4 were never measured
#: against a converged reference, so they are not offered.
CANDIDATE_RATES = (4.0, 2.0, 1.0, 0.5, 0.25)
#: Relative picture error (p95 over the pixels marching changes) that the noise of one sample
#: per pixel hides after denoising; calibrated by ``bench/bench_auto_rates.py`` and the lit
#: suite (docs/light_paths.md).
NOISE_AT_ONE_SPP = 0.10
#: Transmittances closer to 0 or 1 than this do not make the relative bias explode.
_FLOOR = 0.05
#: Cycles' step rate range (``scene.cycles.volume_step_rate``).
MIN_STEP_RATE, MAX_STEP_RATE = 0.01, 100.0


def check_estimator(name: str, step_rate: float | None) -> None:
    """Raise an InputError naming the setting (``estimator``, ``step_rate``) when ``name``
    or ``step_rate`` cannot be used."""
    if name not in ESTIMATORS:
        raise SettingError(f"{{estimator.name}} must be one of {', '.join(ESTIMATORS)}, "
                           "not '{estimator.value}'", estimator=name)
    if step_rate is None:
        return
    if not (isinstance(step_rate, (int, float)) and math.isfinite(step_rate)
            and MIN_STEP_RATE <= step_rate <= MAX_STEP_RATE):
        raise SettingError(f"{{step_rate.name}} must be a number from {MIN_STEP_RATE:g} to "
                           f"{MAX_STEP_RATE:g} (Cycles' range), not {{step_rate.value}}",
                           step_rate=step_rate)
    if name not in ("biased", "auto"):
        raise SettingError("a {step_rate.name} is for the biased estimator (ray marching); "
                           "{estimator.name} '{estimator.value}' does not march",
                           estimator=name, step_rate=step_rate)


def tolerated_bias(spp: float) -> float:
    """The relative pixel bias that hides in the noise of ``spp`` samples per pixel."""
    return NOISE_AT_ONE_SPP / math.sqrt(max(float(spp), 1.0))


def visible_bias(transmittance: np.ndarray, bias: np.ndarray) -> float:
    """The 95th percentile of |dT| / max(min(T, 1 - T), 0.05) over the sampled pixels
    (luminance of each), see the module notes."""
    t = np.asarray(transmittance, np.float64)
    reach = np.maximum(np.minimum(t, 1.0 - t), _FLOOR)
    if t.size == 0:
        return 0.0
    return float(np.percentile(np.abs(np.asarray(bias, np.float64)) / reach, 95))


@dataclass(frozen=True)
class EstimatorChoice:
    """What a run renders volumes with, and why.

    ``biased`` None and ``step_rate`` None mean the scene's own settings.
    ``predicted_bias`` is the visible-bias measure at the chosen rate (auto), ``tolerance``
    what the run's samples allow, ``tried`` each rate auto predicted: {rate: measure}.
    ``sample_pattern``: Cycles' sample pattern auto renders with in place of the scene's
    legacy or blue-noise one (``core.sampling.sample_pattern``), None for the scene's own.
    ``light_tree``: Cycles' light tree as auto renders it (False: off, where the scene has
    one light: ``core.sampling.light_tree``), None for the scene's own.
    ``scatter_sampling``: the media whose volume sampling auto changes while it ray-marches
    ("material:<name>", "world:<name>" -> Cycles' method; ``core.media.scatter_sampling``),
    ``scatter_noise`` the predicted noise of each method per medium, ``scatter_own`` those
    media's own methods (what they render with while auto keeps null scattering).
    """

    estimator: str
    biased: bool | None = None
    step_rate: float | None = None
    predicted_bias: float | None = None
    tolerance: float | None = None
    tried: dict | None = None
    reason: str = ""
    seconds: float = 0.0
    #: Coarser steps for some media (``per_medium_rates``): what carries a medium's step in
    #: Blender ("material:<name>", "world:<name>") -> its rate in scene-rate terms (the
    #: medium marches as if the scene rate were this); ``medium_settings``: the same keys ->
    #: the value the material's ``volume_step_rate`` (the world's ``volume_step_size``) is
    #: given for it, next to the scene rate ``step_rate``.
    medium_rates: dict | None = None
    medium_settings: dict | None = None
    #: What ``per_medium_rates`` worked with, so that ``settled_for`` can choose again
    #: without predicting: {"groups": {key: [media]}, "count": media, "own": {key: the
    #: material's or world's own value}, "largest": rate cap, "tried": [[rates, measure]...]}.
    media: dict | None = None
    #: The prediction itself (``measure_at`` of ``per_medium_rates``), kept while the run
    #: lasts so that a settle at another scene rate can try the media's steps there; not
    #: part of the record (``to_dict``) nor of equality.
    remeasure: Callable | None = field(default=None, repr=False, compare=False)
    sample_pattern: str | None = None
    light_tree: bool | None = None
    scatter_sampling: dict | None = None
    scatter_noise: dict | None = None
    scatter_own: dict | None = None

    def to_dict(self) -> dict:
        data = asdict(replace(self, remeasure=None))
        del data["remeasure"]
        if self.tried is not None:
            data["tried"] = {f"{rate:g}": value for rate, value in self.tried.items()}
        return data

    def describe(self) -> str:
        pattern = "" if self.sample_pattern is None else \
            f"; sample pattern {self.sample_pattern} (blue noise, its sequence rounded up to a power of two)"
        pattern += "; light tree off (one light: the same estimate sooner)" if self.light_tree is False else ""
        if self.biased and self.scatter_sampling:
            pattern += "".join(f"; {key.split(':', 1)[1]} sampled by {method.lower()}"
                               for key, method in self.scatter_sampling.items())
        if self.biased is None:
            return "the scene's own volume settings" + pattern
        if not self.biased:
            return "null scattering (unbiased)" + pattern
        rate = "the scene's step rate" if self.step_rate is None else f"step rate {self.step_rate:g}"
        coarser = "".join(f", {key.split(':', 1)[1]} at {value:g}"
                          for key, value in (self.medium_rates or {}).items())
        return f"ray marching at {rate}{coarser}{pattern}"


def fixed_choice(estimator: str, step_rate: float | None) -> EstimatorChoice:
    """The choice of ``scene``, ``unbiased`` and ``biased`` (nothing to predict)."""
    if estimator == "scene":
        return EstimatorChoice("scene", reason="as the scene is set up")
    if estimator == "unbiased":
        return EstimatorChoice("unbiased", biased=False, reason="asked for")
    if estimator == "biased":
        return EstimatorChoice("biased", biased=True, step_rate=step_rate, reason="asked for")
    raise ValueError(f"'{estimator}' is chosen per scene (auto)")


def choose_step_rate(measure_at, spp: float, rates=CANDIDATE_RATES,
                     largest: float | None = None) -> EstimatorChoice:
    """``auto``: the largest rate whose visible error ``measure_at(rate)`` is within the
    tolerance of ``spp`` samples per pixel, else null scattering. ``measure_at`` is called from the largest rate down and
    stops at the first that passes (the small rates cost the most to predict); ``largest``
    caps the rates tried (a step rate given with ``auto``). A frame range takes one choice
    per shot (``addon.maps.shot_choice``), so nothing here depends on the frame before."""
    ordered = sorted((r for r in rates if largest is None or r <= largest), reverse=True)
    return _first_passing(measure_at, ordered, tolerated_bias(spp), spp, {})


def per_medium_rates(choice: EstimatorChoice, measure_at, groups: dict, count: int, own: dict,
                     rates=CANDIDATE_RATES, largest: float | None = None) -> EstimatorChoice:
    """Auto's ray-marching ``choice`` with coarser steps for the media whose bias allows them
    (Cycles takes a material's ``volume_step_rate`` and the world's ``volume_step_size`` on
    top of the scene rate).

    ``groups``: what carries a step in Blender ("material:<name>", "world:<name>") -> the
    indices of its heterogeneous media among ``count`` media (a material's users share its
    rate). ``measure_at(rates)``: the visible-bias measure with one scene-equivalent rate per
    medium. Each group in turn takes the coarsest candidate above the scene rate (up to
    ``largest``) that keeps the measure within the choice's limit, the others as chosen so
    far: the larger of the tolerance and the choice's own measure (a coarser medium may not
    make the frame's error worse than the choice allows). The candidates are tried
    coarsest first (the bias grows with the step, so the first that passes is the one; the
    coarse ones cost least to predict). With one group the scene rate is that group's
    already: the choice is returned unchanged, without predicting.

    ``own``: each key's value now (the material's ``volume_step_rate``, the world's
    ``volume_step_size``); ``medium_settings`` is it times the medium's rate over the scene
    rate. The trials are kept in ``media`` (``settled_for``).
    """
    if choice.estimator != "auto" or choice.biased is None or choice.tolerance is None or len(groups) < 2:
        return choice
    media = {"groups": {key: list(members) for key, members in groups.items()}, "count": count,
             "own": {key: own[key] for key in groups}, "largest": largest, "tried": []}
    if not choice.biased or choice.step_rate is None or choice.predicted_bias is None:
        return replace(choice, media=media)        # (a settle that marches may try them)
    limit = max(choice.tolerance, choice.predicted_bias)
    base = choice.step_rate
    coarser = sorted((r for r in rates if r > base and (largest is None or r <= largest)), reverse=True)
    current = [base] * count
    kept, measure, tried = {}, choice.predicted_bias, media["tried"]
    for name, members in groups.items():
        for rate in coarser:
            trial = list(current)
            for m in members:
                trial[m] = rate
            value = measure_at(tuple(trial))
            tried.append([trial, value])
            if value <= limit:
                current, measure, kept[name] = trial, value, rate
                break
    if not kept:
        return replace(choice, media=media)
    return replace(choice, medium_rates=kept, predicted_bias=measure, media=media,
                   medium_settings={key: own[key] * rate / base for key, rate in kept.items()},
                   reason=f"{choice.reason}; {', '.join(key.split(':', 1)[1] for key in kept)} "
                          f"coarser, within {limit:.2%} still ({measure:.2%})")


def kept_scene_settings(why: str) -> EstimatorChoice:
    """Auto's guard: the scene's own volume settings, where auto cannot tell what ray
    marching would do to the picture (``why`` says what it cannot tell)."""
    return EstimatorChoice("auto", biased=None, reason=f"kept the scene's volume settings: {why}")


def homogeneous_choice(why: str = "homogeneous media only") -> EstimatorChoice:
    """Homogeneous media (only, or gathering most of the light: ``why``): both estimators are
    exact there (ray marching takes each piece in one step), so only their noise differs,
    and Cycles' ray marching is the noisier at equal samples (road 2.15x null scattering's
    pixel variance, a fog box with a thin smoke 1.5-2.8x). Blender 5 builds no octree for
    homogeneous media, so there is nothing to save."""
    return kept_scene_settings(f"{why}: both estimators are unbiased there and ray marching is "
                               "the noisier")


def chosen_spp(choice: EstimatorChoice) -> float:
    """The samples per pixel an auto choice was made for (from its tolerance)."""
    return (NOISE_AT_ONE_SPP / choice.tolerance) ** 2


def provisional_choice(choice: EstimatorChoice) -> EstimatorChoice:
    """What a time-budgeted run renders its pilot with, before it knows the count its budget
    affords (``settled_for`` then settles the choice): auto's ray-marching choice as it
    is, and where auto chose null scattering, ray marching at the finest rate it predicted.
    Ray marching syncs the scene in milliseconds; null scattering builds Blender 5's octree
    (seconds), which a pilot that ends in ray marching would have paid for nothing. Choices
    other than auto's, without predictions, or whose finest rate no count would accept (not
    even one sample per pixel), are returned unchanged."""
    if choice.estimator != "auto" or choice.biased is not False or not choice.tried:
        return choice
    finest = min(choice.tried)
    if choice.tried[finest] > tolerated_bias(1):
        return choice
    return EstimatorChoice("auto", biased=True, step_rate=finest, predicted_bias=choice.tried[finest],
                           tolerance=choice.tolerance, tried=choice.tried,
                           reason=f"provisional: the finest rate, until the budget's count is known "
                                  f"({choice.reason})", seconds=choice.seconds,
                           sample_pattern=choice.sample_pattern, light_tree=choice.light_tree,
                           scatter_sampling=choice.scatter_sampling, scatter_noise=choice.scatter_noise,
                           scatter_own=choice.scatter_own)


def settled_for(choice: EstimatorChoice, spp: float) -> EstimatorChoice:
    """Auto's ``choice`` made again for a run that gives its pixels ``spp`` samples: a time
    budget's count, known only after its pilot.

    Fewer samples than the choice was made for allow more bias, so a coarser step may pass:
    chosen from the predictions the choice holds. More samples need a finer step: predicted
    while the choice keeps its prediction (``remeasure``, a still's run), which is why a
    still's time budget chooses for a modest count first; without it ``spp`` is taken as the
    choice's own count. The media's own steps are chosen again too: from the trials made at
    the same scene rate, else predicted at the new one (``remeasure``), else the materials'
    and world's own values. Choices other than auto's, or without predictions, are returned
    unchanged."""
    if choice.estimator != "auto" or choice.biased is None or not choice.tried or not choice.tolerance:
        return choice
    tried = dict(choice.tried)
    if choice.remeasure is None:
        spp = min(float(spp), chosen_spp(choice))
        rates = tuple(tried)
    else:
        # Finer rates than were tried (down to the finest candidate) are predicted now.
        rates = tuple(r for r in CANDIDATE_RATES if r <= max(tried))
    again = choose_step_rate(_known_or_predicted(tried, choice.remeasure), float(spp), rates=rates)
    media = choice.media
    if media and again.biased and (again.step_rate == choice.step_rate or choice.remeasure is not None):
        # The media's steps chosen again for the new tolerance: from the trials made at the
        # same scene rate, else predicted while the prediction is at hand (else a
        # combination not tried counts as failing).
        measured = {tuple(trial): value for trial, value in media["tried"]}
        again = per_medium_rates(again, _known_or_predicted(measured, choice.remeasure), media["groups"],
                                 media["count"], media["own"], CANDIDATE_RATES, media["largest"])
    elif media and again.biased:
        # Not measured with the new rate: the materials' and world's own values (a run that
        # rendered its pilot with coarser steps has them set).
        again = replace(again, medium_settings=dict(media["own"]), media=media)
    return replace(again, tried=tried, seconds=choice.seconds, sample_pattern=choice.sample_pattern,
                   light_tree=choice.light_tree, scatter_sampling=choice.scatter_sampling,
                   scatter_noise=choice.scatter_noise, scatter_own=choice.scatter_own)


def _known_or_predicted(known: dict, remeasure):
    """A measure that looks up ``known`` (a rate, or a tuple of rates per medium) and
    predicts what it lacks with ``remeasure``, keeping it there; without one, what is not
    known counts as failing (inf)."""
    def measure(key):
        if key not in known:
            if remeasure is None:
                return math.inf
            known[key] = remeasure(key)
        return known[key]
    return measure


def _first_passing(measure_at, ordered, tolerance: float, spp: float, tried: dict) -> EstimatorChoice:
    for rate in ordered:
        tried[rate] = measure_at(rate)
        if tried[rate] <= tolerance:
            return _marching(rate, tried, tolerance, spp)
    return _null_scattering(tolerance, tried, spp)


def _marching(rate: float, tried: dict, tolerance: float, spp: float, note: str = "",
              reason: str | None = None) -> EstimatorChoice:
    return EstimatorChoice("auto", biased=True, step_rate=rate, predicted_bias=tried[rate],
                           tolerance=tolerance, tried=tried,
                           reason=reason or f"predicted bias {tried[rate]:.2%} <= {tolerance:.2%} at {spp:g} spp{note}")


def _null_scattering(tolerance: float, tried: dict, spp: float) -> EstimatorChoice:
    return EstimatorChoice("auto", biased=False, tolerance=tolerance, tried=tried,
                           reason=f"no step rate tried has a predicted bias within {tolerance:.2%} "
                                  f"at {spp:g} spp")
