"""The Blender side of a farm job's tasks: the maps of a chunk of frames, a share of each of
their rectangles, or (a guided job) the whole frames, each within its time budget.

A task renders its chunk one frame after another in one Blender process, so the scene is
opened once and Cycles syncs it once per chunk; each frame is kept as soon as it is done, so
a task run again renders only what it had not finished. What is done already is decided in
``core`` (``core.farm.files``, ``task_groups``, ``frame_outputs``) before Blender opens the
scene. The pixels come from the code ``xsl-render render`` uses, so the farm's frame equals a
single-process render. ``device`` is set on the opened copy, never written; ``progress`` hears
(fraction of the chunk, message); each task returns one ``TaskOutcome`` per frame."""
from __future__ import annotations

import os
import shutil
import socket
import tempfile
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

from ...core.errors import InputError
from ...core.farm.files import (FrameFiles, guided_inputs, known_scene_inputs, load_plan, maps_inputs,
                               renderer_version, scene_sha256, valid_plan, valid_tile, write_plan_record,
                               write_scene_inputs, write_tile)
from ...core.farm.frame_outputs import FrameSummary, guided_frame_record, valid_frame_outputs, write_frame_outputs
from ...core.farm.task_groups import plan_group
from ...core.files import atomic_path, json_digest
from ...core.maps.camera_rays import CACHE_NAME
from ...core.maps.files import write_map_set
from ...core.maps.options import MapOptions
from ...core.progress import ProgressCallback
from ...core.sampling.finite_pixels import zero_non_finite
from ...core.sampling.guided_plan import GuidedOptions
from ...core.sampling.render_files import frame_attributes, preview_scale
from ...core.sampling.render_options import RenderOptions
from ...core.sampling.tile_plan import make_plan

Log = Callable[[str], None]


@dataclass
class TaskOutcome:
    """What a task did for one frame: its work items, those rendered now and those already
    finished."""

    frame: int
    total: int
    done_now: list[str] = field(default_factory=list)
    reused: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0
    stats: dict | None = None       # a finished frame's statistics (the guided task)


def _open(scene_path, scene_name: str, frame: int, device: str | None):
    """The scene opened at ``frame`` on ``device`` (the opened copy only; never written)."""
    from ..cycles.device import use_device
    from ..scene.blend_session import open_blend

    scene = open_blend(scene_path, scene_name)
    scene.frame_set(frame)
    if device is not None:
        use_device(scene, device)
    return scene


def scene_digest(scene_path, output) -> str:
    """The digest of what the job's scene is made from: the .blend and the identity of every
    file it reads (``addon.scene.scene_inputs``), so that work made from other files is
    redone. Known without Blender while the job's record of them holds
    (``core.farm.files.known_scene_inputs``); else the scene is opened and they are listed
    again, and a file it reads that does not exist fails the task (InputError): Blender would
    render on without it (a fog-less frame, where a library is missing)."""
    blend = scene_sha256(scene_path)
    inputs = known_scene_inputs(output, blend)
    if inputs is None:
        from ..scene.blend_session import open_blend
        from ..scene.scene_inputs import blend_inputs

        open_blend(scene_path)
        inputs, missing = blend_inputs(scene_path)
        if missing:
            more = f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""
            raise InputError(f"the scene reads {missing[0]}, which does not exist{more}")
        write_scene_inputs(output, inputs)
    return json_digest(inputs)


def _part(progress: ProgressCallback | None, start: float, end: float, prefix: str) -> ProgressCallback:
    """``progress`` for one frame of a chunk: its fractions mapped onto [start, end]."""
    def report(fraction: float, message: str):
        if progress is not None:
            return progress(start + (end - start) * min(1.0, max(0.0, fraction)), prefix + message)
        return False
    return report


def _task_record(frames: Sequence[int]) -> dict:
    """Which task made a frame: the process, the machine and the frames of its chunk."""
    return {"frames": list(frames), "pid": os.getpid(), "host": socket.gethostname(),
            "finished": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}


