"""The flicker measure of sequence comparison (core/validation/temporal.py) on synthetic
display-encoded frames: zero for a test equal to the reference or with an error that stands
still, about sqrt(2) sigma for noise drawn anew in every frame, and ranked by amplitude."""
from __future__ import annotations

import math

import numpy as np
import pytest

from xsl_render.core.validation.temporal import ONE_FRAME, STATIC_REFERENCE, temporal_error

H, W = 24, 40


def moving_frames(count: int = 6, height: int = H, width: int = W) -> np.ndarray:
    """A display-encoded sequence in [0.2, 0.8] (no clipping for small noise): a gradient and
    a bright square moving right by 3 px a frame."""
    rows, cols = np.mgrid[0:height, 0:width].astype(np.float32)
    frames = np.empty((count, height, width, 3), np.float32)
    for t in range(count):
        frame = np.stack([0.2 + 0.4 * cols / width, 0.2 + 0.4 * rows / height, np.full_like(rows, 0.4)], 2)
        frame[6:14, 3 * t:3 * t + 8] = 0.75
        frames[t] = frame
    return frames


def noisy(frames: np.ndarray, sigma: float, static: bool, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    shape = frames.shape[1:] if static else frames.shape
    return frames + rng.normal(0.0, sigma, shape).astype(np.float32)


@pytest.mark.parametrize("sigma", [0.005, 0.02, 0.05])
def test_noise_new_every_frame_flickers_and_static_noise_does_not(sigma):
    reference = moving_frames()
    static = temporal_error(reference, noisy(reference, sigma, static=True))
    dynamic = temporal_error(reference, noisy(reference, sigma, static=False))
    assert static["flicker"] < 1e-6 * max(1.0, sigma / 0.01)
    assert dynamic["flicker"] > 100 * max(static["flicker"], 1e-9)
    # noise drawn anew each frame: the change of the error has RMS sqrt(2) sigma
    assert dynamic["flicker"] == pytest.approx(math.sqrt(2) * sigma, rel=0.06)
    assert dynamic["relative_flicker"] == pytest.approx(dynamic["flicker"] / dynamic["reference_motion"])
    assert len(dynamic["transitions"]) == len(reference) - 1


def test_flicker_grows_with_the_amplitude_of_temporal_noise():
    reference = moving_frames()
    values = [temporal_error(reference, noisy(reference, s, static=False))["flicker"] for s in (0.0, 0.01, 0.03)]
    assert values[0] == 0.0 and values[0] < values[1] < values[2]


@pytest.mark.parametrize("kind, expected", [("equal", 0.0), ("bias", 0.0), ("lag", None)])
def test_flicker_of_a_sequence_equal_to_the_reference_is_zero(kind, expected):
    reference = moving_frames()
    test = {"equal": reference.copy(), "bias": reference + 0.05,
            "lag": np.concatenate([reference[:1], reference[:-1]])}[kind]
    result = temporal_error(reference, test)
    if expected is None:       # one frame late: each change is shown a frame after the reference's
        assert result["flicker"] > 0.5 * result["reference_motion"]
    else:
        assert result["flicker"] == pytest.approx(expected, abs=1e-7)
        assert result["relative_flicker"] == pytest.approx(0.0, abs=1e-6)


def test_flicker_of_one_frame_and_of_a_static_reference_says_why_not():
    one = temporal_error(moving_frames(1), moving_frames(1))
    assert one["flicker"] is None and one["skipped"] == ONE_FRAME
    still = np.repeat(moving_frames(1), 4, axis=0)
    result = temporal_error(still, noisy(still, 0.02, static=False))
    assert result["flicker"] > 0 and result["reference_motion"] == 0.0
    assert result["relative_flicker"] is None and result["relative_skipped"] == STATIC_REFERENCE
