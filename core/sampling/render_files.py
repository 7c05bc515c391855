"""The files of one rendered frame: the image, its samples per pixel and the statistics.

``FILE.exr`` (RGBA float, scene-linear), ``FILE_spp.exr`` (samples per pixel, one channel)
and ``FILE_spp.png`` (grey level = spp / max_spp), the same for ``xsl-render render``, the
batch entry and the panel's operators. Every write is atomic, the three files together.

A frame of a range also carries, in its EXR headers, the digest of what it was made from
(``REQUEST_ATTRIBUTE``: the request, the scene's inputs, the frame) and its statistics, so
that a rerun of the same request keeps it (``finished_frame``).
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import output_set, write_json
from ..imageio import image_attributes, write_exr, write_png
from .render_stats import RenderStats

#: EXR header attributes of a frame of a range: what it was made from, and its statistics.
REQUEST_ATTRIBUTE, STATS_ATTRIBUTE = "xsl_render:request", "xsl_render:stats"


def spp_paths(out: Path) -> tuple[Path, Path]:
    """FILE.exr -> (FILE_spp.exr, FILE_spp.png)."""
    out = Path(out)
    return out.with_name(out.stem + "_spp.exr"), out.with_name(out.stem + "_spp.png")


def render_output_paths(out: str | Path, stats_path: str | Path | None = None) -> dict[str, Path | None]:
    """What :func:`write_render_outputs` writes, by the name a user knows it by."""
    spp_exr, spp_png = spp_paths(Path(out))
    return {"--out": Path(out), "its samples": spp_exr, "its samples preview": spp_png,
            "--stats": Path(stats_path) if stats_path else None}


def frame_attributes(mode: str, max_spp: int, seed: int, mean_spp: float) -> dict:
    """The EXR header attributes of a rendered frame and its samples image (the _spp.png's
    white level as ``max_spp``)."""
    return {"xsl_render:mode": mode, "xsl_render:max_spp": max_spp, "xsl_render:seed": seed,
            "xsl_render:mean_spp": float(mean_spp)}


def preview_scale(ceiling: int | None, samples: np.ndarray) -> int:
    """The samples per pixel a _spp.png shows as white: the ceiling, or without one (a
    guided render without --max-spp) the most any pixel got."""
    return max(1, int(np.max(samples))) if ceiling is None else int(ceiling)


def write_render_outputs(out: str | Path, image: np.ndarray, samples: np.ndarray, stats: RenderStats,
                         max_spp: int, seed: int, stats_path: str | Path | None = None,
                         request: str | None = None) -> list[Path]:
    """Write the image and its samples (and ``stats`` as JSON when ``stats_path`` is given),
    all together or none (``core.files.output_set``); ``request``: the digest of what the
    frame was made from, kept in both EXR headers (the image's with ``stats``) for a rerun.

    The time the writes took is added to ``stats`` as the "write" phase (and so to its wall time).
    """
    out = Path(out)
    started = time.perf_counter()
    attributes = frame_attributes(stats.mode, max_spp, seed, stats.mean_spp)
    own = {}
    if request is not None:
        attributes[REQUEST_ATTRIBUTE] = request
        own = {STATS_ATTRIBUTE: json.dumps(stats.to_json(), separators=(",", ":"))}
    spp_exr, spp_png = spp_paths(out)
    with output_set():
        written = [write_exr(out, image, ["R", "G", "B", "A"], attributes=attributes | own),
                   write_exr(spp_exr, samples, ["Y"], attributes=attributes),
                   write_png(spp_png, samples / float(max_spp))]
        stats.phases_s["write"] = time.perf_counter() - started
        if stats_path:
            written.append(write_json(stats_path, stats.to_json()))
    return written


def finished_frame(out: str | Path, request: str) -> RenderStats | None:
    """The statistics of the frame at ``out`` when its three files are there and were made
    from ``request`` (``write_render_outputs``), else None."""
    out = Path(out)
    spp_exr, spp_png = spp_paths(out)
    if not (out.is_file() and spp_exr.is_file() and spp_png.is_file()):
        return None
    try:
        image, samples = image_attributes(out), image_attributes(spp_exr)
        if image.get(REQUEST_ATTRIBUTE) != request or samples.get(REQUEST_ATTRIBUTE) != request:
            return None
        return RenderStats.from_json(json.loads(str(image.get(STATS_ATTRIBUTE))))
    except (InputError, OSError, ValueError, TypeError, AttributeError):
        return None
