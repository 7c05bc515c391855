"""The validation report: one self-contained HTML file (images as data URIs, inline CSS and
SVG, no script) built from results.json and the files beside it.

First, every run of every scene against the converged reference with its equal-quality
speedup over uniform sampling (``report_reference``); then the paper's measure, Tables I and
II against the gold standard (which shares the runs' seed) in the paper's layout. Per scene:
the file and Auto Volumes in the same time (the main job), the director maps, the gold
standard and the XSL render with a magnified crop around the lights, the runs against the
reference, the timing chart (Fig. 8), the paper's tables, and every variant with its sample
counts and difference heatmaps.
"""
from __future__ import annotations

import os
from html import escape
from pathlib import Path

from ..files import write_text
from ..imageio import read_image
from .metrics import FLIP_ERROR_THRESHOLD, MSE_ERROR_THRESHOLD
from .plan import AUTO_RUN, FILE_RUN
from .report_chart import Bar, timing_chart_svg
from .report_images import crop, data_uri, display_image, light_crop_box, write_display_png
from .report_reference import reference_tables, scene_reference_table
from .report_style import CSS
from .vdp import VDP_ERROR_PROBABILITY

METRICS = (("mse", "MSE"), ("vdp", "VDP"), ("flip", "FLIP"))
MAP_LABELS = (("x", "X: transmittance"), ("s", "S: saliency"), ("l", "L: lights"),
              ("xs", "XS"), ("xsl", "XSL"))
#: The runs shown magnified around the lights, when the scene has them.
CROP_RUNS = ("gold", "auto_equal_time", "xsl", "xs", "uniform_equal_time", "adaptive_equal_time",
             "guided_equal_time")
#: The columns of the paper-layout tables: the selective runs the paper reports.
PAPER_COLUMNS = (("xs", "XS"), ("xsl", "XSL"))
SPEED_COLUMNS = PAPER_COLUMNS + (("uniform_equal_time", "uniform"), ("adaptive_equal_time", "adaptive"),
                                 ("guided_equal_time", "guided"))



def write_report(results: dict, out_dir: str | os.PathLike, name: str = "report.html") -> Path:
    """Write ``out_dir/name`` (atomically) from results.json's content; returns its path."""
    out_dir = Path(out_dir)
    return write_text(out_dir / name, build_report(results, out_dir))


def build_report(results: dict, out_dir: Path) -> str:
    scenes = results.get("scenes", {})
    settings = results.get("settings", {})
    vdp = results.get("vdp", {})
    ceilings = sorted({scene.get("max_spp") for scene in scenes.values()} - {None})
    head = (f"<p class=meta>Ceiling {' and '.join(map(str, ceilings)) or '-'} samples per pixel "
            f"(the gold standard's count everywhere), Cycles seed {settings.get('seed')}. "
            "Times as in the paper's Fig. 8: a selective render's time includes making the maps it "
            "uses. The equal-time baselines get the wall time of the XSL run, maps included, as "
            "Cycles' time limit (each then pays its own denoising pass, as XSL did); guided, where "
            "it ran, gets all of it as its budget, its denoising included, and chooses its volume "
            "estimator and sample pattern per scene (auto). Auto Volumes renders the file with "
            "auto's choice at the file's samples and in the gold standard's time (the file as it "
            "renders, its own settings), stopped by Cycles' time limit; the other "
            "uniform runs render 1/8, 1/4 and 1/2 of the ceiling. Wall times (and so speedups) "
            "depend on what else the machine was doing; sample ratios do not. "
            + ("Every frame, the gold standard's too, was denoised with Open Image Denoise "
               "(albedo and normal guided) before it was compared." if settings.get("denoise", False)
               else "No frame was denoised: the raw path-traced frames are compared.")
            + "</p>")
    vdp_line = ("VDP: ColorVideoVDP, probability of detection per pixel." if vdp.get("ran")
                else f"VDP skipped: {escape(str(vdp.get('skipped')))}")
    body = [
        "<h1>xsl_render: Auto Volumes, and the paper's perceptual rendering of participating "
        "media</h1>", head,
        f"<p class=meta>{vdp_line}</p>",
        "<p class=note>Images are shown and compared through Blender's Standard view "
        "(exposure 0, clamp, sRGB). Error pixel: MSE squared error &gt; "
        f"{MSE_ERROR_THRESHOLD:.2e} (one JND on mid grey), FLIP &gt; {FLIP_ERROR_THRESHOLD:g}, "
        f"VDP probability &gt; {VDP_ERROR_PROBABILITY:g} (the paper's threshold).</p>",
        reference_tables(scenes),
        _paper_tables(scenes),
    ]
    for scene_name, scene in scenes.items():
        body.append(_scene_section(scene_name, scene, out_dir))
    return ("<!DOCTYPE html><html lang=en><head><meta charset=utf-8>"
            "<meta name=viewport content='width=device-width,initial-scale=1'>"
            "<title>xsl_render validation</title>"
            f"<style>{CSS}</style></head><body>{''.join(body)}</body></html>\n")


