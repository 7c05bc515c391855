"""Several render passes of one frame merged into one estimate, weighted by their samples.

A Cycles pass holds, per pixel, the mean of its samples. Passes that cover a pixel with
``n_1, n_2, ...`` samples merge into ``sum(n_k * mean_k) / sum(n_k)``: the mean of all the
samples, as one render of ``sum(n_k)`` samples would give (exactly so when the passes are
consecutive ranges of one seed's sample sequence, in expectation when their seeds differ).
The denoising guides (albedo, normal) are means over the same samples and merge the same
way. Unlike ``composite.Compositor``, a pixel may receive any number of passes.
"""
from __future__ import annotations

import numpy as np

from .composite import Window


class PassAccumulator:
    """Sums of samples-weighted passes over a frame.

    Parameters
    ----------
    width, height
        Frame size in pixels.
    channels
        Channels of each pass (4 for Cycles' RGBA Combined pass, 6 for albedo + normal).
    """

    def __init__(self, width: int, height: int, channels: int = 4):
        self.width, self.height = width, height
        self._sums = np.zeros((height, width, channels), np.float64)
        self.samples = np.zeros((height, width), np.float64)

    def add(self, window: Window | None, pixels: np.ndarray, samples: float | np.ndarray) -> None:
        """Add a pass covering ``window`` (None: the whole frame) with ``samples`` per pixel
        (a number, or an array of the window's shape: a time-limited render's own counts)."""
        r0, r1, c0, c1 = (0, self.height, 0, self.width) if window is None else window
        if not (0 <= r0 < r1 <= self.height and 0 <= c0 < c1 <= self.width):
            raise ValueError(f"window {window} lies outside the {self.width}x{self.height} frame")
        if pixels.shape[:2] != (r1 - r0, c1 - c0):
            raise ValueError(f"pixels of shape {pixels.shape[:2]} do not fit window {window}")
        counts = np.broadcast_to(np.asarray(samples, np.float64), (r1 - r0, c1 - c0))
        if (counts < 0).any():
            raise ValueError("a pass cannot have negative samples")
        channels = self._sums.shape[2]
        self._sums[r0:r1, c0:c1] += pixels[:, :, :channels] * counts[..., None]
        self.samples[r0:r1, c0:c1] += counts

    def result(self) -> np.ndarray:
        """The merged image, float32 (H, W, C); ValueError where a pixel has no sample."""
        if not (self.samples > 0).all():
            missing = int((self.samples <= 0).sum())
            raise ValueError(f"{missing} pixels of the {self.width}x{self.height} frame have no sample")
        return (self._sums / self.samples[..., None]).astype(np.float32)
