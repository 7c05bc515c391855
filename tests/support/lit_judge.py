"""``--estimator auto`` judged against the file's own settings on a lit scene, on the image:
the per-seed part of ``bench/bench_auto_lit.py``, which ``tests/test_auto_lit.py`` runs on a
few tiny seeds.

A seed's scene (``lit_scenes``, a saved .blend) goes through ``xsl-render curves``' job
(``addon.validation.curves_runner.CurvesJob``) with two curves: ``file``, uniform sampling
with the file's own settings (the baseline), and ``auto``, uniform sampling with
``--estimator auto``; every run is denoised as the project denoises every run, each timed as
a whole (scene sync, octree, auto's prediction, denoising), and measured against the
converged reference of the file's own settings (another seed, cached under the .blend's
hash). At equal samples auto is *visibly worse* where its p95-tile FLIP exceeds
``VISIBLY_WORSE`` times the file's; the equal-quality speedup is read along the file's curve.

The auto runs' records carry ``auto_source_hash()``: a run rendered by another version of
the package renders again, the file's runs and the references are reused.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: The figures compared (``core.validation.curves_results``): mean FLIP, p95 of 32-px tile
#: FLIP, % of pixels above FLIP 0.103, MSE; ColorVideoVDP's JOD too where it is installed.
METRICS = ("flip", "flip_tile95", "flip_share", "mse")
#: Auto is visibly worse where its p95-tile FLIP is more than this times the file's at equal
#: samples (issue 43's criterion).
VISIBLY_WORSE = 1.10
#: At equal samples auto's MSE may be at most this times the file's: noise differs between
#: estimators by tens of percent, a bias shows as a multiple (issue 43's cloud: 240x).
MSE_WORSE = 1.25
#: A degenerate seed: its reference's mean display value (Blender's Standard view, as the
#: metrics see it: 0 black, 1 white) is below this, about 5 of 255 levels.
DARK_DISPLAY = 0.02


@dataclass(frozen=True)
class Tier:
    """A set of sample counts judged against one reference: ``spp`` the counts auto and the
    file are compared at, ``curve`` the file's counts when the runs are timed (its
    time-quality curve), ``reference_spp`` the reference's samples."""

    reference_spp: int
    spp: tuple[int, ...]
    curve: tuple[int, ...]

    def file_counts(self, timed: bool) -> tuple[int, ...]:
        return tuple(sorted(set(self.spp) | (set(self.curve) if timed else set())))

    @property
    def ceiling(self) -> int:
        """The same in every mode, so a run renders the same pixels timed or not."""
        return max(self.spp + self.curve)


