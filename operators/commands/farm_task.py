"""``xsl-render farm-task maps|tiles|composite|guided``: the steps of a farm job (``xsl-render
farm``), which the job template calls.

Each takes a frame (``--frame N``) or a chunk (``--frames 1-8``, what the template's
``{{Task.Param.Frame}}`` expands to) and renders its frames in one Blender process: ``maps``
(director maps and tile plan per frame), ``tiles`` (task G of K's rectangles), ``composite``
(the frame's EXR, samples and record) and ``guided`` (whole frames within a time budget).
Each is safe to run again: current results are kept (``core.farm.files``). Every step prints
Open Job Description's progress and status lines; a cancelled task exits 143 with nothing
half-written."""
from __future__ import annotations

import sys
from pathlib import Path

from ...core.farm.frame_outputs import FrameSummary
from ...core.farm.task_progress import TaskProgress
from . import argtypes
from .common import (add_guided_arguments, add_map_arguments, add_tile_arguments, parse_resolution,
                     warnings_as_lines)
from .option_flags import add_option
from .options_from_args import (guided_options_from_args, guided_render_options, map_options_from_args,
                                render_options_from_args)

NAME = "farm-task"
HELP = ("run one task of a farm job (maps, tiles or composite of a frame, or a guided frame); "
        "used by job templates")
MODES = ("xs", "xsl")
#: Each task keeps what it finished, with what it was made from, so a rerun resumes.
OUTPUTS_AS_A_SET = False


def _frame_arguments(parser, renders: bool = True) -> None:
    which = parser.add_mutually_exclusive_group(required=True)
    which.add_argument("--frame", type=argtypes.FRAME, help="the frame")
    which.add_argument("--frames", metavar="FRAMES", type=argtypes.FRAMES,
                       help="a chunk of frames, one after another in one process: 1-8, 1-15:2 or "
                            "a list such as 9,11,15-17 (a CHUNK[INT] task parameter's value)")
    parser.add_argument("--output", required=True, metavar="DIR", type=argtypes.output_folder(),
                        help="the job's output folder")
    if renders:
        add_option(parser, "device", help="the Cycles device")


def add_arguments(parser) -> None:
    from ...core import checks

    steps = parser.add_subparsers(dest="step", metavar="STEP")
    steps.required = True

    maps = steps.add_parser("maps", help="director maps and tile plan of a frame")
    maps.add_argument("scene", metavar="SCENE.blend", type=argtypes.SCENE,
                      help="the .blend file (never written)")
    maps.add_argument("--scene-name", required=True, help="which scene of the file")
    _frame_arguments(maps)
    maps.add_argument("--mode", required=True, choices=MODES, help="which director map plans the tiles")
    add_option(maps, "max_spp", required=True, note=False, help="samples per pixel where the map is 1")
    maps.add_argument("--resolution", required=True, metavar="WxH", type=argtypes.RESOLUTION,
                      help="render resolution")
    _map_arguments(maps)
    add_tile_arguments(maps)

    tiles = steps.add_parser("tiles", help="render one task's share of a frame's rectangles")
    tiles.add_argument("scene", metavar="SCENE.blend", type=argtypes.SCENE,
                      help="the .blend file (never written)")
    _frame_arguments(tiles)
    tiles.add_argument("--group", type=int, required=True, help="this task's number, 1..--groups")
    tiles.add_argument("--groups", type=int, required=True, help="tile tasks per frame")

    composite = steps.add_parser("composite", help="assemble a frame from its rectangles")
    _frame_arguments(composite, renders=False)
    composite.add_argument("--groups", type=int, help="tile tasks per frame (for the statistics)")

    guided = steps.add_parser("guided", help="render a frame with the guided sampler within its time budget")
    guided.add_argument("scene", metavar="SCENE.blend", type=argtypes.SCENE,
                      help="the .blend file (never written)")
    guided.add_argument("--scene-name", required=True, help="which scene of the file")
    _frame_arguments(guided)
    guided.add_argument("--resolution", required=True, metavar="WxH", type=argtypes.RESOLUTION,
                        help="render resolution")
    guided.add_argument("--max-spp", type=argtypes.integer(0, checks.MAX_SAMPLES), default=0,
                        help="the most samples any pixel may get; 0: no ceiling (default)")
    add_guided_arguments(guided, budget_required=True)
    add_option(guided, "tile_size", help="edge of the tiles the samples are allocated on")
    add_option(guided, "seed")
    _map_arguments(guided)


def _frames(args) -> tuple[int, ...]:
    """The task's frames: --frame N, or the frames of --frames in ascending order."""
    from ...core.frames import parse_frame_list

    return (args.frame,) if args.frame is not None else parse_frame_list(args.frames)


def _chunk(frames: tuple[int, ...]) -> str:
    """How the status lines name a task's frames: 'frame 7', 'frames 1-8', 'frames 1,3,9'."""
    if len(frames) == 1:
        return f"frame {frames[0]}"
    if frames == tuple(range(frames[0], frames[-1] + 1)):
        return f"frames {frames[0]}-{frames[-1]}"
    return "frames " + ",".join(map(str, frames))


def check(args) -> None:
    """A guided task's request (its time budget and render options, --max-spp 0 being the job
    template's "no ceiling") or a maps task's render options, checked before anything loads;
    ``run`` renders what is checked here."""
    if args.step == "guided":
        from ...core.sampling.render_request import RenderRequest

        args.request = RenderRequest("guided", guided_render_options(args, parse_resolution(args.resolution)),
                                     guided=guided_options_from_args(args)).check()
    elif args.step == "maps":
        args.options = render_options_from_args(args).check()


