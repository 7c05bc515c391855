"""The design of the paper's 2AFC experiment (sections 6.2.1-6.2.2): conditions, timings,
counterbalancing and what counts as a correct answer.

Each participant takes one condition (between subjects, as the paper's 24 + 24) and sees
every scene exactly once (no repeated exposure). The order of the scenes is random per
participant. Where the gold standard appears (first or second, left or right) is
counterbalanced in permuted blocks of two participants of the same condition: the first of
a block gets a random half of the scenes with the gold standard first (left), the second
gets the opposite for every scene. So every scene is shown gold-first to exactly half of
each completed block, and each participant sees the gold standard first in half the scenes.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass

NO_REFERENCE = "no-reference"
REFERENCE = "reference"
CONDITIONS = (NO_REFERENCE, REFERENCE)

# Where the gold standard can be, and so what a participant can answer, per condition.
POSITIONS = {NO_REFERENCE: ("first", "second"), REFERENCE: ("left", "right")}

# Display durations of section 6.2, in milliseconds.
TIMINGS_MS = {
    NO_REFERENCE: {"first": 4000.0, "gap": 2000.0, "second": 4000.0},
    REFERENCE: {"exposure": 8000.0},
}

QUESTIONS = {
    NO_REFERENCE: "Which image had the worse quality?",
    REFERENCE: "Which image is most similar to the reference on top?",
}

AGE_RANGES = ("18-24", "25-34", "35-44", "45-54", "55-64", "65+", "prefer not to say")


@dataclass(frozen=True)
class Trial:
    """One scene in a participant's sequence; ``gold_position`` is one of POSITIONS[condition]."""

    order: int
    scene: str
    gold_position: str


def choose_condition(participants_per_condition: dict[str, int], allowed: tuple[str, ...]) -> str:
    """The allowed condition with the fewest participants so far (ties: the first allowed)."""
    if not allowed:
        raise ValueError("no condition allowed")
    return min(allowed, key=lambda c: (participants_per_condition.get(c, 0), allowed.index(c)))


def gold_first_scenes(scenes: list[str], partner: dict[str, bool] | None,
                      rng: random.Random) -> dict[str, bool]:
    """Which scenes show the gold standard first (or left) to one participant.

    Parameters
    ----------
    scenes
        Every scene of the experiment.
    partner
        ``None`` for the first participant of a counterbalancing block: a random half of
        the scenes (the odd one out by a coin) get the gold standard first. Otherwise the
        first participant's assignment, which this participant gets reversed; a scene the
        partner did not have (added later) is drawn at random.
    rng
        The random source.
    """
    if partner is not None:
        return {scene: (not partner[scene]) if scene in partner else rng.random() < 0.5
                for scene in scenes}
    half = len(scenes) // 2 + (len(scenes) % 2 if rng.random() < 0.5 else 0)
    first = set(rng.sample(list(scenes), half))
    return {scene: scene in first for scene in scenes}


def plan_trials(scenes: list[str], condition: str, gold_first: dict[str, bool],
                rng: random.Random) -> list[Trial]:
    """The participant's trials: every scene once, in random order, gold where assigned."""
    if condition not in CONDITIONS:
        raise ValueError(f"unknown condition {condition!r}")
    first, second = POSITIONS[condition]
    order = list(scenes)
    rng.shuffle(order)
    return [Trial(order=i, scene=scene, gold_position=first if gold_first[scene] else second)
            for i, scene in enumerate(order)]


def is_correct(condition: str, gold_position: str, choice: str) -> bool:
    """Whether an answer is right.

    No reference: "which had the worse quality?" is right when the choice is the selective
    rendering, i.e. not the gold standard. Reference: "which is most similar to the
    reference?" is right when the choice is the gold standard.
    """
    if choice not in POSITIONS[condition] or gold_position not in POSITIONS[condition]:
        raise ValueError(f"{choice!r} is not an answer of the {condition} condition")
    return (choice != gold_position) if condition == NO_REFERENCE else (choice == gold_position)


def durations_from_events(condition: str, events: dict[str, float]) -> dict[str, float]:
    """Display durations (ms) from the page's performance.now() time stamps.

    No reference: ``first_on, first_off, second_on, second_off`` -> first, gap, second.
    Reference: ``on, off`` -> exposure. Raises ValueError for missing, non-finite or
    out-of-order stamps.
    """
    names = (("first_on", "first_off", "second_on", "second_off") if condition == NO_REFERENCE
             else ("on", "off"))
    stamps = []
    for name in names:
        value = events.get(name)
        try:
            stamp = float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) \
                else math.nan
        except OverflowError:           # an int past float's range
            stamp = math.nan
        if not math.isfinite(stamp):
            raise ValueError(f"time stamp {name!r} missing or not a finite number")
        stamps.append(stamp)
    if any(later < earlier for earlier, later in zip(stamps, stamps[1:])):
        raise ValueError("time stamps out of order")
    if condition == NO_REFERENCE:
        return {"first": stamps[1] - stamps[0], "gap": stamps[2] - stamps[1],
                "second": stamps[3] - stamps[2]}
    return {"exposure": stamps[1] - stamps[0]}


def worst_timing_error_ms(condition: str, durations: dict[str, float]) -> float:
    """The largest deviation of a trial's measured durations from the nominal ones."""
    nominal = TIMINGS_MS[condition]
    return max(abs(durations[name] - nominal[name]) for name in nominal)
