"""The contestants of ``xsl-render curves``: which renders make up each time-quality curve.

A curve is one way of rendering at several budgets (uniform at 1/16 .. 1x the ceiling, Cycles'
adaptive at three thresholds, ...); each point is a :class:`Contestant`: a name, the kind of
render that makes it (``addon.validation.contestants.REQUESTS``), its parameters, and maybe
another contestant whose measured time is its budget (``time_of``). The registry is a list of
:class:`CurveSpec`: a new curve is one ``register_curve`` call here and, for a new kind, one
request maker on the Blender side. Baseline curves are the ones speedups are read along."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from ..checks import name_list
from ..errors import Field, InputError, SettingError

#: Uniform budgets as fractions of the ceiling; the point at 1x is the gold standard.
UNIFORM_FRACTIONS = (1 / 16, 1 / 8, 1 / 4, 1 / 2, 1)
#: Cycles' adaptive sampling: noise thresholds, and its sample ceiling in ceilings.
ADAPTIVE_THRESHOLDS = (0.1, 0.05, 0.02)
ADAPTIVE_CEILINGS = 4
#: Ceilings of the selective renders (XS, XSL), in ceilings.
SELECTIVE_FRACTIONS = (1 / 4, 1 / 2, 1, 2)
#: The uniform budgets path guiding is rendered at (the largest three).
GUIDING_POINTS = 3
#: The uniform budgets a time-matched mode gets (fractions of the ceiling: 8/16/32/64 of 64).
TIME_MATCHED_FRACTIONS = (1 / 8, 1 / 4, 1 / 2, 1)


@dataclass(frozen=True)
class Contestant:
    """One point of a curve.

    Attributes
    ----------
    name : file stem and key in curves.json, e.g. "uniform_16spp".
    curve : the curve it belongs to ("uniform", "adaptive", ...).
    kind : the renderer that makes it (a key of ``addon.validation.contestants.RENDERERS``).
    label : how the table and the plot call it.
    params : what the renderer needs (JSON-ready): ``spp``, ``max_spp``, ``noise_threshold``...
    time_of : another contestant whose measured time (median over repeats) is this one's
        time budget, handed to the renderer; None for a contestant with a budget of its own.
    gold : the uniform point at the ceiling, the paper's gold standard (labelled, not
        rendered twice).
    """

    name: str
    curve: str
    kind: str
    label: str
    params: dict = field(default_factory=dict)
    time_of: str | None = None
    gold: bool = False

    def to_dict(self) -> dict:
        return {"name": self.name, "curve": self.curve, "kind": self.kind, "label": self.label,
                "params": dict(self.params), "time_of": self.time_of, "gold": self.gold}


@dataclass(frozen=True)
class CurveSpec:
    """One curve: its name, label, whether runs are measured against it, and its points for
    a given ceiling (``points(ceiling) -> list[Contestant]``)."""

    name: str
    label: str
    points: Callable[[int], list[Contestant]]
    baseline: bool = False


def uniform_budgets(ceiling: int) -> list[int]:
    """Uniform samples per pixel: 1/16 .. 1x the ceiling, rounded, at least 1, each once
    (64 -> 4, 8, 16, 32, 64; 8 -> 1, 2, 4, 8)."""
    return sorted({max(1, round(ceiling * f)) for f in UNIFORM_FRACTIONS})


def _uniform(ceiling: int) -> list[Contestant]:
    return [Contestant(f"uniform_{spp}spp", "uniform", "uniform",
                       f"uniform {spp} spp" + (" (gold)" if spp == ceiling else ""),
                       {"spp": spp}, gold=spp == ceiling)
            for spp in uniform_budgets(ceiling)]


def _adaptive(ceiling: int) -> list[Contestant]:
    most = ADAPTIVE_CEILINGS * ceiling
    return [Contestant(f"adaptive_{threshold:g}", "adaptive", "adaptive",
                       f"adaptive {threshold:g}, max {most} spp",
                       {"noise_threshold": threshold, "max_spp": most})
            for threshold in ADAPTIVE_THRESHOLDS]


def _guiding(ceiling: int) -> list[Contestant]:
    return [Contestant(f"guiding_{spp}spp", "guiding", "guiding", f"path guiding {spp} spp",
                       {"spp": spp})
            for spp in uniform_budgets(ceiling)[-GUIDING_POINTS:]]


def _selective(director: str) -> Callable[[int], list[Contestant]]:
    def points(ceiling: int) -> list[Contestant]:
        ceilings = sorted({max(1, round(ceiling * f)) for f in SELECTIVE_FRACTIONS})
        return [Contestant(f"{director}_{spp}", director, director,
                           f"{director.upper()}, ceiling {spp} spp", {"max_spp": spp})
                for spp in ceilings]
    return points


def time_matched_curve(kind: str, label: str, fractions: tuple[float, ...] = TIME_MATCHED_FRACTIONS,
                       curve: str | None = None, params: dict | None = None) -> CurveSpec:
    """A curve of a time-budgeted mode rendered at the times uniform sampling took at
    ``fractions`` of the ceiling (default 1/8 .. 1x: 8/16/32/64 spp for a ceiling of 64).

    Its points are named ``<curve>_at_uniform_<N>spp`` and take ``time_of`` the uniform point
    (the median of its repeats), which the renderer gets as its budget in seconds.
    """
    name = curve or kind

    def points(ceiling: int) -> list[Contestant]:
        budgets = [b for b in uniform_budgets(ceiling)
                   if any(b == max(1, round(ceiling * f)) for f in fractions)]
        return [Contestant(f"{name}_at_uniform_{spp}spp", name, kind,
                           f"{label}, uniform {spp} spp's time", dict(params or {}),
                           time_of=f"uniform_{spp}spp")
                for spp in budgets]
    return CurveSpec(name, label, points)


CURVES: list[CurveSpec] = [
    CurveSpec("uniform", "uniform", _uniform, baseline=True),
    CurveSpec("adaptive", "Cycles adaptive", _adaptive, baseline=True),
    CurveSpec("guiding", "Cycles path guiding", _guiding),
    CurveSpec("xs", "XS", _selective("xs")),
    CurveSpec("xsl", "XSL", _selective("xsl")),
    # The time-budgeted sampler, at uniform's times: tiles scored by the pilot's gradient
    # alone, and weighted by the XSL map as the paper's perceptual importance.
    time_matched_curve("guided", "guided", params={"importance": "none"}),
    time_matched_curve("guided", "guided, XSL importance", curve="guided_xsl",
                       params={"importance": "xsl"}),
]


def register_curve(spec: CurveSpec) -> CurveSpec:
    """Add a curve to the registry (replacing one of the same name); returns it."""
    CURVES[:] = [c for c in CURVES if c.name != spec.name] + [spec]
    return spec


def curve_names() -> list[str]:
    return [spec.name for spec in CURVES]


def baseline_names() -> list[str]:
    return [spec.name for spec in CURVES if spec.baseline]


def parse_curves(text: str | None) -> tuple[str, ...]:
    """'uniform,xsl' -> those curves in registry order; None: all of them. The uniform curve
    is always in (it is the baseline, and time-matched curves take its times)."""
    names = curve_names()
    if text is None:
        return tuple(names)
    wanted = name_list(text, Field("curves"), names, "curve")
    return tuple(name for name in names if name in {"uniform", *wanted})


def plan_contestants(ceiling: int, curves: tuple[str, ...] | None = None) -> list[Contestant]:
    """Every contestant of the chosen curves for ``ceiling``, in an order where a
    contestant's ``time_of`` source comes before it."""
    if ceiling < 1:
        raise SettingError("{ceiling.name} must be at least 1 (got {ceiling.value})", ceiling=ceiling)
    chosen = set(curve_names() if curves is None else curves)
    plan = [c for spec in CURVES if spec.name in chosen for c in spec.points(ceiling)]
    names = {c.name for c in plan}
    for contestant in plan:
        if contestant.time_of is not None and contestant.time_of not in names:
            raise InputError(f"{contestant.name} takes its time from {contestant.time_of}, "
                             "which is not planned")
    # Sources first: a stable sort on "takes its time from another".
    return sorted(plan, key=lambda c: c.time_of is not None)