def _map_arguments(parser) -> None:
    add_map_arguments(parser)
    parser.add_argument("--minbound-value", choices=("true", "false"),
                        help="MinBound as a value (job templates), overrides --minbound/--no-minbound")


def _map_options(args):
    """The map options, --minbound-value (a job template's) deciding MinBound when given."""
    if args.minbound_value is not None:
        args.minbound = args.minbound_value == "true"
    return map_options_from_args(args)


def _maps(args) -> int:
    from ...addon.farm.tasks import run_maps_task
    from ...addon.maps.director_maps import MapWarning
    from ...core.farm.files import FrameFiles, valid_plan
    from ...core.maps.xmap import XMapWarning

    frames = _frames(args)
    map_options = _map_options(args)
    options = args.options                      # checked by ``check``
    report = TaskProgress()
    report.status(f"{_chunk(frames)}: director maps and tile plans")
    with warnings_as_lines(MapWarning, XMapWarning):
        outcomes = run_maps_task(args.scene, args.scene_name, frames, args.output, args.mode,
                                 map_options, options, device=args.device, progress=report.callback())
    report.progress(1.0)
    for outcome in outcomes:
        files = FrameFiles(Path(args.output), outcome.frame)
        if outcome.reused:
            print(f"frame {outcome.frame}: maps and tile plan already done ({files.plan})")
            continue
        plan = valid_plan(files).plan
        print(f"frame {outcome.frame}: maps and tile plan written in {outcome.seconds:.2f} s: "
              f"{len(plan.rects)} rectangles, mean {plan.mean_spp:.2f} spp, "
              f"ideal speedup {plan.ideal_speedup:.2f}x ({files.plan})")
    return 0


def _tiles(args) -> int:
    from ...addon.farm.tasks import run_tiles_task

    frames = _frames(args)
    label = f"task {args.group}/{args.groups}"
    report = TaskProgress()
    report.status(f"{_chunk(frames)}, {label}: reading the plans")
    outcomes = run_tiles_task(args.scene, frames, args.output, args.group, args.groups,
                              log=lambda line: print(line, flush=True), device=args.device,
                              progress=report.callback())
    report.progress(1.0)
    for warning in dict.fromkeys(w for outcome in outcomes for w in outcome.warnings):
        print(f"xsl-render: warning: {warning}", file=sys.stderr)
    for outcome in outcomes:
        print(f"frame {outcome.frame}, {label}: {outcome.total} rectangles, "
              f"{len(outcome.done_now)} rendered now, {len(outcome.reused)} already done "
              f"({outcome.seconds:.2f} s)")
    return 0


def _blender_denoiser(rgba, albedo, normal, prefilter_guides):
    """Blender's Open Image Denoise, loaded only when a frame is to be denoised."""
    from ...addon.cycles.denoise import denoise

    return denoise(rgba, albedo, normal, prefilter_guides=prefilter_guides)


def _composite(args) -> int:
    from ...core.farm.composite import composite_frame
    from ...core.farm.files import FrameFiles
    from ...core.farm.task_groups import check_groups

    if args.groups is not None:
        check_groups(args.groups)
    frames = _frames(args)
    report = TaskProgress()
    for index, frame in enumerate(frames):
        files = FrameFiles(Path(args.output), frame)
        report.status(f"frame {frame}: compositing")
        result = composite_frame(files, args.groups, denoiser=_blender_denoiser)
        report.progress((index + 1) / len(frames))
        frame_summary = FrameSummary.from_record(result.stats)
        (width, height), state = frame_summary.resolution, "already done" if result.skipped else "written"
        print(f"frame {frame}: {files.image} {state}: {width}x{height}, "
              f"mean {frame_summary.mean_spp:.2f} spp in {frame_summary.renders} rectangles", flush=True)
    return 0


def _guided(args) -> int:
    from ...addon.farm.tasks import run_guided_task
    from ...addon.maps.director_maps import MapWarning
    from ...core.farm.files import FrameFiles
    from ...core.maps.xmap import XMapWarning

    frames = _frames(args)
    guided, options = args.request.guided, args.request.options      # checked by ``check``
    map_options = _map_options(args)
    report = TaskProgress()
    report.status(f"{_chunk(frames)}: guided render within {guided.time_budget:g} s a frame")
    with warnings_as_lines(MapWarning, XMapWarning):
        outcomes = run_guided_task(args.scene, args.scene_name, frames, args.output, guided,
                                   map_options, options, device=args.device, progress=report.callback())
    report.progress(1.0)
    for outcome in outcomes:
        for warning in outcome.warnings:
            print(f"xsl-render: warning: frame {outcome.frame}: {warning}", file=sys.stderr)
        frame_summary = FrameSummary.from_record(outcome.stats)
        (width, height), state = frame_summary.resolution, "already done" if outcome.reused else "written"
        sync = frame_summary.cycles_sync_s
        print(f"frame {outcome.frame}: {FrameFiles(Path(args.output), outcome.frame).image} {state}: "
              f"{width}x{height}, mean {frame_summary.mean_spp:.2f} spp in {frame_summary.renders} render(s), "
              f"{frame_summary.wall_s:.2f} s of its {frame_summary.time_budget_s:.2f} s budget"
              + ("" if sync is None else f", Cycles sync {sync:.2f} s"))
    done = sum(len(outcome.done_now) for outcome in outcomes)
    print(f"{_chunk(frames)}: {done} rendered now, {len(outcomes) - done} already done")
    return 0


def run(args) -> int:
    return {"maps": _maps, "tiles": _tiles, "composite": _composite, "guided": _guided}[args.step](args)
