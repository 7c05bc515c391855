"""The VDP metric of the paper (section 6.1), with ColorVideoVDP as today's VDP.

The paper used Daly's VDP: per pixel the probability P that a viewer detects a difference,
P > 0.75 an error pixel. ColorVideoVDP (``cvvdp``, Mantiuk et al. 2024) is its maintained
successor, optional because it needs PyTorch; when missing the result says so and why. Its
``raw`` heatmap holds ``(10 - JOD) / 10`` per pixel, so the JOD drop is ``d = 10 x heatmap``;
on the Thurstone scale a drop ``d`` is chosen with probability ``Phi(z75 d)``, and removing
lucky guesses gives ``P = 2 Phi(z75 d) - 1``: an error pixel is a predicted drop above about
1.71 JOD."""
from __future__ import annotations

import functools
import time
from importlib.metadata import version

import numpy as np
from scipy.special import ndtr, ndtri

from .metric_result import MetricResult

# The display model ColorVideoVDP assumes: a 24-inch 1920x1080 SDR monitor, 200 cd/m^2
# peak, 1000:1 contrast, office light (250 lux), seen from 0.6 m (about 38 pixels per
# degree; FLIP uses the same geometry, see metrics.PIXELS_PER_DEGREE).
VDP_DISPLAY = "standard_fhd"
# The paper's threshold on the probability of detection (Myszkowski 1998).
VDP_ERROR_PROBABILITY = 0.75
_Z75 = float(ndtri(0.75))

VDP_INSTALL_HINT = "see the optional 'vdp' pins in requirements.lock to install it"


def detection_probability(jod_drop: np.ndarray) -> np.ndarray:
    """Per-pixel probability of detection from a per-pixel JOD drop (see module notes)."""
    drop = np.maximum(np.asarray(jod_drop, dtype=np.float64), 0.0)
    return (2.0 * ndtr(_Z75 * drop) - 1.0).astype(np.float32)


def jod_drop_at(probability: float) -> float:
    """The per-pixel JOD drop at which :func:`detection_probability` reaches ``probability``."""
    return float(ndtri((1.0 + probability) / 2.0) / _Z75)


def vdp_unavailable_reason() -> str | None:
    """None when ColorVideoVDP can run here, else one line saying why not."""
    try:
        _load_cvvdp()
    except ImportError as error:
        return f"ColorVideoVDP (cvvdp) is not installed ({error}); {VDP_INSTALL_HINT}"
    return None


@functools.cache
def _load_cvvdp():
    import pycvvdp  # noqa: F401  (imports torch; seconds, so only once)
    import torch

    return pycvvdp, torch


@functools.cache
def _metric():
    pycvvdp, torch = _load_cvvdp()
    return pycvvdp.cvvdp(display_name=VDP_DISPLAY, heatmap="raw",
                         device=torch.device("cpu"), quiet=True)


def vdp_metric(reference_display: np.ndarray, test_display: np.ndarray) -> MetricResult:
    """ColorVideoVDP on two display-encoded sRGB images ``(H, W, 3)`` in [0, 1].

    Returns the probability-of-detection map, average pixel error = 100 x mean P,
    error pixels: P > 0.75, and ``extra``: ``jod`` (the image's JOD score), the display
    model, its pixels per degree, the cvvdp version and seconds. Skipped, with the reason,
    when ColorVideoVDP is not installed or refuses the images.
    """
    reason = vdp_unavailable_reason()
    if reason:
        return MetricResult.skip("vdp", reason)
    start = time.perf_counter()
    _, torch = _load_cvvdp()
    metric = _metric()
    reference = np.ascontiguousarray(reference_display, dtype=np.float32)
    test = np.ascontiguousarray(test_display, dtype=np.float32)
    try:
        with torch.no_grad():
            jod, stats = metric.predict(test, reference, dim_order="HWC")
    except (RuntimeError, ValueError) as error:     # e.g. an image too small for its pyramid
        message = str(error).strip().splitlines()
        return MetricResult.skip("vdp", f"ColorVideoVDP failed: {message[0] if message else type(error).__name__}")
    heatmap = stats["heatmap"].float().numpy().reshape(reference.shape[:2])
    if not np.isfinite(heatmap).all() or not np.isfinite(float(jod)):
        return MetricResult.skip("vdp", "ColorVideoVDP returned NaN or Inf for these images")
    probability = detection_probability(10.0 * heatmap)
    extra = {"jod": float(jod), "display": VDP_DISPLAY, "ppd": float(metric.pix_per_deg),
             "error_jod_drop": jod_drop_at(VDP_ERROR_PROBABILITY),
             "cvvdp_version": version("cvvdp"), "seconds": time.perf_counter() - start}
    return MetricResult.from_map("vdp", probability, VDP_ERROR_PROBABILITY, extra=extra)


@functools.cache
def _video_metric():
    pycvvdp, torch = _load_cvvdp()
    return pycvvdp.cvvdp(display_name=VDP_DISPLAY, heatmap=None,
                         device=torch.device("cpu"), quiet=True)


def vdp_video(reference_frames: np.ndarray, test_frames: np.ndarray, fps: float) -> dict:
    """ColorVideoVDP's JOD of a whole sequence seen as a video at ``fps`` frames a second.

    Parameters
    ----------
    reference_frames, test_frames
        ``(F, H, W, 3)`` display-encoded sRGB frames in [0, 1] (float16 or float32), in the
        order they are shown; the same display model as :func:`vdp_metric`.
    fps
        Frames per second. One frame is no video: it is scored as an image.

    Returns
    -------
    dict
        ``jod`` (10: no visible difference), ``fps``, ``frames``, ``as_video``, the display
        model, its pixels per degree, the cvvdp version and ``seconds``; or ``jod`` None and
        ``skipped`` saying why (ColorVideoVDP missing, or refusing the frames). Never a zero.
    """
    reason = vdp_unavailable_reason()
    if reason:
        return {"jod": None, "skipped": reason}
    start = time.perf_counter()
    _, torch = _load_cvvdp()
    metric = _video_metric()
    count = int(reference_frames.shape[0])
    as_video = count > 1
    try:
        with torch.no_grad():
            jod, _ = metric.predict(np.ascontiguousarray(test_frames), np.ascontiguousarray(reference_frames),
                                    dim_order="FHWC", frames_per_second=float(fps) if as_video else 0)
    except (RuntimeError, ValueError) as error:     # e.g. frames too small for its pyramid
        message = str(error).strip().splitlines()
        return {"jod": None, "skipped": f"ColorVideoVDP failed: {message[0] if message else type(error).__name__}"}
    if not np.isfinite(float(jod)):
        return {"jod": None, "skipped": "ColorVideoVDP returned NaN or Inf for these frames"}
    return {"jod": float(jod), "fps": float(fps), "frames": count, "as_video": as_video,
            "display": VDP_DISPLAY, "ppd": float(metric.pix_per_deg), "cvvdp_version": version("cvvdp"),
            "seconds": time.perf_counter() - start, "skipped": None}
