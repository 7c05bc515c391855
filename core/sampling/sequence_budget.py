"""The time of a guided animation: one budget shared by the frames of a range.

Plain numbers; the clock is read by the caller (``addon/cycles/guided_render.py``).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

from .sample_counts import BUDGET_OVERRUN, HOLD_RANGE, power_of_two_within, sobol_friendly

#: A later frame prices a sample at what the last this many frames paid for theirs, all
#: together: a frame's own cost moves with what the camera sees (street: 3.4-4.9 s for the
#: same 16 spp), and a count priced by the frame before alone followed those moves
#: (``steady_count`` then let go of the count 4 times in 24 frames).
RATE_WINDOW = 4
#: A held count is not raised in a range's last this many frames: a raise there buys samples
#: for a few frames at the price of a change of noise that plays as flicker (street, 24
#: frames at uniform 16 spp's time: 16 x22, then 32, 32 on what the held count had left
#: unspent). A farm's chunk is a range, so every chunk would end on such a change.
LAST_FRAMES_UNRAISED = 3
#: A range's second frame may raise the first frame's count even among the last frames
#: where it affords this many times it: the first frame's count is the pilot's price, the
#: second's is measured (``steady_count``).
PILOT_MISPRICED = 2.0
#: A frame of a guided animation is never given less than this share of the per-frame budget,
#: whatever the frames before it overran (a short sequence with a long first sync overruns
#: its total instead of starving its frames).
MIN_FRAME_SHARE = 0.5


@dataclass
class SequenceBudget:
    """The time of a guided animation: ``per_frame`` seconds a frame, ``per_frame x frames``
    for the whole range.

    The first frame syncs the scene (seconds for heterogeneous fog: Blender 5 builds its
    volume octree), the others find it synced (one Cycles session for the range). Charging
    that sync to the first frame alone would leave it a pilot and hardly a sample; here a
    frame renders for what the range has left divided by the frames still to render, its
    sync outside that, so the first frame renders like the others and the rest pay its sync
    back. (Mutable: one per run, ``record`` after each frame.)
    """

    per_frame: float
    frames: int
    spent: float = 0.0
    done: int = 0
    #: Seconds per full-resolution pixel-sample over the last ``RATE_WINDOW`` frames (their
    #: final passes, scene sync left out), and the frame before's samples per pixel. None
    #: before the first frame.
    rate: float | None = None
    spp: int | None = None
    #: (seconds, pixel-samples) of those frames' final passes, oldest first.
    recent: list = field(default_factory=list)
    #: The latest frame's denoise seconds, plain and with its guides prefiltered (None until
    #: a frame measured it): a later frame sets aside what its denoise will cost.
    denoise_plain_s: float | None = None
    denoise_prefiltered_s: float | None = None
    #: Whether the latest frame's denoising guides measured noisy (None until measured).
    guides_noisy: bool | None = None

    def next_budget(self) -> float:
        """Seconds for the next frame, its scene sync not included."""
        left = self.per_frame * self.frames - self.spent
        remaining = max(1, self.frames - self.done)
        return max(MIN_FRAME_SHARE * self.per_frame, left / remaining)

    def record(self, seconds: float) -> None:
        """A frame took ``seconds`` (wall, its sync included)."""
        self.spent += float(seconds)
        self.done += 1

    def observe(self, seconds: float, samples: float, spp: int) -> None:
        """A frame's final pass took ``seconds`` for ``samples`` pixel-samples, ``spp`` per
        pixel (a pass that measured nothing is left out)."""
        if seconds > 0.0 and samples > 0:
            self.recent = (self.recent + [(float(seconds), float(samples))])[-RATE_WINDOW:]
            self.rate = sum(s for s, _ in self.recent) / sum(n for _, n in self.recent)
            self.spp = int(spp)

    def observe_denoise(self, seconds: float, prefiltered: bool, noisy: bool) -> None:
        """A frame's denoise took ``seconds``, its guides ``prefiltered`` or not, and they
        measured ``noisy`` or not (``core.sampling.denoise_guides``)."""
        self.guides_noisy = bool(noisy)
        if seconds > 0.0:
            if prefiltered:
                self.denoise_prefiltered_s = float(seconds)
            else:
                self.denoise_plain_s = float(seconds)

    def allowance(self, frame_sample_seconds: float) -> float:
        """Samples per pixel a frame may render beyond its share: the frames left share
        ``BUDGET_OVERRUN`` of the range's budget (one sample per pixel of the whole frame
        costing ``frame_sample_seconds``)."""
        if frame_sample_seconds <= 0.0:
            return 0.0
        return BUDGET_OVERRUN * self.per_frame * self.frames / max(1, self.frames - self.done) / frame_sample_seconds

    def steady_count(self, affordable: float, ceiling: int, frame_sample_seconds: float,
                     sequence: int = 0) -> int:
        """The samples per pixel of a frame of the range that can afford ``affordable`` (its
        share of what the range has left), one sample per pixel of the whole frame costing
        ``frame_sample_seconds``: the frame before's count while the frames left can all
        render it within ``BUDGET_OVERRUN`` over the range's budget and this frame does not
        afford more than ``HOLD_RANGE[1]`` times it (a count that changes from frame to frame
        changes the noise, which shows as flicker), else a fresh count at one Cycles'
        patterns like, within the frame's share (the first frame's, with no frame before);
        either raised to the power of two above it where the allowance reaches it. In the
        range's last ``LAST_FRAMES_UNRAISED`` frames a count that fits is held as it is,
        unless the frame before was the first, priced by its pilot, and this one affords
        ``PILOT_MISPRICED`` times it (a 2-frame range at 64 x 36 pixels whose pilot had
        priced its first frame at half its budget held that count and used 0.5 of its
        budget; a count rounded down leaves at most 1.5x, ``sobol_friendly``).
        ``sequence``: the per-pixel sequence the range's Cycles session already draws from
        (``sobol_friendly``: a count below it is not rounded down)."""
        reach = affordable + self.allowance(frame_sample_seconds)
        closing = (self.frames - self.done <= LAST_FRAMES_UNRAISED
                   and not (self.done == 1 and affordable >= PILOT_MISPRICED * (self.spp or 0)))
        if self.spp and self.spp <= reach and (closing or affordable <= HOLD_RANGE[1] * self.spp):
            count = max(1, min(self.spp, ceiling))
            return count if closing else power_of_two_within(count, reach, ceiling)
        count = sobol_friendly(max(1, min(int(affordable), ceiling)), sequence)
        return power_of_two_within(count, reach, ceiling)

    def to_dict(self) -> dict:
        data = asdict(self)
        del data["recent"]
        return data
