"""report.html of ``xsl-render curves``: the plot and the table of every run with its
equal-quality speedups, one self-contained file (the plot as a data URI, no script).

``speedup_cell`` and ``SPEEDUP_NOTE`` are shared with the validation report, which shows the
same figures for ``experiment`` and ``demo``.
"""
from __future__ import annotations

import os
from html import escape
from pathlib import Path

from ..files import write_text
from .curves_results import frame_count
from .report_images import data_uri
from .report_style import CSS

SPEEDUP_NOTE = ("Equal-quality speedup: the time the baseline curve needs to reach the run's error "
                "(read log-log along the curve's lower envelope) divided by the run's time; above "
                "1.00&times; (in bold) the run is faster at equal quality, otherwise it is not. "
                "<b>*</b> extrapolated beyond the curve's measured range along its end segment.")
METRIC_LABELS = {"flip": "FLIP", "flip_tile95": "FLIP p95 region", "flip_share": "% FLIP > 0.103",
                 "mse": "MSE", "flicker": "flicker", "jod": "JOD"}
_FORMATS = {"flip": ".4f", "flip_tile95": ".4f", "flip_share": ".2f", "mse": ".3g", "flicker": ".4f", "jod": ".3f"}


def speedup_cell(speedup: dict | None) -> str:
    """A table cell: the speedup, bold when faster, a star when extrapolated, '-' (with the
    reason as a tooltip) when it cannot be read."""
    if not speedup or speedup.get("value") is None:
        reason = escape((speedup or {}).get("reason") or "", quote=True)
        return f"<td class=skip title='{reason}'>-</td>"
    value, star = speedup["value"], "*" if speedup.get("extrapolated") else ""
    title = f"the curve needs {speedup['time_to_reach_s']:.2f} s" + (", extrapolated" if star else "")
    css = "win" if speedup.get("faster") else "lose"
    return f"<td class={css} title='{escape(title, quote=True)}'>{value:.2f}&times;{star}</td>"


def _value(value, spec: str) -> str:
    return "<td class=skip>-</td>" if value is None else f"<td>{format(value, spec)}</td>"


def curves_table(data: dict) -> str:
    """Every run in curve order: time, samples, errors and speedups over each baseline."""
    baselines = [name for name, curve in data["curves"].items() if curve["baseline"]]
    metrics = [m for m in data["metrics"] if m != "jod" or any(r.get("jod") is not None
                                                               for r in data["runs"].values())]
    count = frame_count(data)
    time_head = f"time of the {count} frames" if count else "time"
    head = (f"<tr><th class=l rowspan=2>run</th><th rowspan=2>{time_head}</th><th rowspan=2>mean spp</th>"
            + "".join(f"<th rowspan=2>{METRIC_LABELS[m]}</th>" for m in metrics)
            + "".join(f"<th colspan={len(metrics)}>speedup over {escape(data['curves'][b]['label'])}</th>"
                      for b in baselines)
            + "</tr><tr>" + "".join(f"<th>{METRIC_LABELS[m]}</th>" for _ in baselines for m in metrics)
            + "</tr>")
    rows = []
    for curve_name, curve in data["curves"].items():
        for name in curve["points"]:
            run = data["runs"][name]
            repeats = len(run["repeats"])
            time_cell = f"{run['seconds']:.2f} s" + (f" <span class=note>(median of {repeats})</span>"
                                                     if repeats > 1 else "")
            cells = [f"<td class=l>{escape(run['label'])}</td>", f"<td>{time_cell}</td>",
                     _value(run["mean_spp"], ".1f")]
            cells += [_value(run.get(m), _FORMATS[m]) for m in metrics]
            for baseline in baselines:
                speedups = run["speedups"].get(baseline)
                if speedups is None:
                    cells.append(f"<td class=skip colspan={len(metrics)}>its own curve</td>")
                else:
                    cells += [speedup_cell(speedups.get(m)) for m in metrics]
            css = " class=gold" if run.get("gold") else (" class=equal" if curve["baseline"] else "")
            rows.append(f"<tr{css}>{''.join(cells)}</tr>")
    return f"<table>{head}{''.join(rows)}</table><p class=note>{SPEEDUP_NOTE}</p>"


def write_curves_report(data: dict, out_dir: str | os.PathLike, png: str | os.PathLike,
                        name: str = "report.html") -> Path:
    """Write ``out_dir/name``: header, the plot, the table."""
    scene, reference = data["scene"], data["reference"]
    inputs = reference.get("inputs", {})
    vdp = data.get("vdp", {})
    png = Path(png)
    count = frame_count(data)
    where = f"frame {scene['frame']}" if not count else f"frames {escape(scene.get('frame_range', ''))}"
    body = [
        f"<h1>Time-quality curves: {escape(scene['scene'])}"
        + (f", mean over {count} frames" if count else "") + "</h1>",
        f"<p class=meta>{escape(Path(scene['file']).name)}, {where}, "
        f"{scene['size'][0]}x{scene['size'][1]} pixels, ceiling {data['ceiling']} spp (the gold "
        f"standard: uniform at the ceiling). {data['repeats']} repeat(s) per run with seeds "
        f"{', '.join(map(str, data['seeds']))}: median time and median error. Every error is "
        f"measured against a converged reference of {inputs.get('spp', '?')} spp, seed "
        f"{inputs.get('seed', '?')} ({escape(str(reference.get('source')))}), denoised like every "
        "run. A run's time is everything it does: maps, scene sync, renders, denoising. "
        "Wall times depend on what else the machine was doing.</p>",
        (f"<p class=meta>Each run renders the {count} frames one after another in one Cycles "
         "session, as an animation render does (the scene synced once): its time is the whole "
         "run, each error the mean over its frames, each frame measured against that frame's "
         "reference; flicker is the error of the frame-to-frame changes against the "
         "reference's own (0: no flicker), JOD the sequence's seen as a video at "
         f"{scene.get('fps', 24):g} frames a second.</p>" if count else ""),
        "<p class=meta>" + ("VDP: ColorVideoVDP JOD (10 = no visible difference)." if vdp.get("ran")
                            else f"VDP skipped: {escape(str(vdp.get('skipped')))}") + "</p>",
        f"<figure><img alt='time-quality curves' src='{data_uri(png)}'></figure>" if png.is_file() else "",
        "<h2>Every run</h2>", curves_table(data),
    ]
    for warning in data.get("warnings", []):
        body.append(f"<p class=note>warning: {escape(warning)}</p>")
    html = ("<!DOCTYPE html><html lang=en><head><meta charset=utf-8>"
            "<meta name=viewport content='width=device-width,initial-scale=1'>"
            f"<title>xsl_render curves: {escape(scene['scene'])}</title>"
            f"<style>{CSS}</style></head><body>{''.join(body)}</body></html>\n")
    return write_text(Path(out_dir) / name, html)