# -- numbers -----------------------------------------------------------------------------
def _metric(run: dict, metric: str, key: str, digits: int = 2, suffix: str = "%") -> str:
    summary = run.get("metrics", {}).get(metric)
    if not summary:
        return "<td class=skip>-</td>"
    if summary.get("skipped"):
        return f"<td class=skip title='{escape(summary['skipped'], quote=True)}'>skipped</td>"
    value = summary.get(key)
    return "<td class=skip>-</td>" if value is None else f"<td>{_number(value, digits)}{suffix}</td>"


def _number(value: float, digits: int = 2) -> str:
    """``digits`` decimals, but small values keep three significant digits (0.0042, not 0.00)."""
    return f"{value:.{digits}f}" if abs(value) >= 10 ** (1 - digits) or value == 0 else f"{value:.3g}"


def _paper_tables(scenes: dict) -> str:
    columns = [(name, key, f"{name} {label}") for name, scene in scenes.items()
               for key, label in PAPER_COLUMNS if key in scene.get("runs", {})]
    if not columns:
        return ""
    header = "<tr><th class=l></th>" + "".join(f"<th>{escape(c[2])}</th>" for c in columns) + "</tr>"
    out = []
    for title, key in (("Table I: average pixel error against the gold standard (the paper's measure)",
                        "average_error_percent"),
                       ("Table II: error pixels against the gold standard (the paper's measure)",
                        "error_pixel_percent")):
        rows = "".join(
            f"<tr><td class=l>{label}</td>"
            + "".join(_metric(scenes[name]["runs"][run], metric, key) for name, run, _ in columns) + "</tr>"
            for metric, label in METRICS)
        out.append(f"<h3>{title}</h3><table>{header}{rows}</table>")
    rows = []
    for name, scene in scenes.items():
        shown = [(key, label) for key, label in SPEED_COLUMNS if key in scene.get("runs", {})]
        for index, (key, label) in enumerate(shown):
            run = scene["runs"][key]
            first = f"<td class=l rowspan={len(shown)}>{escape(name)}</td>" if index == 0 else ""
            css = " class=equal" if run.get("kind") in ("uniform", "adaptive") else ""
            rows.append(f"<tr{css}>{first}<td class=l>{escape(run.get('label', key))}</td>"
                        f"<td>{_speedup(run)}</td><td>{_ratio(run)}</td>"
                        f"{_metric(run, 'flip', 'mean_flip', 4, '')}"
                        f"{_metric(run, 'mse', 'average_error_percent')}</tr>")
    out.append("<h3>Time and error against the gold standard "
               "<span class=note>(maps included in the selective times; uniform and adaptive got "
               "XSL's time to render in, guided all of it, its denoising included; the time ratio is "
               "not a speedup at equal quality)</span></h3><table>"
               "<tr><th class=l>scene</th><th class=l>run</th>"
               "<th>gold's time / run's time</th><th title='gold samples / samples of the run: the "
               "ratio a renderer without fixed costs would get'>sample ratio</th>"
               "<th>mean FLIP</th><th>MSE average error</th></tr>"
               f"{''.join(rows)}</table>")
    return ("<h2>The paper's measure: against the gold standard</h2><p class=meta>As in the paper's "
            "Tables I and II, each run against the gold standard, rendered with the runs' own seed: "
            "every run shares gold's first samples, and gold's own noise hides part of the "
            "difference, so these errors are smaller than against the converged reference above "
            "(guided, where it ran, renders with auto's estimator and sample pattern, so it shares "
            "none of them: against gold it looks worse than it is).</p>"
            + "".join(out))


