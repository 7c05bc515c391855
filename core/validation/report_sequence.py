"""report.html of ``xsl-render compare`` on two sequences: the sequence's figures, the
per-frame curves of mean FLIP and p95-tile FLIP, a strip of frames (test, reference, FLIP
heat map) and every frame's numbers; one self-contained file (pictures as data URIs, the
chart as inline SVG, no script), like the other reports."""
from __future__ import annotations

import math
import os
import tempfile
from html import escape
from pathlib import Path

import numpy as np

from ..files import write_text
from ..imageio import write_png
from .heatmap import colourise
from .report_chart import Line, line_chart_svg
from .report_images import data_uri
from .report_style import CSS
from .sequence import FrameComparison

#: Width of a thumbnail in pixels (frames are shrunk by a whole factor to at most this).
THUMB_WIDTH = 192
#: Frames drawn in the strip at most: evenly spaced, the worst frame always among them.
STRIP_MAX = 24
LABELS = {"flip": "mean FLIP", "flip_tile95": "p95 of 32-px tile FLIP", "flip_share": "% px FLIP > 0.103",
          "mse": "MSE"}
FORMATS = {"flip": ".4f", "flip_tile95": ".4f", "flip_share": ".2f", "mse": ".3g"}
COLOURS = {"flip": "#3b6ea5", "flip_tile95": "#c0392b"}
_CSS = """
.strip{display:grid;grid-auto-flow:column;grid-template-rows:auto auto auto auto;
       grid-template-columns:72px;grid-auto-columns:minmax(110px,180px);gap:4px 6px;overflow-x:auto;
       padding-bottom:6px}
.strip .row{font-size:12px;color:#444;align-self:center;white-space:nowrap}
.strip .cap{font-size:12px;color:#222;white-space:nowrap}.strip .worst{color:#8a1c1c;font-weight:700}
td.wrap{white-space:normal;max-width:560px;text-align:left}
"""


