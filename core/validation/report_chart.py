"""The charts of the reports as inline SVG: no script, no library, nothing fetched, so they
draw the same in any browser and in a saved file. The timing chart of the validation report
(the paper's Fig. 8) and the per-frame curves of a sequence comparison."""
from __future__ import annotations

import math
from dataclasses import dataclass
from html import escape

COLOURS = {"gold": "#6b6b6b", "maps": "#d9a441", "render": "#3b6ea5", "equal": "#8a5fb0",
           "guided": "#2a9d8f"}
#: The legend's entries; "guided" only where a guided run is drawn.
_LEGEND = (("gold", "gold standard"), ("maps", "maps"), ("render", "selective render"),
           ("equal", "equal-time render"), ("guided", "guided render"))
_ROW = 26
_LABEL_W = 210
_BAR_W = 420
_VALUE_W = 170


@dataclass(frozen=True)
class Bar:
    """One horizontal bar: seconds spent on maps and on rendering, and how it is drawn.

    ``kind`` picks the render colour: "gold", "render" (selective) or "equal" (equal time).
    """

    label: str
    maps_s: float
    render_s: float
    kind: str = "render"
    note: str = ""

    @property
    def total(self) -> float:
        return self.maps_s + self.render_s


def timing_chart_svg(bars: list[Bar], title: str = "") -> str:
    """Horizontal bars on one time axis, maps stacked before rendering, value and note at the
    end of each bar; a legend underneath."""
    longest = max((bar.total for bar in bars), default=0.0) or 1.0
    height = _ROW * len(bars) + 52
    width = _LABEL_W + _BAR_W + _VALUE_W
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" class="chart" role="img" '
             f'viewBox="0 0 {width} {height}" width="{width}" height="{height}">']
    if title:
        parts.append(f"<title>{escape(title)}</title>")
    for index, bar in enumerate(bars):
        y = 6 + index * _ROW
        maps_w = _BAR_W * bar.maps_s / longest
        render_w = _BAR_W * bar.render_s / longest
        parts.append(f'<text x="{_LABEL_W - 8}" y="{y + 15}" text-anchor="end">{escape(bar.label)}</text>')
        if maps_w > 0:
            parts.append(f'<rect x="{_LABEL_W}" y="{y + 3}" width="{maps_w:.2f}" height="16" '
                         f'fill="{COLOURS["maps"]}"><title>maps {bar.maps_s:.2f} s</title></rect>')
        parts.append(f'<rect x="{_LABEL_W + maps_w:.2f}" y="{y + 3}" width="{max(render_w, 0.5):.2f}" '
                     f'height="16" fill="{COLOURS.get(bar.kind, COLOURS["render"])}">'
                     f'<title>render {bar.render_s:.2f} s</title></rect>')
        value = f"{bar.total:.1f} s" + (f"  {bar.note}" if bar.note else "")
        parts.append(f'<text x="{_LABEL_W + maps_w + render_w + 6:.2f}" y="{y + 15}">{escape(value)}</text>')
    legend_y = 6 + len(bars) * _ROW + 14
    x = _LABEL_W
    drawn = {bar.kind for bar in bars}
    for key, text in _LEGEND:
        if key == "guided" and key not in drawn:
            continue
        parts.append(f'<rect x="{x}" y="{legend_y}" width="12" height="12" fill="{COLOURS[key]}"/>')
        parts.append(f'<text x="{x + 16}" y="{legend_y + 11}">{text}</text>')
        x += 24 + 7 * len(text)
    parts.append("</svg>")
    return "".join(parts)


@dataclass(frozen=True)
class Line:
    """One curve of :func:`line_chart_svg`: a value per x (None: no point there)."""

    label: str
    values: list[float | None]
    colour: str


_PLOT_W, _PLOT_H = 640, 220
_LEFT, _RIGHT, _TOP, _BOTTOM = 64, 24, 12, 58


