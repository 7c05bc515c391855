"""``xsl-render reference SCENE.blend --out REF.exr``: the converged reference of a scene.

A uniform render with far more samples than any contestant (default ``max(1024, 16 x the
ceiling)``, the ceiling being --max-spp or the scene's own Cycles samples), a seed no
contestant uses (7), denoised as every run is, written as float32 OpenEXR. Cached by the
file's bytes, scene, frame, resolution, samples, seed, Blender version and denoiser version
(``core.validation.reference``): a second call copies the cached image and says so.
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

    add_scene_arguments(parser)
    parser.add_argument("--out", required=True, metavar="REF.exr", type=argtypes.output_file(".exr"),
                        help="where to write the reference")
    parser.add_argument("--spp", type=argtypes.SAMPLES, metavar="N",
                        help="samples per pixel (default max(1024, 16 x the ceiling))")
    parser.add_argument("--seed", type=argtypes.SEED, default=REFERENCE_SEED,
                        help=f"Cycles seed (default {REFERENCE_SEED}; contestants use 0, 1, 2, ...)")
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
        print(f"reference: rendered {what} in {reference.stats['reference_wall_s']:.1f} s, "
              f"cached as {reference.path} -> {out}")
    else:
        where = "shipped with the repository" if reference.source == "shipped" else "user cache"
        print(f"reference: cached ({where}) {what}: {reference.path} -> {out}")
    print(f"reference: key {inputs.key}", file=sys.stderr)
    return 0
