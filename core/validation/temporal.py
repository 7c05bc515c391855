"""Flicker: how much more (or less) a test sequence changes from frame to frame than its
reference does.

A render's noise that is new in every frame flickers, where the same error in every frame
stands still; per-frame metrics (FLIP, MSE) cannot tell the two apart, a viewer of the
animation can. The measure compares each frame-to-frame change of the test with the
reference's own change over the same two frames, in the display-encoded space the metrics
compare (:func:`~.metrics.display_pair`), so that a camera or a light that moves is not
counted as flicker, only what the test's motion adds to or takes from the reference's.
"""
from __future__ import annotations

import math

import numpy as np

#: Why the flicker of a sequence of fewer than two frames is not given.
ONE_FRAME = "one frame: no consecutive frames to compare"
#: Why the relative flicker is not given when the reference never changes.
STATIC_REFERENCE = "the reference does not change from frame to frame (its temporal RMS is 0)"


def _rms(values: np.ndarray) -> float:
    values = values.astype(np.float64, copy=False)
    return math.sqrt(float(np.mean(values * values)))


class TemporalError:
    """Flicker of a test sequence against its reference, fed one frame pair at a time.

    With display-encoded frames ``T_t`` (test) and ``R_t`` (reference), ``t = 0 .. N-1``
    (``(H, W, C)`` arrays in [0, 1], consecutive in the order given), the error of
    transition ``t`` (from frame ``t-1`` to frame ``t``, ``t >= 1``) is

    ``e_t = RMS( (T_t - T_{t-1}) - (R_t - R_{t-1}) )``,

    the root mean square over every pixel and channel; the reference's own change is
    ``m_t = RMS( R_t - R_{t-1} )``. The sequence's figures are

    - ``flicker = mean_t e_t``: 0 for a test equal to the reference and for an error that
      stays the same in every frame (static noise, a constant bias), and growing with
      temporal noise: noise of standard deviation ``s`` drawn anew in every frame gives
      about ``sqrt(2) s``;
    - ``reference_motion = mean_t m_t``: how much the reference itself changes;
    - ``relative_flicker = flicker / reference_motion``: the flicker against the change a
      viewer expects (None when the reference does not change at all).

    Equivalently ``e_t`` is the RMS of the change of the error image ``T_t - R_t`` between
    consecutive frames. Frames are taken in the order given: a sequence with gaps (every
    second frame) is measured across the gaps.
    """

    def __init__(self) -> None:
        self._previous: tuple[np.ndarray, np.ndarray] | None = None
        self.transitions: list[float] = []
        self.reference_changes: list[float] = []

    def add(self, reference: np.ndarray, test: np.ndarray) -> float | None:
        """Feed the next frame pair; returns ``e_t`` of the transition into it (None for the
        first frame)."""
        reference = np.asarray(reference, dtype=np.float32)
        test = np.asarray(test, dtype=np.float32)
        if reference.shape != test.shape:
            raise ValueError(f"frame shapes differ: {reference.shape} and {test.shape}")
        error = test - reference
        value = None
        if self._previous is not None:
            previous_reference, previous_error = self._previous
            if previous_reference.shape != reference.shape:
                raise ValueError("every frame of a sequence must have one shape")
            value = _rms(error - previous_error)
            self.transitions.append(value)
            self.reference_changes.append(_rms(reference - previous_reference))
        self._previous = (reference.copy(), error)
        return value

    def result(self) -> dict:
        """``flicker``, ``reference_motion``, ``relative_flicker`` (class notes), the
        per-transition ``e_t`` and ``m_t`` lists, and ``skipped``/``relative_skipped``: why a
        figure is None."""
        if not self.transitions:
            return {"flicker": None, "reference_motion": None, "relative_flicker": None,
                    "transitions": [], "reference_changes": [], "skipped": ONE_FRAME,
                    "relative_skipped": ONE_FRAME}
        flicker = float(np.mean(self.transitions))
        motion = float(np.mean(self.reference_changes))
        relative = flicker / motion if motion > 0.0 else None
        return {"flicker": flicker, "reference_motion": motion, "relative_flicker": relative,
                "transitions": list(self.transitions), "reference_changes": list(self.reference_changes),
                "skipped": None, "relative_skipped": None if relative is not None else STATIC_REFERENCE}


def temporal_error(reference_frames, test_frames) -> dict:
    """:class:`TemporalError` of two whole sequences, ``(N, H, W, C)`` arrays (or lists of
    ``(H, W, C)`` frames) of display-encoded values; see the class for the definitions."""
    if len(reference_frames) != len(test_frames):
        raise ValueError(f"{len(reference_frames)} reference frames against {len(test_frames)} test frames")
    meter = TemporalError()
    for reference, test in zip(reference_frames, test_frames):
        meter.add(reference, test)
    return meter.result()