def _speedup(run: dict) -> str:
    value = run.get("speedup_over_gold")
    return "-" if value is None else f"{value:.2f}&times;"


def _ratio(run: dict) -> str:
    value = run.get("sample_ratio_over_gold")
    return "-" if value is None else f"{value:.2f}&times;"


def _scene_table(runs: dict) -> str:
    head = ("<tr><th class=l rowspan=2>run</th><th rowspan=2>time</th><th rowspan=2>gold's time / "
            "run's</th>"
            "<th rowspan=2>mean spp</th><th colspan=3>average pixel error (Table I)</th>"
            "<th colspan=3>error pixels (Table II)</th><th rowspan=2>mean FLIP</th>"
            "<th rowspan=2>JOD</th></tr><tr>" + "<th>MSE</th><th>VDP</th><th>FLIP</th>" * 2 + "</tr>")
    rows = []
    for name, run in runs.items():
        css = "gold" if name == "gold" else ("equal" if run.get("kind") in ("uniform", "adaptive") else "")
        time_cell = f"{run['time_s']:.2f} s"
        if run.get("maps_s"):
            time_cell += f" <span class=note>({run['maps_s']:.2f} maps)</span>"
        if run.get("done_early"):
            time_cell += " <span class=note title='every sample rendered before the limit'>(done early)</span>"
        cells = [f"<td class=l>{escape(run.get('label', name))}</td>", f"<td>{time_cell}</td>",
                 f"<td>{'-' if name == 'gold' else _speedup(run)}</td>",
                 f"<td>{run.get('mean_spp', 0):.2f}</td>"]
        if name == "gold":
            cells.append("<td class=skip colspan=8>the reference</td>")
        else:
            cells += [_metric(run, m, "average_error_percent") for m, _ in METRICS]
            cells += [_metric(run, m, "error_pixel_percent") for m, _ in METRICS]
            cells += [_metric(run, "flip", "mean_flip", 4, ""), _metric(run, "vdp", "jod", 3, "")]
        rows.append(f"<tr class='{css}'>{''.join(cells)}</tr>")
    return f"<table>{head}{''.join(rows)}</table>"


def _chart(scene_name: str, runs: dict) -> str:
    bars = []
    for name, run in runs.items():
        kind = "gold" if name == "gold" else ("equal" if run.get("kind") in ("uniform", "adaptive")
                                              else "guided" if run.get("kind") == "guided" else "render")
        flip = (run.get("equal_quality") or {}).get("flip") or {}
        note = "" if flip.get("value") is None else \
            f"equal FLIP: {flip['value']:.2f}x uniform's speed" + (" (extrapolated)" if flip["extrapolated"] else "")
        bars.append(Bar(run.get("label", name), run.get("maps_s", 0.0), run.get("render_s", 0.0), kind, note))
    return timing_chart_svg(bars, f"{scene_name}: wall time per run")


# -- pictures ----------------------------------------------------------------------------
def _img(path: Path, caption: str, css: str = "", overlay: str = "") -> str:
    if not path.is_file():
        return f"<figure><figcaption class=skip>{escape(caption)}: missing</figcaption></figure>"
    image = f"<img class='{css}' alt='{escape(caption, quote=True)}' src='{data_uri(path)}'>"
    if overlay:
        image = f"<div class=framed>{image}{overlay}</div>"
    return f"<figure>{image}<figcaption>{escape(caption)}</figcaption></figure>"


