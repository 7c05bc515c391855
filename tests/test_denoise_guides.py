"""Which frames' denoising guides are noisy enough to be denoised first
(core.sampling.denoise_guides)."""
from __future__ import annotations

import numpy as np
import pytest

from xsl_render.core.sampling.denoise_guides import NOISY_GUIDE_MEDIAN, guide_noise, guides_are_noisy


def _albedo(height: int = 48, width: int = 64) -> np.ndarray:
    """A clean guide: flat regions, a hard edge and a texture stripe, as surfaces give."""
    albedo = np.full((height, width, 3), 0.6, np.float32)
    albedo[:, width // 2:] = (0.2, 0.3, 0.8)
    albedo[::4, :, 0] = 0.9
    return albedo


def test_clean_guides_with_edges_and_texture_are_not_noisy():
    assert guide_noise(_albedo()) < NOISY_GUIDE_MEDIAN
    assert not guides_are_noisy(_albedo())


@pytest.mark.parametrize("share, noisy", [(1.0, True), (0.75, True), (0.3, False)])
def test_noise_over_most_of_the_frame_is_noisy_and_a_band_of_it_is_not(share, noisy):
    """In fog a pixel's guide is the mean over its 16 samples of the surface's albedo or the
    medium's, whichever each sample met first; a band of fog near the horizon (road's world
    fog) leaves most of the frame exact."""
    rng = np.random.default_rng(1)
    albedo = _albedo()
    rows = int(share * albedo.shape[0])
    in_medium = rng.binomial(16, 0.5, size=albedo[:rows].shape[:2])[..., None] / 16.0
    albedo[:rows] = in_medium * 0.95 + (1.0 - in_medium) * albedo[:rows]
    assert guides_are_noisy(albedo) is noisy


def test_frames_too_small_for_a_neighbourhood_are_not_noisy():
    assert guide_noise(np.random.default_rng(0).random((2, 9, 3))) == 0.0
