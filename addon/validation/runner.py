"""The objective validation of the paper (sections 5 and 6.1) on real scenes, resumable.

For each scene: the director maps, the gold standard, the selective renders (X only, S only,
XS, XSL, XSL without MinBound where asked), uniform sampling at fractions of the ceiling,
uniform and Cycles adaptive sampling at the wall time the XSL run took (maps included), Auto
Volumes at the file's samples and in the gold standard's time; MSE,
FLIP and VDP of each against the converged reference (``addon.validation.reference``: cached,
or rendered once) and, the paper's measure, of each but gold against the gold standard.
Every finished step is kept on disk with the hash of its inputs (``core.validation.store``)
and reused by the next run, so a run killed midway continues.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

from ...core.files import write_json
from ...core.imageio import write_exr, write_png
from ...core.maps.director import xs_map, xsl_map
from ...core.maps.files import read_map_set, write_map_set
from ...core.maps.options import MapOptions
from ...core.progress import ProgressCallback, WeightedSteps
from ...core.sampling.guided_plan import GuidedOptions
from ...core.sampling.render_options import RenderOptions
from ...core.sampling.render_request import RenderRequest
from ...core.sampling.render_stats import RenderStats
from ...core.validation.compare import compare_with_gold
from ...core.validation.plan import (AUTO_CEILING_FACTOR, GOLD, ValidationSettings, Variant, map_seconds,
                                    scaled_size, scene_variants)
from ...core.validation.reference import default_reference_spp, find_reference
from ...core.validation.results import scene_summary
from ...core.validation.store import file_sha256, inputs_hash, read_record, write_record
from ...core.validation.vdp import vdp_unavailable_reason

#: Relative cost of each step, in gold renders, for the overall progress fraction.
STEP_WEIGHTS = {"maps": 0.5, "gold": 1.0, "selective": 0.4, "uniform": 0.4, "adaptive": 0.4, "guided": 0.4,
                "auto": 1.0, "metrics": 0.1}


@dataclass(frozen=True)
class SceneJob:
    """A scene to validate.

    ``name`` names its folder and its section of the report; ``max_spp`` overrides the
    settings' ceiling for this scene (one .blend can be validated at two ceilings under two
    names); ``compare_minbound`` also renders XSL without MinBound (the paper's road scene).
    """

    name: str
    path: Path
    max_spp: int | None = None
    compare_minbound: bool = False

    def variants(self, settings: ValidationSettings) -> list[Variant]:
        return scene_variants(settings.variants, self.compare_minbound)


def plan_weights(jobs: list[SceneJob], settings: ValidationSettings) -> list[float]:
    """The steps' weights, in plan order; a render costs in proportion to its samples (the
    reference's weight assumes it must be rendered; a cached one is reweighted)."""
    weights = []
    for job in jobs:
        variants = job.variants(settings)
        spp = job.max_spp or settings.max_spp
        ceiling = spp / settings.max_spp
        weights += [STEP_WEIGHTS["maps"]] * len({v.map_options.minbound for v in variants if v.map_options})
        weights += [(v.spp_fraction if v.spp_fraction else STEP_WEIGHTS[v.kind]) * ceiling for v in variants]
        weights += [STEP_WEIGHTS["metrics"]] * (len(variants) - 1)
        weights.append((settings.reference_spp or default_reference_spp(spp)) / settings.max_spp)
        weights += [STEP_WEIGHTS["metrics"]] * len(variants)
    return weights


def run_validation(jobs: list[SceneJob], settings: ValidationSettings, out_dir: str | Path,
                   progress: ProgressCallback | None = None) -> dict:
    """Validate every scene in ``jobs`` into ``out_dir``; returns (and writes) results.json.

    The result holds, per scene, each variant's timing, samples and metrics, whether the
    render was made now or reused, and the paths of its files relative to ``out_dir``.
    """
    import bpy  # noqa: F401  (the session the scenes are opened in)

    out_dir = Path(out_dir)
    vdp_reason = None if settings.vdp else "not requested (--no-vdp)"
    if vdp_reason is None:
        vdp_reason = vdp_unavailable_reason()
    results = {"settings": settings.to_dict(),
               "vdp": {"ran": vdp_reason is None, "skipped": vdp_reason},
               "scenes": {}, "rendered": 0, "reused": 0}
    steps = WeightedSteps(progress, plan_weights(jobs, settings))
    for job in jobs:
        options = settings.render_options(job.max_spp)
        results["scenes"][job.name] = _SceneRun(job, settings, options, out_dir, steps, results).run()
        write_json(out_dir / "results.json", results)
    return results


class _SceneRun:
    def __init__(self, job: SceneJob, settings: ValidationSettings, options: RenderOptions,
                 out_dir: Path, steps: WeightedSteps, results: dict):
        self.job, self.settings, self.options = job, settings, options
        self.out_dir, self.steps, self.results = out_dir, steps, results
        self.folder = out_dir / job.name
        self.records: dict[str, dict] = {}
        self.maps: dict[bool, tuple] = {}
        self.warnings: list[str] = []
        self.reused: set[str] = set()
        self.scene = None
        self.warm = False

    # -- helpers --------------------------------------------------------------------------
    def rel(self, path: Path) -> str:
        return Path(path).relative_to(self.out_dir).as_posix()

    def open_scene(self, warm: bool = True):
        """Open the .blend the first time a step needs Blender (a fully reused scene with a
        given resolution never does)."""
        if self.scene is None:
            from ..scene.blend_session import open_blend

            self.scene = open_blend(self.job.path)
        if warm and not self.warm:
            from .contestants import warm_up

            warm_up(self.scene)         # no timed render pays Cycles' one-time start-up
            self.warm = True
        return self.scene

    # -- the scene ------------------------------------------------------------------------
    def run(self) -> dict:
        self.sha256 = file_sha256(self.job.path)
        self.size = self.settings.resolution or scaled_size(self.scene_size(), self.settings.longest_side)
        variants = self.job.variants(self.settings)
        for minbound in dict.fromkeys(v.map_options.minbound for v in variants if v.map_options):
            self.maps[minbound] = self.director_maps(minbound)
        for variant in variants:
            self.records[variant.name] = self.render(variant)
        for variant in variants:
            if variant.name != GOLD:
                self.compare(variant)
        reference = self.reference()
        for variant in variants:
            self.compare_with_reference(variant, reference)
        return scene_summary(self.job, self.sha256, self.size, self.options, variants, self.records,
                             {mb: info for mb, (_, _, info) in self.maps.items()}, self.warnings,
                             self.reused, reference.to_dict())

    def scene_size(self) -> tuple[int, int]:
        """The scene's own render size (opens the .blend, renders nothing)."""
        from ..scene.probe import render_size

        return render_size(self.open_scene(warm=False))

    # -- maps -----------------------------------------------------------------------------
    def director_maps(self, minbound: bool):
        folder = self.folder / ("maps" if minbound else "maps_no_minbound")
        map_options = MapOptions(minbound=minbound)
        inputs = {"step": "maps", "scene_sha256": self.sha256, "size": list(self.size),
                  "map_options": map_options.to_dict()}
        digest = inputs_hash(inputs)
        self.steps.begin(f"{self.job.name}: maps")
        record = read_record(folder / "inputs.json", digest,
                             tuple(folder / f"{n}.exr" for n in ("x", "s", "l", "xs", "xsl")))
        if record is not None:
            maps = read_map_set(folder)
            self.results["reused"] += 1
        else:
            from ..maps.director_maps import compute_maps

            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                maps = compute_maps(self.open_scene(), map_options, size=self.size,
                                    cache_dir=self.folder / "cache",
                                    progress=self.steps.sub(f"{self.job.name}: maps"))
            self.warnings += [str(w.message) for w in caught]
            write_map_set(folder, maps)
            write_record(folder / "inputs.json", {"inputs": inputs, "input_hash": digest})
            self.results["rendered"] += 1
        self.steps.finish()
        info = {"folder": self.rel(folder), "seconds": maps.info.get("seconds", {}),
                "lights": maps.info.get("l", {}), "warnings": maps.info.get("warnings", []),
                "minbound": minbound}
        return maps, digest, info

    def director(self, variant: Variant):
        maps, digest, _ = self.maps[variant.map_options.minbound]
        o = variant.map_options
        xs = xs_map(maps.x, maps.s, o.wx, o.ws, o.xs_op)
        director = xs if variant.director == "xs" else xsl_map(xs, maps.l, o.wxs, o.wl, o.xsl_op)
        return director, digest, map_seconds(variant, maps.info.get("seconds", {}))

    # -- renders --------------------------------------------------------------------------
    def render_inputs(self, variant: Variant) -> dict:
        inputs = {"step": "render", "scene_sha256": self.sha256, "size": list(self.size),
                  "variant": variant.to_dict(), "options": self.options.to_dict()}
        if variant.kind == "selective":
            inputs["maps_hash"] = self.maps[variant.map_options.minbound][1]
        if variant.equal_time:
            # Its source's wall time (XSL's, maps included; gold's for Auto Volumes). A time
            # limit covers the rendering, so it gets it without the source's denoising pass
            # and pays its own on top; guided's budget covers its whole run, its denoising too.
            source = self.records[variant.time_source]
            timed = RenderStats.from_json(source["stats"])
            inputs["budget_s"] = timed.wall_s if variant.kind == "guided" else timed.render_seconds
            inputs["budget_from_hash"] = source["input_hash"]
        return inputs

    @staticmethod
    def request(variant: Variant, options: RenderOptions, inputs: dict) -> RenderRequest:
        """The render request of a variant: the gold standard, a selective render from its
        director map (its stats named after the variant), uniform at a share of the ceiling
        or at XSL's time, Cycles' adaptive sampling at XSL's time, guided in XSL's time, or
        Auto Volumes (uniform with auto's estimator) at the file's samples or in its time
        (up to ``AUTO_CEILING_FACTOR`` times the ceiling, so that Cycles' time limit stops it),
        the ceiling every other run has."""
        if variant.kind == "auto":
            auto = replace(options, estimator="auto")
            if variant.spp_fraction is not None:
                return RenderRequest("uniform", auto, spp=variant.spp(options.max_spp))
            return RenderRequest("uniform", replace(auto, max_spp=AUTO_CEILING_FACTOR * options.max_spp),
                                 seconds=inputs["budget_s"])
        if variant.kind == "gold":
            return RenderRequest("gold", options)
        if variant.kind == "selective":
            return RenderRequest(variant.director, options, label=variant.name)
        if variant.kind == "uniform" and variant.spp_fraction is not None:
            return RenderRequest("uniform", options, spp=variant.spp(options.max_spp))
        if variant.kind == "guided":
            return RenderRequest("guided", replace(options, estimator="auto"),
                                 guided=GuidedOptions(time_budget=float(inputs["budget_s"])),
                                 map_options=MapOptions())
        return RenderRequest(variant.kind, options, seconds=inputs["budget_s"])

    def render(self, variant: Variant) -> dict:
        from ...core.progress import run_steps
        from ..render_dispatch import request_frame_job

        exr = self.folder / f"{variant.name}.exr"
        spp_exr, spp_png = exr.with_name(f"{variant.name}_spp.exr"), exr.with_name(f"{variant.name}_spp.png")
        inputs = self.render_inputs(variant)
        digest = inputs_hash(inputs)
        label = f"{self.job.name}: {variant.name}"
        self.steps.begin(label)
        record = read_record(exr.with_suffix(".json"), digest, (exr, spp_exr, spp_png))
        if record is not None:
            self.results["reused"] += 1
            self.reused.add(variant.name)
            self.steps.finish()
            return record
        options = RenderOptions(**{**self.options.to_dict(), "resolution": tuple(self.size)}).check()
        scene, progress = self.open_scene(), self.steps.sub(label, echo=f"{variant.kind}: ")
        director, map_seconds = None, 0.0
        if variant.kind == "selective":
            director, _, map_seconds = self.director(variant)
        job = request_frame_job(self.request(variant, options, inputs).check(), director_map=director,
                                map_seconds=map_seconds, progress=progress)
        outcome = run_steps(job(scene), progress).outcome
        self.warnings += outcome.warnings
        started = time.perf_counter()
        attributes = {"xsl_render:mode": variant.name, "xsl_render:max_spp": options.max_spp}
        write_exr(exr, outcome.image, ["R", "G", "B", "A"], attributes=attributes)
        write_exr(spp_exr, outcome.samples, ["Y"], attributes=attributes)
        write_png(spp_png, outcome.samples / float(options.max_spp))
        outcome.stats.write_s = time.perf_counter() - started     # not part of the timing
        record = {"inputs": inputs, "input_hash": digest, "stats": outcome.stats.to_json(),
                  "files": {"image": self.rel(exr), "spp": self.rel(spp_exr), "spp_png": self.rel(spp_png)}}
        write_record(exr.with_suffix(".json"), record)
        self.results["rendered"] += 1
        self.steps.finish()
        return record

    # -- metrics --------------------------------------------------------------------------
    def compare(self, variant: Variant) -> None:
        record, gold = self.records[variant.name], self.records[GOLD]
        digest = inputs_hash({"step": "metrics", "render": record["input_hash"],
                              "gold": gold["input_hash"], "vdp": self.settings.vdp})
        label = f"{self.job.name}: metrics of {variant.name}"
        self.steps.begin(label)
        heatmaps = record.get("comparison", {}).get("heatmaps", {})
        if record.get("metrics_hash") != digest or not all(
                (self.out_dir / p).is_file() for p in heatmaps.values()):
            comparison = compare_with_gold(self.out_dir / gold["files"]["image"],
                                           self.out_dir / record["files"]["image"],
                                           self.folder / "heatmaps" / variant.name, vdp=self.settings.vdp)
            comparison["heatmaps"] = {k: self.rel(Path(v)) for k, v in comparison["heatmaps"].items()}
            record.update(comparison=comparison, metrics_hash=digest)
            write_record(self.folder / f"{variant.name}.json", record)
        self.steps.finish()

    # -- the converged reference ----------------------------------------------------------
    def reference(self):
        """The scene's converged reference at this size: cached (shipped with the repository,
        or in the user cache) or rendered now and cached."""
        from .reference import ensure_reference, reference_inputs

        scene = self.open_scene(warm=False)
        inputs = reference_inputs(scene, self.job.path, spp=self.settings.reference_spp,
                                  resolution=self.size, max_spp=self.options.max_spp,
                                  blend_sha256=self.sha256)
        if find_reference(inputs.key) is not None:
            self.steps.reweight(STEP_WEIGHTS["metrics"])
        label = f"{self.job.name}: converged reference ({inputs.spp} spp)"
        self.steps.begin(label)
        reference = ensure_reference(scene, inputs, progress=self.steps.sub(label, echo="uniform: "),
                                     file_name=self.job.path.name)
        self.results["reused" if reference.source != "rendered" else "rendered"] += 1
        self.steps.finish()
        return reference

    def compare_with_reference(self, variant: Variant, reference) -> None:
        """MSE, FLIP and VDP of a run (gold included) against the converged reference."""
        record = self.records[variant.name]
        digest = inputs_hash({"step": "reference_metrics", "render": record["input_hash"],
                              "reference": reference.inputs.key, "vdp": self.settings.vdp})
        label = f"{self.job.name}: {variant.name} against the reference"
        self.steps.begin(label)
        heatmaps = record.get("reference_comparison", {}).get("heatmaps", {})
        if record.get("reference_metrics_hash") != digest or not all(
                (self.out_dir / p).is_file() for p in heatmaps.values()):
            comparison = compare_with_gold(reference.path, self.out_dir / record["files"]["image"],
                                           self.folder / "heatmaps" / f"{variant.name}_vs_reference",
                                           vdp=self.settings.vdp)
            comparison["heatmaps"] = {k: self.rel(Path(v)) for k, v in comparison["heatmaps"].items()}
            record.update(reference_comparison=comparison, reference_metrics_hash=digest)
            write_record(self.folder / f"{variant.name}.json", record)
        self.steps.finish()
