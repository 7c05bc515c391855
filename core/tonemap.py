"""Tone maps from scene-linear HDR renders to display-referred [0, 1] images, for two questions.

:func:`tonemap` (saliency: what would catch the eye?) follows the scene's brightness: the
global photographic operator of Reinhard et al. (SIGGRAPH 2002, eqs. 1-3: the log-average
luminance to middle grey, then ``L / (1 + L)``, hue kept, sRGB-encoded), so a sunlit road and a
night lamp both expose well and glows compress instead of clipping; eq. 3 rather than the
white-point variant, which one firefly would set. :func:`standard_view` (the metrics: would a
viewer see a difference?) is Blender's fixed "Standard" view, the same for both images, so a
difference in the output is one in the renders. Rec. 709 luminance weights."""
from __future__ import annotations

import numpy as np

from .imageio import linear_to_srgb

#: The key a of Reinhard et al.: the log-average luminance is mapped to middle grey.
KEY = 0.18

#: δ of Reinhard's eq. 1, in scene-linear units: keeps black pixels from sending the
#: log-average to zero while being far below any lit surface.
LOG_DELTA = 1e-4

#: Rec. 709 / sRGB luminance weights (Blender's default scene-linear primaries).
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def luminance(hdr_rgb: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance of a ``(..., 3)`` scene-linear image (negatives taken as 0)."""
    return np.maximum(np.asarray(hdr_rgb, dtype=np.float32), 0.0) @ LUMINANCE_WEIGHTS


def log_average_luminance(hdr_rgb: np.ndarray) -> float:
    """The key luminance ``L̄_w`` of Reinhard et al. (2002), eq. 1.

    Pass it to :func:`tonemap` to expose several images alike (a reference and a test
    render compared by a metric must not each get their own exposure).
    """
    rgb = _checked(hdr_rgb)
    return float(np.exp(np.mean(np.log(LOG_DELTA + luminance(rgb).astype(np.float64)))))


def tonemap(hdr_rgb: np.ndarray, log_average: float | None = None) -> np.ndarray:
    """Scene-linear RGB to display-referred, sRGB-encoded RGB in [0, 1].

    Parameters
    ----------
    hdr_rgb : ndarray, shape (..., 3)
        Scene-linear colour (e.g. a Cycles render), finite. Negative values (denoiser
        undershoot) count as 0.
    log_average : float, optional
        The key luminance to expose for; by default this image's own
        (:func:`log_average_luminance`).

    Returns
    -------
    ndarray, float32, same shape
        Display-referred values in [0, 1]. A black image stays black.
    """
    rgb = np.maximum(_checked(hdr_rgb), 0.0)
    key = log_average_luminance(rgb) if log_average is None else float(log_average)
    if not key > 0.0 or not np.isfinite(key):
        raise ValueError(f"the key luminance must be positive and finite, got {log_average}")
    world = luminance(rgb)
    scaled = (KEY / key) * world                                   # eq. 2
    display = scaled / (1.0 + scaled)                              # eq. 3
    ratio = np.zeros_like(world)
    np.divide(display, world, out=ratio, where=world > 0.0)
    return linear_to_srgb(np.clip(rgb * ratio[..., None], 0.0, 1.0))


def _checked(hdr_rgb: np.ndarray) -> np.ndarray:
    rgb = np.asarray(hdr_rgb, dtype=np.float32)
    if rgb.ndim < 1 or rgb.shape[-1] != 3:
        raise ValueError(f"expected RGB values on the last axis, got shape {rgb.shape}")
    if not np.isfinite(rgb).all():
        raise ValueError("the image has NaN or infinite values")
    return rgb


def standard_view(hdr_rgb: np.ndarray, exposure_ev: float = 0.0) -> np.ndarray:
    """Scene-linear RGB -> display-referred sRGB in [0, 1], float32.

    The transform is ``srgb_oetf(clip(hdr_rgb * 2**exposure_ev, 0, 1))``: a fixed exposure,
    a hard clamp, and the sRGB transfer curve (IEC 61966-2-1). With the default exposure
    of 0 EV it is Blender's "Standard" view transform, i.e. what Blender shows for a
    render that uses it. It has no image statistics in it, so two renders of the same
    scene (gold and selective) go through exactly the same curve and a difference in the
    output is a difference in the renders, never in the tone map.

    Parameters
    ----------
    hdr_rgb : (H, W, C) scene-linear radiance (Rec.709 primaries, as Cycles writes).
    exposure_ev : exposure in stops applied before the clamp.
    """
    # The factor stays a finite float32 however large the exposure (0 * inf would be NaN);
    # what it sends past float32's range is white after the clamp anyway.
    factor = np.float32(min(2.0 ** float(np.clip(exposure_ev, -1000.0, 1000.0)),
                            float(np.finfo(np.float32).max)))
    with np.errstate(over="ignore"):
        scaled = np.asarray(hdr_rgb, dtype=np.float32) * factor
    return linear_to_srgb(scaled)
