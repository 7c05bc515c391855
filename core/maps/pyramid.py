"""Dyadic Gaussian pyramids and the across-scale operations of Itti, Koch & Niebur (1998,
section 2): nine scales from 1:1 to 1:256, the across-scale difference ``⊖`` (eqs. 1-4,
:func:`center_surround`) and addition ``⊕`` (eqs. 5-7, :func:`reduce_to_level`).

A level keeps ``ceil(n / 2)`` pixels of the level above (scikit-image's convention), so odd
sizes and small images work, and pixel centres stay aligned across levels (no half-pixel
drift)."""
from __future__ import annotations

import math

import numpy as np
from skimage.transform import pyramid_reduce, resize

#: The number of spatial scales, 0 (the image) to 8 (reduced 1:256).
PYRAMID_LEVELS = 9

#: Standard deviation (pixels of the finer level) of the low-pass filter applied before each
#: 2:1 subsampling. Burt & Adelson's 5-tap binomial kernel [1 4 6 4 1]/16, which Itti's
#: implementation uses, has variance 1; this is the Gaussian with the same variance.
#: (scikit-image's default, 2/3, would let more aliasing through.)
REDUCE_SIGMA = 1.0


def level_shape(shape: tuple[int, int], level: int) -> tuple[int, int]:
    """The ``(rows, cols)`` of pyramid level ``level`` for an image of ``shape``.

    Each level halves the size of the one above, rounding up: ``n_k = ceil(n_{k-1} / 2)``.
    """
    rows, cols = int(shape[0]), int(shape[1])
    for _ in range(level):
        rows, cols = math.ceil(rows / 2), math.ceil(cols / 2)
    return rows, cols


def reduce_level(image: np.ndarray) -> np.ndarray:
    """One pyramid step: Gaussian low-pass (sigma :data:`REDUCE_SIGMA`) then 2:1 subsampling.

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, C)
        A float map; channels, if any, are reduced independently.

    Returns
    -------
    ndarray, shape (ceil(H/2), ceil(W/2)[, C]), same float dtype.
    """
    channel_axis = -1 if image.ndim == 3 else None
    # order=1 with scikit-image's centre-aligned grid averages the two finer pixels that
    # straddle each coarser pixel centre; mode "reflect" keeps a constant image constant.
    return pyramid_reduce(image, downscale=2, sigma=REDUCE_SIGMA, order=1, mode="reflect",
                          preserve_range=True, channel_axis=channel_axis)


def gaussian_pyramid(image: np.ndarray, levels: int = PYRAMID_LEVELS) -> list[np.ndarray]:
    """The dyadic Gaussian pyramid ``[scale 0, ..., scale levels-1]`` of ``image``.

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, C)
        Scale 0. Stacking several feature channels along the last axis builds their
        pyramids in one pass.
    levels : int
        How many scales, 9 in Itti et al. (1998).

    Returns
    -------
    list of ndarray
        ``pyramid[k]`` has shape :func:`level_shape` ``(image.shape, k)``.
    """
    if levels < 1:
        raise ValueError(f"a pyramid needs at least one level, got {levels}")
    pyramid = [np.asarray(image)]
    for _ in range(1, levels):
        pyramid.append(reduce_level(pyramid[-1]))
    return pyramid


def resample(image: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Bilinear resampling of a map to ``shape`` (rows, cols) on the centre-aligned grid.

    This is the interpolation of the across-scale difference ``⊖`` (Itti et al. 1998,
    section 2.1): a coarse map brought to a finer scale. Outside the outermost pixel
    centres the map is held at its edge value.
    """
    shape = (int(shape[0]), int(shape[1])) + tuple(image.shape[2:])
    if image.shape == shape:
        return image
    return resize(image, shape, order=1, mode="edge", anti_aliasing=False,
                  preserve_range=True).astype(image.dtype, copy=False)


def center_surround(pyramid: list[np.ndarray], center: int, surround: int) -> np.ndarray:
    """``|P(c) ⊖ P(s)|``: the centre-surround feature map at the centre scale.

    Equations 1 and 4 of Itti et al. (1998): the surround level ``s`` is interpolated to the
    centre level ``c`` and subtracted point by point; the absolute value is the map.

    Parameters
    ----------
    pyramid : list of ndarray
        A pyramid from :func:`gaussian_pyramid` (or maps of the same shapes).
    center, surround : int
        Scales ``c < s``.

    Returns
    -------
    ndarray
        Shape of ``pyramid[center]``.
    """
    if not 0 <= center < surround < len(pyramid):
        raise ValueError(f"need 0 <= c < s < {len(pyramid)}, got c={center}, s={surround}")
    fine = pyramid[center]
    return np.abs(fine - resample(pyramid[surround], fine.shape[:2]))


def reduce_to_level(image: np.ndarray, from_level: int, to_level: int) -> np.ndarray:
    """Bring a map at scale ``from_level`` down to scale ``to_level`` by pyramid steps.

    The reduction of the across-scale addition ``⊕`` (equations 5-7): the same low-pass and
    2:1 subsampling as the pyramid, so the result has exactly the shape of level
    ``to_level``.
    """
    if to_level < from_level:
        raise ValueError(f"cannot reduce from scale {from_level} up to scale {to_level}")
    for _ in range(to_level - from_level):
        image = reduce_level(image)
    return image
