"""Equal-quality speedup: how long a baseline needs to reach a run's error, read along the
baseline's time-quality curve, divided by the run's own time.

Noise makes a measured curve wiggle, so it is read along its lower envelope (sorted by time, a
point stays only when its error is below every faster point's): the baseline is never made to
look slower than it was once measured to be. Errors after denoising fall about as a power of
the samples, so ``log(seconds)`` is interpolated piecewise linearly in ``log(error)``; an error
outside the envelope is reached along the end segment's slope and marked ``extrapolated``.
FLIP, MSE and flicker are errors; ColorVideoVDP's JOD is read as its drop below 10."""
from __future__ import annotations

import math
from dataclasses import dataclass

#: Metrics read along curves, and whether their value is an error (lower is better).
#: flicker: a frame sequence's (``core.validation.temporal``), for runs over several frames.
LOWER_IS_BETTER = {"flip": True, "flip_tile95": True, "flip_share": True, "mse": True, "flicker": True,
                   "jod": False}
#: ColorVideoVDP's score for an image identical to the reference.
JOD_MAX = 10.0


@dataclass(frozen=True)
class Point:
    """One measured run on a curve: its wall time and its error (lower is better)."""

    seconds: float
    error: float
    name: str = ""


@dataclass(frozen=True)
class Reach:
    """The time a curve needs to reach an error.

    Attributes
    ----------
    seconds : the time, or None when it cannot be read (``reason`` says why).
    extrapolated : True when the error lies outside the curve's measured range and the time
        comes from extending an end segment.
    reason : why ``seconds`` is None.
    """

    seconds: float | None
    extrapolated: bool = False
    reason: str | None = None


@dataclass(frozen=True)
class Speedup:
    """A run's equal-quality speedup over one curve on one metric.

    ``value`` = ``time_to_reach_s`` / the run's seconds; ``faster`` is True only when the
    value is above 1 (a tie is not faster).
    """

    value: float | None
    time_to_reach_s: float | None
    extrapolated: bool
    reason: str | None = None

    @property
    def faster(self) -> bool:
        return self.value is not None and self.value > 1.0

    def to_dict(self) -> dict:
        return {"value": self.value, "time_to_reach_s": self.time_to_reach_s,
                "extrapolated": self.extrapolated, "faster": self.faster, "reason": self.reason}


def as_error(metric: str, value: float | None) -> float | None:
    """A metric's value as an error, lower is better: FLIP and MSE as they are, JOD as its
    drop below 10 (``JOD_MAX - JOD``). None stays None; an unknown metric raises KeyError."""
    if value is None:
        return None
    return float(value) if LOWER_IS_BETTER[metric] else JOD_MAX - float(value)


def _usable(point: Point) -> bool:
    """Only points with positive, finite time and error have a place on a log-log curve."""
    return (math.isfinite(point.seconds) and math.isfinite(point.error)
            and point.seconds > 0 and point.error > 0)


def monotone_envelope(points: list[Point]) -> list[Point]:
    """The curve's lower envelope: error strictly decreasing as time increases.

    Parameters
    ----------
    points
        The measured points, in any order. Points with a zero, negative or non-finite time
        or error are left out (they have no logarithm).

    Returns
    -------
    list of Point
        Sorted by time; a point is kept only when its error is below the error of every
        point that took less time (of two points with the same time, the better one).

    Examples
    --------
    >>> [p.seconds for p in monotone_envelope([Point(1, .05), Point(2, .06), Point(4, .03)])]
    [1, 4]
    """
    kept: list[Point] = []
    for point in sorted(filter(_usable, points), key=lambda p: (p.seconds, p.error)):
        if not kept or point.error < kept[-1].error:
            kept.append(point)
    return kept


def _log_time_at(a: Point, b: Point, error: float) -> float:
    """log(seconds) at ``error`` on the straight log-log line through ``a`` and ``b``."""
    slope = (math.log(b.seconds) - math.log(a.seconds)) / (math.log(b.error) - math.log(a.error))
    return math.log(a.seconds) + (math.log(error) - math.log(a.error)) * slope


