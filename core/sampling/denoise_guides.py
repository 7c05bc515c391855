"""Whether a frame's denoising guides are noisy enough to be denoised first.

In fog Cycles writes the albedo and normal guides at the first scattering event, so where a
ray may scatter before its surface they are as noisy as the image and OIDN keeps that noise
as detail; denoised first (``prefilter_guides``) they lower the error where the media fill the
frame, and only cost time where the guides are exact (docs/performance.md, "Denoising guides
in fog"). The measure: the median over the frame of each pixel's albedo distance from the
median of its 3x3 neighbourhood; edges and textures move few pixels, noise most."""
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