def _box_overlay(box, shape) -> str:
    row0, row1, col0, col1 = box
    height, width = shape[:2]
    return (f"<div class=box style='left:{100 * col0 / width:.3f}%;top:{100 * row0 / height:.3f}%;"
            f"width:{100 * (col1 - col0) / width:.3f}%;height:{100 * (row1 - row0) / height:.3f}%'></div>")


def _scene_section(scene_name: str, scene: dict, out_dir: Path) -> str:
    runs = scene.get("runs", {})
    folder = out_dir / scene_name
    display_dir = folder / "display"
    size = scene.get("size", ["?", "?"])
    parts = [f"<h2 id='{escape(scene_name, quote=True)}'>{escape(scene_name)}</h2>",
             f"<p class=meta>{size[0]}x{size[1]} pixels, ceiling {scene.get('max_spp')} spp. "
             f"File {escape(Path(scene.get('file', '')).name)}.</p>"]
    for warning in scene.get("warnings", []):
        parts.append(f"<p class=note>warning: {escape(warning)}</p>")

    maps_info = scene.get("maps", {}).get("minbound") or next(iter(scene.get("maps", {}).values()), None)
    l_map = None
    if maps_info:
        maps_dir = out_dir / maps_info["folder"]
        seconds = maps_info.get("seconds", {})
        parts.append(f"<h3>Director maps <span class=note>({seconds.get('total', 0):.2f} s"
                     f"{', MinBound' if maps_info.get('minbound') else ''})</span></h3><div class='grid maps'>")
        for key, label in MAP_LABELS:
            parts.append(_img(maps_dir / "preview" / f"{key}.png", label))
        parts.append("</div>")
        if (maps_dir / "l.exr").is_file():
            l_map = read_image(maps_dir / "l.exr")[..., 0]

    displays = {}
    for name, run in runs.items():
        display = display_image(out_dir / run["files"]["image"])
        displays[name] = display
        write_display_png(display_dir / f"{name}.png", display)
    if "gold" not in displays:
        return "".join(parts)
    parts[2:2] = [_main_job(runs, display_dir)] if AUTO_RUN in displays else []
    box, where = light_crop_box(l_map, displays["gold"])
    overlay = _box_overlay(box, displays["gold"].shape)
    shown = "xsl" if "xsl" in displays else next((n for n in displays if n != "gold"), None)
    parts.append("<h3>Gold standard and selective rendering</h3><div class='grid pair'>")
    parts.append(_img(display_dir / "gold.png", runs["gold"]["label"], overlay=overlay))
    if shown:
        flip = (runs[shown].get("reference_metrics") or {}).get("flip") or {}
        against = f", mean FLIP {flip['mean_flip']:.4f} against the reference" if flip.get("mean_flip") is not None else ""
        parts.append(_img(display_dir / f"{shown}.png", f"{runs[shown]['label']}: "
                          f"{runs[shown]['time_s']:.2f} s{against}", overlay=overlay))
    parts.append("</div>")
    parts.append(f"<h3>Around the lights <span class=note>(crop: {escape(where)}; "
                 "magnified, pixels kept sharp)</span></h3><div class='grid crops'>")
    for name in CROP_RUNS:
        if name in displays:
            path = write_display_png(display_dir / f"{name}_crop.png", crop(displays[name], box))
            parts.append(_img(path, runs[name]["label"], css="zoom"))
    parts.append("</div>")

    parts.append(scene_reference_table(scene_name, scene))
    parts.append("<h3>Time (Fig. 8)</h3>" + _chart(scene_name, runs))
    parts.append("<h3>Against the gold standard (the paper's measure)</h3>" + _scene_table(runs))

    parts.append("<h3>Every run: FLIP against the converged reference, and every metric against "
                 "the gold standard <span class=note>(samples per pixel: white = ceiling; heatmaps: "
                 "magma, bright = large difference, error-pixel threshold at the same colour for MSE "
                 "and FLIP)</span></h3>")
    heatmaps = [m for m in ("flip", "mse", "vdp")
                if any(run.get("heatmaps", {}).get(m) for run in runs.values())]
    parts.append(f"<div class='grid runs' style='grid-template-columns:1.1fr repeat({3 + len(heatmaps)},1fr)'>")
    parts += ["<div></div>", "<div class=note>image</div>", "<div class=note>samples per pixel</div>",
              "<div class=note>FLIP against the reference</div>"]
    parts += [f"<div class=note>{m.upper()} against gold</div>" for m in heatmaps]
    for name, run in runs.items():
        parts.append(f"<div class=name>{escape(run.get('label', name))}</div>")
        parts.append(_img(display_dir / f"{name}.png", f"{run['time_s']:.2f} s"))
        parts.append(_img(out_dir / run["files"]["spp_png"], f"mean {run.get('mean_spp', 0):.2f} spp"))
        flip = run.get("reference_metrics", {}).get("flip", {})
        path = run.get("reference_heatmaps", {}).get("flip")
        parts.append(_img(out_dir / path, f"mean FLIP {flip.get('mean_flip', 0):.4f}") if path
                     else "<div class=note>-</div>")
        for metric in heatmaps:
            parts.append(_heatmap_cell(run, metric, out_dir, name == "gold"))
    parts.append("</div>")
    if "vdp" not in heatmaps:
        parts.append("<p class=note>No VDP heatmaps: VDP did not run (see the top of the report).</p>")
    return "".join(parts)


