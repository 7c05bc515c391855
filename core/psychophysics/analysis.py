"""From stored 2AFC answers to the paper's analysis: counts and chi-square per cell (Table III),
percent correct with sd (Figs. 13-14), and an audit of the display timings the page measured.
"""
from __future__ import annotations

from collections import defaultdict

from .plan import worst_timing_error_ms
from .stats import analyse_cell
from .store import AnswerRow


def analyse_answers(rows: list[AnswerRow], timing_tolerance_ms: float = 50.0,
                    exclude_off_timing: bool = False) -> dict:
    """Analyse every (scene, condition) cell of the answers.

    Parameters
    ----------
    rows
        The stored answers (``store.read_answers``).
    timing_tolerance_ms
        A trial whose measured display durations miss the nominal ones by more than this,
        or during which the page was hidden, counts as off timing.
    exclude_off_timing
        Leave off-timing trials out of the counts (they are always reported).

    Returns
    -------
    dict
        ``cells``: one dict per cell, sorted by scene then condition, with the fields of
        ``stats.CellResult``, ``apa`` (the Table III wording) and ``timing``
        (worst deviation in ms, trials off timing, trials with the page hidden);
        ``participants``, ``trials``, ``excluded``, ``timing_tolerance_ms`` and ``timing`` over
        every trial (also those of cells left with no trial to count).
    """
    groups: dict[tuple[str, str], list[AnswerRow]] = defaultdict(list)
    for row in rows:
        groups[(row.scene, row.condition)].append(row)
    cells, excluded = [], 0
    total = {"worst_error_ms": 0.0, "off_timing": 0, "page_hidden": 0}
    for (scene, condition), answers in sorted(groups.items()):
        errors = [worst_timing_error_ms(condition, a.durations) for a in answers]
        off = [e > timing_tolerance_ms or a.page_hidden for a, e in zip(answers, errors)]
        kept = [a for a, is_off in zip(answers, off) if not (exclude_off_timing and is_off)]
        excluded += len(answers) - len(kept)
        timing = {"worst_error_ms": max(errors), "off_timing": sum(off),
                  "page_hidden": sum(a.page_hidden for a in answers)}
        total = {"worst_error_ms": max(total["worst_error_ms"], timing["worst_error_ms"]),
                 "off_timing": total["off_timing"] + timing["off_timing"],
                 "page_hidden": total["page_hidden"] + timing["page_hidden"]}
        if not kept:
            continue
        correct = sum(a.correct for a in kept)
        result = analyse_cell(scene, condition, correct, len(kept) - correct)
        cells.append({**result.as_dict(), "apa": result.apa(), "timing": timing})
    return {"cells": cells, "participants": len({row.participant_id for row in rows}),
            "trials": len(rows), "excluded": excluded, "timing_tolerance_ms": timing_tolerance_ms,
            "timing": total}


def format_report(report: dict) -> str:
    """The report as a plain-text table."""
    header = (f"{'scene':<16} {'condition':<13} {'N':>3} {'correct':>7} {'incorrect':>9} "
              f"{'% correct (sd)':>15}  chi-square")
    lines = [header, "-" * len(header)]
    for cell in report["cells"]:
        percent = f"{cell['percent_correct']:.1f} ({cell['percent_sd']:.1f})"
        lines.append(f"{cell['scene']:<16} {cell['condition']:<13} {cell['n']:>3} "
                     f"{cell['correct']:>7} {cell['incorrect']:>9} {percent:>15}  {cell['apa']}")
    # Over every trial, so that the trials excluded are among those counted off timing.
    worst, off, hidden = (report["timing"][key] for key in ("worst_error_ms", "off_timing", "page_hidden"))
    lines.append("")
    lines.append(f"{report['participants']} participants, {report['trials']} trials; display "
                 f"timing: worst deviation {worst:.1f} ms from 4 s / 2 s / 8 s, {off} trials off "
                 f"by more than {report['timing_tolerance_ms']:g} ms or with the page hidden "
                 f"({hidden} hidden)" + (f", {report['excluded']} excluded" if report["excluded"] else ""))
    return "\n".join(lines)
