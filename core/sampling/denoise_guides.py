"""Whether a frame's denoising guides are noisy enough to be denoised first.

In fog Cycles writes the albedo and normal guides at the first scattering event, so where a
camera ray may scatter before its surface the guides are as noisy as the image, and OIDN
keeps that noise as detail. Denoised first (``addon.cycles.denoise``'s ``prefilter_guides``),
they lowered mean FLIP at 16 spp by 7-27 % on the example scenes whose media fill much of the
frame (balls_a, balls_b, statue) and by 2 % on road, whose world fog leaves most pixels'
guides exact: there the prefilter's time (1.1 s at 512x288) bought nothing
(``bench/bench_denoise_guides.py``, README "Denoising guides in fog").

The measure: the median over the frame of each pixel's albedo (summed over RGB) distance
from the median of its 3x3 neighbourhood. Edges and textures move few pixels; noise moves
most. Measured at 4 / 16 / 32 spp: road 0.0000 at every count; balls_a 0.0054 / 0.0034 /
0.0016, statue 0.039 / 0.023 / 0.012, balls_b 0.20 / 0.060 / 0.030. (It costs 0.04 s at
512x288.)
"""
from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

#: Above this median distance the guides are denoised first (between road's 0.0000 and
#: balls_a's 0.0016 at 32 spp, the smallest of the scenes where it paid).
NOISY_GUIDE_MEDIAN = 0.001


def guide_noise(albedo: np.ndarray) -> float:
    """The median over pixels of |a - median3x3(a)|, ``a`` the albedo guide (H, W, 3) summed
    over its channels."""
    albedo = np.asarray(albedo, np.float32)[..., :3].sum(axis=-1)
    if albedo.shape[0] < 3 or albedo.shape[1] < 3:
        return 0.0
    padded = np.pad(albedo, 1, mode="edge")
    windows = sliding_window_view(padded, (3, 3)).reshape(*albedo.shape, 9)
    local = np.partition(windows, 4, axis=-1)[..., 4]
    return float(np.median(np.abs(albedo - local)))


def guides_are_noisy(albedo: np.ndarray, threshold: float = NOISY_GUIDE_MEDIAN) -> bool:
    """True where most of the frame's albedo guide is noise (``guide_noise`` above
    ``threshold``): worth denoising before it guides the image's denoise."""
    return guide_noise(albedo) > threshold
