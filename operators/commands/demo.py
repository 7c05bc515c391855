"""``xsl-render demo``: the main job on the bundled road scene. The file as it renders (the
gold standard: its 64 samples, its settings) against Auto Volumes in the same time and at the
same samples; the paper's director maps, its XS and XSL renders, uniform at 1/8-1/2 of the
ceiling (the file's time-quality curve) and the equal-time baselines; each against the
converged reference (shipped in example_blends/references/) with its equal-quality speedup,
and the paper's Tables I-II against gold, in one HTML report whose path is printed last.

``--full`` renders every version of the paper (X only, S only, XSL without MinBound) at 16
and 64 spp. Finished work in --out is reused: a rerun, or a run after Ctrl-C, does what is left.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .experiment import add_quality_arguments, run_and_report

NAME = "demo"
HELP = ("the main job on the bundled road scene: the file as it renders against Auto Volumes in "
        "the same time, and the paper's maps and renders, in one HTML report (a few minutes; "
        "--full: every version of the paper at 16 and 64 spp)")
SCENE = "road"
QUICK_VARIANTS = ("gold", "auto_file_samples", "auto_equal_time", "xs", "xsl", "uniform_eighth",
                  "uniform_quarter", "uniform_half", "uniform_equal_time", "adaptive_equal_time",
                  "guided_equal_time")
#: The example scenes' own ceiling (the default), and the ceilings of --full: the paper's 16 too.
DEFAULT_CEILING = 64
FULL_CEILINGS = (16, 64)
#: Finished steps are kept as they come (a rerun reuses them), not held back for the end.
OUTPUTS_AS_A_SET = False


def add_arguments(parser) -> None:
    from . import argtypes
    from .option_flags import add_option

    parser.add_argument("--out", default="xsl-demo", metavar="DIR", type=argtypes.output_folder(),
                        help="output folder; finished work in it is reused (default xsl-demo)")
    parser.add_argument("--full", action="store_true",
                        help="every version of the paper (X only, S only, XS, XSL with and without "
                             "MinBound) plus the equal-time baselines, at 16 and at 64 spp")
    add_quality_arguments(parser)
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    # For tests and quick looks: a smaller frame, another ceiling, another scene.
    parser.add_argument("--resolution", type=argtypes.RESOLUTION, help=argparse.SUPPRESS)
    add_option(parser, "max_spp", help=argparse.SUPPRESS)
    parser.add_argument("--scene", type=argtypes.SCENE, help=argparse.SUPPRESS)


def run(args) -> int:
    from ...addon.scene.blend_session import check_blend_file
    from ...addon.validation.runner import SceneJob
    from ...core.validation.example_scenes import example_scene_path
    from ...core.validation.plan import DEFAULT_VARIANTS, ValidationSettings
    from ...core.validation.store import check_output_folder
    from .common import parse_resolution

    path = check_blend_file(args.scene if args.scene else example_scene_path(SCENE))
    ceilings = (args.max_spp,) if args.max_spp else (FULL_CEILINGS if args.full else (DEFAULT_CEILING,))
    settings = ValidationSettings(max_spp=ceilings[0], resolution=parse_resolution(args.resolution),
                                  vdp=args.vdp, denoise=args.denoise, reference_spp=args.reference_spp,
                                  variants=DEFAULT_VARIANTS if args.full else QUICK_VARIANTS)
    for ceiling in ceilings:        # InputError for impossible options, before any work
        settings.render_options(ceiling)
    out = check_output_folder(args.out)
    name = Path(path).stem
    jobs = [SceneJob(name if len(ceilings) == 1 else f"{name}_{spp}spp", path, max_spp=spp,
                     compare_minbound=args.full) for spp in ceilings]
    what = ("every version" if args.full
            else "the file against Auto Volumes in its time and at its samples; XS, XSL, uniform at "
                 "1/8-1/2 of the ceiling, uniform, adaptive and guided at XSL's time")
    size = args.resolution or "the scene's own size"
    print(f"demo: {name}.blend at {size}, {' and '.join(map(str, ceilings))} spp: maps, {what}, "
          f"MSE/FLIP/VDP against the converged reference, report in {out}", file=sys.stderr)
    run_and_report(jobs, settings, out, NAME, args.quiet)
    return 0
