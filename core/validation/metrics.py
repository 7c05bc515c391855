"""Difference metrics between a gold-standard render and a selective one (paper section 6.1).

As the paper reports them, per metric: the average pixel error (the per-pixel difference map
averaged, in %) and the percentage of error pixels, with the map itself, for MSE on
display-referred images, NVIDIA's FLIP and ColorVideoVDP (the maintained successor of Daly's
VDP, optional: :mod:`.vdp`). All see the same observer (:data:`PIXELS_PER_DEGREE`) and, where
they compare display values, the same display transform (:func:`standard_view`)."""
from __future__ import annotations

import math
import time

import numpy as np

from ..imageio import linear_to_srgb
from ..tonemap import standard_view
from .image_pair import ImagePair
from .metric_result import MetricResult
from .vdp import vdp_metric

# ---------------------------------------------------------------------------------------
# The observer. ColorVideoVDP's 'standard_fhd' display (a 24-inch 1920x1080 monitor seen
# from 0.6 m) is the one VDP uses; FLIP gets the same geometry so both metrics judge the
# same viewer. It is close to the paper's own experiment: a 17-inch 1280x1024 monitor seen
# from 60 cm, about 40 pixels per degree.
VIEWING_DISTANCE_M = 0.6
DISPLAY_WIDTH_PX = 1920
DISPLAY_WIDTH_M = 24 * 0.0254 * 16 / math.hypot(16, 9)   # width of a 24-inch 16:9 screen
PIXELS_PER_DEGREE = VIEWING_DISTANCE_M * DISPLAY_WIDTH_PX / DISPLAY_WIDTH_M * math.pi / 180

# ---------------------------------------------------------------------------------------
# Error-pixel thresholds. MSE and FLIP have no threshold of their own, so both use one
# just-noticeable colour difference, Delta E*ab = 2.3 (Sharma 2003), measured on flat
# mid-grey patches: L* = 50 against L* = 52.3.
JND_DELTA_E = 2.3
JND_LIGHTNESS = 50.0


def srgb_of_lightness(lightness: float) -> float:
    """The display-encoded sRGB value of a grey of CIE lightness L* (D65 white)."""
    luminance = ((lightness + 16) / 116) ** 3 if lightness > 8 else lightness / 903.3
    return float(linear_to_srgb(np.float32(luminance)))


# A mid grey one JND lighter is ~5.8 8-bit levels higher; each image may also be off by
# half a level from 8-bit rounding, so one or two levels of difference are not an error.
MSE_ERROR_THRESHOLD = (srgb_of_lightness(JND_LIGHTNESS + JND_DELTA_E)
                       - srgb_of_lightness(JND_LIGHTNESS)) ** 2
# FLIP's value for the same pair of flat patches at PIXELS_PER_DEGREE (flip-evaluator 1.7;
# tests/test_metrics.py recomputes it). Flat patches have no edges, so this is FLIP's
# colour term alone.
FLIP_ERROR_THRESHOLD = 0.103

# The display transform: fixed exposure, clamp, sRGB OETF (see standard_view).
DISPLAY_EXPOSURE_EV = 0.0


def display_transform_description(hdr: bool, exposure_ev: float = DISPLAY_EXPOSURE_EV) -> str:
    """One line saying how the images were turned into display values."""
    if not hdr:
        return "none: LDR inputs are display-encoded sRGB already"
    return (f"exposure {exposure_ev:+g} EV, clamp to [0, 1], sRGB OETF "
            "(Blender's Standard view transform)")


def display_pair(pair: ImagePair, exposure_ev: float = DISPLAY_EXPOSURE_EV) -> tuple[np.ndarray, np.ndarray]:
    """The two images as a viewer's display shows them: HDR through :func:`standard_view`,
    LDR as stored (already display-encoded)."""
    if pair.hdr:
        return standard_view(pair.reference, exposure_ev), standard_view(pair.test, exposure_ev)
    return pair.reference, pair.test


def mse_metric(reference_display: np.ndarray, test_display: np.ndarray) -> MetricResult:
    """Per-pixel squared error of display-referred images, averaged over R, G and B.

    Values are in [0, 1] (display values are). Average pixel error = 100 x mean; an error
    pixel has squared error > :data:`MSE_ERROR_THRESHOLD` (one JND on mid grey, ~5.8
    8-bit levels). The heatmap is scaled so that this threshold sits at the colour of
    FLIP's error threshold.
    """
    start = time.perf_counter()
    difference = reference_display.astype(np.float32) - test_display.astype(np.float32)
    squared = np.mean(difference * difference, axis=2)
    return MetricResult.from_map(
        "mse", squared, MSE_ERROR_THRESHOLD,
        heatmap_full_scale=MSE_ERROR_THRESHOLD / FLIP_ERROR_THRESHOLD,
        extra={"mse": float(squared.mean(dtype=np.float64)),
               "seconds": time.perf_counter() - start})


