"""``xsl-render reference SCENE.blend --out REF.exr``: the converged reference of a scene.

A uniform render with far more samples than any contestant (default ``max(1024, 16 x the
ceiling)``, the ceiling being --max-spp or the scene's own Cycles samples), a seed no
contestant uses (7), denoised as every run is, written as float32 OpenEXR. Cached by the
file's bytes, scene, frame, resolution, samples, seed, Blender version and denoiser version
(``core.validation.reference``): a second call copies the cached image and says so.

``--frames 1-24 --out 'ref/frame_####.exr'``: the reference of each frame, in one process
and one Cycles session (static volumes are synced once), each cached and copied to its
numbered file as soon as it is done, so Ctrl-C keeps the frames already finished.
"""
from __future__ import annotations

import sys
from pathlib import Path

NAME = "reference"
HELP = ("render (or find in the cache) the converged reference of a scene: uniform, 16x the "
        "ceiling and at least 1024 spp, seed 7, denoised like every run")


def add_arguments(parser) -> None:
    from ...core.validation.reference import REFERENCE_SEED
    from . import argtypes
    from .common import add_scene_arguments
    from .option_flags import add_option

    add_scene_arguments(parser)
    parser.add_argument("--out", required=True, metavar="REF.exr", type=argtypes.output_file(".exr"),
                        help="where to write the reference (with --frames: its last run of # "
                             "becomes the frame number, ref/frame_####.exr, else 4 digits are "
                             "added before .exr)")
    parser.add_argument("--frames", metavar="FRAMES", type=argtypes.FRAMES,
                        help="the references of these frames (1-24, 1-24:2 or a list such as "
                             "1-3,8), one after another in one Cycles session, each cached")
    parser.add_argument("--spp", type=argtypes.SAMPLES, metavar="N",
                        help="samples per pixel (default max(1024, 16 x the ceiling))")
    add_option(parser, "seed", default=REFERENCE_SEED, help="Cycles seed (contestants use 0, 1, 2, ...)")
    parser.add_argument("--max-spp", type=ceiling, metavar="CEILING",
                        help="the contestants' ceiling the default samples follow (default: the "
                             "scene's own Cycles samples)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def ceiling(text: str) -> int:
    """A contestants' ceiling whose default reference (16 x it) Cycles can still render."""
    from ...core.checks import MAX_SAMPLES
    from ...core.validation.reference import SPP_PER_CEILING
    from . import argtypes

    limit = f" (its reference takes {SPP_PER_CEILING}x as many samples; Cycles' limit)"
    return argtypes.integer(1, MAX_SAMPLES // SPP_PER_CEILING, limit)(text)


def _frames(args) -> tuple[int, ...] | None:
    """The --frames list (None without it)."""
    from ...core.errors import InputError
    from ...core.frames import parse_frame_list

    if args.frames is None:
        return None
    if args.frame is not None:
        raise InputError("--frame and --frames cannot be combined")
    return parse_frame_list(args.frames)


def check(args) -> None:
    _frames(args)


def files(args) -> tuple[dict, dict]:
    """With --frames, every frame's file (each checked like --out before Blender loads)."""
    from ...core.frames import frame_path

    frames = _frames(args)
    if frames is None:
        return {}, {}
    return {}, {f"frame {frame}": frame_path(str(args.out), frame) for frame in frames}


def outputs_as_a_set(args) -> bool:
    """One reference appears with the command's end; with --frames each frame as it is done."""
    return args.frames is None


def scene_file(args) -> Path:
    """The .blend the scene comes from: SCENE.blend, or inside Blender the open file, which
    must be saved (the cache is keyed by the file's bytes)."""
    from ...core.errors import InputError

    if args.scene is not None:
        return Path(args.scene)
    import bpy

    if not bpy.data.filepath:
        raise InputError("the open file was never saved; the reference cache is keyed by the .blend file")
    if bpy.data.is_dirty:
        raise InputError("the open file has unsaved changes; save it first (the reference cache "
                         "is keyed by the .blend file)")
    return Path(bpy.data.filepath)


def run(args) -> int:
    from ...core.validation.reference import copy_file
    from .common import parse_resolution

    out = Path(args.out)                # every option was checked while it was parsed
    resolution = parse_resolution(args.resolution)

    from ...addon.scene.blend_session import open_blend
    from ...addon.validation.reference import ensure_reference, reference_inputs
    from ..interrupt import InterruptToCancel
    from ..progress_bar import ProgressBar

    path = scene_file(args)
    scene = open_blend(args.scene, args.scene_name)
    frames = _frames(args)
    if frames is not None:
        return _run_frames(args, scene, path, resolution, frames)
    inputs = reference_inputs(scene, path, spp=args.spp, seed=args.seed, resolution=resolution,
                              frame=args.frame, max_spp=args.max_spp)
    bar = None if args.quiet else ProgressBar(NAME)
    try:
        with InterruptToCancel() as interrupt:
            reference = ensure_reference(scene, inputs, progress=interrupt.wrap(bar), file_name=path.name)
    finally:
        if bar is not None:
            bar.close()
    copy_file(reference.path, out)
    size = f"{inputs.resolution[0]}x{inputs.resolution[1]}"
    what = f"{size}, {inputs.spp} spp, seed {inputs.seed}, frame {inputs.frame}"
    if reference.source == "rendered":
        print(f"reference: rendered {what} in {reference.run.seconds:.1f} s, "
              f"cached as {reference.path} -> {out}")
    else:
        where = "shipped with the repository" if reference.source == "shipped" else "user cache"
        print(f"reference: cached ({where}) {what}: {reference.path} -> {out}")
    print(f"reference: key {inputs.key}", file=sys.stderr)
    return 0


def _describe(reference) -> str:
    inputs = reference.inputs
    return (f"{inputs.resolution[0]}x{inputs.resolution[1]}, {inputs.spp} spp, seed {inputs.seed}, "
            f"frame {inputs.frame}")


def _run_frames(args, scene, path: Path, resolution, frames) -> int:
    """Every frame's reference, found or rendered, copied to its numbered file as it is ready."""
    from ...addon.validation.reference import ensure_references, reference_inputs
    from ...core.files import file_sha256
    from ...core.frames import frame_path
    from ...core.validation.reference import copy_file
    from ..interrupt import InterruptToCancel
    from ..progress_bar import ProgressBar

    digest = file_sha256(path)
    inputs = [reference_inputs(scene, path, spp=args.spp, seed=args.seed, resolution=resolution,
                               frame=frame, max_spp=args.max_spp, blend_sha256=digest)
              for frame in frames]
    counts = {"rendered": 0, "cached": 0}

    def on_frame(reference) -> None:
        out = Path(frame_path(str(args.out), reference.inputs.frame))
        copy_file(reference.path, out)
        if reference.source == "rendered":
            counts["rendered"] += 1
            print(f"reference: rendered {_describe(reference)} in "
                  f"{reference.run.seconds:.1f} s (Cycles synced the scene for "
                  f"{reference.run.cycles_sync_s:.1f} s) -> {out}", flush=True)
        else:
            counts["cached"] += 1
            where = "shipped with the repository" if reference.source == "shipped" else "user cache"
            print(f"reference: cached ({where}) {_describe(reference)} -> {out}", flush=True)
        print(f"reference: frame {reference.inputs.frame} key {reference.inputs.key}", file=sys.stderr)

    bar = None if args.quiet else ProgressBar(NAME)
    try:
        with InterruptToCancel() as interrupt:
            ensure_references(scene, inputs, progress=interrupt.wrap(bar), file_name=path.name,
                              on_frame=on_frame)
    finally:
        if bar is not None:
            bar.close()
    print(f"reference: {len(frames)} frames, {counts['rendered']} rendered, {counts['cached']} from the cache")
    return 0
