"""The saliency map of Itti, Koch & Niebur (1998, IEEE PAMI 20(11)), without bpy; equation
numbers are the paper's.

From a display-referred RGB image: intensity and broadly tuned colour channels (hue dropped
below a tenth of the peak intensity); Gaussian pyramids of ``I``, ``R - G``, ``B - Y`` and Gabor
orientation energy; 42 centre-surround feature maps (eqs. 1-4); the normalisation ``N(.)``,
conspicuity maps by across-scale addition (5-7) and ``S`` their mean (8). The colour maps are
``|RG(c) - RG(s)|``, the double-opponent contrast of eqs. 2-3 (and Itti's own code): adding the
two terms literally would make a uniform red field as salient as a red spot."""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy import ndimage
from skimage.morphology import local_maxima

from .gabor import ORIENTATIONS, oriented_energy
from .pyramid import (PYRAMID_LEVELS, center_surround, gaussian_pyramid, reduce_to_level,
                      resample)

#: Centre scales c and centre-surround scale differences δ (s = c + δ).
CENTER_SCALES = (2, 3, 4)
SURROUND_DELTAS = (3, 4)
#: The scale of the conspicuity maps and of S.
CONSPICUITY_SCALE = 4

#: ``M``, the fixed range ``[0, M]`` of N(.). Its value is immaterial: every map at one stage
#: is multiplied by the same power of it.
NORMALIZED_MAX = 1.0

#: Local maxima below this fraction of M are not counted by N(.). The paper does not give a
#: threshold; Itti's implementation uses a tenth of the range, which keeps the ripples of a
#: near-empty map from pulling the mean of the "other maxima" towards zero.
LOCAL_MAX_THRESHOLD = 0.1

#: Relative size of float32 round-off in a feature map. A map whose whole range is below this
#: times the feature's natural scale is numerically empty (e.g. a uniform image), and N(.)
#: must not blow the round-off up to the full range.
ROUNDOFF = 1e-5

#: Pixels whose intensity is at most this fraction of the image maximum carry no hue.
HUE_INTENSITY_FRACTION = 0.1


class FeatureKey(NamedTuple):
    """Names one feature map: ``feature`` is ``"I"``, ``"RG"``, ``"BY"`` or ``"O<θ>"``
    (``"O0"``, ``"O45"``, ``"O90"``, ``"O135"``); ``c`` and ``s`` are its scales."""

    feature: str
    c: int
    s: int


@dataclass(frozen=True)
class SaliencyMaps:
    """Everything the model computes for one image.

    Attributes
    ----------
    feature_maps : dict[FeatureKey, ndarray]
        The 42 centre-surround maps, each at its centre scale ``c``.
    intensity, colour, orientation : ndarray
        The conspicuity maps ``Ī``, ``C̄``, ``Ō`` (equations 5-7) at scale 4.
    saliency : ndarray
        ``S`` (equation 8) at scale 4.
    """

    feature_maps: dict
    intensity: np.ndarray
    colour: np.ndarray
    orientation: np.ndarray
    saliency: np.ndarray


def scale_pairs() -> list[tuple[int, int]]:
    """The six ``(c, s)`` pairs: ``c ∈ {2, 3, 4}``, ``s = c + δ``, ``δ ∈ {3, 4}``."""
    return [(c, c + delta) for c in CENTER_SCALES for delta in SURROUND_DELTAS]


