"""The validation report's first section: every run against the converged reference, with
its equal-quality speedup over the scene's uniform curve (results.json's
``reference_metrics`` and ``equal_quality``, see ``core.validation.results``)."""
from __future__ import annotations

from html import escape

from .curves_report import SPEEDUP_NOTE, speedup_cell
from .curves_results import metric_values

_FORMATS = {"flip": ".4f", "mse": ".3g", "jod": ".3f"}
_LABELS = {"flip": "mean FLIP", "mse": "MSE", "jod": "JOD"}


def _metrics(scenes: dict) -> list[str]:
    """FLIP and MSE, and JOD where ColorVideoVDP ran for some run."""
    jod = any(metric_values(run.get("reference_metrics", {}))["jod"] is not None
              for scene in scenes.values() for run in scene.get("runs", {}).values())
    return ["flip", "mse"] + (["jod"] if jod else [])


def _rows(name: str, scene: dict, metrics: list[str], with_scene: bool) -> list[str]:
    runs = scene.get("runs", {})
    rows = []
    for index, (key, run) in enumerate(runs.items()):
        values = metric_values(run.get("reference_metrics", {}))
        cells = []
        if with_scene and index == 0:
            cells.append(f"<td class=l rowspan={len(runs)}>{escape(name)}</td>")
        cells += [f"<td class=l>{escape(run.get('label', key))}</td>", f"<td>{run['time_s']:.2f} s</td>",
                  f"<td>{run.get('stats', {}).get('mean_spp', 0):.1f}</td>"]
        cells += ["<td class=skip>-</td>" if values[m] is None else f"<td>{format(values[m], _FORMATS[m])}</td>"
                  for m in metrics]
        speedups = run.get("equal_quality")
        if run.get("kind") in ("gold", "uniform"):
            cells.append(f"<td class=skip colspan={len(metrics)}>on the uniform curve</td>")
        elif speedups is None:
            cells.append(f"<td class=skip colspan={len(metrics)}>no uniform curve (fewer than two "
                         "uniform runs)</td>")
        else:
            cells += [speedup_cell(speedups.get(m)) for m in metrics]
        css = " class=gold" if key == "gold" else (" class=equal" if run.get("kind") in ("uniform", "adaptive") else "")
        rows.append(f"<tr{css}>{''.join(cells)}</tr>")
    return rows


def _table(rows: list[str], metrics: list[str], with_scene: bool) -> str:
    head = ("<tr>" + ("<th class=l rowspan=2>scene</th>" if with_scene else "")
            + "<th class=l rowspan=2>run</th><th rowspan=2>time</th><th rowspan=2>mean spp</th>"
            + "".join(f"<th rowspan=2>{_LABELS[m]}</th>" for m in metrics)
            + f"<th colspan={len(metrics)}>equal-quality speedup over uniform</th></tr><tr>"
            + "".join(f"<th>{_LABELS[m]}</th>" for m in metrics) + "</tr>")
    return f"<table>{head}{''.join(rows)}</table>"


def reference_description(scene: dict) -> str:
    """'a converged reference of 1024 spp, seed 7 (shipped with the repository)'."""
    reference = scene.get("reference") or {}
    inputs = reference.get("inputs", {})
    source = {"shipped": "shipped with the repository", "cache": "from the cache",
              "rendered": "rendered for this run"}.get(reference.get("source"), str(reference.get("source")))
    return f"a converged reference of {inputs.get('spp', '?')} spp, seed {inputs.get('seed', '?')} ({source})"


def reference_tables(scenes: dict) -> str:
    """The report's first section: every run of every scene against its converged reference."""
    if not scenes:
        return ""
    metrics = _metrics(scenes)
    rows = [row for name, scene in scenes.items() for row in _rows(name, scene, metrics, True)]
    described = "; ".join(f"{escape(name)}: {escape(reference_description(scene))}"
                          for name, scene in scenes.items())
    return ("<h2>All scenes against the converged reference</h2>"
            "<p class=meta>Every run, the gold standard included, compared with a uniform render of far "
            "more samples and a seed no run uses, denoised like every run (" + described + "). "
            "The uniform curve is the gold standard and the uniform runs at fractions of the "
            "ceiling and at XSL's time.</p>"
            + _table(rows, metrics, True) + f"<p class=note>{SPEEDUP_NOTE}</p>")


def scene_reference_table(name: str, scene: dict) -> str:
    """One scene's runs against its converged reference."""
    metrics = _metrics({name: scene})
    return (f"<h3>Against the converged reference <span class=note>({escape(reference_description(scene))})"
            "</span></h3>" + _table(_rows(name, scene, metrics, False), metrics, False))
