"""``xsl-render maps SCENE.blend --out DIR``: every director map of the paper as EXRs.

Writes DIR/z.exr x.exr snapshot.exr s.exr l.exr xs.exr xsl.exr, maps.json (every
parameter used and the seconds each map took), preview/*.png, and the ray cache
zcache.npz that makes a rerun with changed media instant.
"""
from __future__ import annotations

from pathlib import Path

from . import argtypes
from .common import add_map_arguments, add_scene_arguments, parse_resolution, warnings_as_lines
from .options_from_args import map_options_from_args

NAME = "maps"
HELP = "compute the Z, X, snapshot, S, L, XS and XSL maps of the active camera"


def add_arguments(parser) -> None:
    add_scene_arguments(parser)
    parser.add_argument("--out", required=True, metavar="DIR", type=argtypes.output_folder(),
                        help="folder for the maps")
    add_map_arguments(parser)


def files(args) -> tuple[dict, dict]:
    """What ``maps`` writes into --out DIR: the map set and the ray cache."""
    from ...core.maps.camera_rays import CACHE_NAME
    from ...core.maps.files import map_set_paths

    outputs = {f"--out's {name}": path for name, path in map_set_paths(args.out).items()}
    outputs["--out's ray cache"] = Path(args.out) / CACHE_NAME
    return {}, outputs


def run(args) -> int:
    # Check every option before Blender is even loaded.
    options = map_options_from_args(args)
    size = parse_resolution(args.resolution)
    out = Path(args.out)

    import bpy

    from ...addon.maps.director_maps import MapWarning, compute_maps
    from ...addon.scene.blend_session import open_blend
    from ...core.maps.files import write_map_set
    from ...core.maps.xmap import XMapWarning
    scene = open_blend(args.scene, args.scene_name)
    with warnings_as_lines(MapWarning, XMapWarning):
        maps = compute_maps(scene, options, size=size, frame=args.frame, cache_dir=out,
                            depsgraph=bpy.context.evaluated_depsgraph_get())
    maps.info["file"] = str(args.scene)
    write_map_set(out, maps)
    seconds = maps.info["seconds"]
    height, width = maps.x.shape
    print(f"wrote {out}/{{z,x,snapshot,s,l,xs,xsl}}.exr, maps.json and preview/ ({width}x{height}); "
          + ", ".join(f"{k} {v:.2f} s" for k, v in seconds.items()))
    return 0