def auto_source_hash() -> str:
    """A hash of the package's Python sources (core and addon): what auto renders with."""
    import xsl_render

    root = Path(xsl_render.__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(p for part in ("core", "addon") for p in (root / part).rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def register_curves(tier: Tier, timed: bool, auto_key: str) -> tuple[str, str]:
    """Register the ``file`` (baseline) and ``auto`` curves for ``tier``; their names."""
    from xsl_render.core.validation.contestants import Contestant, CurveSpec, register_curve

    def file_points(ceiling: int):
        return [Contestant(f"file_{spp}spp", "file", "uniform", f"file {spp} spp", {"spp": spp})
                for spp in tier.file_counts(timed)]

    def auto_points(ceiling: int):
        return [Contestant(f"auto_{spp}spp", "auto", "uniform", f"auto {spp} spp",
                           {"spp": spp, "estimator": "auto", "auto_source": auto_key})
                for spp in tier.spp]

    register_curve(CurveSpec("file", "the file's own settings", file_points, baseline=True))
    register_curve(CurveSpec("auto", "--estimator auto", auto_points))
    return ("file", "auto")


def run_tier(blend: Path, tier: Tier, size: tuple[int, int], out_dir: Path, timed: bool = False,
             repeats: int = 1) -> dict:
    """The curves of one scene for one tier (curves.json's content, also written to
    ``out_dir``); finished runs and the reference are reused. The curves registry is left as
    it was found (``xsl-render curves`` in the same process must not plan these)."""
    from xsl_render.addon.validation.curves_runner import CurvesJob, CurvesSettings
    from xsl_render.core.files import write_json
    from xsl_render.core.validation.contestants import CURVES
    from xsl_render.core.validation.vdp import vdp_unavailable_reason

    registered = list(CURVES)
    try:
        curves = register_curves(tier, timed, auto_source_hash())
        settings = CurvesSettings(ceiling=tier.ceiling, resolution=tuple(size), repeats=repeats, curves=curves,
                                  vdp=vdp_unavailable_reason() is None, reference_spp=tier.reference_spp)
        data = CurvesJob(blend, settings, out_dir).run()
    finally:
        CURVES[:] = registered
    write_json(Path(out_dir) / "curves.json", data)
    return data


def display_mean(path) -> float:
    """The mean display value of an HDR image as the metrics see it (Standard view)."""
    from xsl_render.core.imageio import read_image
    from xsl_render.core.tonemap import standard_view

    return float(standard_view(read_image(path)[..., :3]).mean())


def auto_choice(run: dict) -> dict:
    """What auto rendered with (its stats' estimator record), in the few fields a table shows."""
    chosen = ((run.get("repeats") or [{}])[0].get("stats") or {}).get("estimator") or {}
    keep = ("biased", "step_rate", "predicted_bias", "tolerance", "medium_rates", "scatter_sampling",
            "light_tree", "sample_pattern", "seconds", "reason")
    return {key: chosen.get(key) for key in keep}


def choice_text(choice: dict) -> str:
    biased = choice.get("biased")
    if biased is None:
        return "scene"
    if not biased:
        return "null sc."
    text = f"march {choice.get('step_rate') or 'sc'}"
    if choice.get("medium_rates"):
        text += "+m"
    return text


def verdict(data: dict, tier: Tier) -> dict:
    """Per count of ``tier.spp``: the file's and auto's figures, auto's over the file's at
    equal samples, whether auto is visibly worse, its equal-quality speedups over the file's
    curve (meaningful only when timed), and auto's choice; and the reference's darkness."""
    runs = data["runs"]
    out = {"reference": {"spp": data["reference"]["inputs"]["spp"], "key": data["reference"]["key"],
                         "render_s": data["reference"].get("render_s"),
                         "display_mean": display_mean(data["reference"]["path"])},
           "counts": {}}
    for spp in tier.spp:
        file, auto = runs[f"file_{spp}spp"], runs[f"auto_{spp}spp"]
        ratios = {m: (auto[m] / file[m] if file.get(m) and auto.get(m) is not None else None) for m in METRICS}
        speedups = {m: (auto["speedups"].get("file") or {}).get(m) for m in METRICS}
        out["counts"][str(spp)] = {
            "file": {m: file.get(m) for m in (*METRICS, "jod", "seconds")},
            "auto": {m: auto.get(m) for m in (*METRICS, "jod", "seconds")},
            "ratio": ratios,
            "visibly_worse": bool(auto["flip_tile95"] > VISIBLY_WORSE * file["flip_tile95"]),
            "speedup": {m: (s or {}).get("value") for m, s in speedups.items()},
            "extrapolated": {m: bool((s or {}).get("extrapolated")) for m, s in speedups.items()},
            "choice": auto_choice(auto),
        }
    return out


def is_dark(result: dict) -> bool:
    return result["reference"]["display_mean"] < DARK_DISPLAY


def equal_samples(blend: Path, tier: Tier, size: tuple[int, int], out_dir: Path) -> dict:
    """``verdict`` of the untimed runs of one tier: auto against the file at equal samples."""
    return verdict(run_tier(blend, tier, size, out_dir), tier)


def ratio_text(value) -> str:
    return "    -" if value is None or not np.isfinite(value) else f"{value:5.2f}"
