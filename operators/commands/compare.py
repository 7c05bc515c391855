"""``xsl-render compare REF TEST``: MSE, FLIP and VDP between a reference and a test image, or
between two frame sequences.

One line per metric: the paper's average pixel error (%), its percentage of error pixels and
their threshold, and the metric's own score; ``--json`` writes every number, ``--heatmap`` the
FLIP map, ``--heatmap-dir`` every metric's. Two sequences (``out/frame_####.exr`` or a folder of
frames, ``core/validation/frame_sequence.py``) are compared frame by frame and as a whole
(means, worst frame, flicker, video JOD); ``--report`` writes an HTML page of them."""
from __future__ import annotations

from pathlib import Path

from ...core.validation.sequence import DEFAULT_FPS

NAME = "compare"
HELP = ("difference metrics (MSE, FLIP, VDP) between a reference and a test image, or two frame "
        "sequences (per frame, flicker, video JOD): average pixel error, error pixels, heatmaps")


#: Bounds of --exposure in stops: 2^64 times any render's radiance still fits a float32.
MAX_EXPOSURE_EV = 64.0
#: The maps --heatmap-dir writes.
HEATMAP_NAMES = ("mse", "flip", "vdp")
#: The maps --heatmap-dir writes per frame of a sequence (VDP scores the sequence as a video).
FRAME_HEATMAP_NAMES = ("mse", "flip")


def add_arguments(parser) -> None:
    from . import argtypes

    image = argtypes.image_or_frames()
    parser.add_argument("reference", metavar="REF", type=image,
                        help="reference image (gold standard): .exr, .png or .jpg; or a frame sequence: "
                             "a pattern such as 'ref/frame_####.exr' or a folder of numbered .exr frames")
    parser.add_argument("test", metavar="TEST", type=image,
                        help="test image of the same size and kind as REF, or a sequence if REF is one")
    parser.add_argument("--frames", metavar="LIST", type=argtypes.FRAMES,
                        help="sequences: the frames to compare, e.g. 1-24 or 1-3,8 (default: every frame "
                             "found; the two sequences must then hold the same frames)")
    parser.add_argument("--fps", type=argtypes.number(above=0.0, hi=1000.0), metavar="N",
                        help=f"sequences: frames per second of the video JOD (default {DEFAULT_FPS:g})")
    parser.add_argument("--report", metavar="FILE.html", type=argtypes.output_file(".html"),
                        help="sequences: write an HTML page with the per-frame curves and a strip of "
                             "frames (test, reference, FLIP)")
    parser.add_argument("--json", metavar="FILE", type=argtypes.output_file(),
                        help="write all numbers to this JSON file")
    parser.add_argument("--heatmap", metavar="FILE.png", type=argtypes.output_file(".png"),
                        help="write the FLIP difference map as a magma PNG")
    parser.add_argument("--heatmap-dir", metavar="DIR", type=argtypes.output_folder(),
                        help="write every metric's map as DIR/mse.png, flip.png, vdp.png (magma); for "
                             "sequences every frame's, DIR/mse_0001.png, flip_0001.png, ...")
    parser.add_argument("--exposure", type=argtypes.number(-MAX_EXPOSURE_EV, MAX_EXPOSURE_EV),
                        default=0.0, metavar="EV",
                        help="exposure in stops of the display transform for EXR inputs (default 0: "
                             "Blender's Standard view)")
    parser.add_argument("--no-vdp", action="store_true",
                        help="skip ColorVideoVDP (the slow metric; it is optional anyway)")


def heatmap_path(folder: str | Path, metric: str) -> Path:
    """Where --heatmap-dir DIR keeps a metric's map: DIR/<metric>.png."""
    return Path(folder) / f"{metric}.png"


def frame_pairs(args) -> list | None:
    """The matched and checked frames of two sequences (``FramePair`` list), None for two
    single images; found once, the first time it is asked for. InputError, before any work,
    for a sequence against an image, a frame one side lacks, or frames of another size or kind."""
    if not hasattr(args, "compare_frames"):
        args.compare_frames = _find_frame_pairs(args)
    return args.compare_frames


def _find_frame_pairs(args):
    from ...core.errors import InputError
    from ...core.frames import parse_frame_list
    from ...core.validation.frame_sequence import check_frames, find_frames, is_sequence, match_frames

    sides = {"REF": args.reference, "TEST": args.test}
    kinds = {label: is_sequence(text) for label, text in sides.items()}
    if not any(kinds.values()):
        return None
    if not all(kinds.values()):
        one, other = ("REF", "TEST") if kinds["TEST"] else ("TEST", "REF")
        raise InputError(f"{other} is a sequence of frames and {one} one image ({sides[one]}): "
                         "compare an image with an image, a sequence with a sequence")
    frames = parse_frame_list(args.frames) if args.frames else None
    reference = find_frames(args.reference, "REF", frames)
    test = find_frames(args.test, "TEST", frames)
    pairs = match_frames(reference, test, frames)
    args.compare_size = check_frames(pairs)
    return pairs


