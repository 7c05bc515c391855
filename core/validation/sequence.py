"""A test animation against its reference: every frame compared as ``compare`` compares one
image (mean FLIP, the 95th percentile of 32-px tile FLIP, the share of pixels over 0.103,
MSE), and the sequence as a whole: the means and worst frame of those, its flicker
(:mod:`.temporal`) and ColorVideoVDP's JOD of the sequence played as a video. Frames are read
one pair at a time, so a long sequence needs one frame pair's memory (plus, for the video JOD
only, every display-encoded frame at half precision)."""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..checks import physical_memory
from .curves_results import metric_values
from .frame_sequence import FramePair, FrameSize
from .image_pair import read_pair
from .metric_result import MetricResult
from .metrics import compare_images, display_pair
from .temporal import TemporalError
from .vdp import vdp_unavailable_reason, vdp_video

#: The per-frame figures summarised over the sequence (all lower is better).
FRAME_METRICS = ("flip", "flip_tile95", "flip_share", "mse")
#: Frames per second when none is given: the frame rate of Blender's default scene.
DEFAULT_FPS = 24.0
#: The share of this machine's memory the video JOD may hold its frames in.
VIDEO_MEMORY_SHARE = 0.25
#: Why a frame has no VDP figure of its own.
PER_FRAME_VDP = "per frame: the sequence is scored as a video (sequence.vdp)"


@dataclass(frozen=True)
class FrameComparison:
    """One frame's comparison as it is made, for what the caller draws or writes of it.

    ``results``: each metric's :class:`~.metric_result.MetricResult` with its per-pixel map;
    ``reference_display``, ``test_display``: the frames as the metrics' display shows them;
    ``record``: the frame's entry of :func:`compare_sequence`'s ``frames``.
    """

    frame: int
    results: dict[str, MetricResult]
    reference_display: np.ndarray
    test_display: np.ndarray
    record: dict


def video_bytes(count: int, size: FrameSize) -> int:
    """Memory the video JOD keeps its frames in: both sequences, RGB, float16 (ColorVideoVDP
    takes a copy of its own as it starts)."""
    return 2 * count * size.height * size.width * 3 * 2


def video_skip_reason(count: int, size: FrameSize, vdp: bool) -> str | None:
    """Why the video JOD will not run (None when it will): not asked for, ColorVideoVDP
    missing, or the frames too many for this machine's memory."""
    if not vdp:
        return "not requested (--no-vdp)"
    reason = vdp_unavailable_reason()
    if reason:
        return reason
    memory, needed = physical_memory(), video_bytes(count, size)
    if memory is not None and needed > VIDEO_MEMORY_SHARE * memory:
        return (f"the {count} frames as a video need {needed / 1e9:.1f} GB, more than a quarter of "
                f"this machine's {memory / 1e9:.1f} GB; compare fewer frames (--frames)")
    return None


def compare_sequence(pairs: list[FramePair], size: FrameSize, exposure_ev: float = 0.0,
                     fps: float = DEFAULT_FPS, vdp: bool = True,
                     each: Callable[[FrameComparison], None] | None = None) -> dict:
    """Compare every frame pair, in order, and the sequence as a whole.

    Parameters
    ----------
    pairs
        The matched frames (:func:`~.frame_sequence.match_frames`), checked
        (:func:`~.frame_sequence.check_frames`, which gave ``size``).
    exposure_ev
        Exposure of the display transform for HDR frames (as ``compare --exposure``).
    fps
        Frames per second of the video JOD.
    vdp
        False leaves the video JOD out (reported as skipped, never a zero).
    each
        Called with every frame's :class:`FrameComparison` once it is made (heatmaps,
        thumbnails), before the next frame is read.

    Returns
    -------
    dict
        ``frames``: per frame ``frame``, ``reference``, ``test`` (paths), ``flip``,
        ``flip_tile95``, ``flip_share``, ``mse``, ``flicker`` (None for the first frame) and
        ``metrics`` (every metric's summary, as single-image ``compare`` gives it);
        ``sequence``: :func:`summarise`'s summary.
    """
    skip = video_skip_reason(len(pairs), size, vdp)
    video = None if skip else np.empty((2, len(pairs), size.height, size.width, 3), np.float16)
    meter = TemporalError()
    records = []
    for index, files in enumerate(pairs):
        pair = read_pair(files.reference, files.test)
        results = compare_images(pair, exposure_ev, vdp=False)
        results["vdp"] = MetricResult.skip("vdp", PER_FRAME_VDP)
        reference_display, test_display = display_pair(pair, exposure_ev)
        flicker = meter.add(reference_display, test_display)
        if video is not None:
            video[0, index], video[1, index] = reference_display, test_display
        summaries = {name: result.summary() for name, result in results.items()}
        values = metric_values(summaries)
        record = {"frame": files.frame, "reference": os.fspath(files.reference), "test": os.fspath(files.test),
                  **{metric: values[metric] for metric in FRAME_METRICS}, "flicker": flicker,
                  "metrics": summaries}
        records.append(record)
        if each is not None:
            each(FrameComparison(files.frame, results, reference_display, test_display, record))
    video_jod = vdp_video(video[0], video[1], fps) if video is not None else {"jod": None, "skipped": skip}
    return {"frames": records, "sequence": summarise(records, meter.result(), video_jod, fps)}


def summarise(records: list[dict], temporal: dict, video_jod: dict, fps: float) -> dict:
    """The sequence's summary: ``count``, ``frame_numbers``, ``fps``, ``mean`` and
    ``worst`` (``{"frame", "value"}``, the highest) of each per-frame figure of
    :data:`FRAME_METRICS`, ``flicker`` (:meth:`~.temporal.TemporalError.result`) and ``vdp``
    (:func:`~.vdp.vdp_video`)."""
    mean, worst = {}, {}
    for metric in FRAME_METRICS:
        values = [(record[metric], record["frame"]) for record in records if record[metric] is not None]
        mean[metric] = float(np.mean([value for value, _ in values])) if values else None
        if values:
            value, frame = max(values, key=lambda item: item[0])
            worst[metric] = {"frame": frame, "value": value}
        else:
            worst[metric] = None
    return {"count": len(records), "frame_numbers": [record["frame"] for record in records], "fps": float(fps),
            "mean": mean, "worst": worst, "flicker": temporal, "vdp": video_jod}


def frame_heatmap_path(folder: str | os.PathLike, metric: str, frame: int) -> Path:
    """Where ``compare --heatmap-dir DIR`` keeps a frame's map of a sequence:
    ``DIR/<metric>_<frame, 4 digits>.png``, Blender's padding."""
    return Path(folder) / f"{metric}_{frame:04d}.png"
