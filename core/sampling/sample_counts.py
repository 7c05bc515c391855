"""How many samples per pixel a guided frame renders: counts Cycles' sample patterns like.

Cycles' patterns stratify best at powers of two, and after denoising it shows: a count just
above a power of two renders at it (``sobol_friendly``), one just below it is raised to it
where the budget's slack reaches (``power_of_two_within``), the columns of a flat pass and
the frames of a range hold one count (``column_count``, ``HOLD_RANGE``). Plain numbers; the
clock is read by the caller.
"""
from __future__ import annotations

#: A whole-frame count this little above a power of two is rounded down to it (see
#: ``sobol_friendly``), up to ``POWER_OF_TWO_LARGEST``. Measured up to 48 samples. The
#: budget is a ceiling: a run may end up to a third early, where the extra samples would
#: have bought little (statue, road, balls_b) or made the frame worse (balls_a).
POWER_OF_TWO_SLACK = 1.5
POWER_OF_TWO_LARGEST = 32


def sobol_friendly(count: int, sequence: int = 0) -> int:
    """``count`` samples per pixel, or the power of two below it when that is within
    ``POWER_OF_TWO_SLACK`` and not below ``sequence``: Cycles' sample patterns stratify best
    at powers of two, and after denoising the difference shows. ``sequence`` is the length
    of the per-pixel sequence the render's Cycles session already draws from
    (``core.sampling.sample_pattern.session_sequence``): a count below it takes the first
    samples of that longer sequence, which a rounding down does not make a power of two's
    own pattern (balls_a, blue noise: 8 spp after a 16-spp render in one session, mean FLIP
    0.0789 against 0.0637 fresh), so the count is kept whole. Measured (uniform, auto's estimator, mean FLIP against
    the converged reference, in ``docs/bench_sample_counts.txt``), with the legacy Tabulated
    Sobol pattern (medians of 4 seeds, 2 for 22 and 36-48): balls_a 16 / 18 / 20 / 22 / 24
    spp 0.0411 / 0.0455 / 0.0439 / 0.0434 / 0.0393, 32 / 36 / 40 / 44 / 48 spp 0.0307 /
    0.0328 / 0.0311 / 0.0305 / 0.0274; statue 16 / 18 / 20 / 22 / 24 spp 0.0454 / 0.0457 /
    0.0448 / 0.0434 / 0.0421; balls_b 16 / 18 / 20 / 24 spp 0.0521 / 0.0520 / 0.0503 /
    0.0479. With Blender 5's pure blue noise (auto's pattern before it rounded the sequence
    up, ``sample_pattern``; means of 2 seeds):
    balls_a 16 / 18 / 20 / 22 / 24 / 28 / 32 spp 0.0377 / 0.0476 / 0.0463 / 0.0421 / 0.0373 /
    0.0383 / 0.0274; statue 16 / 20 / 22 / 24 / 32 spp 0.0445 / 0.0439 / 0.0421 / 0.0411 /
    0.0378; balls_b 16 / 20 / 22 spp 0.0505 / 0.0491 / 0.0484; road 0.0400 / 0.0387 /
    0.0377. So on balls_a every count from 17 to 31 is no better than 16, with blue noise
    much worse at 18-22; elsewhere 20-23 samples buy 2-6 % of FLIP for 25-45 % more time,
    about what the power of two's own curve gives, so rounding them down costs nothing in
    equal-quality speed. Guided's three columns at mean counts of 35-37 spp measured FLIP
    0.0308 on balls_a, where 32 in every column gave 0.0274 (``docs/bench_sample_pattern.txt``).
    With the rounded sequence auto renders with now, 20 samples still buy nothing over 16 on
    balls_a and statue (0.0284 / 0.0407 against 0.0276 / 0.0409; ``docs/bench_round_counts.txt``),
    so the rounding stays."""
    count = int(count)
    if count < 2:
        return max(count, 1)
    power = 1 << (count.bit_length() - 1)
    if power > POWER_OF_TWO_LARGEST or power < sequence:
        return count
    return power if count < POWER_OF_TWO_SLACK * power else count


#: A flat pass's later column keeps the first one's count from the low end of this range of
#: it (``column_count``); a later frame of a guided range keeps the frame before's until it
#: affords more than the high end (``SequenceBudget.steady_count``).
HOLD_RANGE = (0.85, 1.3)