def _carry_rays(previous: Path | None, folder: Path) -> None:
    """Give ``folder`` the previous frame's ray cache when it has none: the X map reuses the
    camera rays while the camera and geometry stay (its key says whether they did) and casts
    new ones otherwise, so a chunk of a still shot casts them once."""
    source, target = (None if previous is None else previous / CACHE_NAME), folder / CACHE_NAME
    if source is None or not source.is_file() or target.exists():
        return
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(target) as temporary:
        shutil.copyfile(source, temporary)


def run_maps_task(scene_path: str | Path, scene_name: str, frames: Sequence[int], output: str | Path,
                  mode: str, map_options: MapOptions, options: RenderOptions,
                  device: str | None = None, progress: ProgressCallback | None = None) -> list[TaskOutcome]:
    """Director maps and tile plan of each of ``frames`` that has no finished plan for the same
    inputs; each plan is written as soon as its frame's maps are."""
    from ..scene.blend_session import check_blend_file

    check_blend_file(scene_path)
    digest = scene_digest(scene_path, output)
    outcomes, todo = {}, []
    for frame in frames:
        started = time.perf_counter()
        files = FrameFiles(Path(output), frame)
        inputs = maps_inputs(digest, scene_name, frame, mode, map_options.to_dict(), options)
        if valid_plan(files, inputs) is not None:
            outcomes[frame] = TaskOutcome(frame, 1, reused=[files.stem],
                                          seconds=time.perf_counter() - started)
        else:
            todo.append((files, inputs))
    if todo:
        from ..cycles.selective_render import guide_prefilter
        from ..maps.director_maps import compute_maps

        scene = _open(scene_path, scene_name, todo[0][0].frame, device)
        previous, skipped = None, len(frames) - len(todo)
        for index, (files, inputs) in enumerate(todo):
            started = time.perf_counter()
            _carry_rays(previous, files.maps)
            report = _part(progress, (skipped + index) / len(frames), (skipped + index + 1) / len(frames),
                           f"frame {files.frame}: ")
            maps = compute_maps(scene, map_options, size=options.resolution, frame=files.frame,
                                cache_dir=files.maps, progress=report)
            maps.info["file"] = str(scene_path)
            write_map_set(files.maps, maps)
            plan = make_plan(maps.director(mode), options)
            write_plan_record(files, inputs, plan, files.maps / f"{mode}.exr",
                              {"seconds": maps.info["seconds"], "warnings": maps.info.get("warnings", []),
                               "ray_cache_hit": bool(maps.info["x"]["cache"]["hit"]),
                               "task": _task_record(frames),
                               # The file's denoiser, which the composite denoises as (the
                               # .blend's digest above covers it).
                               "denoise_prefilter": guide_prefilter(scene)})
            outcomes[files.frame] = TaskOutcome(files.frame, 1, done_now=[files.stem],
                                                seconds=time.perf_counter() - started)
            previous = files.maps
    return [outcomes[frame] for frame in frames]


