"""``xsl-render farm-task maps|tiles|composite``: the steps of a farm job (``xsl-render farm``).

The job template calls these; a person rarely does. Each is safe to run again: finished,
current results are kept (``core.farm.files``), so a crashed or cancelled job resumes.

    farm-task maps SCENE.blend --frame N --output DIR --scene-name S --mode xs|xsl
        --max-spp N --resolution WxH [map options] [tile options]
        -> DIR/work/frame_NNNN/maps/ and plan.json
    farm-task tiles SCENE.blend --frame N --output DIR --group G --groups K
        -> DIR/work/frame_NNNN/tiles/<rectangle>.exr + .json for the rectangles of task G of K
    farm-task composite --frame N --output DIR [--groups K]
        -> DIR/frame_NNNN.exr, frame_NNNN_spp.exr/.png, frame_NNNN.json
"""
from __future__ import annotations

import sys
from pathlib import Path

from . import argtypes
from .common import (add_map_arguments, add_tile_arguments, map_options_from_args,
                     render_options_from_args, warnings_as_lines)

NAME = "farm-task"
HELP = "run one task of a farm job (maps, tiles or composite of a frame); used by job templates"
MODES = ("xs", "xsl")
#: Each task keeps what it finished, with what it was made from, so a rerun resumes.
OUTPUTS_AS_A_SET = False


def _frame_arguments(parser) -> None:
    parser.add_argument("--frame", type=argtypes.FRAME, required=True, help="the frame")
    parser.add_argument("--output", required=True, metavar="DIR", type=argtypes.output_folder(),
                        help="the job's output folder")


def add_arguments(parser) -> None:
    steps = parser.add_subparsers(dest="step", metavar="STEP")
    steps.required = True

    maps = steps.add_parser("maps", help="director maps and tile plan of a frame")
    maps.add_argument("scene", metavar="SCENE.blend", type=argtypes.SCENE, help="the .blend file (never written)")
    maps.add_argument("--scene-name", required=True, help="which scene of the file")
    _frame_arguments(maps)
    maps.add_argument("--mode", required=True, choices=MODES, help="which director map plans the tiles")
    maps.add_argument("--max-spp", type=argtypes.SAMPLES, required=True,
                      help="samples per pixel where the map is 1")
    maps.add_argument("--resolution", required=True, metavar="WxH", type=argtypes.RESOLUTION,
                      help="render resolution")
    add_map_arguments(maps)
    maps.add_argument("--minbound-value", choices=("true", "false"),
                      help="MinBound as a value (job templates), overrides --minbound/--no-minbound")
    add_tile_arguments(maps)

    tiles = steps.add_parser("tiles", help="render one task's share of a frame's rectangles")
    tiles.add_argument("scene", metavar="SCENE.blend", type=argtypes.SCENE, help="the .blend file (never written)")
    _frame_arguments(tiles)
    tiles.add_argument("--group", type=int, required=True, help="this task's number, 1..--groups")
    tiles.add_argument("--groups", type=int, required=True, help="tile tasks per frame")

    composite = steps.add_parser("composite", help="assemble a frame from its rectangles")
    _frame_arguments(composite)
    composite.add_argument("--groups", type=int, help="tile tasks per frame (for the statistics)")


def _maps(args) -> int:
    from ...addon.farm_tasks import run_maps_task
    from ...addon.maps.director_maps import MapWarning
    from ...core.farm.files import FrameFiles, valid_plan
    from ...core.maps.xmap import XMapWarning

    if args.minbound_value is not None:
        args.minbound = args.minbound_value == "true"
    map_options = map_options_from_args(args)
    options = render_options_from_args(args)
    with warnings_as_lines(MapWarning, XMapWarning):
        outcome = run_maps_task(args.scene, args.scene_name, args.frame, args.output, args.mode,
                                map_options, options)
    files = FrameFiles(Path(args.output), args.frame)
    if outcome.reused:
        print(f"frame {args.frame}: maps and tile plan already done ({files.plan})")
        return 0
    plan = valid_plan(files).plan
    print(f"frame {args.frame}: maps and tile plan written in {outcome.seconds:.2f} s: "
          f"{len(plan.rects)} rectangles, mean {plan.mean_spp:.2f} spp, "
          f"ideal speedup {plan.ideal_speedup:.2f}x ({files.plan})")
    return 0


def _tiles(args) -> int:
    from ...addon.farm_tasks import run_tiles_task

    def log(line: str) -> None:
        print(f"frame {args.frame}, task {args.group}/{args.groups}: {line}", flush=True)

    outcome = run_tiles_task(args.scene, args.frame, args.output, args.group, args.groups, log=log)
    for warning in outcome.warnings:
        print(f"xsl-render: warning: {warning}", file=sys.stderr)
    print(f"frame {args.frame}, task {args.group}/{args.groups}: {outcome.total} rectangles, "
          f"{len(outcome.done_now)} rendered now, {len(outcome.reused)} already done "
          f"({outcome.seconds:.2f} s)")
    return 0


def _blender_denoiser(rgba, albedo, normal):
    """Blender's Open Image Denoise, loaded only when a frame is to be denoised."""
    from ...addon.cycles.denoise import denoise

    return denoise(rgba, albedo, normal)


def _composite(args) -> int:
    from ...core.farm.composite import composite_frame
    from ...core.farm.files import FrameFiles
    from ...core.farm.task_groups import check_groups

    if args.groups is not None:
        check_groups(args.groups)
    files = FrameFiles(Path(args.output), args.frame)
    result = composite_frame(files, args.groups, denoiser=_blender_denoiser)
    stats = result.stats
    state = "already done" if result.skipped else "written"
    print(f"frame {args.frame}: {files.image} {state}: {stats['resolution'][0]}x{stats['resolution'][1]}, "
          f"mean {stats['mean_spp']:.2f} spp in {stats['renders']} rectangles")
    return 0


def run(args) -> int:
    return {"maps": _maps, "tiles": _tiles, "composite": _composite}[args.step](args)
