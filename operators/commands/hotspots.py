"""``xsl-render hotspots IMAGE FIXATIONS.csv --out PNG``: gaze hotspots over a stimulus (Fig. 15)."""
from __future__ import annotations

NAME = "hotspots"
HELP = ("hotspot plot of section 6.5: total fixation duration, spread by a Gaussian of one "
        "degree of visual angle and clipped at a maximum, lighting a black mask over the stimulus")


def add_arguments(parser) -> None:
    from ...core.psychophysics.hotspots import (PAPER_DISTANCE_CM, PAPER_SCREEN_WIDTH_CM,
                                                PAPER_SCREEN_WIDTH_PX)

    from . import argtypes

    parser.add_argument("image", metavar="IMAGE", type=argtypes.input_file(what="image file"),
                        help="the stimulus as shown (PNG; EXR is sRGB-encoded)")
    parser.add_argument("fixations", metavar="FIXATIONS.csv", type=argtypes.input_file(what="fixations file"),
                        help="rows of x, y (image pixels, top-left origin), duration_ms")
    parser.add_argument("--out", required=True, metavar="FILE.png", type=argtypes.output_file(".png"),
                        help="the hotspot plot")
    parser.add_argument("--max-ms", type=argtypes.POSITIVE, default=4000.0,
                        help="total duration that lights a pixel fully (default 4000, the paper's)")
    parser.add_argument("--distance-cm", type=argtypes.POSITIVE, default=PAPER_DISTANCE_CM,
                        help=f"viewing distance (default {PAPER_DISTANCE_CM:g} cm)")
    parser.add_argument("--screen-width-cm", type=argtypes.POSITIVE, default=round(PAPER_SCREEN_WIDTH_CM, 2),
                        help="visible width of the display (default: the paper's 17\" 5:4, "
                             f"{PAPER_SCREEN_WIDTH_CM:.2f} cm)")
    parser.add_argument("--screen-width-px", type=argtypes.PIXELS, default=PAPER_SCREEN_WIDTH_PX,
                        help=f"horizontal resolution of the display (default {PAPER_SCREEN_WIDTH_PX})")
    parser.add_argument("--sigma-deg", type=argtypes.POSITIVE, default=1.0,
                        help="standard deviation of the Gaussian in degrees of visual angle (default 1)")


def run(args) -> int:
    import numpy as np

    from ...core.imageio import image_is_float, linear_to_srgb, read_image, write_png
    from ...core.psychophysics.hotspots import (fixation_duration_map, hotspot_image,
                                                pixels_per_degree, read_fixations)

    per_degree = pixels_per_degree(args.distance_cm, args.screen_width_cm, args.screen_width_px)
    fixations = read_fixations(args.fixations)
    stimulus = read_image(args.image)
    if image_is_float(args.image):          # linear radiance (EXR, HDR): encode for display
        stimulus = linear_to_srgb(stimulus)
    channels = stimulus.shape[2]
    rgb = (stimulus[:, :, :3] if channels >= 3 else np.repeat(stimulus[:, :, :1], 3, axis=2))
    rgb = np.clip(np.nan_to_num(rgb), 0.0, 1.0)
    height, width = rgb.shape[:2]
    durations = fixation_duration_map(fixations, height, width, args.sigma_deg * per_degree)
    write_png(args.out, hotspot_image(rgb, durations, args.max_ms))
    inside = ((fixations[:, 0] >= 0) & (fixations[:, 0] < width)
              & (fixations[:, 1] >= 0) & (fixations[:, 1] < height)).sum()
    print(f"{len(fixations)} fixations ({inside} on the image), {fixations[:, 2].sum():.0f} ms in "
          f"all; 1 degree = {per_degree:.1f} px; peak {durations.max():.0f} ms "
          f"(clipped at {args.max_ms:g}) -> {args.out}")
    return 0