def files(args) -> tuple[dict, dict]:
    """The images compared (every frame of a sequence), and the maps of --heatmap-dir, each
    an output of its own."""
    from ...core.validation.sequence import frame_heatmap_path

    pairs = frame_pairs(args)
    if pairs is None:
        inputs = {"REF": args.reference, "TEST": args.test}
        outputs = {f"--heatmap-dir's {name}.png": heatmap_path(args.heatmap_dir, name)
                   for name in HEATMAP_NAMES} if args.heatmap_dir else {}
        return inputs, outputs
    inputs, outputs = {}, {}
    for pair in pairs:
        inputs[f"frame {pair.frame} of REF"] = pair.reference
        inputs[f"frame {pair.frame} of TEST"] = pair.test
        if args.heatmap_dir:
            for name in FRAME_HEATMAP_NAMES:
                path = frame_heatmap_path(args.heatmap_dir, name, pair.frame)
                outputs[f"--heatmap-dir's {path.name}"] = path
    return inputs, outputs


def check(args) -> None:
    """Options for sequences only, or for single images only."""
    from ...core.errors import InputError

    if frame_pairs(args) is None:
        for option, value in (("--frames", args.frames), ("--fps", args.fps), ("--report", args.report)):
            if value is not None:
                raise InputError(f"{option} is for sequences; REF and TEST are single images "
                                 "(give patterns such as 'out/frame_####.exr' or folders of frames)")
    elif args.heatmap:
        raise InputError("--heatmap names one image's map; for sequences give --heatmap-dir DIR "
                         "(every frame's maps, DIR/flip_0001.png, ...)")


def run(args) -> int:
    if frame_pairs(args) is not None:
        return run_sequences(args)
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


def run_sequences(args) -> int:
    """Two sequences: every frame, then the sequence (``core/validation/sequence.py``)."""
    from ...core.files import write_json
    from ...core.validation.heatmap import write_heatmap
    from ...core.validation.metrics import display_transform_description
    from ...core.validation.report_sequence import FrameStrip, write_sequence_report
    from ...core.validation.sequence import compare_sequence, frame_heatmap_path

    size, written = args.compare_size, []
    strip = FrameStrip() if args.report else None

    def each(comparison) -> None:
        if args.heatmap_dir:
            for name in FRAME_HEATMAP_NAMES:
                result = comparison.results[name]
                written.append(write_heatmap(frame_heatmap_path(args.heatmap_dir, name, comparison.frame),
                                             result.per_pixel, result.heatmap_full_scale))
        if strip is not None:
            strip.add(comparison)

    compared = compare_sequence(frame_pairs(args), size, exposure_ev=args.exposure,
                                fps=args.fps or DEFAULT_FPS, vdp=not args.no_vdp, each=each)
    data = {"reference": str(args.reference), "test": str(args.test),
            "dynamic_range": "HDR" if size.hdr else "LDR", "width": size.width, "height": size.height,
            "display_transform": display_transform_description(size.hdr, args.exposure),
            **compared, "heatmaps": [str(path) for path in written]}
    if args.json:
        write_json(args.json, data)
    if args.report:
        write_sequence_report(args.report, data, strip)
    print(format_sequence_table(data))
    if written:
        print(f"heatmaps {len(written)} in {args.heatmap_dir}")
    if args.report:
        print(f"report   {args.report}")
    return 0


def format_sequence_table(data: dict) -> str:
    """A line per frame, then the means, the worst frames, the flicker and the video JOD."""
    columns = (("flip", "mean FLIP", ".4f"), ("flip_tile95", "p95 tile", ".4f"),
               ("flip_share", "% > 0.103", ".2f"), ("mse", "MSE", ".3g"), ("flicker", "flicker", ".4g"))

    def number(value, spec: str) -> str:
        return "-" if value is None else format(value, spec)

    lines = [f"{'frame':>8} " + " ".join(f"{label:>10}" for _, label, _ in columns)]
    for record in data["frames"]:
        lines.append(f"{record['frame']:>8} " + " ".join(f"{number(record[key], spec):>10}"
                                                          for key, _, spec in columns))
    sequence = data["sequence"]
    lines.append(f"{'mean':>8} " + " ".join(f"{number(sequence['mean'].get(key), spec):>10}"
                                            for key, _, spec in columns[:-1]))
    lines.append(f"{'worst':>8} " + " ".join(
        f"{number((sequence['worst'][key] or {}).get('value'), spec):>10}" for key, _, spec in columns[:-1]))
    lines.append(f"{'at frame':>8} " + " ".join(
        f"{(sequence['worst'][key] or {}).get('frame', '-'):>10}" for key, _, _ in columns[:-1]))
    flicker = sequence["flicker"]
    if flicker["skipped"]:
        lines.append(f"flicker  skipped: {flicker['skipped']}")
    else:
        relative = (f"{flicker['relative_flicker']:.3g} of the reference's own change"
                    if flicker["relative_flicker"] is not None else flicker["relative_skipped"])
        lines.append(f"flicker  {flicker['flicker']:.4g} RMS (display values) over "
                     f"{len(flicker['transitions'])} frame changes; relative: {relative}")
    vdp = sequence["vdp"]
    if vdp["jod"] is None:
        lines.append(f"VDP      skipped: {vdp['skipped']}")
    else:
        lines.append(f"VDP      JOD {vdp['jod']:.3f} ({'video' if vdp['as_video'] else 'image'}, "
                     f"{vdp['fps']:g} fps, {vdp['display']})")
    if data["dynamic_range"] == "HDR":
        lines.append("(EXR: MSE, flicker and VDP compare the display-referred frames, FLIP uses HDR-FLIP)")
    return "\n".join(lines)
