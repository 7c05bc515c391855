"""What each panel operator does, as a job: steps (``core.progress``) and a finish.

The operators (``maps_operator.py``, ``render_operators.py``, ``compare_operator.py``) only
build a job from the scene and their own properties and hand it to ``job_operator.py``,
which runs it modally (the panel) or in one go (scripts, ``blender -b``). Keeping the jobs
here, apart from the operator classes, lets tests step them exactly as a modal operator does.
"""
from __future__ import annotations

import hashlib
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..core.checks import separate_files, writable_file
from ..core.errors import InputError
from ..core.frames import frame_path, has_frame_marker
from ..core.maps.files import MapSet
from ..core.panel.settings import guided_options, map_options, render_options
from ..core.progress import Steps
from ..core.sampling.render_files import render_output_paths, write_render_outputs


@dataclass
class JobResult:
    """What a finished job tells the artist: one report line and the image to look at."""

    report: str
    image: object = None
    warnings: list[str] = field(default_factory=list)


@dataclass
class Job:
    label: str                                  # "Maps", "Selective render", ...
    steps: Steps
    finish: Callable[[object], JobResult]       # runs once, outside every preserved_scene


def ray_cache_dir(scene) -> Path:
    """This session's ray cache for the scene: recomputing maps after a change to the media
    only (the paper's "instant recomputation") reuses the rays cast before. The cache key
    (camera and geometry) is checked on every use, so a stale cache is never used."""
    import bpy

    base = Path(bpy.app.tempdir or tempfile.gettempdir()) / "xsl_render_rays"
    digest = hashlib.sha1(f"{bpy.data.filepath}\0{scene.name}".encode()).hexdigest()[:12]
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", scene.name)[:40]
    return base / f"{safe}-{digest}"


# -- maps ----------------------------------------------------------------------------------
def maps_job(scene) -> Job:
    from ..addon.maps.director_maps import map_steps
    from ..addon.panel.image_display import MAP_IMAGES, show_maps

    options = map_options(scene.xsl_render)

    def finish(maps: MapSet) -> JobResult:
        images = show_maps(maps)
        shown = next(image for image in images if image.name == MAP_IMAGES[scene.xsl_render.director.lower()])
        return JobResult(maps_report(maps), shown, list(maps.info["warnings"]))

    return Job("Maps", map_steps(scene, options, cache_dir=ray_cache_dir(scene)), finish)


def maps_report(maps: MapSet) -> str:
    seconds = maps.info["seconds"]
    width, height = maps.info["size"]
    rays = "reused" if maps.info["x"]["cache"]["hit"] else "cast"
    return (f"Maps {width}x{height} in {seconds['total']:.2f} s: X {seconds['x']:.2f} s (camera rays "
            f"{rays}), snapshot {seconds['snapshot']:.2f} s, S {seconds['s']:.2f} s, L {seconds['l']:.2f} s")


# -- renders -------------------------------------------------------------------------------
def selective_job(scene, animation: bool = False, filepath: str = "", budget: bool = False) -> Job:
    """Maps, then the selective render driven by the director map chosen in the panel; or
    (``budget``) the render within the panel's time budget (its importance map computed first,
    inside the budget; the frames of an animation share their budgets)."""
    from ..addon.render_dispatch import request_frame_job
    from ..core.sampling.sequence_budget import SequenceBudget
    from ..core.sampling.render_request import RenderRequest

    settings = scene.xsl_render
    options = render_options(settings, budget)
    sequence = None
    if budget:
        request = RenderRequest("guided", options, guided=guided_options(settings),
                                map_options=map_options(settings)).check()
        label = "Time budget render"
        # An animation's frames share its time (the first frame's scene sync paid back by the rest).
        if animation:
            sequence = SequenceBudget(request.guided.time_budget, len(animation_frames(scene)))
    else:
        request = RenderRequest(settings.director.lower(), options, map_options=map_options(settings)).check()
        label = f"{request.mode.upper()} render"
    frame_job = request_frame_job(request, ray_cache_dir(scene), sequence)
    if animation:
        return _animation_job(scene, label, frame_job, options, filepath, gold=False)
    return Job(label, frame_job(scene), _still_finish(scene, options, filepath, gold=False))


