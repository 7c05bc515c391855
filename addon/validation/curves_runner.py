"""``xsl-render curves``: time-quality curves of every contestant against the converged
reference, resumable.

For one scene at one resolution: the reference (given, cached or rendered), then every
contestant of the chosen curves (``core.validation.contestants``) once per seed, each timed
as a whole (``addon.validation.contestants``) and compared with the reference (HDR-FLIP,
MSE, ColorVideoVDP's JOD where installed). The results, medians and equal-quality speedups
go to DIR/curves.json (``core.validation.curves_results``), DIR/curves.png and
DIR/report.html.

Layout of DIR::

    curves.json, curves.png, report.html
    runs/<contestant>_seed<k>.exr    the denoised render
    runs/<contestant>_seed<k>.json   its record: inputs and their hash, seconds, stats, metrics

A record is written after its image, both atomically, and reused while the hash of its
inputs is unchanged (the scene file's bytes, size, frame, contestant, seed, budget, Blender
and denoiser versions); its metrics are redone only when the reference changes.
"""
from __future__ import annotations

import statistics
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...core.errors import InputError
from ...core.files import file_sha256, write_json
from ...core.imageio import read_image, write_exr
from ...core.progress import ProgressCallback, WeightedSteps
from ...core.sampling.render_options import RenderOptions
from ...core.validation.contestants import CURVES, Contestant, plan_contestants
from ...core.validation.curves_results import (STATS_KEPT, build_curves, metric_values,
                                               summarise_run)
from ...core.validation.image_pair import check_pair
from ...core.validation.metrics import compare_images
from ...core.validation.reference import (REFERENCE_SEED, check_contestant_seeds,
                                          default_reference_spp, find_reference, read_reference)
from ...core.validation.store import inputs_hash, read_record, write_record
from ...core.validation.vdp import vdp_unavailable_reason
from ..cycles.denoise import DENOISE_VERSION
from ..scene.probe import render_size
from .contestants import run_contestant, warm_up
from .reference import blender_version, ensure_reference, reference_inputs, scene_ceiling

#: Most repeats accepted (each repeat renders every contestant again).
MAX_REPEATS = 50


@dataclass(frozen=True)
class CurvesSettings:
    """The knobs of one ``curves`` run.

    ``ceiling`` None: the scene's own Cycles samples. ``seed``: the first contestant seed
    (repeats use seed, seed + 1, ...). ``reference``: an EXR to use instead of the cached or
    rendered one; ``reference_spp``: the reference's samples (default max(1024, 16 x ceiling)).
    """

    ceiling: int | None = None
    resolution: tuple[int, int] | None = None
    frame: int | None = None
    scene_name: str | None = None
    repeats: int = 1
    seed: int = 0
    curves: tuple[str, ...] | None = None
    vdp: bool = True
    reference: Path | None = None
    reference_spp: int | None = None

    @property
    def seeds(self) -> list[int]:
        return list(range(self.seed, self.seed + self.repeats))

    def check(self) -> "CurvesSettings":
        """InputError (one line) for impossible values, before any scene is opened."""
        if not 1 <= self.repeats <= MAX_REPEATS:
            raise InputError(f"--repeats must be between 1 and {MAX_REPEATS} (got {self.repeats})")
        if self.seed < 0:
            raise InputError(f"--seed must not be negative (got {self.seed})")
        if self.ceiling is not None and self.ceiling < 1:
            raise InputError(f"--max-spp must be at least 1 (got {self.ceiling})")
        if self.reference_spp is not None and self.reference_spp < 1:
            raise InputError(f"--reference-spp must be at least 1 (got {self.reference_spp})")
        if self.reference is None:
            check_contestant_seeds(self.seeds, REFERENCE_SEED)
        elif not Path(self.reference).is_file():
            raise InputError(f"no such reference file: {self.reference}")
        return self


def _cost(contestant: Contestant, ceiling: int, runs: dict[str, Contestant]) -> float:
    """A run's expected cost in samples per pixel, for the progress bar only."""
    params = contestant.params
    if contestant.time_of is not None:
        return _cost(runs[contestant.time_of], ceiling, runs)
    if "spp" in params:
        return float(params["spp"])
    if "noise_threshold" in params:
        return 0.4 * params["max_spp"]
    return 0.5 * params.get("max_spp", ceiling) + 0.1 * ceiling


