"""``xsl-render saliency IMAGE --out FILE.exr [--png FILE.png]``: the saliency map of an image.

The Itti-Koch-Niebur (1998) model of ``core.maps.saliency`` on any PNG, JPEG, TIFF or EXR, with
no scene and no Blender: float files (renders) are tone mapped first (``core.tonemap``).
The map is a one-channel float32 EXR at the image's resolution, 0 (least) to 1 (most
salient).
"""
from __future__ import annotations

NAME = "saliency"
HELP = "Itti-Koch-Niebur saliency map of any image (no scene needed)"


def add_arguments(parser) -> None:
    from . import argtypes

    parser.add_argument("image", metavar="IMAGE", type=argtypes.input_file(what="image file"),
                        help="PNG, JPEG, TIFF or EXR (8/16-bit, float, grey, RGB or RGBA); "
                             "float images are scene-linear and get tone mapped")
    parser.add_argument("--out", required=True, metavar="FILE.exr", type=argtypes.output_file(".exr"),
                        help="where to write the map (float32, one channel, image resolution)")
    parser.add_argument("--png", metavar="FILE.png", type=argtypes.output_file(".png"),
                        help="also write an 8-bit grey preview")


def run(args) -> int:
    # Imported here: the other commands should not pay for scikit-image at start-up.
    import time

    from pathlib import Path

    from ...core.errors import InputError
    from ...core.imageio import write_exr, write_png
    from ...core.maps.saliency import saliency_map
    from ...core.maps.saliency_input import read_display_rgb

    out = Path(args.out)
    preview = Path(args.png) if args.png else None
    rgb = read_display_rgb(args.image)
    started = time.perf_counter()
    smap = saliency_map(rgb)
    seconds = time.perf_counter() - started
    try:
        write_exr(out, smap, attributes={"xsl:map": "S", "xsl:model": "Itti-Koch-Niebur 1998"})
        if preview is not None:
            write_png(preview, smap)
    except OSError as error:
        raise InputError(f"cannot write {error.filename or out}: {error.strerror or error}") from None
    height, width = smap.shape
    print(f"wrote {out} ({width}x{height}, saliency in {seconds:.2f} s)"
          + (f" and {preview}" if preview is not None else ""))
    return 0