def gold_job(scene, animation: bool = False, filepath: str = "", banded: bool = False) -> Job:
    """Max samples everywhere: one Cycles render, or (``banded``, the panel) full-width bands
    bit-identical to it that a modal operator can stop between."""
    from ..addon.cycles.banded_gold import gold_band_steps
    from ..addon.frame_jobs import estimated_frame, stepped_render_frame
    from ..addon.render_dispatch import request_frame_job
    from ..core.sampling.render_request import RenderRequest

    options = render_options(scene.xsl_render)
    if banded:
        # Not another mode: the gold render cut so that a modal operator can stop between bands.
        frame_job = estimated_frame(
            lambda chosen: stepped_render_frame(lambda s: gold_band_steps(s, chosen)),
            options, options.max_spp)
    else:
        frame_job = request_frame_job(RenderRequest("gold", options).check())
    if animation:
        return _animation_job(scene, "Gold render", frame_job, options, filepath, gold=True)
    return Job("Gold render", frame_job(scene), _still_finish(scene, options, filepath, gold=True))


def still_output(filepath: str, frame: int = 0) -> str:
    """The EXR file a still render writes (``filepath`` made absolute), checked before the
    render: the files are EXR as ``xsl-render render`` writes them, whatever the name says
    otherwise, so another extension is refused rather than written as EXR under it. Empty:
    no file."""
    import bpy

    if not filepath:
        return ""
    path = bpy.path.abspath(filepath)
    still = frame_path(path, frame) if has_frame_marker(path) else path
    writable_file(still, (".exr",), name="the output path")
    check_outputs([still])
    return path


def check_outputs(paths: list[str]) -> None:
    """The files a render writes (each image with its ``_spp`` files) against the open
    .blend and each other, as the command line checks them (``core.checks.separate_files``)."""
    import bpy

    outputs = {}
    for path in paths:
        name = Path(path).name
        outputs.update({f"the output {name}" if label == "--out" else
                        f"{name}'s {label.removeprefix('its ')}": file
                        for label, file in render_output_paths(path).items()})
    separate_files({"the open file": bpy.data.filepath or None}, outputs)


def _still_finish(scene, options, filepath: str, gold: bool):
    from ..addon.panel.image_display import show_maps, show_render

    path = still_output(filepath, scene.frame_current)

    def finish(result) -> JobResult:
        outcome = result.outcome
        warnings = list(outcome.warnings)
        if result.maps is not None:
            show_maps(result.maps)
            warnings += result.maps.info["warnings"]
        image, _ = show_render(outcome, options.max_spp, gold=gold)
        report = render_report(outcome.stats)
        if path:
            written = frame_path(path, result.frame) if has_frame_marker(path) else path
            write_render_outputs(written, outcome.image, outcome.samples, outcome.stats,
                                 options.max_spp, options.seed)
            report += f" -> {written}"
        return JobResult(report, image, warnings)

    return finish


def render_report(stats) -> str:
    """The status line of a panel render (``RenderStats``)."""
    width, height = stats.resolution
    head = f"{stats.mode.upper()} {width}x{height}: mean {stats.mean_spp:.1f} spp"
    if stats.guided is not None:
        importance = stats.guided.importance
        weighed = "" if importance == "none" else f", error weighed by {importance.upper()}"
        return (f"{head} (ceiling {stats.max_spp}{weighed}) in {stats.renders} render(s), "
                f"{stats.wall_s:.1f} s of a {stats.time_budget_s:g} s budget")
    share = 100.0 * stats.total_samples / max(1, stats.gold_samples)
    return (f"{head} ({share:.0f}% of the gold standard's samples) in {stats.renders} render(s), "
            f"{stats.wall_s:.1f} s")


@dataclass(frozen=True)
class PanelFrame:
    """One frame of the panel's animation render, as written."""

    frame: int
    path: str
    stats: object                           # its ``RenderStats``
    warnings: list[str]


def animation_frames(scene) -> range:
    """The frames the panel's animation render renders: the scene's range and step."""
    return range(scene.frame_start, scene.frame_end + 1, max(1, scene.frame_step))


