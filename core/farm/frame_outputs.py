"""The finished files of a farm frame, written as one set, and how a rerun knows they are current.

``frame_NNNN.exr`` (RGBA), ``frame_NNNN_spp.exr`` / ``_spp.png`` (samples per pixel) and
``frame_NNNN.json`` (the statistics, which are also the frame's record: the digest of what
the frame was made from and the hashes of its images). All four are written under temporary
names and renamed into place only once every one is written, the record last
(``core.files.atomic_paths``), so a task killed at any moment leaves the previous set or the
new one, and a frame counts as finished only when its record names the same inputs and its
images still have the recorded hashes. The selective job's composite step and the guided
job's render step both finish their frames here.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..files import atomic_paths, file_sha256, json_digest, write_json
from ..imageio import write_exr, write_png
from .files import RECORD_FORMAT, FrameFiles, read_record, recorded_file_intact, remove_partial_files

#: The record kind of a finished frame (selective composite and guided render alike).
FRAME_KIND = "xsl-render farm frame"


@dataclass(frozen=True)
class FrameSummary:
    """What a task reports of a finished frame, read from its record."""

    resolution: tuple[int, int]
    mean_spp: float
    renders: int
    wall_s: float
    time_budget_s: float | None = None      # a guided frame's
    cycles_sync_s: float | None = None

    @classmethod
    def from_record(cls, record: dict) -> "FrameSummary":
        return cls(tuple(record["resolution"]), float(record["mean_spp"]), int(record["renders"]),
                   float(record["wall_s"]), record.get("time_budget_s"), record.get("cycles_sync_s"))


def valid_frame_outputs(files: FrameFiles, inputs_digest: str) -> dict | None:
    """The frame's statistics when its files are finished and were made from the inputs of
    ``inputs_digest``, else None."""
    record = read_record(files.stats)
    if record is None or record.get("inputs") != inputs_digest:
        return None
    if not (recorded_file_intact(record, "image_sha256", files.image)
            and recorded_file_intact(record, "spp_sha256", files.spp_image)):
        return None
    return record


def guided_frame_record(inputs: dict, stats: dict) -> dict:
    """The statistics of a guided render as the record of a frame made from ``inputs``
    (``core.farm.files.guided_inputs``); the image hashes are filled in when written."""
    return {"format": RECORD_FORMAT, "kind": FRAME_KIND, "inputs": json_digest(inputs),
            "image_sha256": None, "spp_sha256": None, **stats, "inputs_detail": inputs}


def write_frame_outputs(files: FrameFiles, image: np.ndarray, samples: np.ndarray, spp_scale: float,
                        attributes: dict, record: dict) -> dict:
    """Write the frame's image, samples and ``stats`` as one set (see the module docstring).

    ``record`` is the frame's statistics as its record (``format``, ``kind``, ``inputs``);
    the images' hashes, the time the writes took (phase "write") and ``wall_s`` (the sum of
    the phases) are added. The PNG's grey level is spp / ``spp_scale``. Returns ``record``.
    """
    started = time.perf_counter()
    for path in (files.image, files.spp_image, files.spp_preview, files.stats):
        remove_partial_files(path)
    with atomic_paths(files.image, files.spp_image, files.spp_preview, files.stats) as temporaries:
        image_path, spp_path, preview_path, stats_path = temporaries
        write_exr(image_path, image, ["R", "G", "B", "A"], attributes=attributes, atomic=False)
        write_exr(spp_path, samples, ["Y"], attributes=attributes, atomic=False)
        write_png(preview_path, samples / float(spp_scale), atomic=False)
        record["image_sha256"] = file_sha256(image_path)
        record["spp_sha256"] = file_sha256(spp_path)
        record["phases_s"]["write"] = time.perf_counter() - started
        record["wall_s"] = sum(record["phases_s"].values())
        write_json(stats_path, record, atomic=False)
    return record
