"""The Blender side of a farm job's tasks: the maps of a frame, a share of its rectangles,
or (a guided job) the whole frame within its time budget.

What is done already and what a task owns is decided in ``core`` (``core.farm.files``,
``core.farm.task_groups``, ``core.farm.frame_outputs``) before Blender opens the scene, so a
task with nothing left to do returns at once. The pixels come from
``selective_render.render_rect`` and ``animation.guided_frame``, the same code
``xsl-render render`` uses, so the farm's frame equals a single-process render of the plan
(selective), or is the render ``xsl-render render --mode guided`` makes (guided).

``device`` (the job's Device: CPU or GPU) is set on the opened copy of the scene, never
written; None keeps the scene's own. ``progress`` gets (fraction, message) as the task goes
(the farm-task command prints them as Open Job Description's progress and status lines).
"""
from __future__ import annotations

import os
import socket
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..core.errors import InputError
from ..core.farm.files import (FrameFiles, guided_inputs, load_plan, maps_inputs, renderer_version,
                               scene_sha256, valid_plan, valid_tile, write_plan_record, write_tile)
from ..core.farm.frame_outputs import guided_frame_record, valid_frame_outputs, write_frame_outputs
from ..core.farm.task_groups import plan_group
from ..core.files import json_digest
from ..core.maps.files import write_map_set
from ..core.maps.options import MapOptions
from ..core.progress import ProgressCallback
from ..core.sampling.guided_plan import GuidedOptions
from ..core.sampling.render_files import frame_attributes, preview_scale
from ..core.sampling.render_options import RenderOptions
from ..core.sampling.tile_plan import make_plan

Log = Callable[[str], None]


@dataclass
class TaskOutcome:
    """What a task did: its work items, those rendered now and those already finished."""

    total: int
    done_now: list[str] = field(default_factory=list)
    reused: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0
    stats: dict | None = None       # a finished frame's statistics (the guided task)


def _open(scene_path, scene_name: str, frame: int, device: str | None):
    """The scene opened at ``frame`` on ``device`` (the opened copy only; never written)."""
    from .cycles.device import use_device
    from .scene.blend_session import open_blend

    scene = open_blend(scene_path, scene_name)
    scene.frame_set(frame)
    if device is not None:
        use_device(scene, device)
    return scene


def run_maps_task(scene_path: str | Path, scene_name: str, frame: int, output: str | Path,
                  mode: str, map_options: MapOptions, options: RenderOptions,
                  device: str | None = None, progress: ProgressCallback | None = None) -> TaskOutcome:
    """Director maps and tile plan of ``frame`` unless a finished plan for the same inputs exists."""
    from .scene.blend_session import check_blend_file

    started = time.perf_counter()
    files = FrameFiles(Path(output), frame)
    check_blend_file(scene_path)
    inputs = maps_inputs(scene_sha256(scene_path), scene_name, frame, mode, map_options.to_dict(), options)
    if valid_plan(files, inputs) is not None:
        return TaskOutcome(1, reused=[files.stem], seconds=time.perf_counter() - started)

    from .maps.director_maps import compute_maps

    scene = _open(scene_path, scene_name, frame, device)
    maps = compute_maps(scene, map_options, size=options.resolution, frame=frame, cache_dir=files.maps,
                        progress=progress)
    maps.info["file"] = str(scene_path)
    write_map_set(files.maps, maps)
    plan = make_plan(maps.director(mode), options)
    write_plan_record(files, inputs, plan, files.maps / f"{mode}.exr",
                      {"seconds": maps.info["seconds"], "warnings": maps.info.get("warnings", [])})
    return TaskOutcome(1, done_now=[files.stem], seconds=time.perf_counter() - started)