def time_to_reach(curve: list[Point], error: float) -> Reach:
    """The time the curve needs to reach ``error``, interpolated log-log.

    Parameters
    ----------
    curve
        The curve's measured points (made monotone here with :func:`monotone_envelope`).
    error
        The error to reach (lower is better; see :func:`as_error` for JOD).

    Returns
    -------
    Reach
        Inside the envelope's error range: ``log(seconds)`` interpolated linearly in
        ``log(error)`` between the two points around it. Above its largest error (worse than
        its fastest point) or below its smallest (better than its slowest): the end segment's
        log-log line extended, ``extrapolated`` True. No time (``seconds`` None, with the
        reason) for an error that is not positive, an empty curve, or a curve of one point
        whose error is not exactly ``error`` (no slope to extend).
    """
    if error is None or not math.isfinite(error) or error <= 0:
        return Reach(None, reason=f"no time for an error of {error} (only positive errors have a logarithm)")
    envelope = monotone_envelope(curve)
    if not envelope:
        return Reach(None, reason="the curve has no usable point")
    first, last = envelope[0], envelope[-1]
    if len(envelope) == 1:
        if error == first.error:
            return Reach(first.seconds)
        return Reach(None, reason="the curve has one point: no slope to extend")
    if error > first.error:
        return Reach(math.exp(_log_time_at(envelope[0], envelope[1], error)), extrapolated=True)
    if error < last.error:
        return Reach(math.exp(_log_time_at(envelope[-2], envelope[-1], error)), extrapolated=True)
    for a, b in zip(envelope, envelope[1:]):
        if b.error <= error <= a.error:
            if error == a.error:
                return Reach(a.seconds)
            if error == b.error:
                return Reach(b.seconds)
            return Reach(math.exp(_log_time_at(a, b, error)))
    raise AssertionError("unreachable: the error lies inside a strictly decreasing envelope")


def equal_quality_speedup(curve: list[Point], error: float | None, seconds: float) -> Speedup:
    """``time_to_reach(curve, error) / seconds``: how many times less time the run took than
    the curve needs for the same error (above 1: faster at equal quality).

    Parameters
    ----------
    curve
        The baseline's points (seconds, error), error lower-is-better.
    error
        The run's error on the same metric (use :func:`as_error` for JOD).
    seconds
        The run's wall time.
    """
    if error is None:
        return Speedup(None, None, False, "no error measured")
    if not (math.isfinite(seconds) and seconds > 0):
        return Speedup(None, None, False, f"the run's time {seconds} is not positive")
    reach = time_to_reach(curve, error)
    if reach.seconds is None:
        return Speedup(None, None, False, reach.reason)
    return Speedup(reach.seconds / seconds, reach.seconds, reach.extrapolated)


def curve_points(members: list[tuple[str, float, dict]], metric: str) -> list[Point]:
    """The points of one metric from runs given as ``(name, seconds, {metric: value})``, the
    value turned into an error (:func:`as_error`); runs without that metric are left out."""
    return [Point(seconds, as_error(metric, values.get(metric)), name)
            for name, seconds, values in members if values.get(metric) is not None]


def speedups_against(curves: dict[str, list[tuple[str, float, dict]]],
                     run: tuple[str, float, dict],
                     metrics: tuple[str, ...] = ("flip", "mse", "jod"),
                     own_curve: str | None = None) -> dict[str, dict[str, dict]]:
    """A run's equal-quality speedups over every baseline curve, on every metric.

    Parameters
    ----------
    curves
        Baseline name -> its runs, each ``(name, seconds, {metric: value})`` (a value None
        or missing: not measured).
    run
        ``(name, seconds, {metric: value})`` of the run to place.
    metrics
        The metrics to read; JOD is read as its drop below 10 (:func:`as_error`).
    own_curve
        The baseline the run belongs to, if any: it is left out (a point read along its own
        curve measures nothing but that curve's noise).

    Returns
    -------
    dict
        ``{baseline: {metric: Speedup.to_dict()}}``.
    """
    _, seconds, values = run
    out: dict[str, dict[str, dict]] = {}
    for baseline, members in curves.items():
        if baseline == own_curve:
            continue
        out[baseline] = {metric: equal_quality_speedup(curve_points(members, metric),
                                                       as_error(metric, values.get(metric)),
                                                       seconds).to_dict()
                         for metric in metrics}
    return out