def run_tiles_task(scene_path: str | Path, frames: Sequence[int], output: str | Path, group: int,
                   groups: int, log: Log | None = None, device: str | None = None,
                   progress: ProgressCallback | None = None) -> list[TaskOutcome]:
    """Render the rectangles of each of ``frames`` that task ``group`` of ``groups`` owns and
    that have no finished image yet, the frames one after another in one Cycles session;
    each rectangle is written (image, then record) as soon as it is rendered."""
    from ..scene.blend_session import check_blend_file

    log = log or (lambda line: None)
    check_blend_file(scene_path)
    digest = scene_digest(scene_path, output)
    work = []
    for frame in frames:
        started = time.perf_counter()
        files = FrameFiles(Path(output), frame)
        record = load_plan(files)
        if digest != record.scene_digest:
            raise InputError(f"{scene_path} is not the scene the maps of frame {frame} were computed "
                             "from (it changed, or is another file); rerun the maps step")
        if renderer_version() != record.blender:
            raise InputError(f"frame {frame} was planned with Blender {record.blender} but this machine "
                             f"renders with {renderer_version()}; one job needs one Blender release")
        mine = plan_group(record.plan.rects, group, groups, record.options.render_cost)
        outcome = TaskOutcome(frame, len(mine))
        todo = []
        for rect in mine:
            if valid_tile(files, record, rect) is None:
                todo.append(rect)
            else:
                outcome.reused.append(files.rect_name(rect))
        outcome.seconds = time.perf_counter() - started
        work.append((files, record, todo, outcome))
    outcomes = [outcome for *_, outcome in work]
    pending = [item for item in work if item[2]]
    if not pending:
        return outcomes

    from ..cycles.selective_render import prepare_render, render_rect
    from ..scene.state import preserved_scene

    names = {record.scene_name for _, record, _, _ in pending}
    if len(names) > 1:
        raise InputError(f"the frames {', '.join(str(f) for f in frames)} were planned from "
                         f"different scenes ({', '.join(sorted(names))}); one task renders one scene")
    label = f"task {group}/{groups}"
    total = sum(outcome.total for outcome in outcomes) or 1
    done = sum(len(outcome.reused) for outcome in outcomes)
    report = progress or (lambda fraction, message: None)
    report(done / total, f"{label}: opening the scene, "
           f"{sum(len(todo) for _, _, todo, _ in pending)} rectangles to render")
    scene = _open(scene_path, pending[0][1].scene_name, pending[0][0].frame, device)
    renderer, made_for = None, None
    with preserved_scene(scene):
        try:
            for files, record, todo, outcome in pending:
                started = time.perf_counter()
                frame, options = files.frame, record.options
                scene.frame_set(frame)
                width, height, warnings = prepare_render(scene, options)
                outcome.warnings = warnings
                if (width, height) != (record.plan.width, record.plan.height):
                    raise InputError(f"the plan of frame {frame} is {record.plan.width}x"
                                     f"{record.plan.height} but the scene renders {width}x{height}; "
                                     "rerun the maps step")
                renderer, made_for = _window_renderer(renderer, made_for, scene, options)
                for rect in todo:
                    piece = render_rect(renderer, rect, options)
                    # (As a frame's are, before its composite denoises: core.sampling.finite_pixels.)
                    pixels, non_finite = zero_non_finite(piece.pixels, whole_frame=False)
                    guides = None if piece.guides is None else zero_non_finite(piece.guides, whole_frame=False)[0]
                    write_tile(files, record, rect, pixels, piece.samples, guides=guides, details={
                        "group": group, "groups": groups, "spp": rect.spp, "non_finite_pixels": non_finite,
                        "samples_rendered": piece.rendered.samples_rendered,
                        "seconds": piece.rendered.seconds,
                        "cycles_sync_s": piece.rendered.sync_seconds, "render_id": uuid.uuid4().hex,
                        "pid": os.getpid(), "host": socket.gethostname(), "frames": list(frames),
                        "finished": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})
                    name = files.rect_name(rect)
                    outcome.done_now.append(name)
                    log(f"frame {frame}, {label}: rendered {name} at {rect.spp} spp in "
                        f"{piece.rendered.seconds:.2f} s")
                    done += 1
                    report(done / total, f"frame {frame}, {label}: rendered "
                           f"{len(outcome.reused) + len(outcome.done_now)} of {outcome.total} rectangles")
                outcome.seconds += time.perf_counter() - started
        finally:
            if renderer is not None:
                renderer.close()
    return outcomes