#: HDR-FLIP's exposure range (flip-evaluator 1.7, ``computeExposureParams``): from
#: log2(x_max / max luminance) to log2(x_max / max(median luminance, float32 epsilon)) of the
#: reference, where x_max is the radiance its ACES tone map brings to 0.85.
_FLIP_ACES = (0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14)
_FLIP_A = _FLIP_ACES[0] - 0.85 * _FLIP_ACES[3]
_FLIP_B = _FLIP_ACES[1] - 0.85 * _FLIP_ACES[4]
_FLIP_C = _FLIP_ACES[2] - 0.85 * _FLIP_ACES[5]
FLIP_X_MAX = (-_FLIP_B + math.sqrt(_FLIP_B ** 2 - 4 * _FLIP_A * _FLIP_C)) / (2 * _FLIP_A)
_FLIP_EPSILON = float(np.finfo(np.float32).eps)


def hdr_flip_exposures(reference: np.ndarray, test: np.ndarray) -> dict:
    """Exposure parameters for HDR-FLIP where its own choice fails, else ``{}``.

    FLIP takes its exposure range from the reference; a reference whose brightest pixel is
    below float32's epsilon (black, or nearly) gives a start above the stop, and the library
    then ends the whole process. Such a reference gets the range the test image would have
    had (start from its brightest pixel), so that black against black is no error and
    anything brighter than black is one.
    """
    from ..tonemap import luminance

    if float(luminance(reference).max()) > 2.0 * _FLIP_EPSILON:
        return {}
    brightest = max(float(luminance(test).max()), _FLIP_EPSILON)
    return {"startExposure": math.log2(FLIP_X_MAX / brightest),
            "stopExposure": math.log2(FLIP_X_MAX / _FLIP_EPSILON)}


def flip_metric(reference: np.ndarray, test: np.ndarray, hdr: bool,
                pixels_per_degree: float = PIXELS_PER_DEGREE) -> MetricResult:
    """FLIP (flip-evaluator): LDR-FLIP on display-encoded images, HDR-FLIP on linear ones.

    HDR-FLIP tone-maps both images itself over a range of exposures chosen from the
    reference (FLIP's own method, ACES tone mapper) and keeps the worst LDR-FLIP per pixel;
    negative radiance (not displayable) is clamped to 0 first, as FLIP requires.
    Average pixel error = 100 x mean FLIP; error pixel: FLIP > :data:`FLIP_ERROR_THRESHOLD`.
    """
    import flip_evaluator

    start = time.perf_counter()
    mode = "HDR" if hdr else "LDR"
    ref = np.ascontiguousarray(np.maximum(reference, 0.0) if hdr else reference, dtype=np.float32)
    tst = np.ascontiguousarray(np.maximum(test, 0.0) if hdr else test, dtype=np.float32)
    parameters = {"ppd": float(pixels_per_degree), **(hdr_flip_exposures(ref, tst) if hdr else {})}
    flip_map, mean_flip, used = flip_evaluator.evaluate(
        ref, tst, mode, applyMagma=False, computeMeanError=True, parameters=parameters)
    extra = {"mode": f"{mode}-FLIP", "mean_flip": float(mean_flip), "ppd": float(used["ppd"])}
    if hdr:
        extra.update(start_exposure=float(used["startExposure"]),
                     stop_exposure=float(used["stopExposure"]),
                     num_exposures=int(used["numExposures"]), tonemapper=str(used["tonemapper"]))
    extra["tile95_flip"] = tile_percentile(flip_map[:, :, 0])
    extra["seconds"] = time.perf_counter() - start
    return MetricResult.from_map("flip", flip_map[:, :, 0], FLIP_ERROR_THRESHOLD, extra=extra)


#: Edge of the regions whose mean FLIP "no region visibly worse" looks at.
REGION_TILE = 32


def tile_percentile(per_pixel: np.ndarray, tile: int = REGION_TILE, q: float = 95.0) -> float:
    """The ``q``-th percentile of the mean of ``per_pixel`` over ``tile``-px squares (the
    edge ones cut by the frame): how bad the worst regions are, where a frame mean hides
    a smudge in one corner."""
    height, width = per_pixel.shape
    means = [float(per_pixel[r:r + tile, c:c + tile].mean(dtype=np.float64))
             for r in range(0, height, tile) for c in range(0, width, tile)]
    return float(np.percentile(means, q))


def compare_images(pair: ImagePair, exposure_ev: float = DISPLAY_EXPOSURE_EV,
                   vdp: bool = True) -> dict[str, MetricResult]:
    """All metrics on one pair: ``{"mse": ..., "flip": ..., "vdp": ...}``.

    MSE and VDP compare display-referred images (:func:`display_pair`). FLIP compares HDR
    renders with HDR-FLIP and LDR images with LDR-FLIP; for HDR renders the LDR-FLIP mean
    of the display-referred pair is kept too (``extra["mean_ldr_flip_display"]``), the FLIP
    figure under the same display transform as the other metrics. ``vdp=False`` reports VDP
    as skipped (it is the slow one).
    """
    ref_display, test_display = display_pair(pair, exposure_ev)
    results = {"mse": mse_metric(ref_display, test_display),
               "flip": flip_metric(pair.reference, pair.test, pair.hdr)}
    if pair.hdr:
        ldr_flip = flip_metric(ref_display, test_display, hdr=False)
        results["flip"].extra["mean_ldr_flip_display"] = ldr_flip.extra["mean_flip"]
    results["vdp"] = (vdp_metric(ref_display, test_display) if vdp
                      else MetricResult.skip("vdp", "not requested (--no-vdp)"))
    return results
