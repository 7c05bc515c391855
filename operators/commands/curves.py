"""``xsl-render curves SCENE.blend --out DIR``: time-quality curves and equal-quality speedups.

Uniform at 1/16 .. 1x the ceiling (the last is the gold standard), Cycles' adaptive at three
thresholds, path guiding, XS and XSL at four ceilings, at one resolution, denoised alike,
each timed whole and compared with the converged reference; DIR/curves.json, curves.png and
report.html, and the table printed. Finished runs in DIR are reused. With ``--frames`` every
run renders the frames in one Cycles session, each frame against its own reference
(``addon.validation.curves_runner``)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "curves"
#: Finished runs are kept as they come (the curves resume), not held back for the end.
OUTPUTS_AS_A_SET = False
HELP = ("time-quality curves (uniform, Cycles adaptive, path guiding, XS, XSL) against the "
        "converged reference, with each run's equal-quality speedup; DIR/curves.json, "
        "curves.png, report.html (resumable)")


def add_arguments(parser) -> None:
    from ...addon.validation.curves_runner import MAX_REPEATS
    from ...core.validation.contestants import curve_names
    from . import argtypes
    from .common import add_scene_arguments
    from .option_flags import add_option
    from .reference import ceiling

    add_scene_arguments(parser)
    parser.add_argument("--out", required=True, metavar="DIR", type=argtypes.output_folder(),
                        help="output folder; finished runs in it are reused")
    parser.add_argument("--frames", metavar="FRAMES", type=argtypes.FRAMES,
                        help="render every run over these frames (1-24, 1-24:2 or a list such as "
                             "1-3,8) in one Cycles session, each frame against its own reference: "
                             "errors are the means over the frames, plus the sequence's flicker")
    parser.add_argument("--max-spp", type=ceiling, metavar="CEILING",
                        help="the ceiling: gold's samples per pixel, the budgets follow it "
                             "(default: the scene's own Cycles samples)")
    parser.add_argument("--repeats", type=argtypes.integer(1, MAX_REPEATS), default=1, metavar="N",
                        help="render every run N times with seeds 0..N-1 and report the median "
                             "time and error (default 1)")
    parser.add_argument("--reference", metavar="REF.exr", type=argtypes.input_file(what="reference file"),
                        help="the converged reference to compare with (default: `xsl-render "
                             "reference` at the same size, from the cache or rendered now)")
    parser.add_argument("--reference-spp", type=argtypes.SAMPLES, metavar="N",
                        help="samples of the reference made here (default max(1024, 16 x ceiling))")
    parser.add_argument("--curves", metavar="LIST",
                        help=f"curves to render (default all: {', '.join(curve_names())}); "
                             "uniform is always in")
    add_option(parser, "seed", help="first contestant seed (never the reference's)")
    parser.add_argument("--vdp", action=argparse.BooleanOptionalAction, default=True,
                        help="ColorVideoVDP's JOD where it is installed (default on)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def _frames(args) -> tuple[int, ...] | None:
    """The --frames list (None without it); --frame and --reference do not go with it."""
    from ...core.errors import InputError
    from ...core.frames import parse_frame_list

    if args.frames is None:
        return None
    if args.frame is not None:
        raise InputError("--frame and --frames cannot be combined")
    if args.reference is not None:
        raise InputError("--reference is one frame's reference and cannot be combined with --frames "
                         "(each frame's reference is cached: xsl-render reference --frames)")
    return parse_frame_list(args.frames)


def check(args) -> None:
    _frames(args)


def run(args) -> int:
    from ...addon.validation.curves_runner import CurvesSettings, run_curves
    from ...core.validation.contestants import parse_curves
    from ...core.validation.curves_results import table_lines
    from ...core.validation.store import check_output_folder
    from ..interrupt import InterruptToCancel
    from ..progress_bar import ProgressBar
    from .common import parse_resolution
    from .reference import scene_file

    settings = CurvesSettings(
        ceiling=args.max_spp, resolution=parse_resolution(args.resolution), frame=args.frame,
        scene_name=args.scene_name, repeats=args.repeats, seed=args.seed,
        curves=parse_curves(args.curves), vdp=args.vdp,
        reference=Path(args.reference) if args.reference else None,
        reference_spp=args.reference_spp, frames=_frames(args)).check()
    out = check_output_folder(args.out)
    path = scene_file(args)
    bar = None if args.quiet else ProgressBar(NAME)
    try:
        with InterruptToCancel() as interrupt:
            data = run_curves(args.scene, settings, out, progress=interrupt.wrap(bar), blend_file=path)
    finally:
        if bar is not None:
            bar.close()
    for warning in data["warnings"]:
        print(f"xsl-render: warning: {warning}", file=sys.stderr)
    reference, scene = data["reference"], data["scene"]
    where = (f"frame {scene['frame']}" if not scene.get("frames") else
             f"frames {scene['frame_range']}, mean over {len(scene['frames'])} frames")
    print(f"{Path(scene['file']).name} (scene '{scene['scene']}', {where}) at "
          f"{scene['size'][0]}x{scene['size'][1]}, ceiling "
          f"{data['ceiling']} spp; reference {reference['inputs'].get('spp')} spp, seed "
          f"{reference['inputs'].get('seed')} ({reference['source']}); {data['repeats']} repeat(s)")
    print("\n".join(table_lines(data)))
    if not data["vdp"]["ran"]:
        print(f"VDP skipped: {data['vdp']['skipped']}")
    print(f"{data['rendered']} run(s) rendered, {data['reused']} reused; {out / 'curves.json'}, "
          f"{out / 'curves.png'}")
    print(f"report: {(out / 'report.html').resolve()}")
    return 0