def _window_renderer(renderer, made_for: tuple | None, scene, options: RenderOptions):
    """(renderer, what it was made for): one Cycles window renderer for the frames of a chunk
    (persistent data: the scene is synced once), a new one only where a frame's plan asks for
    another seed, denoising guides or size."""
    from ..cycles.tile_render import CyclesWindowRenderer
    from ..scene.probe import render_size

    wanted = (options.seed, options.denoise, render_size(scene))
    if renderer is not None and made_for == wanted:
        return renderer, made_for
    if renderer is not None:
        renderer.close()
    return CyclesWindowRenderer(scene, options.seed, guides=options.denoise), wanted


def run_guided_task(scene_path: str | Path, scene_name: str, frames: Sequence[int], output: str | Path,
                    guided: GuidedOptions, map_options: MapOptions, options: RenderOptions,
                    device: str | None = None, progress: ProgressCallback | None = None) -> list[TaskOutcome]:
    """Render each of ``frames`` whose files are not finished for the same inputs with the
    guided sampler, one after another in one Cycles session (``frame_jobs.frames_steps``),
    as ``xsl-render render --mode guided --frames`` does: the frames rendered share
    ``guided.time_budget`` each (``SequenceBudget``: the first one's scene sync is paid back
    by the others), a frame's importance map inside its share, camera rays kept for the next
    frame. Each frame's image, samples and statistics are written as one set
    (``core.farm.frame_outputs``) as soon as it is rendered. ``options``: the resolution,
    seed and denoising; its ``max_spp`` the ceiling the statistics report. A frame's
    ``warnings`` hold its render's (a budget overrun among them)."""
    from ..scene.blend_session import check_blend_file

    check_blend_file(scene_path)
    digest = scene_digest(scene_path, output)
    uses_maps = guided.importance != "none"
    outcomes, inputs = {}, {}
    for frame in frames:
        started = time.perf_counter()
        files = FrameFiles(Path(output), frame)
        inputs[frame] = guided_inputs(digest, scene_name, frame, guided.to_dict(),
                                      map_options.to_dict() if uses_maps else None, options)
        finished = valid_frame_outputs(files, json_digest(inputs[frame]))
        if finished is not None:
            outcomes[frame] = TaskOutcome(frame, 1, reused=[files.stem], stats=finished,
                                          seconds=time.perf_counter() - started)
    todo = [frame for frame in frames if frame not in outcomes]
    if todo:
        from ...core.progress import run_steps, scaled_steps
        from ...core.sampling.sequence_budget import SequenceBudget
        from ...core.sampling.render_request import RenderRequest
        from ..frame_jobs import frames_steps
        from ..render_dispatch import request_frame_job

        def on_frame(result) -> None:
            files = FrameFiles(Path(output), result.frame)
            outcome = result.outcome
            frame_stats = outcome.stats
            frame_stats.frame, frame_stats.file, frame_stats.out = result.frame, str(scene_path), str(files.image)
            stats = guided_frame_record(inputs[result.frame],
                                        {**frame_stats.to_json(), "task": _task_record(frames)})
            scale = preview_scale(options.max_spp if options.has_ceiling else None, outcome.samples)
            attributes = frame_attributes(frame_stats.mode, scale, options.seed, frame_stats.mean_spp)
            write_frame_outputs(files, outcome.image, outcome.samples, scale, attributes, stats)
            outcomes[result.frame] = TaskOutcome(result.frame, 1, done_now=[files.stem],
                                                 warnings=list(outcome.warnings),
                                                 seconds=FrameSummary.from_record(stats).wall_s, stats=stats)

        scene = _open(scene_path, scene_name, todo[0], device)
        sequence = SequenceBudget(guided.time_budget, len(todo))
        rays = Path(tempfile.mkdtemp(prefix="xsl-rays-"))
        try:
            request = RenderRequest("guided", options, guided=guided, map_options=map_options)
            job = request_frame_job(request, rays, sequence)
            run_steps(scaled_steps(frames_steps(scene, todo, job, on_frame),
                                   1.0 - len(todo) / len(frames), 1.0), progress)
        finally:
            shutil.rmtree(rays, ignore_errors=True)
    return [outcomes[frame] for frame in frames]
