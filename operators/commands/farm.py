"""``xsl-render farm SCENE.blend --bundle DIR``: an Open Job Description job bundle.

Writes DIR/template.yaml (steps Maps, Tiles and Composite for xs and xsl; one step Render
for ``--mode guided --time-budget SECONDS``; every task renders a chunk of ``--frames-per-task``
frames in one Blender process; see ``core.farm.job_template``),
DIR/parameter_values.yaml, DIR/asset_references.yaml (the .blend and every file it reads:
``addon.scene.external_files``), DIR/worker_requirements.txt (the pinned versions a worker
installs: ``core.farm.worker_requirements``) and our marker file. Submit DIR to a farm that
speaks Open Job Description (``deadline bundle submit DIR`` on AWS Deadline Cloud), or run it
here with ``openjd run DIR/template.yaml -p SceneFile=SCENE.blend``. A bundle folder that
exists and is not ours is refused.
"""
from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from ...core.errors import InputError
from ...core.farm.blender_job import BLENDER
from ...core.option_table import DEFAULT_TASKS_PER_FRAME, OPTIONS
from ...core.farm.worker_environment import WorkerSetup
from ...core.farm.worker_setup import SETUPS
from . import argtypes
from .common import add_guided_arguments, add_map_arguments, add_tile_arguments, parse_resolution
from .option_flags import add_option
from .options_from_args import guided_options_from_args, guided_render_options, map_options_from_args

NAME = "farm"
HELP = "write an Open Job Description job bundle that renders the scene on a render farm"
#: The longest task timeout: a week, as the longest time budget (core.farm.farm_job checks it).
MAX_TIMEOUT = 7 * 24 * 3600


def add_arguments(parser) -> None:
    parser.add_argument("scene", metavar="SCENE.blend", type=argtypes.SCENE, help="the .blend file (never written)")
    parser.add_argument("--bundle", required=True, metavar="DIR", type=argtypes.output_folder(),
                        help="folder for the job bundle")
    parser.add_argument("--scene-name", help="which scene of the file (default: the active one)")
    parser.add_argument("--frames", metavar="FRAMES", type=argtypes.FRAMES,
                        help="frames to render: 12, 1-250, 1-250:2 or a list such as 1-3,8 "
                             "(default: the scene's range)")
    parser.add_argument("--resolution", metavar="WxH", type=argtypes.RESOLUTION,
                        help="render resolution (default: the scene's)")
    add_option(parser, "max_spp", note=False,
               help="samples per pixel where the map is 1 (default: the scene's Cycles samples); "
                    "guided: an optional per-pixel ceiling (default none)")
    parser.add_argument("--mode", choices=("blender", "xs", "xsl", "guided"), default=None,
                        help="blender (the default for an animation): Blender renders the file as "
                             "it is set up, with Auto Volumes, a chunk of frames a task; xs, xsl "
                             "(a still's default): the director map that plans the tiles; guided: "
                             "each frame rendered within --time-budget by one task")
    parser.add_argument("--blender", metavar="PATH",
                        help=f"--mode blender: the Blender command on the farm's machines, with the "
                             f"xsl_render extension installed (default {BLENDER})")
    parser.add_argument("--auto-volumes", action=argparse.BooleanOptionalAction, default=True,
                        help="--mode blender: render with Auto Volumes (default on)")
    add_option(parser, "tasks_per_frame")
    add_option(parser, "frames_per_task", metavar="N",
               help=f"{OPTIONS['frames_per_task'].help} (parameter FramesPerTask; the tasks' timeout "
                    "is made for this many)")
    parser.add_argument("--output", metavar="DIR",
                        help="where the job writes its frames (default: DIR/output of the bundle)")
    parser.add_argument("--executable", metavar="PATH",
                        help="the xsl-render command on the farm's machines (default: xsl-render, "
                             "found on each worker's PATH)")
    add_option(parser, "device", help="Cycles device of the renders; GPU makes the rendering steps "
                                      "ask for a GPU in their host requirements")
    parser.add_argument("--task-timeout", metavar="SECONDS", type=argtypes.integer(1, MAX_TIMEOUT),
                        help="seconds a task may run before the farm cancels it (default: for "
                             "each frame of a task, twice the time budget plus 15 minutes for "
                             "guided, 12 hours otherwise)")
    parser.add_argument("--worker-setup", choices=SETUPS, default="none",
                        help="how a worker gets xsl-render: none (installed, on PATH; default), "
                             "pip or conda (installed by the job's environment, once per worker)")
    parser.add_argument("--worker-package", metavar="SPEC",
                        help="the xsl-render package as pip installs it on a worker: a wheel's "
                             "path or URL, git+https://..., or a name on its index "
                             f"(default {WorkerSetup.package})")
    add_map_arguments(parser)
    add_tile_arguments(parser)
    add_guided_arguments(parser)