def run_tiles_task(scene_path: str | Path, frame: int, output: str | Path, group: int, groups: int,
                   log: Log | None = None, device: str | None = None,
                   progress: ProgressCallback | None = None) -> TaskOutcome:
    """Render the rectangles of ``frame`` that task ``group`` of ``groups`` owns and that have
    no finished image yet; each is written (image, then record) as soon as it is rendered."""
    from .scene.blend_session import check_blend_file

    started = time.perf_counter()
    log = log or (lambda line: None)
    files = FrameFiles(Path(output), frame)
    check_blend_file(scene_path)
    record = load_plan(files)
    if scene_sha256(scene_path) != record.scene_digest:
        raise InputError(f"{scene_path} is not the scene the maps of frame {frame} were computed "
                         "from (it changed, or is another file); rerun the maps step")
    if renderer_version() != record.blender:
        raise InputError(f"frame {frame} was planned with Blender {record.blender} but this machine "
                         f"renders with {renderer_version()}; one job needs one Blender release")
    options = record.options
    mine = plan_group(record.plan.rects, group, groups, options.render_cost)
    outcome = TaskOutcome(len(mine))
    todo = []
    for rect in mine:
        if valid_tile(files, record, rect) is None:
            todo.append(rect)
        else:
            outcome.reused.append(files.rect_name(rect))
    if not todo:
        outcome.seconds = time.perf_counter() - started
        return outcome

    from .cycles.selective_render import prepare_render, render_rect
    from .cycles.tile_render import CyclesWindowRenderer
    from .scene.state import preserved_scene

    report = progress or (lambda fraction, message: None)
    report(len(outcome.reused) / len(mine), f"opening the scene, {len(todo)} rectangles to render")
    scene = _open(scene_path, record.scene_name, frame, device)
    with preserved_scene(scene):
        width, height, outcome.warnings = prepare_render(scene, options)
        if (width, height) != (record.plan.width, record.plan.height):
            raise InputError(f"the plan of frame {frame} is {record.plan.width}x{record.plan.height} "
                             f"but the scene renders {width}x{height}; rerun the maps step")
        with CyclesWindowRenderer(scene, options.seed, guides=options.denoise) as renderer:
            for rect in todo:
                piece = render_rect(renderer, rect, options)
                write_tile(files, record, rect, piece.pixels, piece.samples, guides=piece.guides, details={
                    "group": group, "groups": groups, "spp": rect.spp,
                    "samples_rendered": piece.rendered.samples_rendered,
                    "seconds": piece.rendered.seconds, "render_id": uuid.uuid4().hex,
                    "pid": os.getpid(), "host": socket.gethostname(),
                    "finished": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})
                name = files.rect_name(rect)
                outcome.done_now.append(name)
                log(f"rendered {name} at {rect.spp} spp in {piece.rendered.seconds:.2f} s")
                done = len(outcome.reused) + len(outcome.done_now)
                report(done / len(mine), f"rendered {done} of {len(mine)} rectangles")
    outcome.seconds = time.perf_counter() - started
    return outcome


def run_guided_task(scene_path: str | Path, scene_name: str, frame: int, output: str | Path,
                    guided: GuidedOptions, map_options: MapOptions, options: RenderOptions,
                    device: str | None = None, progress: ProgressCallback | None = None) -> TaskOutcome:
    """Render ``frame`` with the guided sampler within ``guided.time_budget`` (its importance
    map inside the budget) unless its files are finished for the same inputs; write the
    image, samples and statistics as one set (``core.farm.frame_outputs``). ``options``:
    the resolution, seed and denoising; its ``max_spp`` the ceiling the statistics report.
    ``TaskOutcome.warnings`` holds the render's (a budget overrun among them)."""
    from .scene.blend_session import check_blend_file

    started = time.perf_counter()
    files = FrameFiles(Path(output), frame)
    check_blend_file(scene_path)
    uses_maps = guided.importance != "none"
    inputs = guided_inputs(scene_sha256(scene_path), scene_name, frame, guided.to_dict(),
                           map_options.to_dict() if uses_maps else None, options)
    finished = valid_frame_outputs(files, json_digest(inputs))
    if finished is not None:
        return TaskOutcome(1, reused=[files.stem], seconds=time.perf_counter() - started, stats=finished)

    from ..core.progress import run_steps
    from .animation import estimated_frame, guided_frame
    from .maps.estimator_choice import estimator_spp

    scene = _open(scene_path, scene_name, frame, device)
    job = estimated_frame(lambda chosen: guided_frame(guided, map_options, chosen), options,
                          estimator_spp("guided", options, {"guided": guided}))
    outcome = run_steps(job(scene), progress).outcome
    stats = guided_frame_record(inputs, {**outcome.stats, "frame": frame, "file": str(scene_path),
                                         "out": str(files.image)})
    scale = preview_scale(guided.max_spp, outcome.samples)
    attributes = frame_attributes(stats["mode"], scale, options.seed, stats["mean_spp"])
    write_frame_outputs(files, outcome.image, outcome.samples, scale, attributes, stats)
    return TaskOutcome(1, done_now=[files.stem], warnings=list(outcome.warnings),
                       seconds=time.perf_counter() - started, stats=stats)
