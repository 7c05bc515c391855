"""Pixels Cycles rendered infinite or NaN, set to 0 as Cycles sets a non-finite sample.

Cycles makes every sample's contribution finite before it adds it to a pixel (a non-finite
one counts as 0: ``film_clamp_light``'s ``ensure_finite`` in its kernel), but a pixel's sum of
finite samples can still overflow 32-bit floats: an emitter of strength 1e38, whose light the
fog scatters everywhere. Neither OIDN (one such pixel spreads over its neighbours, several
black out the frame) nor an EXR of ours (``core.imageio.write_exr`` refuses them) can take
them, so they are treated as Cycles treats such a sample, before denoising, and the run says
how many there were. A frame with no finite pixel is not an image: bad input.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError


def zero_non_finite(image: np.ndarray, whole_frame: bool = True) -> tuple[np.ndarray, int]:
    """``image`` (H, W, C) with every infinite or NaN value set to 0, and the number of
    pixels that had one (``image`` itself when there were none). InputError when every
    pixel had one and ``image`` is a whole frame (not one rectangle of it)."""
    bad = ~np.isfinite(image)
    if not bad.any():
        return image, 0
    pixels = int(bad.any(axis=-1).sum())
    if whole_frame and pixels == image.shape[0] * image.shape[1]:
        raise InputError("every pixel Cycles rendered is infinite or NaN (light too strong for 32-bit "
                         "floats: an emission or lamp strength near 1e38?)")
    return np.where(bad, np.float32(0.0), image).astype(image.dtype, copy=False), pixels


def non_finite_warning(pixels: int) -> str:
    """What a run says about the ``pixels`` ``zero_non_finite`` set to 0."""
    return (f"{pixels} pixel(s) Cycles rendered were infinite or NaN (light too strong for 32-bit "
            "floats) and were set to 0 (before any denoising), as Cycles does with a non-finite sample")