def _output(args, bundle: Path) -> str:
    """The OutputDir value: relative to the bundle when inside it (a PATH default must be)."""
    if args.output is None:
        return "output"
    output = Path(args.output).absolute()
    try:
        return output.relative_to(bundle.absolute()).as_posix() or "."
    except ValueError:
        return str(output)


def tile_options(args, max_spp: int, resolution):
    """``RenderOptions`` of the tile options with ``max_spp`` (the scene's samples unless given)."""
    from ...core.sampling.render_options import RenderOptions

    return RenderOptions(
        max_spp=max_spp, min_spp=args.min_spp, tile_size=args.tile_size,
        tile_quantile=args.tile_quantile, spp_levels=args.spp_levels, seed=args.seed,
        margin=args.margin, render_cost=args.render_cost, adaptive_threshold=args.adaptive_threshold,
        resolution=resolution).check()


#: Options of the xs, xsl and guided jobs, refused by a Blender job (the file's own settings).
_TILE_OR_GUIDED = ("max_spp", "tasks_per_frame", "time_budget", "resolution", "executable", "worker_package")


def _mode(args, frames: str | None) -> str | None:
    """--mode, else blender for a job of several frames and xsl for one (None: the frames are
    the scene's range, not known before it is opened); InputError for an option of the modes
    a Blender job does not take, or the other way round."""
    from ...core.frames import parse_frame_list

    mode = args.mode
    if mode is None and frames is not None:
        mode = "blender" if len(parse_frame_list(frames)) > 1 else "xsl"
    if mode == "blender":
        for name in _TILE_OR_GUIDED:
            if getattr(args, name, None) is not None:
                raise InputError(f"--{name.replace('_', '-')} is for --mode xs, xsl or guided (an "
                                 "animation's job is --mode blender: the file's own settings)")
        if args.worker_setup != "none":
            raise InputError("--worker-setup is for --mode xs, xsl or guided: a Blender job takes "
                             "the extension installed in the worker's Blender")
    elif mode is not None and args.blender is not None:
        raise InputError(f"--blender is for --mode blender (got --mode {mode})")
    return mode


def run(args) -> int:
    from ...core.farm.assets import asset_references
    from ...core.farm.job_bundle import check_bundle_folder, write_bundle
    from ...core.farm.job_template import FarmJob, job_template, parameter_values, parse_frames
    from ...core.farm.worker_requirements import pinned_closure, requirements_text

    # Everything that needs no scene first: a bad option fails before Blender loads.
    map_options = map_options_from_args(args)
    frames = parse_frames(args.frames) if args.frames is not None else None
    mode = _mode(args, frames)
    if mode == "blender":
        return _run_blender(args, frames)
    resolution = parse_resolution(args.resolution)
    args.mode = mode or "xsl"
    guided, tasks_per_frame = _guided_or_tiles(args)
    if guided is not None:
        guided_render_options(args, resolution)                # checked now, set later
    else:
        tile_options(args, args.max_spp or max(1, args.min_spp), resolution)     # checked now, set later
    bundle = check_bundle_folder(args.bundle)
    worker = WorkerSetup(setup=args.worker_setup,
                         package=args.worker_package or WorkerSetup.package).check()
    try:
        requirements = requirements_text(pinned_closure())
    except LookupError as error:
        raise InputError(f"cannot write the worker's requirements: {error}") from None

    from ...addon.scene.blend_session import open_blend
    from ...addon.scene.external_files import external_files
    from ...addon.scene.probe import camera_model, render_size

    scene_path = Path(args.scene).absolute()
    scene = open_blend(scene_path, args.scene_name)
    camera_model(scene)                     # InputError for a scene without a camera
    if frames is None:
        frames = parse_frames(f"{scene.frame_start}-{scene.frame_end}:{scene.frame_step}")
        if mode is None:                    # the scene's range decides: an animation's job is Blender's
            args.mode = None
            if _mode(args, frames) == "blender":
                return _run_blender(args, frames, scene)
            args.mode = "xsl"
    if guided is not None:
        options = guided_render_options(args, resolution or render_size(scene))
        what = (f"guided within {guided.time_budget:g} s per frame "
                + (f"up to {options.max_spp} spp" if options.has_ceiling else "without a ceiling")
                + f", importance {guided.importance}")
    else:
        max_spp = args.max_spp if args.max_spp is not None else int(scene.cycles.samples)
        options = tile_options(args, max_spp, resolution or render_size(scene))
        what = f"{args.mode} up to {max_spp} spp, {tasks_per_frame} tile tasks per frame"
    device = args.device or ("GPU" if scene.cycles.device == "GPU" else "CPU")
    job = FarmJob(scene=scene_path, scene_name=scene.name, frames=frames,
                  output=_output(args, bundle), mode=args.mode, map_options=map_options,
                  options=options, tasks_per_frame=tasks_per_frame,
                  executable=args.executable or "xsl-render", guided=guided, device=device,
                  task_timeout=args.task_timeout, worker=worker,
                  frames_per_task=args.frames_per_task).check()
    files = external_files()
    assets = asset_references(scene_path, files, bundle / job.output)
    write_bundle(bundle, job_template(job), parameter_values(job),
                 {"scene": str(scene_path), "scene_name": scene.name, "frames": frames},
                 assets=assets, requirements=requirements)
    _warn(scene, files)
    width, height = options.resolution
    command = ["openjd", "run", f"{bundle}/template.yaml", "-p", f"SceneFile={scene_path}"]
    if Path(job.output).is_absolute():
        command += ["-p", f"OutputDir={job.output}"]
    print(f"wrote {bundle}/template.yaml and parameter_values.yaml: frames {frames}, "
          f"{width}x{height}, {what}, up to {job.frames_per_task} frame(s) a task, on the "
          f"{device}; {len(files.found)} file(s) the scene reads "
          f"in asset_references.yaml; run here with: {shlex.join(command)}")
    return 0