class CurvesJob:
    """One ``curves`` run; ``run()`` returns curves.json's content (and writes the files)."""

    def __init__(self, blend: str | Path | None, settings: CurvesSettings, out_dir: str | Path,
                 progress: ProgressCallback | None = None, blend_file: str | Path | None = None):
        self.blend, self.settings = blend, settings.check()
        self.blend_file = Path(blend_file or blend)
        self.out_dir = Path(out_dir)
        self.progress = progress
        self.warm = False
        self.warnings: list[str] = []
        self.counts = {"rendered": 0, "reused": 0}

    # -- setup -------------------------------------------------------------------------
    def open(self):
        from ..scene.blend_session import open_blend

        scene = open_blend(self.blend, self.settings.scene_name)
        if self.settings.frame is not None:
            scene.frame_set(self.settings.frame)
        self.scene = scene
        self.sha256 = file_sha256(self.blend_file)
        self.ceiling = self.settings.ceiling or scene_ceiling(scene)
        self.size = tuple(self.settings.resolution or render_size(scene))
        RenderOptions(max_spp=self.ceiling, resolution=self.size).check().check_frame(*self.size)
        self.contestants = plan_contestants(self.ceiling, self.settings.curves)
        return scene

    def reference(self, steps: WeightedSteps):
        """The reference's pixels and its description; renders it when it is not cached."""
        if self.settings.reference is not None:
            given = read_reference(self.settings.reference, self.size)
            check_contestant_seeds(self.settings.seeds, given.seed)
            steps.reweight(0.01)
            steps.begin("reference: given")
            info = {"path": str(given.path), "key": given.key or file_sha256(given.path), "source": "given",
                    "inputs": {"spp": given.spp, "seed": given.seed}}
            steps.finish()
            return given.image, info
        inputs = reference_inputs(self.scene, self.blend_file, spp=self.settings.reference_spp,
                                  resolution=self.size, frame=self.scene.frame_current,
                                  max_spp=self.ceiling, blend_sha256=self.sha256)
        check_contestant_seeds(self.settings.seeds, inputs.seed)
        if find_reference(inputs.key) is not None:
            steps.reweight(0.01)
        steps.begin(f"reference ({inputs.spp} spp)")
        reference = ensure_reference(self.scene, inputs, progress=steps.sub("reference", echo="uniform: "),
                                     file_name=self.blend_file.name)
        steps.finish()
        return read_image(reference.path), reference.to_dict()

    # -- runs --------------------------------------------------------------------------
    def run_inputs(self, contestant: Contestant, seed: int, budget_s: float | None) -> dict:
        inputs = {"step": "curve_run", "scene_sha256": self.sha256, "scene": self.scene.name,
                  "frame": self.scene.frame_current, "size": list(self.size), "seed": seed,
                  "contestant": {k: v for k, v in contestant.to_dict().items() if k != "label"},
                  "blender": blender_version(),
                  "denoise": DENOISE_VERSION}
        if budget_s is not None:
            inputs["budget_s"] = budget_s
        return inputs

    def render(self, contestant: Contestant, seed: int, budget_s: float | None,
               steps: WeightedSteps) -> dict:
        folder = self.out_dir / "runs"
        stem = f"{contestant.name}_seed{seed}"
        exr, record_path = folder / f"{stem}.exr", folder / f"{stem}.json"
        inputs = self.run_inputs(contestant, seed, budget_s)
        digest = inputs_hash(inputs)
        label = f"{contestant.name} (seed {seed})"
        steps.begin(label)
        record = read_record(record_path, digest, (exr,))
        if record is not None:
            self.counts["reused"] += 1
            record["reused"] = True
        else:
            if not self.warm:
                warm_up(self.scene)
                self.warm = True
            options = RenderOptions(max_spp=self.ceiling, seed=seed, resolution=self.size).check()
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                outcome, seconds = run_contestant(self.scene, contestant, options, budget_s,
                                                  progress=steps.sub(label))
            self.warnings += outcome.warnings + [str(w.message) for w in caught]
            write_exr(exr, outcome.image, ["R", "G", "B", "A"],
                      attributes={"xsl_render:contestant": contestant.name, "xsl_render:seed": seed})
            stats = {key: outcome.stats[key] for key in STATS_KEPT if key in outcome.stats}
            record = {"inputs": inputs, "input_hash": digest, "seconds": seconds, "stats": stats,
                      "file": exr.relative_to(self.out_dir).as_posix()}
            write_record(record_path, record)
            self.counts["rendered"] += 1
            record["reused"] = False
        steps.finish()
        return record

    def measure(self, record: dict, reference: np.ndarray, reference_key: str) -> dict:
        """The record's metrics against the reference (reused while the reference is the same)."""
        digest = inputs_hash({"step": "curve_metrics", "run": record["input_hash"],
                              "reference": reference_key, "vdp": self.settings.vdp})
        if record.get("metrics_hash") != digest:
            image = read_image(self.out_dir / record["file"])
            pair = check_pair(reference, image, hdr=True, names=("the reference", record["file"]))
            results = compare_images(pair, vdp=self.settings.vdp)
            reused = record.pop("reused")
            record.update(metrics={name: result.summary() for name, result in results.items()},
                          metrics_hash=digest)
            write_record(self.out_dir / Path(record["file"]).with_suffix(".json"), record)
            record["reused"] = reused
        return record

    # -- the whole job -----------------------------------------------------------------
    def run(self) -> dict:
        self.open()
        by_name = {c.name: c for c in self.contestants}
        seeds = self.settings.seeds
        weights = [default_reference_spp(self.ceiling) if self.settings.reference_spp is None
                   else float(self.settings.reference_spp)]
        weights += [_cost(c, self.ceiling, by_name) for c in self.contestants for _ in seeds]
        steps = WeightedSteps(self.progress, weights)
        reference, reference_info = self.reference(steps)
        vdp_reason = None if self.settings.vdp else "not requested (--no-vdp)"
        if vdp_reason is None:
            vdp_reason = vdp_unavailable_reason()
        records: dict[str, list[dict]] = {}
        budgets: dict[str, float | None] = {}
        # Contestants with a budget of their own first, repeat by repeat (so a change in the
        # machine's load spreads over every contestant); then those timed by another's median.
        for timed in (False, True):
            for seed in seeds:
                for contestant in self.contestants:
                    if (contestant.time_of is not None) != timed:
                        continue
                    budget = None
                    if contestant.time_of is not None:
                        budget = statistics.median(r["seconds"] for r in records[contestant.time_of])
                    budgets[contestant.name] = budget
                    record = self.render(contestant, seed, budget, steps)
                    self.measure(record, reference, reference_info["key"])
                    records.setdefault(contestant.name, []).append(record)
        runs = {c.name: summarise_run(c, [self.repeat_entry(r) for r in records[c.name]], budgets[c.name])
                for c in self.contestants}
        self.check_guiding(runs)
        header = {"scene": {"file": str(self.blend_file), "sha256": self.sha256, "scene": self.scene.name,
                            "frame": self.scene.frame_current, "size": list(self.size)},
                  "ceiling": self.ceiling, "reference": reference_info, "repeats": len(seeds),
                  "seeds": seeds, "vdp": {"ran": vdp_reason is None, "skipped": vdp_reason},
                  "warnings": list(dict.fromkeys(self.warnings)), **self.counts}
        return build_curves(header, CURVES, runs)

    def repeat_entry(self, record: dict) -> dict:
        stats = record["stats"]
        return {"seed": record["inputs"]["seed"], "seconds": record["seconds"],
                "mean_spp": stats.get("mean_spp"), **metric_values(record["metrics"]),
                "file": record["file"], "reused": record["reused"], "stats": stats}

    def check_guiding(self, runs: dict[str, dict]) -> None:
        """Say, per path-guiding repeat, whether Cycles used guiding: its image differs from
        the uniform render with the same samples and seed (guiding ignored: identical)."""
        for run in runs.values():
            if run["kind"] != "guiding":
                continue
            uniform = runs.get(f"uniform_{run['params']['spp']}spp")
            same = {r["seed"]: r for r in (uniform or {}).get("repeats", [])}
            for repeat in run["repeats"]:
                twin = same.get(repeat["seed"])
                guiding = repeat["stats"].setdefault("path_guiding", {})
                if twin is None:
                    guiding["effect"] = "unknown: no uniform run with the same samples and seed"
                    continue
                identical = np.array_equal(read_image(self.out_dir / repeat["file"]),
                                           read_image(self.out_dir / twin["file"]))
                guiding["effect"] = ("ignored by Cycles: identical to uniform with the same samples and seed"
                                     if identical else "used: the image differs from uniform with the same "
                                                       "samples and seed")
                if identical:
                    self.warnings.append(f"{run['name']}: Cycles ignored path guiding")


def run_curves(blend: str | Path | None, settings: CurvesSettings, out_dir: str | Path,
               progress: ProgressCallback | None = None, blend_file: str | Path | None = None) -> dict:
    """Run the curves of one scene into ``out_dir``: curves.json, curves.png, report.html.

    ``blend`` is the .blend to open (None inside Blender: the open file, whose path
    ``blend_file`` must then give). Returns curves.json's content.
    """
    from ...core.validation.curves_plot import write_curves_png
    from ...core.validation.curves_report import write_curves_report

    job = CurvesJob(blend, settings, out_dir, progress, blend_file)
    data = job.run()
    out_dir = Path(out_dir)
    write_json(out_dir / "curves.json", data)
    png = write_curves_png(data, out_dir / "curves.png")
    write_curves_report(data, out_dir, png)
    return data
