"""``xsl-render render SCENE.blend --out FILE.exr``: the file rendered as Blender renders it (its
samples, denoiser, compositor and outputs) with Auto Volumes (``--estimator scene``: without),
``addon.blender_render``. With ``--mode``, the paper's renders and the baselines
(``--mode gold|xs|xsl|uniform|adaptive [--max-spp N]``, counts defaulting to the scene's
samples) and ``--mode guided --time-budget SECONDS``, every mode with auto's estimator unless
``--estimator`` says otherwise.

With --mode it writes FILE.exr (RGBA float), FILE_spp.exr and FILE_spp.png (samples per pixel)
and, with --stats, the run's statistics as JSON; a ``#`` run in FILE's name becomes the frame
number, and ``--frames`` renders an animation (``render_animation.py``)."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from ...core.checks import separate_files
from ...core.errors import InputError
from ...core.frames import frame_path, has_frame_marker, parse_frame_list
from ...core.sampling.render_files import render_output_paths, write_render_outputs
from . import argtypes
from .argtypes import declared_files
from .common import (add_guided_arguments, add_map_arguments, add_scene_arguments, add_tile_arguments,
                     warnings_as_lines)
from .option_flags import add_option
from .options_from_args import map_file_of, render_request_from_args
from .render_modes import check_scene, spp_scale, summary_line

NAME = "render"
HELP = ("render the scene as Blender does with Auto Volumes, or (--mode) selectively (xs, xsl), "
        "within a time budget where the error is (guided), or as a baseline (gold, uniform, adaptive)")
MODES = ("gold", "xs", "xsl", "uniform", "adaptive", "guided")


def add_arguments(parser) -> None:
    # What renders a shot (the file as Blender renders it, with Auto Volumes) comes first.
    add_scene_arguments(parser)
    parser.add_argument("--out", required=True, metavar="FILE.exr", type=argtypes.output_file(".exr"),
                        help="the rendered image")
    add_option(parser, "estimator")       # how Cycles estimates the volumes (volume_estimator)
    parser.add_argument("--stats", metavar="FILE.json", type=argtypes.output_file(),
                        help="write the run's statistics here")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    modes = parser.add_argument_group(
        "modes: the paper's renders, the baselines and a time budget (without --mode the file "
        "renders as Blender renders it)")
    modes.add_argument("--mode", choices=MODES, default=None,
                       help="gold: max-spp everywhere; xs/xsl: samples from the director map; "
                            "uniform: equal samples (or time) everywhere; adaptive: Cycles' adaptive "
                            "sampling; guided: within --time-budget, the samples spread evenly (or "
                            "by --importance, or by a pilot's error scores with --guided-exponent > 0)")
    add_option(modes, "max_spp", note=False,
               help="samples per pixel: every pixel's (gold, uniform), where the director map is 1 "
                    "(xs, xsl), the ceiling (adaptive, guided); default the scene's own samples, "
                    "guided none")
    modes.add_argument("--frames", metavar="FRAMES", type=argtypes.FRAMES,
                       help="render these frames (1-48, 1-48:2 or a list such as 1-3,8), each "
                            "with its own maps (the camera rays are cast once while camera and "
                            "geometry stay still); --out names them "
                            "like Blender: its last run of # becomes the frame number "
                            "(out/frame_####.exr), else 4 digits are added before .exr; a rerun "
                            "keeps the frames an earlier run of the same request finished")
    budget = parser.add_argument_group("budget (uniform, adaptive)")
    budget.add_argument("--spp", type=argtypes.SAMPLES,
                        help="uniform: samples per pixel (default --max-spp, else the scene's own)")
    budget.add_argument("--budget-from", metavar="STATS.json", type=argtypes.input_file(what="stats file"),
                        help="stats of a selective run: uniform takes its mean samples, "
                             "adaptive its wall time")
    budget.add_argument("--equal-time", nargs="?", type=float, const=-1.0, metavar="SECONDS",
                        help="uniform: render for this wall time instead (without SECONDS: the "
                             "wall time in --budget-from); Cycles' own time limit stops it")
    budget.add_argument("--noise-threshold", type=argtypes.number(above=0.0, hi=1.0), default=None,
                        help="adaptive: Cycles' noise threshold (default Cycles' own, 0.01)")
    add_guided_arguments(parser)
    maps = parser.add_argument_group("director map (xs, xsl; computed on the fly unless given)")
    maps.add_argument("--map", metavar="FILE.exr", type=argtypes.input_file(what="director map"),
                      help="the director map, values in [0, 1] at render size")
    maps.add_argument("--maps", metavar="DIR", type=argtypes.input_folder("maps folder"),
                      help="folder of `xsl-render maps`: uses DIR/xs.exr or DIR/xsl.exr")
    maps.add_argument("--save-maps", metavar="DIR", type=argtypes.output_folder(),
                      help="also write the maps computed on the fly here")
    add_map_arguments(parser)
    add_tile_arguments(parser, modes)
    add_option(parser.add_argument_group("volume estimator (expert)"), "step_rate", metavar="RATE")


def files(args, out: str | Path | None = None) -> tuple[dict, dict]:
    """The files the render reads beyond its options (the map of --maps DIR) and writes: the
    image with its ``_spp`` files (every frame's, for --frames), --stats, the maps of
    --save-maps. ``out``: the image's name once a ``#`` in it became the frame number."""
    from ...core.maps.camera_rays import CACHE_NAME
    from ...core.maps.files import map_set_paths
    from ...core.sampling.render_request import MODE_TRAITS
    from .render_animation import maps_folder

    if args.mode is None:
        return {}, {"--out": Path(out or args.out), "--stats": args.stats}
    traits = MODE_TRAITS[args.mode]
    inputs = {"--maps' map": map_file_of(args)} if args.maps else {}
    # --save-maps keeps maps computed here (a frame range's ray cache too): none for a
    # baseline, or a map given.
    save_maps = args.save_maps if traits.computes_maps and not (args.map or args.maps) else None
    frames = _frames(args)
    outputs = {}
    if frames is None:
        outputs.update(render_output_paths(out or args.out, args.stats))
        if save_maps and traits.director_map:
            outputs.update({f"--save-maps' {name}": path for name, path in map_set_paths(save_maps).items()})
        return inputs, outputs
    for frame in frames:
        path = frame_path(str(args.out), frame)
        for label, file in render_output_paths(path).items():
            outputs[label.replace("its ", f"frame {frame}'s ") if label != "--out" else f"frame {frame}"] = file
        if save_maps:
            folder = maps_folder(save_maps, frame)
            outputs.update({f"--save-maps' {folder.name}/{name}": path
                            for name, path in map_set_paths(folder).items()})
    if save_maps:
        outputs["--save-maps' ray cache"] = Path(save_maps) / CACHE_NAME
    outputs["--stats"] = args.stats
    return inputs, outputs


def check(args) -> None:
    """The whole request, before anything else (``cli.py``): every option, and what relates
    them (uniform's --spp under the ceiling, guided's --time-budget and only guided's, every
    other mode's --max-spp, a budget file that reads). ``run`` renders the request built here
    (``args.request``)."""
    frames = _frames(args)
    if args.mode is None:
        _check_as_blender(args)
        return
    args.request = render_request_from_args(args)
    if frames is not None and args.request[1] is not None:
        raise InputError("--frames computes every frame's own maps; --map and --maps hold one frame's")


#: Options of the modes only: without --mode the file's own settings render.
_MODE_ONLY = ("max_spp", "map", "maps", "save_maps", "frames", "spp", "budget_from", "equal_time",
              "noise_threshold", "time_budget", "step_rate")


def _check_as_blender(args) -> None:
    """Without --mode: the file's own settings render, so an option of the modes is refused,
    and the estimator is Auto Volumes (auto) or the file's (scene)."""
    for name in _MODE_ONLY:
        if getattr(args, name, None) is not None:
            flag = "--" + name.replace("_", "-")
            raise InputError(f"{flag} needs --mode (without it the file renders as Blender renders it)")
    if args.estimator not in ("auto", "scene"):
        raise InputError(f"--estimator {args.estimator} needs --mode (without it: auto, Auto Volumes, "
                         "or scene, the file's own settings)")


def _run_as_blender(args) -> int:
    from ...addon.blender_render import render_still
    from ...addon.scene.blend_session import open_blend
    from ...addon.scene.state import preserved_scene
    from ...core.files import write_json

    out = Path(args.out)
    scene = open_blend(args.scene, args.scene_name)
    with preserved_scene(scene):
        if args.frame is not None:
            scene.frame_set(args.frame)        # an opened copy is never written to its file
        if args.resolution is not None:
            from .common import parse_resolution

            (scene.render.resolution_x, scene.render.resolution_y), scene.render.resolution_percentage = \
                parse_resolution(args.resolution), 100
        if has_frame_marker(str(out)):
            out = Path(frame_path(str(out), scene.frame_current))
            separate_files(declared_files(args)[0], files(args, out)[1])
        still = render_still(scene, out, auto=args.estimator != "scene")
    if args.stats:
        write_json(args.stats, still.to_dict())
    print(f"blender: {still.describe()} -> {out}")
    return 0


def outputs_as_a_set(args) -> bool:
    """One frame's files appear together; an animation keeps each frame as it is done."""
    return args.frames is None


def _read_map(path: Path):
    from ...core.imageio import read_image
    from ...core.sampling.tile_plan import check_director_map

    if not path.exists():
        raise InputError(f"no such director map: {path}")
    image = read_image(path)
    # Channels, NaN and range now, before the scene is opened; the size once it is.
    return check_director_map(image, image.shape[1], image.shape[0])


def run(args) -> int:
    if args.mode is None:
        return _run_as_blender(args)
    out = Path(args.out)
    frames = _frames(args)
    request, map_file = args.request                  # built and checked by ``check``
    options = request.options
    started = time.perf_counter()
    director_map = _read_map(map_file) if map_file is not None else None
    map_seconds = time.perf_counter() - started

    from ...addon.maps.director_maps import MapWarning
    from ...addon.render_dispatch import request_frame_job
    from ...addon.scene.blend_session import open_blend
    from ...addon.scene.state import preserved_scene
    from ...core.maps.files import write_map_set
    from ...core.maps.xmap import XMapWarning
    from ...core.progress import run_steps
    from ..interrupt import InterruptToCancel
    from ..progress_bar import ProgressBar

    scene = open_blend(args.scene, args.scene_name)
    request = request.at_scene_samples(int(scene.cycles.samples))     # counts left to the scene
    options = request.options
    check_scene(scene, options, args.mode, director_map)
    if frames is not None:
        from .render_animation import render_frames

        return render_frames(scene, args, request, frames, out)
    bar = None if args.quiet else ProgressBar(args.mode)
    # Inside Blender (the batch entry) this is the user's open scene: give its frame back.
    with preserved_scene(scene):
        if args.frame is not None:
            scene.frame_set(args.frame)        # an opened copy is never written to its file
        if has_frame_marker(str(out)):
            out = Path(frame_path(str(out), scene.frame_current))
            # The frame's number is known now: its files go through the check again.
            separate_files(declared_files(args)[0], files(args, out)[1])
        try:
            with InterruptToCancel() as interrupt, warnings_as_lines(MapWarning, XMapWarning):
                progress = interrupt.wrap(bar)
                job = request_frame_job(request, director_map=director_map, map_seconds=map_seconds,
                                        progress=progress)
                result = run_steps(job(scene), progress)
        finally:
            if bar is not None:
                bar.close()
    outcome = result.outcome
    if args.save_maps and result.maps is not None:
        write_map_set(args.save_maps, result.maps)
    for warning in outcome.warnings:
        print(f"xsl-render: warning: {warning}", file=sys.stderr)
    stats = outcome.stats
    stats.file, stats.out = str(args.scene), str(out)
    request.record_budget(stats)
    write_render_outputs(out, outcome.image, outcome.samples, stats, spp_scale(request, outcome),
                         options.seed, args.stats)
    print(summary_line(args.mode, stats, out))
    return 0


def _frames(args):
    """The --frames list (None without it), checked before the scene is opened."""
    if args.frames is None:
        return None
    if args.frame is not None:
        raise InputError("--frame and --frames cannot be combined")
    return parse_frame_list(args.frames)
