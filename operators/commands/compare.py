"""``xsl-render compare REF TEST``: MSE, FLIP and VDP between a reference and a test image.

Prints one line per metric: the paper's average pixel error (%) and percentage of error
pixels, the threshold that makes a pixel an error, and the metric's own score (MSE, mean
FLIP, ColorVideoVDP's JOD). ``--json`` writes every number, ``--heatmap`` the FLIP map as a
magma PNG, ``--heatmap-dir`` the maps of all metrics (mse.png, flip.png, vdp.png).
"""
from __future__ import annotations

from pathlib import Path

NAME = "compare"
HELP = ("difference metrics (MSE, FLIP, VDP) between a reference and a test image: "
        "average pixel error, error pixels, heatmaps")


#: Bounds of --exposure in stops: 2^64 times any render's radiance still fits a float32.
MAX_EXPOSURE_EV = 64.0
#: The maps --heatmap-dir writes.
HEATMAP_NAMES = ("mse", "flip", "vdp")


def add_arguments(parser) -> None:
    from . import argtypes

    image = argtypes.input_file(what="image file")
    parser.add_argument("reference", metavar="REF", type=image,
                        help="reference image (gold standard): .exr, .png or .jpg")
    parser.add_argument("test", metavar="TEST", type=image, help="test image of the same size and kind as REF")
    parser.add_argument("--json", metavar="FILE", type=argtypes.output_file(),
                        help="write all numbers to this JSON file")
    parser.add_argument("--heatmap", metavar="FILE.png", type=argtypes.output_file(".png"),
                        help="write the FLIP difference map as a magma PNG")
    parser.add_argument("--heatmap-dir", metavar="DIR", type=argtypes.output_folder(),
                        help="write every metric's map as DIR/mse.png, flip.png, vdp.png (magma)")
    parser.add_argument("--exposure", type=argtypes.number(-MAX_EXPOSURE_EV, MAX_EXPOSURE_EV),
                        default=0.0, metavar="EV",
                        help="exposure in stops of the display transform for EXR inputs (default 0: "
                             "Blender's Standard view)")
    parser.add_argument("--no-vdp", action="store_true",
                        help="skip ColorVideoVDP (the slow metric; it is optional anyway)")


def heatmap_path(folder: str | Path, metric: str) -> Path:
    """Where --heatmap-dir DIR keeps a metric's map: DIR/<metric>.png."""
    return Path(folder) / f"{metric}.png"


def files(args) -> tuple[dict, dict]:
    """The maps of --heatmap-dir, each an output of its own."""
    if not args.heatmap_dir:
        return {}, {}
    return {}, {f"--heatmap-dir's {name}.png": heatmap_path(args.heatmap_dir, name)
                for name in HEATMAP_NAMES}


def run(args) -> int:
    from ...core.files import write_json
    from ...core.validation.heatmap import write_heatmap
    from ...core.validation.image_pair import read_pair
    from ...core.validation.metrics import compare_images, display_transform_description

    pair = read_pair(args.reference, args.test)
    results = compare_images(pair, exposure_ev=args.exposure, vdp=not args.no_vdp)

    written = []
    if args.heatmap:
        flip = results["flip"]
        written.append(write_heatmap(args.heatmap, flip.per_pixel, flip.heatmap_full_scale))
    if args.heatmap_dir:
        for name, result in results.items():
            if result.per_pixel is not None:
                written.append(write_heatmap(heatmap_path(args.heatmap_dir, name),
                                             result.per_pixel, result.heatmap_full_scale))
    if args.json:
        write_json(args.json, {
            "reference": str(args.reference), "test": str(args.test),
            "dynamic_range": "HDR" if pair.hdr else "LDR",
            "width": pair.width, "height": pair.height,
            "display_transform": display_transform_description(pair.hdr, args.exposure),
            "metrics": {name: result.summary() for name, result in results.items()},
            "heatmaps": [str(path) for path in written]})

    print(format_table(results, pair.hdr))
    for path in written:
        print(f"heatmap  {path}")
    return 0


def format_table(results: dict, hdr: bool) -> str:
    """One line per metric; a skipped metric says why."""
    lines = [f"{'metric':<6} {'avg error %':>12} {'error px %':>11}  {'error pixel if':<18} score"]
    for name, result in results.items():
        label = name.upper()
        if result.skipped:
            lines.append(f"{label:<6} skipped: {result.skipped}")
            continue
        extra = result.extra
        if name == "mse":
            rule, score = f"sq. err > {result.threshold:.2e}", f"MSE {extra['mse']:.3g}"
        elif name == "flip":
            rule, score = f"FLIP > {result.threshold:g}", f"mean FLIP {extra['mean_flip']:.4f} ({extra['mode']})"
        else:
            rule, score = f"P > {result.threshold:g}", f"JOD {extra['jod']:.3f} ({extra['display']})"
        lines.append(f"{label:<6} {result.average_error_percent:>12.4f} "
                     f"{result.error_pixel_percent:>11.4f}  {rule:<18} {score}")
    if hdr:
        lines.append("(EXR: MSE and VDP compare the display-referred images, FLIP uses HDR-FLIP)")
    return "\n".join(lines)
