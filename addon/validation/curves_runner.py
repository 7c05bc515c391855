"""``xsl-render curves``: time-quality curves of every contestant against the converged
reference, resumable.

For one scene at one resolution: the reference (given, cached or rendered), then every
contestant of the chosen curves once per seed, timed as a whole and compared with the
reference; the medians and equal-quality speedups go to DIR/curves.json, curves.png and
report.html. Each run's image and record (``runs/<contestant>_seed<k>``) are written
atomically and reused while the hash of their inputs holds (scene bytes, size, frame,
contestant, seed, budget, Blender and denoiser versions). Over frames every run renders the
whole range in one Cycles session and is measured per frame against that frame's reference,
with the sequence's flicker and video JOD; it is reused only whole."""
from __future__ import annotations

import statistics
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...core.errors import InputError, SettingError
from ...core.files import file_sha256, write_json
from ...core.frames import frame_path
from ...core.imageio import read_image, write_exr
from ...core.progress import ProgressCallback, WeightedSteps
from ...core.sampling.render_options import RenderOptions
from ...core.validation.contestants import CURVES, Contestant, plan_contestants
from ...core.validation.curves_results import (FRAME_FIGURES, METRICS, SEQUENCE_METRICS, STATS_KEPT,
                                               build_curves, metric_values, sequence_values,
                                               summarise_run)
from ...core.validation.image_pair import check_pair
from ...core.validation.metrics import compare_images
from ...core.validation.reference import (REFERENCE_SEED, check_contestant_seeds,
                                          default_reference_spp, find_reference, read_reference)
from ...core.validation.store import inputs_hash, read_record, write_record
from ...core.validation.vdp import vdp_unavailable_reason
from ..cycles.denoise import DENOISE_VERSION
from ..scene.probe import render_size
from .contestants import run_contestant, run_contestant_frames, warm_up, without_frames
from .reference import (blender_version, ensure_reference, ensure_references, reference_inputs,
                        scene_ceiling)

#: Most repeats accepted (each repeat renders every contestant again).
MAX_REPEATS = 50
#: Statistics kept for each frame of a run over frames (beside ``STATS_KEPT``).
FRAME_STATS_KEPT = STATS_KEPT + ("cycles_sync_s", "sequence_budget", "maps")
#: How a run over frames names its frames inside its folder (``core.frames.frame_path``).
FRAME_NAME = "frame_####.exr"


