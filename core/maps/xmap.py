"""The extinction map X of the paper (section 4.1) from a cached Z buffer.

X(pixel) = luminance of exp(-tau) per RGB channel: the fraction of the light leaving the
first surface that reaches the eye. Pixels whose ray hits nothing have no surface to
attenuate; the physics there is the transmittance to the clip end (for an infinite world
fog, practically 0; the paper sets such pixels to 0). *MinBound* replaces them with the
smallest X of the pixels that do hit something, so the sky is sampled like the most
fogged-in surface instead of not at all.
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from ..media.volume_medium import VolumeMedium
from .camera_rays import CameraRays
from .transmittance import DEFAULT_SAMPLES, DEFAULT_TOLERANCE, optical_depth

#: Rec. 709 weights (linear sRGB, Blender's default scene-linear space).
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
NO_MEDIA_WARNING = "the scene has no participating media: the X map is 1 everywhere"


class XMapWarning(UserWarning):
    """Something about the X map the user should know, but not an error."""


def luminance(rgb: np.ndarray) -> np.ndarray:
    return np.asarray(rgb, dtype=np.float64) @ LUMINANCE


def apply_minbound(x: np.ndarray, sky: np.ndarray) -> tuple[np.ndarray, float | None]:
    """Give every sky pixel the smallest X of the non-sky pixels (paper 4.1, MinBound).

    Returns the new map and the value used (None when there is no finite pixel, in which
    case the map is returned unchanged).
    """
    x = np.array(x, dtype=np.float32, copy=True)
    sky = np.asarray(sky, dtype=bool)
    if not sky.any() or sky.all():
        return x, None
    value = x[~sky].min()
    x[sky] = value
    return x, float(value)


def x_map_from_cached_rays(rays: CameraRays, media: list[VolumeMedium], minbound: bool = True,
                           extra_tau: np.ndarray | None = None, samples: int = DEFAULT_SAMPLES,
                           tolerance: float | None = DEFAULT_TOLERANCE,
                           ) -> tuple[np.ndarray, np.ndarray, dict]:
    """The X map of ``media`` seen along already cast ``rays``: no ray is cast here.

    Parameters
    ----------
    rays : CameraRays
        The cached Z buffer.
    media : list of VolumeMedium
        Media evaluated in numpy (those with ``evaluable``); others must come in through
        ``extra_tau``.
    minbound : bool
        Fill sky pixels with the smallest X of the other pixels (the paper's MinBound);
        otherwise they keep the transmittance to the clip end.
    extra_tau : (h, w, 3) array, optional
        Optical depth measured elsewhere (Cycles' transmittance of the media numpy cannot
        evaluate), added to what is integrated here.
    samples : int
        Midpoint samples per interval for heterogeneous media when every ray is marched
        (``tolerance`` None).
    tolerance : float or None
        Transmittance tolerance of the adaptive ray grid that integrates heterogeneous
        media (``core.maps.ray_grid_depth``); None marches every ray instead (slow; a reference).

    Returns
    -------
    x : (H, W) float32
        The X map at the whole render resolution (0 outside a render border's window).
    transmittance : (h, w, 3) float32
        exp(-tau) per channel inside the window. With MinBound on, rays that hit nothing
        are not integrated at all (MinBound overwrites their X), and read 1 here.
    info : dict
        Timings, the MinBound value, per-medium methods, warnings.
    """
    start = time.perf_counter()
    info: dict = {"warnings": []}
    if not media and extra_tau is None:
        warnings.warn(NO_MEDIA_WARNING, XMapWarning, stacklevel=2)
        info["warnings"].append(NO_MEDIA_WARNING)
        tau = np.zeros(rays.shape + (3,))
        info["media"] = []
    else:
        # MinBound overwrites every sky pixel: integrating those rays (often the longest,
        # out to the clip end) would be wasted work.
        only = rays.hit if (minbound and rays.hit.any()) else None
        tau, info["media"] = optical_depth(rays, [m for m in media if m.evaluable], samples, only,
                                           tolerance)
        if extra_tau is not None:
            tau = tau + extra_tau
    transmittance = np.exp(-tau).astype(np.float32)
    x, info["minbound"] = x_from_transmittance(rays, transmittance, minbound)
    info["sky_pixels"] = int((~rays.hit).sum())
    info["seconds"] = time.perf_counter() - start
    return x, transmittance, info


def x_from_transmittance(rays: CameraRays, transmittance: np.ndarray,
                         minbound: bool = True) -> tuple[np.ndarray, float | None]:
    """The X map at the whole render resolution (0 outside the window) from the
    transmittance (h, w, 3) along ``rays``, and the MinBound value (None if unused)."""
    x = np.clip(luminance(transmittance), 0.0, 1.0).astype(np.float32)
    value = None
    if minbound:
        x, value = apply_minbound(x, ~rays.hit)
    return rays.full_frame(x, fill=0.0), value


def with_ties(transmittance: np.ndarray, passing: np.ndarray | None = None,
              measured: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """The transmittance (h, w, 3) at the rays where Cycles' answer depends on how it
    breaks a tie between coincident faces (``CameraRays.ties``).

    ``passing`` (h, w) is the share of the samples that pass the first surface into
    nothing (they count 0: the oracle's world is black); ``measured`` ((h, w) bool, (h, w,
    3)) the pixels a Cycles render measured, whose values replace ours.
    """
    out = np.array(transmittance, dtype=np.float32, copy=True)
    if passing is not None:
        out *= (1.0 - passing)[..., None].astype(np.float32)
    if measured is not None:
        mask, values = measured
        out[mask] = values[mask]
    return out
