"""curves.png: the time-quality curves of ``xsl-render curves`` as two log-log panels,
mean FLIP against seconds and MSE against seconds, one line per curve through the runs'
medians, every repeat as a small point beside them, the gold standard marked. Over frames
the errors are the means over the frames and the seconds those of the whole run."""
from __future__ import annotations

import math
import os
from pathlib import Path

from ..errors import InputError
from ..files import atomic_path
from .curves_results import frame_count

#: Colours and markers per curve (others cycle through matplotlib's defaults).
STYLES = {"uniform": ("#1f1f1f", "o"), "adaptive": ("#8a5fb0", "s"), "guiding": ("#2a9d8f", "^"),
          "xs": ("#d9822b", "D"), "xsl": ("#3b6ea5", "v"), "guided": ("#c0392b", "*"), "guided_xsl": ("#e377c2", "P"),
          "auto": ("#1a7f37", "X"), "guided_auto": ("#c0392b", "*")}
PANELS = (("flip", "mean HDR-FLIP against the reference"), ("mse", "MSE against the reference"))


def write_curves_png(data: dict, path: str | os.PathLike) -> Path:
    """Write the two panels of ``data`` (curves.json's content) as a PNG, atomically."""
    try:
        from matplotlib.figure import Figure
        from matplotlib.ticker import FuncFormatter
    except ImportError:
        raise InputError("the plot needs matplotlib (install it from requirements.lock)") from None
    count = frame_count(data)
    figure = Figure(figsize=(12, 5.2), dpi=110)
    axes = figure.subplots(1, 2)
    # Enough distinct colours for a step-rate sweep (six curves) beside the named ones.
    palette = iter(["#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#8c564b", "#9467bd", "#ff7f0e",
                    "#2ca02c", "#d62728", "#1f77b4"])
    # One style per curve for both panels (the palette is drawn from once per curve).
    styles = {name: STYLES.get(name) or (next(palette, "#444444"), "o") for name in data["curves"]}
    for axis, (metric, title) in zip(axes, PANELS):
        for name, curve in data["curves"].items():
            colour, marker = styles[name]
            runs = [data["runs"][point] for point in curve["points"]]
            line = [(run["seconds"], run[metric]) for run in runs
                    if run["seconds"] and run[metric] is not None and run[metric] > 0]
            if not line:
                continue
            xs, ys = zip(*line)
            axis.plot(xs, ys, marker=marker, color=colour, linewidth=1.6, markersize=6,
                      label=curve["label"] + (" (baseline)" if curve["baseline"] else ""))
            repeats = [(r["seconds"], r[metric]) for run in runs for r in run["repeats"]
                       if r.get(metric) is not None and r[metric] > 0 and r["seconds"] > 0]
            if len(repeats) > len(line):
                rx, ry = zip(*repeats)
                axis.scatter(rx, ry, s=10, color=colour, alpha=0.35, linewidths=0)
            for run in runs:
                if run.get("gold") and run[metric] is not None and run[metric] > 0:
                    axis.annotate("gold", (run["seconds"], run[metric]), textcoords="offset points",
                                  xytext=(6, 6), fontsize=8)
        axis.set_xscale("log")
        axis.set_yscale("log")
        for scale, scientific, digits in ((axis.xaxis, False, (1, 2, 3, 5)),
                                          (axis.yaxis, metric == "mse", (1, 2, 3, 4, 5, 6, 8))):
            scale.set_major_formatter(FuncFormatter(_tick_label(scientific, digits)))
            scale.set_minor_formatter(FuncFormatter(_tick_label(scientific, digits)))
        axis.set_xlabel(f"wall time of the run over {count} frames, s (maps, sync, renders, denoise)"
                        if count else "wall time per frame, s (maps, sync, render, denoise)")
        axis.set_ylabel(title)
        axis.grid(True, which="both", alpha=0.25)
        axis.set_title(title, fontsize=10)
    axes[0].legend(fontsize=8, loc="best")
    reference = data.get("reference", {}).get("inputs", {})
    size = data["scene"]["size"]
    figure.suptitle(f"{data['scene']['scene']} ({Path(data['scene']['file']).name}) at {size[0]}x{size[1]}, "
                    f"ceiling {data['ceiling']} spp: error against a converged reference of "
                    f"{reference.get('spp', '?')} spp (seed {reference.get('seed', '?')})"
                    + (f", medians of {data['repeats']} repeats" if data["repeats"] > 1 else "")
                    + (f"; errors: mean over {count} frames" if count else ""),
                    fontsize=10)
    figure.tight_layout(rect=(0, 0, 1, 0.95))
    path = Path(path)
    with atomic_path(path) as tmp:
        figure.savefig(tmp, format="png")
    return path


def _tick_label(scientific: bool, digits: tuple[int, ...]):
    """Log-axis tick labels as plain numbers (0.2, 3, 40; 2e-5 for MSE) at the ticks whose
    leading digit is in ``digits`` only, so that a narrow range (errors often span less than a
    decade) still has labels and a wide one (seconds) is not crowded."""
    def label(value: float, _position) -> str:
        if value <= 0:
            return ""
        leading = int(round(value / 10 ** math.floor(math.log10(value) + 1e-9)))
        if leading not in digits:
            return ""
        return f"{value:.0e}".replace("e-0", "e-").replace("e+0", "e") if scientific else f"{value:g}"
    return label