@dataclass(frozen=True)
class CurvesSettings:
    """The knobs of one ``curves`` run.

    ``ceiling`` None: the scene's own Cycles samples. ``seed``: the first contestant seed
    (repeats use seed, seed + 1, ...). ``reference``: an EXR to use instead of the cached or
    rendered one; ``reference_spp``: the reference's samples (default max(1024, 16 x ceiling)).
    ``frames``: render every run over these frames (``core.frames.parse_frame_list``) in one
    Cycles session, instead of the one frame ``frame`` (the scene's current one when None).
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
    frames: tuple[int, ...] | None = None

    @property
    def seeds(self) -> list[int]:
        return list(range(self.seed, self.seed + self.repeats))

    def check(self) -> "CurvesSettings":
        """InputError (one line) for impossible values, before any scene is opened."""
        if not 1 <= self.repeats <= MAX_REPEATS:
            raise SettingError(f"{{repeats.name}} must be between 1 and {MAX_REPEATS} "
                               "(got {repeats.value})", repeats=self.repeats)
        if self.seed < 0:
            raise SettingError("{seed.name} must not be negative (got {seed.value})", seed=self.seed)
        if self.ceiling is not None and self.ceiling < 1:
            raise SettingError("{ceiling.name} must be at least 1 (got {ceiling.value})",
                               ceiling=self.ceiling)
        if self.reference_spp is not None and self.reference_spp < 1:
            raise SettingError("{reference_spp.name} must be at least 1 (got {reference_spp.value})",
                               reference_spp=self.reference_spp)
        if self.frames is not None:
            if not self.frames:
                raise SettingError("{frames.name} names no frame", frames=self.frames)
            if self.frame is not None:
                raise SettingError("{frame.name} and {frames.name} cannot be combined",
                                   frame=self.frame, frames=self.frames)
            if self.reference is not None:
                # The command that fills the cache is named as typed: it is a command, not a setting.
                raise SettingError("{reference.name} is one frame's reference; with {frames.name} "
                                   "each frame's comes from the cache (`xsl-render reference "
                                   "--frames`) or is rendered",
                                   reference=self.reference, frames=self.frames)
        if self.reference is None:
            check_contestant_seeds(self.seeds, REFERENCE_SEED)
        elif not Path(self.reference).is_file():
            raise InputError(f"no such reference file: {self.reference}")
        return self


def frames_text(frames: list[int]) -> str:
    """A frame list as ``--frames`` writes it: runs of one step as ``A-B`` or ``A-B:S``
    (at least three frames for a step above 1), single frames as they are ([1, 2, 3, 8] ->
    "1-3,8")."""
    items, index = [], 0
    while index < len(frames):
        end = index
        if index + 1 < len(frames):
            step = frames[index + 1] - frames[index]
            while end + 1 < len(frames) and frames[end + 1] - frames[end] == step:
                end += 1
            if step != 1 and end - index < 2:
                end = index
        first, last = frames[index], frames[end]
        if end == index:
            items.append(str(first))
        else:
            step = frames[index + 1] - first
            items.append(f"{first}-{last}" + (f":{step}" if step != 1 else ""))
        index = end + 1
    return ",".join(items)


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
        self.fps = float(scene.render.fps) / float(scene.render.fps_base or 1.0)
        self.frames = None if self.settings.frames is None else list(self.settings.frames)
        if self.frames is not None:
            missing = without_frames(self.contestants)
            if missing:
                raise SettingError(f"{{frames.name}}: {', '.join(missing)} cannot render over "
                                   "frames; leave their curves out ({curves.name})",
                                   frames=self.frames, curves=self.settings.curves)
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
        if self.frames is not None:
            return self.frame_references(steps)
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

    def frame_references(self, steps: WeightedSteps):
        """Each frame's reference, cached or rendered (one Cycles session for those rendered):
        ``{frame: path}`` and their description (per frame, and a key of them all)."""
        inputs = [reference_inputs(self.scene, self.blend_file, spp=self.settings.reference_spp,
                                   resolution=self.size, frame=frame, max_spp=self.ceiling,
                                   blend_sha256=self.sha256)
                  for frame in self.frames]
        check_contestant_seeds(self.settings.seeds, inputs[0].seed)
        if all(find_reference(item.key) is not None for item in inputs):
            steps.reweight(0.01)
        steps.begin(f"references of {len(inputs)} frames ({inputs[0].spp} spp)")
        references = ensure_references(self.scene, inputs, progress=steps.sub("references"),
                                       file_name=self.blend_file.name)
        steps.finish()
        frames = [reference.to_dict() for reference in references]
        info = {"key": inputs_hash({"step": "curve_references", "keys": [item["key"] for item in frames]}),
                "source": "+".join(dict.fromkeys(item["source"] for item in frames)),
                "inputs": {"spp": inputs[0].spp, "seed": inputs[0].seed}, "frames": frames}
        return {reference.inputs.frame: reference.path for reference in references}, info

    # -- runs --------------------------------------------------------------------------
    def run_inputs(self, contestant: Contestant, seed: int, budget_s: float | None) -> dict:
        where = ({"frame": self.scene.frame_current} if self.frames is None
                 else {"frames": list(self.frames)})
        inputs = {"step": "curve_run", "scene_sha256": self.sha256, "scene": self.scene.name,
                  **where, "size": list(self.size), "seed": seed,
                  "contestant": {k: v for k, v in contestant.to_dict().items() if k != "label"},
                  "blender": blender_version(),
                  "denoise": DENOISE_VERSION}
        if budget_s is not None:
            inputs["budget_s"] = budget_s
        return inputs

    def render(self, contestant: Contestant, seed: int, budget_s: float | None,
               steps: WeightedSteps) -> dict:
        if self.frames is not None:
            return self.render_frames(contestant, seed, budget_s, steps)
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
            record = {"inputs": inputs, "input_hash": digest, "seconds": seconds,
                      "stats": outcome.stats.to_json(keep=STATS_KEPT),
                      "file": exr.relative_to(self.out_dir).as_posix()}
            write_record(record_path, record)
            self.counts["rendered"] += 1
            record["reused"] = False
        steps.finish()
        return record

    def render_frames(self, contestant: Contestant, seed: int, budget_s: float | None,
                      steps: WeightedSteps) -> dict:
        """A run over every frame (module notes): its frames written as they are done, its
        record once all are."""
        stem = f"{contestant.name}_seed{seed}"
        folder, record_path = self.out_dir / "runs" / stem, self.out_dir / "runs" / f"{stem}.json"
        paths = {frame: Path(frame_path(str(folder / FRAME_NAME), frame)) for frame in self.frames}
        inputs = self.run_inputs(contestant, seed, budget_s)
        digest = inputs_hash(inputs)
        label = f"{contestant.name} (seed {seed})"
        steps.begin(label)
        record = read_record(record_path, digest, tuple(paths.values()))
        if record is not None:
            self.counts["reused"] += 1
            record["reused"] = True
            steps.finish()
            return record
        if not self.warm:
            warm_up(self.scene)
            self.warm = True
        options = RenderOptions(max_spp=self.ceiling, seed=seed, resolution=self.size).check()
        every = []

        def on_frame(result) -> dict:
            outcome = result.outcome
            path = paths[result.frame]
            write_exr(path, outcome.image, ["R", "G", "B", "A"],
                      attributes={"xsl_render:contestant": contestant.name, "xsl_render:seed": seed,
                                  "xsl_render:frame": result.frame})
            self.warnings.extend(f"frame {result.frame}: {w}" for w in outcome.warnings)
            every.append(outcome.stats)
            return {"frame": result.frame, "file": path.relative_to(self.out_dir).as_posix(),
                    "stats": outcome.stats.to_json(keep=FRAME_STATS_KEPT)}

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            frames, seconds = run_contestant_frames(self.scene, contestant, options, self.frames, budget_s,
                                                    on_frame, progress=steps.sub(label))
        self.warnings += [str(w.message) for w in caught]
        stats = {"mode": every[0].mode, "frames": len(frames),
                 "mean_spp": float(np.mean([s.mean_spp for s in every])),
                 "total_samples": sum(s.total_samples for s in every),
                 "cycles_sync_s": sum(s.cycles_sync_s or 0.0 for s in every),
                 "frame_wall_s": sum(s.wall_s for s in every)}
        if every[0].path_guiding is not None:
            stats.update(path_guiding=dict(every[0].path_guiding))
        record = {"inputs": inputs, "input_hash": digest, "seconds": seconds, "stats": stats,
                  "file": folder.relative_to(self.out_dir).as_posix(), "frames": frames}
        write_record(record_path, record)
        self.counts["rendered"] += 1
        record["reused"] = False
        steps.finish()
        return record

    def measure(self, record: dict, reference, reference_key: str) -> dict:
        """The record's metrics against the reference (reused while the reference is the same);
        over frames ``reference`` is ``{frame: path}``."""
        if self.frames is not None:
            return self.measure_frames(record, reference, reference_key)
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

    def measure_frames(self, record: dict, references: dict, reference_key: str) -> dict:
        """Every frame against its reference and the run as a sequence (``compare_sequence``:
        per-frame figures, their means, flicker, the video JOD at the scene's frame rate)."""
        from ...core.validation.frame_sequence import FramePair, FrameSize
        from ...core.validation.sequence import compare_sequence

        digest = inputs_hash({"step": "curve_metrics", "run": record["input_hash"], "reference": reference_key,
                              "vdp": self.settings.vdp, "fps": self.fps})
        if record.get("metrics_hash") != digest:
            pairs = [FramePair(entry["frame"], Path(references[entry["frame"]]), self.out_dir / entry["file"])
                     for entry in record["frames"]]
            compared = compare_sequence(pairs, FrameSize(self.size[0], self.size[1], True), fps=self.fps,
                                        vdp=self.settings.vdp)
            reused = record.pop("reused")
            for entry, measured in zip(record["frames"], compared["frames"]):
                entry.update({figure: measured[figure] for figure in FRAME_FIGURES}, metrics=measured["metrics"])
            record.update(sequence=compared["sequence"], metrics_hash=digest)
            write_record(self.out_dir / "runs" / f"{Path(record['file']).name}.json", record)
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
        metrics = METRICS if self.frames is None else SEQUENCE_METRICS
        runs = {c.name: summarise_run(c, [self.repeat_entry(r) for r in records[c.name]], budgets[c.name],
                                      metrics)
                for c in self.contestants}
        self.check_guiding(runs)
        scene = {"file": str(self.blend_file), "sha256": self.sha256, "scene": self.scene.name,
                 "frame": self.scene.frame_current, "size": list(self.size)}
        if self.frames is not None:
            scene.update(frame=self.frames[0], frames=list(self.frames),
                         frame_range=frames_text(self.frames), fps=self.fps)
        header = {"scene": scene,
                  "ceiling": self.ceiling, "reference": reference_info, "repeats": len(seeds),
                  "seeds": seeds, "vdp": {"ran": vdp_reason is None, "skipped": vdp_reason},
                  "warnings": list(dict.fromkeys(self.warnings)), **self.counts}
        return build_curves(header, CURVES, runs, metrics)

    def repeat_entry(self, record: dict) -> dict:
        recorded = record["stats"]          # the run record's copy of its stats (STATS_KEPT)
        if self.frames is not None:
            frames = [{"frame": entry["frame"], "file": entry["file"], "seconds": entry["stats"].get("wall_s"),
                       "mean_spp": entry["stats"].get("mean_spp"),
                       **{figure: entry.get(figure) for figure in FRAME_FIGURES}, "stats": entry["stats"]}
                      for entry in record["frames"]]
            return {"seed": record["inputs"]["seed"], "seconds": record["seconds"],
                    "mean_spp": recorded.get("mean_spp"), **sequence_values(record["sequence"]),
                    "file": record["file"], "reused": record["reused"], "stats": recorded,
                    "frames": frames}
        return {"seed": record["inputs"]["seed"], "seconds": record["seconds"],
                "mean_spp": recorded.get("mean_spp"), **metric_values(record["metrics"]),
                "file": record["file"], "reused": record["reused"], "stats": recorded}

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
                files = ([(repeat["file"], twin["file"])] if self.frames is None else
                         [(a["file"], b["file"]) for a, b in zip(repeat["frames"], twin["frames"])])
                identical = all(np.array_equal(read_image(self.out_dir / a), read_image(self.out_dir / b))
                                for a, b in files)
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