def shrink(image: np.ndarray, width: int = THUMB_WIDTH) -> np.ndarray:
    """``image`` (``(H, W)`` or ``(H, W, C)``) shrunk by the smallest whole factor that makes
    it at most ``width`` wide, each new pixel the mean of its block (edges cut)."""
    factor = max(1, math.ceil(image.shape[1] / width))
    if factor == 1:
        return np.asarray(image, dtype=np.float32)
    height, wide = (image.shape[0] // factor) or 1, (image.shape[1] // factor) or 1
    cut = np.asarray(image[:height * factor, :wide * factor], dtype=np.float32)
    blocks = cut.reshape(height, factor, wide, factor, *image.shape[2:])
    return blocks.mean(axis=(1, 3))


class FrameStrip:
    """Thumbnails of every frame as it is compared (test, reference, FLIP heat map), small
    enough to keep for a long sequence; the report draws :data:`STRIP_MAX` of them."""

    def __init__(self) -> None:
        self.thumbnails: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def add(self, comparison: FrameComparison) -> None:
        flip = comparison.results["flip"]
        self.thumbnails[comparison.frame] = (
            shrink(comparison.test_display), shrink(comparison.reference_display),
            colourise(shrink(flip.per_pixel), flip.heatmap_full_scale))


def strip_frames(frames: list[int], worst: int | None, limit: int = STRIP_MAX) -> list[int]:
    """Which frames the strip shows: all when they are few, else ``limit`` evenly spaced
    ones with ``worst`` among them."""
    if len(frames) <= limit:
        return list(frames)
    chosen = {frames[int(round(i))] for i in np.linspace(0, len(frames) - 1, limit - (worst is not None))}
    if worst is not None:
        chosen.add(worst)
    return sorted(chosen)


def _cell(value, spec: str) -> str:
    return "<td class=skip>-</td>" if value is None else f"<td>{format(value, spec)}</td>"


def _summary_table(sequence: dict) -> str:
    rows = ["<tr><th class=l>figure</th><th>mean over frames</th><th>worst frame</th><th>its value</th></tr>"]
    for metric, label in LABELS.items():
        worst = sequence["worst"].get(metric) or {}
        rows.append(f"<tr><td class=l>{label}</td>{_cell(sequence['mean'].get(metric), FORMATS[metric])}"
                    f"<td>{escape(str(worst.get('frame', '-')))}</td>{_cell(worst.get('value'), FORMATS[metric])}</tr>")
    flicker = sequence["flicker"]
    for key, label, note in (("flicker", "flicker (RMS of change errors)", flicker.get("skipped")),
                             ("reference_motion", "reference's own change (RMS)", flicker.get("skipped")),
                             ("relative_flicker", "relative flicker", flicker.get("relative_skipped"))):
        value = flicker.get(key)
        cell = _cell(value, ".4g") if value is not None else f"<td class='skip wrap'>{escape(str(note))}</td>"
        rows.append(f"<tr><td class=l>{label}</td>{cell}<td colspan=2 class=skip></td></tr>")
    vdp = sequence["vdp"]
    jod = (f"<td>{vdp['jod']:.3f}</td><td colspan=2 class=l>{'video' if vdp.get('as_video') else 'image'} "
           f"at {vdp.get('fps', 0):g} fps, {escape(str(vdp.get('display')))}</td>") if vdp.get("jod") is not None \
        else f"<td colspan=3 class='skip wrap'>skipped: {escape(str(vdp.get('skipped')))}</td>"
    rows.append(f"<tr><td class=l>ColorVideoVDP JOD of the sequence</td>{jod}</tr>")
    return f"<table>{''.join(rows)}</table>"


def _frames_table(frames: list[dict]) -> str:
    head = ("<tr><th>frame</th>" + "".join(f"<th>{label}</th>" for label in LABELS.values())
            + "<th>flicker into it</th></tr>")
    rows = [f"<tr><td>{record['frame']}</td>"
            + "".join(_cell(record[metric], FORMATS[metric]) for metric in LABELS)
            + _cell(record["flicker"], ".4g") + "</tr>" for record in frames]
    return f"<table>{head}{''.join(rows)}</table>"


def _strip(data: dict, strip: FrameStrip, folder: Path) -> str:
    frames = [record["frame"] for record in data["frames"] if record["frame"] in strip.thumbnails]
    worst = (data["sequence"]["worst"].get("flip") or {}).get("frame")
    shown = strip_frames(frames, worst)
    by_frame = {record["frame"]: record for record in data["frames"]}
    cells = ["<div class=row></div>", "<div class=row>test</div>", "<div class=row>reference</div>",
             "<div class=row>FLIP</div>"]
    for frame in shown:
        css = " worst" if frame == worst else ""
        cells.append(f"<div class='cap{css}'>frame {frame}: {by_frame[frame]['flip']:.4f}</div>")
        for kind, image in zip(("test", "reference", "FLIP"), strip.thumbnails[frame]):
            png = write_png(folder / f"{kind}_{frame}.png", image, atomic=False)
            cells.append(f"<img class=zoom alt='frame {frame} {kind}' src='{data_uri(png)}'>")
    note = (f"<p class=note>{len(shown)} of {len(frames)} frames, evenly spaced; the frame of the "
            "highest mean FLIP in red.</p>" if len(shown) < len(frames) else
            "<p class=note>The frame of the highest mean FLIP in red.</p>")
    return f"<div class=strip>{''.join(cells)}</div>{note}"


def write_sequence_report(path: str | os.PathLike, data: dict, strip: FrameStrip) -> Path:
    """Write the report of ``data`` (what ``compare --json`` writes for sequences) with the
    thumbnails of ``strip``."""
    sequence, frames = data["sequence"], data["frames"]
    numbers = [record["frame"] for record in frames]
    chart = line_chart_svg(numbers, [Line(LABELS[m], [r[m] for r in frames], COLOURS[m]) for m in COLOURS],
                           title="per-frame FLIP", y_label="FLIP")
    with tempfile.TemporaryDirectory() as folder:
        strip_html = _strip(data, strip, Path(folder))
    body = [
        "<h1>Sequence comparison</h1>",
        f"<p class=meta>Test {escape(str(data['test']))} against reference {escape(str(data['reference']))}: "
        f"{sequence['count']} frames ({numbers[0]} to {numbers[-1]}), {data['width']}x{data['height']} "
        f"pixels, {data['dynamic_range']}; display transform: {escape(data['display_transform'])}.</p>",
        "<h2>The sequence</h2>", _summary_table(sequence),
        "<p class=note>Flicker: the mean over consecutive frames of the RMS of (test change) minus "
        "(reference change) in display values; 0 for a test equal to the reference or with an error "
        "that stands still, growing with noise that changes every frame. Relative: against the "
        "reference's own mean change. JOD: ColorVideoVDP on the whole sequence played at "
        f"{sequence['fps']:g} frames a second (10: no visible difference).</p>",
        "<h2>Per frame</h2>", chart, "<h2>Frames</h2>", strip_html, _frames_table(frames),
    ]
    html = ("<!DOCTYPE html><html lang=en><head><meta charset=utf-8>"
            "<meta name=viewport content='width=device-width,initial-scale=1'>"
            f"<title>xsl_render compare: {escape(Path(str(data['test'])).name)}</title>"
            f"<style>{CSS}{_CSS}</style></head><body>{''.join(body)}</body></html>\n")
    return write_text(path, html)