def column_count(held: int, affordable: float, frame_affordable: float, sequence: int = 0,
                 priced_by_pilot: bool = True) -> int:
    """The count of a flat pass's later column: ``held`` (the count of the columns before it);
    ``sobol_friendly(affordable, sequence)`` where the column affords less than ``HOLD_RANGE[0]`` of it;
    more, ``sobol_friendly(affordable)``, only where the first column was priced too dear:
    ``held`` was the pilot's price (``priced_by_pilot``: the column after the first) and the
    whole frame affords more than it beyond a rounding down to it. The column after that
    holds the count the clock set (raised again, a last column took every second left and
    ran 1.1x over its 4-s budget where the clock's 30 % noise slowed it).

    ``affordable``: the column's count by the clock (the time left over the columns left);
    ``frame_affordable``: the count the whole final pass would have afforded at the cost per
    sample its finished columns measured. A column affords more than the count before it in
    two ways. Either the columns before it were rounded down (``sobol_friendly``: 20
    affordable, 16 rendered) and their slack all fell to the last column (road at 14.1 s: 16
    / 16 / 32, 14.4 s): then ``sobol_friendly(frame_affordable)`` is ``held``, and the column
    holds. Road at a 14.1-s budget (2026-11-28): raised, 16 / 16 / 32 spp in 14.4 s, mean
    FLIP 0.0384, p95 region FLIP 0.0642, MSE 4.69e-5; held, 16 / 16 / 16 in 10.8-12.2 s (5
    runs), 0.0400, 0.0642, 4.72e-5. The raise bought 4 % of mean FLIP and nothing else for a
    quarter more time, less than uniform sampling gains in it (on the demo's uniform curve
    1.00x against 1.11x at equal mean FLIP), and left the frame uneven; held, the frame ends
    early. Or the pilot priced the first column too dear (balls_b's columns came out 4 / 16 /
    29; a quarter-resolution pilot of 64 x 36 pixels misjudged a full-resolution sample up to
    2x, its per-sample cost in Cycles being mostly fixed): the first column is rendered by
    then, and the later ones spend the time it left (the test fog at 96 x 54 pixels and 4 s
    took 32 / 85 / 85 spp in 2.5 s, 0.62 of its budget, and 55 / 55 / 55 in 2.9 s when the
    later columns held, where their clock afforded 95).

    One frame at one count where the clock allows: the pilot's timing is noisy at small
    budgets (a quarter-resolution render of a few samples in ~0.07 s), and the columns paced
    after a misjudged first one came out uneven, which scored worse than their mean count
    (balls_a at uniform 16 spp's time, blue noise: columns averaging 14.3 / 15.3 / 16.0 spp,
    mean FLIP 0.0564 / 0.0445 / 0.0375; ``docs/bench_sample_pattern.txt``). That compares
    frames of equal total; once a first column is rendered below the frame's count, more
    samples in the later ones only lower their error. Holding costs at most the held count
    beyond what a column affords by the clock (the budget's 15 %) or leaves what the rounding
    down saved unspent (a count between two powers of two buys little, ``sobol_friendly``)."""
    if affordable < HOLD_RANGE[0] * held:
        return sobol_friendly(int(affordable), sequence)
    if priced_by_pilot and sobol_friendly(int(frame_affordable), sequence) > held:
        return max(held, sobol_friendly(int(affordable), sequence))
    return held


#: A guided run may end this share over its budget to render at the power of two above its
#: count (``power_of_two_within``). A range: without it a held count that cost a little more
#: than each frame's share left the last frames to pay back all of it, and they dropped
#: (street, frames 1-8 at uniform 32 spp's time: 16, 32 x6, 16 spp, each change a flicker;
#: measured at 0.1 too, where the pricing error of 2-s frames ran a 2-frame range 1.12x
#: over). A still: road at uniform 32 spp's time rendered 28-29 spp in 85-92 % of its budget.
BUDGET_OVERRUN = 0.05


def power_of_two_within(count: int, reach: float, ceiling: int) -> int:
    """The largest power of two within ``reach`` (and the ceiling) where that is above
    ``count``, else ``count``. A power of two renders better than the count below it
    beyond what the samples add (Blender 5's blue noise, street frame 1: 28 spp mean
    FLIP 0.0690, 32 spp 0.0662; a guided range at 29 spp on every frame scored 0.0697)."""
    top = int(min(reach, ceiling))
    if top < 1:
        return count
    power = 1 << (top.bit_length() - 1)
    return max(power, count)


def still_count(affordable: float, allowance: float, ceiling: int, sequence: int = 0) -> int:
    """A still's whole-frame count where it affords ``affordable`` samples per pixel and
    ``allowance`` more within ``BUDGET_OVERRUN``: at a count Cycles' patterns like
    (``sobol_friendly``, ``sequence`` the session's), raised to the power of two above it
    where the allowance reaches."""
    count = sobol_friendly(max(1, min(int(affordable), ceiling)), sequence)
    return power_of_two_within(count, affordable + allowance, ceiling)