def nice_step(span: float, ticks: int = 5) -> float:
    """A step of 1, 2 or 5 times a power of ten giving about ``ticks`` ticks over ``span``."""
    if span <= 0 or not math.isfinite(span):
        return 1.0
    rough = span / ticks
    power = 10 ** math.floor(math.log10(rough))
    return next(step * power for step in (1, 2, 5, 10) if step * power >= rough)


def line_chart_svg(x: list[int], lines: list[Line], title: str = "", x_label: str = "frame",
                   y_label: str = "") -> str:
    """Curves over whole-numbered x (frames) on one linear axis from 0, a point per value
    with its number as a tooltip, the legend underneath."""
    values = [v for line in lines for v in line.values if v is not None]
    top = max(values, default=0.0) * 1.08 or 1.0
    step = nice_step(top)
    top = math.ceil(top / step - 1e-9) * step
    first, last = (min(x), max(x)) if x else (0, 1)
    width, height = _LEFT + _PLOT_W + _RIGHT, _TOP + _PLOT_H + _BOTTOM

    def px(value: float) -> float:
        return _LEFT + (_PLOT_W / 2 if last == first else _PLOT_W * (value - first) / (last - first))

    def py(value: float) -> float:
        return _TOP + _PLOT_H * (1 - value / top)

    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" class="chart" role="img" '
             f'viewBox="0 0 {width} {height}" width="{width}" height="{height}">']
    if title:
        parts.append(f"<title>{escape(title)}</title>")
    digits = max(0, -math.floor(math.log10(step)))
    for index in range(int(round(top / step)) + 1):
        y = py(index * step)
        parts.append(f'<line x1="{_LEFT}" x2="{_LEFT + _PLOT_W}" y1="{y:.1f}" y2="{y:.1f}" stroke="#e2e2e2"/>')
        parts.append(f'<text x="{_LEFT - 6}" y="{y + 4:.1f}" text-anchor="end">{index * step:.{digits}f}</text>')
    x_step = max(1, int(nice_step(last - first, 10)))
    for tick in range(math.ceil(first / x_step) * x_step, last + 1, x_step):
        parts.append(f'<text x="{px(tick):.1f}" y="{_TOP + _PLOT_H + 16}" text-anchor="middle">{tick}</text>')
    parts.append(f'<rect x="{_LEFT}" y="{_TOP}" width="{_PLOT_W}" height="{_PLOT_H}" fill="none" stroke="#999"/>')
    parts.append(f'<text x="{_LEFT + _PLOT_W / 2}" y="{_TOP + _PLOT_H + 32}" text-anchor="middle">{escape(x_label)}</text>')
    if y_label:
        parts.append(f'<text transform="translate(14 {_TOP + _PLOT_H / 2}) rotate(-90)" '
                     f'text-anchor="middle">{escape(y_label)}</text>')
    for line in lines:
        points = [(px(xi), py(v), xi, v) for xi, v in zip(x, line.values) if v is not None]
        if len(points) > 1:
            path = " ".join(f"{a:.1f},{b:.1f}" for a, b, _, _ in points)
            parts.append(f'<polyline points="{path}" fill="none" stroke="{line.colour}" stroke-width="1.8"/>')
        for a, b, xi, v in points:
            parts.append(f'<circle cx="{a:.1f}" cy="{b:.1f}" r="2.6" fill="{line.colour}">'
                         f'<title>{escape(line.label)}, frame {xi}: {v:.4g}</title></circle>')
    legend_x = _LEFT
    for line in lines:
        y = _TOP + _PLOT_H + 44
        parts.append(f'<rect x="{legend_x}" y="{y}" width="12" height="12" fill="{line.colour}"/>')
        parts.append(f'<text x="{legend_x + 16}" y="{y + 11}">{escape(line.label)}</text>')
        legend_x += 32 + 7 * len(line.label)
    parts.append("</svg>")
    return "".join(parts)