def _run_blender(args, frames: str | None, scene=None) -> int:
    """The plain Blender job (``core.farm.blender_job``)."""
    from ...addon.scene.blend_session import open_blend
    from ...addon.scene.external_files import external_files
    from ...addon.scene.probe import camera_model
    from ...core.farm.assets import asset_references
    from ...core.farm.blender_job import BlenderJob, blender_job_template, blender_parameter_values
    from ...core.farm.job_bundle import check_bundle_folder, write_bundle
    from ...core.farm.job_template import parse_frames

    bundle = check_bundle_folder(args.bundle)
    scene_path = Path(args.scene).absolute()
    if scene is None:
        scene = open_blend(scene_path, args.scene_name)
        camera_model(scene)
    if frames is None:
        frames = parse_frames(f"{scene.frame_start}-{scene.frame_end}:{scene.frame_step}")
    device = args.device or ("GPU" if scene.cycles.device == "GPU" else "CPU")
    job = BlenderJob(scene=scene_path, scene_name=scene.name, frames=frames, output=_output(args, bundle),
                     executable=args.blender or BLENDER, device=device, auto_volumes=args.auto_volumes,
                     frames_per_task=args.frames_per_task, task_timeout=args.task_timeout).check()
    files = external_files()
    assets = asset_references(scene_path, files, bundle / job.output)
    write_bundle(bundle, blender_job_template(job), blender_parameter_values(job),
                 {"scene": str(scene_path), "scene_name": scene.name, "frames": frames, "mode": "blender"},
                 assets=assets)
    _warn(scene, files)
    command = ["openjd", "run", f"{bundle}/template.yaml", "-p", f"SceneFile={scene_path}"]
    if Path(job.output).is_absolute():
        command += ["-p", f"OutputDir={job.output}"]
    volumes = "with Auto Volumes" if job.auto_volumes else "with the file's own volume settings"
    print(f"wrote {bundle}/template.yaml and parameter_values.yaml: a Blender job, frames {frames} "
          f"as the file renders them {volumes}, up to {job.frames_per_task} frame(s) a task, on the "
          f"{device}; {len(files.found)} file(s) the scene reads in asset_references.yaml; run "
          f"here with: {shlex.join(command)}")
    return 0


def _warn(scene, files) -> None:
    """What would make the job fail or differ on a worker, one line each."""
    if scene.render.engine != "CYCLES":
        print(f"xsl-render: warning: scene '{scene.name}' renders with {scene.render.engine}; "
              "the farm job uses Cycles", file=sys.stderr)
    for path in files.missing:
        print(f"xsl-render: warning: the scene reads {path}, which does not exist; the job's "
              "tasks fail until it does", file=sys.stderr)
    for path in files.absolute_in_blend:
        print(f"xsl-render: warning: the .blend names {path} by an absolute path: a worker "
              "finds it only at that same path (File > External Data > Make Paths Relative)",
              file=sys.stderr)


def _guided_or_tiles(args):
    """(GuidedOptions, 1) for --mode guided, (None, tile tasks per frame) for xs and xsl;
    InputError for an option of the other kind."""
    from ...core.sampling.render_request import MODE_TRAITS

    if MODE_TRAITS[args.mode].time_budget:
        if args.tasks_per_frame is not None:
            raise InputError("--tasks-per-frame is for xs and xsl: a guided frame is one task")
        return guided_options_from_args(args), 1
    if args.time_budget is not None:
        raise InputError(f"--time-budget is for --mode guided (got --mode {args.mode})")
    return None, DEFAULT_TASKS_PER_FRAME if args.tasks_per_frame is None else args.tasks_per_frame