def _animation_job(scene, label: str, frame_job, options, filepath: str, gold: bool) -> Job:
    """The scene's frame range, each frame written as a numbered EXR as soon as it is done."""
    import bpy

    from ..addon.frame_jobs import frames_steps
    from ..addon.panel.image_display import (GOLD_IMAGE, GOLD_SAMPLES_IMAGE, MAP_IMAGES,
                                             RENDER_IMAGE, SAMPLES_IMAGE, ensure_image, show_maps,
                                             show_render)
    from ..addon.scene.probe import render_size

    pattern = bpy.path.abspath(filepath or scene.render.filepath)
    if not pattern:
        raise InputError("no output path for the frames: set one in the panel or in Output properties")
    frames = animation_frames(scene)
    check_outputs([frame_path(pattern, frame) for frame in frames])
    # frames_steps removes datablocks made during the run, so the images exist beforehand.
    width, height = render_size(scene)
    names = [(GOLD_IMAGE, False), (GOLD_SAMPLES_IMAGE, True)] if gold else \
        [(RENDER_IMAGE, False), (SAMPLES_IMAGE, True)] + [(name, key != "snapshot")
                                                          for key, name in MAP_IMAGES.items()]
    for name, data in names:
        ensure_image(name, width, height, data)

    def on_frame(result) -> PanelFrame:
        path = frame_path(pattern, result.frame)
        outcome = result.outcome
        write_render_outputs(path, outcome.image, outcome.samples, outcome.stats,
                             options.max_spp, options.seed)
        show_render(outcome, options.max_spp, gold=gold)
        if result.maps is not None:
            show_maps(result.maps)
        maps = outcome.stats.maps
        return PanelFrame(result.frame, path, outcome.stats,
                          list(outcome.warnings) + (list(maps.warnings) if maps is not None else []))

    def finish(done: list[PanelFrame]) -> JobResult:
        hits = [entry.stats.maps.ray_cache_hit for entry in done if entry.stats.maps is not None]
        report = (f"{label}: {len(done)} frame(s) {frames.start}..{frames.stop - 1} -> "
                  f"{Path(done[0].path).parent if done else pattern}")
        if hits:
            report += f"; camera rays cast {hits.count(False)}x, reused {hits.count(True)}x"
        image = bpy.data.images.get(GOLD_IMAGE if gold else RENDER_IMAGE)
        warnings = list(dict.fromkeys(w for entry in done for w in entry.warnings))
        return JobResult(report, image, warnings)

    return Job(f"{label} (animation)", frames_steps(scene, frames, frame_job, on_frame), finish)


# -- compare -------------------------------------------------------------------------------
def compare_job() -> Job:
    """The gold standard against the selective render: FLIP and MSE, and FLIP's heatmap."""
    import bpy

    from ..addon.panel.image_display import (GOLD_IMAGE, HEATMAP_IMAGE, RENDER_IMAGE, read_pixels,
                                             show)
    from ..core.validation.heatmap import colourise
    from ..core.validation.image_pair import check_pair
    from ..core.validation.metrics import compare_images

    def steps():
        gold, test = bpy.data.images.get(GOLD_IMAGE), bpy.data.images.get(RENDER_IMAGE)
        if gold is None or test is None:
            raise InputError(f"render '{GOLD_IMAGE}' and '{RENDER_IMAGE}' first (Gold Render, Selective Render)")
        yield 0.0, "reading images"
        pair = check_pair(read_pixels(gold), read_pixels(test), hdr=True, names=(GOLD_IMAGE, RENDER_IMAGE))
        yield 0.1, "MSE and FLIP"
        return compare_images(pair, vdp=False)

    def finish(results) -> JobResult:
        flip, mse = results["flip"], results["mse"]
        numbers = {"mean_flip": float(flip.extra["mean_flip"]), "mse": float(mse.extra["mse"]),
                   "flip_error_pixels_percent": float(flip.error_pixel_percent),
                   "mse_error_pixels_percent": float(mse.error_pixel_percent),
                   "flip_mode": str(flip.extra["mode"])}
        image = show(HEATMAP_IMAGE, colourise(flip.per_pixel, flip.heatmap_full_scale), data=True,
                     info=numbers)
        report = (f"Gold vs {RENDER_IMAGE}: mean FLIP {numbers['mean_flip']:.4f} ({numbers['flip_mode']}), "
                  f"MSE {numbers['mse']:.3g}; error pixels FLIP {numbers['flip_error_pixels_percent']:.2f} %, "
                  f"MSE {numbers['mse_error_pixels_percent']:.2f} %")
        return JobResult(report, image)

    return Job("Compare", steps(), finish)