def opponent_channels(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Intensity and the two colour-opponent channels of section 2.1.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3)
        Display-referred colour, non-negative.

    Returns
    -------
    intensity, red_green, blue_yellow : ndarray, float32, shape (H, W)
        ``I = (r + g + b)/3``, ``R - G`` and ``B - Y`` with the broadly tuned channels
        computed from ``r, g, b`` normalised by ``I`` (0 where ``I <= max(I)/10``).
    """
    rgb = np.asarray(rgb, dtype=np.float32)
    intensity = rgb.mean(axis=2)
    peak = float(intensity.max())
    coloured = intensity > HUE_INTENSITY_FRACTION * peak
    scale = np.zeros_like(intensity)
    np.divide(1.0, intensity, out=scale, where=coloured)
    r, g, b = (rgb[:, :, i] * scale for i in range(3))
    red = np.maximum(r - (g + b) / 2, 0)
    green = np.maximum(g - (r + b) / 2, 0)
    blue = np.maximum(b - (r + g) / 2, 0)
    yellow = np.maximum((r + g) / 2 - np.abs(r - g) / 2 - b, 0)
    return intensity, red - green, blue - yellow


def normalize_map(feature: np.ndarray, floor: float = 0.0) -> np.ndarray:
    """The map normalisation operator ``N(.)`` of section 2.3.

    1. Scale the map to the fixed range ``[0, M]``.
    2. Find its global maximum ``M`` and the mean ``m̄`` of all its *other* local maxima.
    3. Multiply the whole map by ``(M - m̄)²``.

    A map with one strong peak is promoted; a map with many comparable peaks is suppressed.
    A local maximum is a connected plateau higher than all its 8-neighbours, counted once;
    maxima below :data:`LOCAL_MAX_THRESHOLD` ``· M`` are ignored (see there). With no other
    maximum ``m̄ = 0``.

    Parameters
    ----------
    feature : ndarray, shape (H, W)
    floor : float
        A map whose range (max - min) is at most this is treated as empty (round-off).

    Returns
    -------
    ndarray, float32
        Zeros for an empty or constant map.
    """
    feature = np.asarray(feature, dtype=np.float32)
    low, high = float(feature.min()), float(feature.max())
    if not high - low > floor:
        return np.zeros_like(feature)
    scaled = (feature - low) * np.float32(NORMALIZED_MAX / (high - low))
    peaks = local_maxima(scaled, connectivity=2, allow_borders=True)
    labels, count = ndimage.label(peaks, structure=np.ones((3, 3), dtype=bool))
    heights = np.sort(np.asarray(ndimage.maximum(scaled, labels, np.arange(1, count + 1))))
    others = heights[:-1]
    others = others[others >= LOCAL_MAX_THRESHOLD * NORMALIZED_MAX]
    mean_others = float(others.mean()) if others.size else 0.0
    return scaled * np.float32((NORMALIZED_MAX - mean_others) ** 2)


def feature_maps(rgb: np.ndarray) -> dict[FeatureKey, np.ndarray]:
    """The 42 centre-surround feature maps (equations 1-4), each at its centre scale.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3)
        Display-referred colour in [0, 1] (other non-negative ranges work too).

    Returns
    -------
    dict[FeatureKey, ndarray]
        6 intensity, 6 red-green, 6 blue-yellow and 24 orientation maps, float32.
    """
    rgb = _checked_rgb(rgb)
    intensity, red_green, blue_yellow = opponent_channels(rgb)
    stacked = gaussian_pyramid(np.stack([intensity, red_green, blue_yellow], axis=2),
                               PYRAMID_LEVELS)
    intensity_pyr = [level[:, :, 0] for level in stacked]
    colour_pyrs = {"RG": [level[:, :, 1] for level in stacked],
                   "BY": [level[:, :, 2] for level in stacked]}
    # Orientation only where the centre-surround maps read it: scales 2..8.
    first = min(CENTER_SCALES)
    energy = {level: oriented_energy(intensity_pyr[level])
              for level in range(first, PYRAMID_LEVELS)}
    orientation_pyrs = {theta: [None] * first + [energy[level][theta]
                                                 for level in range(first, PYRAMID_LEVELS)]
                        for theta in ORIENTATIONS}

    maps: dict[FeatureKey, np.ndarray] = {}
    for c, s in scale_pairs():
        maps[FeatureKey("I", c, s)] = center_surround(intensity_pyr, c, s)
    for name, pyramid in colour_pyrs.items():
        for c, s in scale_pairs():
            maps[FeatureKey(name, c, s)] = center_surround(pyramid, c, s)
    for theta, pyramid in orientation_pyrs.items():
        for c, s in scale_pairs():
            maps[FeatureKey(f"O{theta}", c, s)] = center_surround(pyramid, c, s)
    return maps


def _roundoff_floors(rgb: np.ndarray) -> dict[str, float]:
    """Per-feature range below which a feature map is round-off (see :data:`ROUNDOFF`).

    Intensity and orientation scale with the image's brightness; the opponent channels are
    normalised by intensity, so their natural scale is 1.
    """
    brightness = float(np.asarray(rgb, dtype=np.float32).mean(axis=2).max())
    return {"I": ROUNDOFF * brightness, "O": ROUNDOFF * brightness, "RG": ROUNDOFF,
            "BY": ROUNDOFF}


def _across_scale_sum(maps: dict[FeatureKey, np.ndarray], features: tuple[str, ...],
                      floor: float) -> np.ndarray:
    """``⊕`` over the six (c, s) pairs of ``N(map)`` summed over ``features``, at scale 4."""
    total = None
    for c, s in scale_pairs():
        at_c = sum(normalize_map(maps[FeatureKey(name, c, s)], floor) for name in features)
        at_4 = reduce_to_level(at_c, c, CONSPICUITY_SCALE)
        total = at_4 if total is None else total + at_4
    return total


def itti_koch_niebur(rgb: np.ndarray) -> SaliencyMaps:
    """Feature maps, conspicuity maps and the saliency map ``S`` at scale 4 (section 2).

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3)
        Display-referred colour, non-negative and finite.

    Returns
    -------
    SaliencyMaps
    """
    rgb = _checked_rgb(rgb)
    maps = feature_maps(rgb)
    floors = _roundoff_floors(rgb)
    intensity = _across_scale_sum(maps, ("I",), floors["I"])                 # (5)
    colour = _across_scale_sum(maps, ("RG", "BY"), floors["RG"])              # (6)
    orientation = sum(normalize_map(_across_scale_sum(maps, (f"O{theta}",), floors["O"]))
                      for theta in ORIENTATIONS)                             # (7)
    saliency = (normalize_map(intensity) + normalize_map(colour)
                + normalize_map(orientation)) / 3.0                          # (8)
    return SaliencyMaps(maps, intensity, colour, orientation, saliency.astype(np.float32))


def saliency_map(rgb: np.ndarray) -> np.ndarray:
    """``S`` of an image, resampled to the image's resolution and scaled to [0, 1].

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3)
        Display-referred colour, non-negative and finite, at least 2x2 pixels.

    Returns
    -------
    ndarray, float32, shape (H, W)
        0 at the least and 1 at the most salient place; 0 everywhere for an image with no
        contrast at all. ``S`` lives at scale 4 (1:16), so an image under 32 pixels in both
        directions has a one-pixel ``S`` and gets a flat map too.
    """
    rgb = _checked_rgb(rgb)
    coarse = itti_koch_niebur(rgb).saliency
    full = np.maximum(resample(coarse, rgb.shape[:2]), 0.0)
    low, high = float(full.min()), float(full.max())
    if not high > low:
        return np.zeros(rgb.shape[:2], dtype=np.float32)
    return ((full - low) / (high - low)).astype(np.float32)


def _checked_rgb(rgb: np.ndarray) -> np.ndarray:
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"expected an (H, W, 3) RGB image, got shape {rgb.shape}")
    if rgb.shape[0] < 2 or rgb.shape[1] < 2:
        raise ValueError(f"the saliency model needs at least 2x2 pixels, got "
                         f"{rgb.shape[1]}x{rgb.shape[0]}")
    if not np.isfinite(rgb).all():
        raise ValueError("the image has NaN or infinite pixels")
    if (rgb < 0).any():
        raise ValueError("the image has negative pixels")
    return rgb.astype(np.float32, copy=False)
