"""``xsl-render experiment-analyse DB``: the chi-square analysis of Table III and Figs. 13-14."""
from __future__ import annotations

import json

NAME = "experiment-analyse"
HELP = ("per scene and condition: correct/incorrect counts, chi-square against 50/50 with "
        "its p value, percent correct with its binomial sd; optional bar chart (PNG)")


def add_arguments(parser) -> None:
    from . import argtypes

    parser.add_argument("db", metavar="DB", type=argtypes.input_file(what="answers database"),
                        help="the answers database of experiment-serve")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--chart", metavar="FILE.png", type=argtypes.output_file(".png"),
                        help="write a bar chart of percent correct with sd error bars")
    parser.add_argument("--timing-tolerance-ms", type=argtypes.number(lo=0.0), default=50.0,
                        help="count trials whose measured display durations missed the nominal "
                             "4 s / 2 s / 8 s by more than this (default 50 ms)")
    parser.add_argument("--exclude-off-timing", action="store_true",
                        help="leave those trials, and trials during which the page was hidden, "
                             "out of the counts (they are always reported)")


def run(args) -> int:
    from ...core.errors import InputError
    from ...core.psychophysics.store import read_answers

    answers = read_answers(args.db)
    if not answers:
        raise InputError(f"{args.db} holds no answers yet")
    # scipy.stats takes a second or two to import: only once the input is known to be good.
    from ...core.psychophysics.analysis import analyse_answers, format_report

    report = analyse_answers(answers, args.timing_tolerance_ms, args.exclude_off_timing)
    if not report["cells"]:
        raise InputError("every answer was excluded as off timing")
    if args.chart:
        from ...core.psychophysics.chart import write_bar_chart
        write_bar_chart(report["cells"], args.chart)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print(format_report(report))
        if args.chart:
            print(f"chart: {args.chart}")
    return 0
