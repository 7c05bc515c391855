"""The HDR -> display tone map (core.tonemap): Reinhard et al. 2002 eqs. 1-3 plus sRGB."""
from __future__ import annotations

import math

import numpy as np
import pytest

from xsl_render.core.tonemap import LOG_DELTA, log_average_luminance, tonemap


def _srgb(v):
    return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055


@pytest.mark.parametrize("level", [0.01, 1.0, 250.0])
def test_uniform_grey_goes_to_the_key_by_hand(level):
    # L̄w = exp(log(δ + L)) = δ + L; L = 0.18 L / (δ + L); Ld = L / (1 + L); then sRGB.
    scaled = 0.18 * level / (LOG_DELTA + level)
    expected = _srgb(scaled / (1 + scaled))
    out = tonemap(np.full((3, 5, 3), level, np.float32))
    assert out.dtype == np.float32 and out.shape == (3, 5, 3)
    np.testing.assert_allclose(out, expected, rtol=1e-5)


def test_log_average_by_hand():
    image = np.zeros((1, 2, 3), np.float32)
    image[0, 0] = 1.0
    image[0, 1] = 4.0
    assert log_average_luminance(image) == pytest.approx(
        math.exp(0.5 * (math.log(1 + LOG_DELTA) + math.log(4 + LOG_DELTA))), rel=1e-6)


def test_exposure_follows_the_scene():
    rng = np.random.default_rng(0)
    image = rng.random((16, 16, 3), dtype=np.float32) + 0.05
    np.testing.assert_allclose(tonemap(image * 1000.0), tonemap(image), atol=2e-3)


def test_shared_key_exposes_two_images_alike():
    rng = np.random.default_rng(1)
    reference = rng.random((8, 8, 3), dtype=np.float32)
    key = log_average_luminance(reference)
    brighter = tonemap(reference * 2.0, log_average=key)
    assert (brighter >= tonemap(reference, log_average=key) - 1e-7).all()
    assert brighter.mean() > tonemap(reference, log_average=key).mean()


def test_highlights_compress_without_clipping_and_order_is_kept():
    levels = np.array([0.0, 0.1, 1.0, 10.0, 100.0, 1e4], np.float32)
    image = np.repeat(levels[None, :, None], 3, axis=2)
    out = tonemap(image)[0, :, 0]
    assert out[0] == 0.0
    assert (np.diff(out) > 0).all()
    assert out.max() < 1.0


def test_hue_is_kept_and_negatives_and_black_are_safe():
    image = np.zeros((2, 2, 3), np.float32)
    image[0, 0] = (0.2, 0.1, 0.05)
    image[0, 1] = (-0.01, 0.0, 0.0)          # denoiser undershoot
    out = tonemap(image)
    assert out[0, 0, 0] > out[0, 0, 1] > out[0, 0, 2] > 0
    assert (out[0, 1] == 0).all() and (out[1] == 0).all()
    assert not tonemap(np.zeros((4, 4, 3), np.float32)).any()


@pytest.mark.parametrize("bad", [np.full((2, 2, 3), np.nan), np.full((2, 2, 3), np.inf),
                                 np.zeros((2, 2, 4)), np.zeros((2, 2))])
def test_refuses_non_rgb_or_non_finite(bad):
    with pytest.raises(ValueError):
        tonemap(bad)