def _main_job(runs: dict, display_dir: Path) -> str:
    """The file as it renders beside Auto Volumes in the same time, each with its time, samples
    and error against the reference, and Auto Volumes' equal-quality speedup along the file's
    curve; then Auto Volumes at the file's own samples, where it ran."""
    def caption(name: str) -> str:
        run = runs[name]
        flip = ((run.get("reference_metrics") or {}).get("flip") or {}).get("mean_flip")
        label = "The file as it renders (the gold standard)" if name == FILE_RUN else run["label"]
        words = f"{label}: {run['time_s']:.2f} s, {run.get('mean_spp', 0):.0f} spp"
        return words + (f", mean FLIP {flip:.4f}" if flip is not None else "")

    speedup = ((runs[AUTO_RUN].get("equal_quality") or {}).get("flip") or {}).get("value")
    faster = (f"Auto Volumes reaches its error {speedup:.2f}&times; sooner than the file does "
              "(mean FLIP, read along the file's own time-quality curve)." if speedup else
              "No equal-quality speedup could be read (the file's curve needs two points).")
    same = runs.get("auto_file_samples")
    if same is not None:
        faster += (f" At the file's own samples it took {same['time_s']:.2f} s against "
                   f"{runs[FILE_RUN]['time_s']:.2f} s.")
    return ("<h3>The file and Auto Volumes in the same time</h3><div class='grid pair'>"
            + _img(display_dir / f"{FILE_RUN}.png", caption(FILE_RUN))
            + _img(display_dir / f"{AUTO_RUN}.png", caption(AUTO_RUN))
            + f"</div><p class=note>{faster}</p>")


def _heatmap_cell(run: dict, metric: str, out_dir: Path, reference: bool) -> str:
    if reference:
        return "<div class=note>reference</div>"
    summary = run.get("metrics", {}).get(metric, {})
    if summary.get("skipped"):
        return f"<div class=note>{metric.upper()} skipped: {escape(summary['skipped'])}</div>"
    path = run.get("heatmaps", {}).get(metric)
    if not path:
        return "<div class=note>-</div>"
    caption = (f"{_number(summary.get('average_error_percent', 0))}% avg, "
               f"{_number(summary.get('error_pixel_percent', 0))}% error px")
    return _img(out_dir / path, caption)
