"""``xsl-render xmap SCENE.blend --out DIR``: the Z buffer and X map (paper 4.1) as EXRs.

Writes DIR/z.exr (distance along each camera ray to the first surface; sky = 1e10, the
value Cycles' Depth pass uses), DIR/x.exr (transmittance luminance in [0, 1]),
DIR/xmap.json (parameters, media, seconds) and DIR/zcache.npz (the rays, reused when
only the media change).
"""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

from ...core.errors import InputError
from . import argtypes
from .common import add_scene_arguments, parse_resolution
from .option_flags import add_option

#: Midpoint samples per interval: beyond this a reference march takes hours at any size.
MAX_SAMPLES = 4096
NAME = "xmap"
HELP = "compute the Z buffer and the X (extinction) map of the active camera"


def add_arguments(parser) -> None:
    add_scene_arguments(parser)
    parser.add_argument("--out", required=True, metavar="DIR", type=argtypes.output_folder(),
                        help="folder for z.exr, x.exr, xmap.json")
    add_option(parser, "minbound")
    parser.add_argument("--tolerance", type=argtypes.number(above=0.0, below=1.0), default=None,
                        help="transmittance tolerance of the adaptive ray grid that integrates "
                             "heterogeneous media (smaller is slower and closer; default 0.03)")
    parser.add_argument("--samples", type=argtypes.integer(1, MAX_SAMPLES), default=None,
                        help="march every pixel's ray with this many midpoint samples per "
                             "interval instead of the adaptive grid (slow; a reference)")


def output_paths(folder: str | Path) -> dict[str, Path]:
    """The files ``xmap`` writes into ``folder``, by name."""
    from ...core.maps.camera_rays import CACHE_NAME

    return {name: Path(folder) / name for name in ("z.exr", "x.exr", "xmap.json", CACHE_NAME)}


def files(args) -> tuple[dict, dict]:
    return {}, {f"--out's {name}": path for name, path in output_paths(args.out).items()}


def check(args) -> None:
    if args.samples is not None and args.tolerance is not None:
        raise InputError("--samples and --tolerance exclude each other")


def run(args) -> int:
    import bpy

    from ...addon.maps.xmap import compute_x_map
    from ...addon.scene.blend_session import open_blend
    from ...addon.scene.state import preserved_scene
    from ...core.files import write_json
    from ...core.imageio import write_exr
    from ...core.maps.camera_rays import SKY_DEPTH, depth_to_exr
    from ...core.maps.transmittance import DEFAULT_SAMPLES, DEFAULT_TOLERANCE
    from ...core.maps.xmap import XMapWarning

    size = parse_resolution(args.resolution)
    samples = DEFAULT_SAMPLES if args.samples is None else args.samples
    tolerance = None if args.samples is not None else (args.tolerance or DEFAULT_TOLERANCE)
    scene = open_blend(args.scene, args.scene_name)
    out = Path(args.out)
    paths = output_paths(out)
    # Inside Blender (the batch entry) this is the user's open scene: frame and size go back.
    with preserved_scene(scene), warnings.catch_warnings(record=True) as caught:
        if args.frame is not None:
            scene.frame_set(args.frame)
        if size is not None:
            scene.render.resolution_x, scene.render.resolution_y = size
            scene.render.resolution_percentage = 100
        warnings.simplefilter("always")
        x, z, info = compute_x_map(scene, cache_dir=out, minbound=args.minbound,
                                   depsgraph=bpy.context.evaluated_depsgraph_get(), samples=samples,
                                   tolerance=tolerance)
    write_exr(paths["z.exr"], depth_to_exr(z), ["Z"],
              attributes={"xsl:z": "distance along the camera ray", "xsl:sky": SKY_DEPTH})
    write_exr(paths["x.exr"], x, ["Y"])
    info["file"] = str(args.scene)
    write_json(paths["xmap.json"], info)
    for message in dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, XMapWarning)):
        print(f"xsl-render: warning: {message}", file=sys.stderr)
    seconds = info["seconds"]
    print(f"wrote {paths['z.exr']} and {paths['x.exr']} ({x.shape[1]}x{x.shape[0]}, "
          f"{seconds['total']:.2f} s, rays {'from cache' if info['cache']['hit'] else 'cast'})")
    return 0
