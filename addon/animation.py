"""Frame ranges: each frame gets its own maps and render, the camera rays are cast once.

The paper (4.1): the Z buffer "allows for instant recomputations of the X map if the
description of the medium in the scene changes (such as dynamic fog or smoke)". Every
frame's maps share one ray cache folder; its key is the camera and the geometry, so while
only the medium is animated, frames 2..N reuse the rays of frame 1 and only integrate the
new densities along them (a moving camera or object simply recasts them).

The guided render's frame job (``guided_frame``) computes its importance map inside the
frame's own time budget. Used by ``xsl-render render`` (and the batch entry), the farm's
guided task and the panel's render operators, as steps (``core.progress``): the command line
drives them in one go, the panel one step per timer tick.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

from ..core.maps.files import MapSet
from ..core.maps.options import MapOptions
from ..core.progress import Steps, scaled_steps, timed_steps
from ..core.sampling.guided_plan import GuidedOptions
from ..core.sampling.render_options import RenderOptions
from .cycles.guided_render import guided_steps
from .cycles.selective_render import RenderOutcome, selective_steps
from .maps.director_maps import map_steps, named_map_steps
from .maps.estimator_choice import with_estimator_choice
from .scene.state import preserved_scene

#: Share of a selective frame's progress bar given to its maps.
MAP_SHARE = 0.25
#: Share of a guided frame's progress bar given to its importance map (when it has one).
IMPORTANCE_SHARE = 0.15


@dataclass
class FrameResult:
    """One rendered frame."""

    frame: int
    outcome: RenderOutcome
    maps: MapSet | None = None


#: Renders the scene at its current frame, as steps.
FrameJob = Callable[[object], Steps[FrameResult]]


def frames_steps(scene, frames: Sequence[int], render_frame: FrameJob,
                 on_frame: Callable[[FrameResult], object]) -> Steps[list]:
    """Render ``frames`` in order; ``on_frame(result)`` (write files, show images) runs as
    soon as a frame is done, so a cancelled run keeps every finished frame. Returns the list
    of what ``on_frame`` returned. The scene's frame and settings are restored at the end.

    Datablocks created inside are removed at the end (``preserved_scene``), so images
    shown by ``on_frame`` must exist before the run starts.
    """
    frames = list(frames)
    done = []
    with preserved_scene(scene):
        for index, frame in enumerate(frames):
            scene.frame_set(frame)
            result = yield from scaled_steps(render_frame(scene), index / len(frames),
                                             (index + 1) / len(frames),
                                             f"frame {frame} ({index + 1}/{len(frames)}): ")
            done.append(on_frame(result))
    return done


def selective_frame(map_options: MapOptions, options: RenderOptions, mode: str,
                    cache_dir) -> FrameJob:
    """A frame job for xs / xsl: the frame's maps (rays cached in ``cache_dir``), then the
    selective render driven by the map named ``mode``."""

    def steps(scene) -> Steps[FrameResult]:
        maps = yield from scaled_steps(map_steps(scene, map_options, size=options.resolution,
                                                 cache_dir=cache_dir), 0.0, MAP_SHARE, "maps: ")
        outcome = yield from scaled_steps(
            selective_steps(scene, maps.director(mode), options, mode, maps.info["seconds"]["total"]),
            MAP_SHARE, 1.0)
        outcome.stats["maps"] = maps_summary(maps)
        return FrameResult(scene.frame_current, outcome, maps)

    return steps


def guided_frame(guided: GuidedOptions, map_options: MapOptions | None, options: RenderOptions,
                 cache_dir=None) -> FrameJob:
    """A frame job for the guided render within ``guided.time_budget``: the importance map
    it asks for first (rays cached in ``cache_dir``), inside the budget (its seconds, not the
    time spent waiting between steps, are passed on as spent), then the guided render. The
    command line, the farm and the panel all render guided frames through this job."""
    guided.check()

    def steps(scene) -> Steps[FrameResult]:
        importance, map_seconds, start = None, 0.0, 0.0
        if guided.importance != "none":
            maps = named_map_steps(scene, guided.importance, map_options, options.resolution, cache_dir)
            importance, map_seconds = yield from scaled_steps(
                timed_steps(maps), 0.0, IMPORTANCE_SHARE, f"{guided.importance.upper()} map: ")
            start = IMPORTANCE_SHARE
        outcome = yield from scaled_steps(guided_steps(scene, options, guided, importance, map_seconds),
                                          start, 1.0)
        return FrameResult(scene.frame_current, outcome)

    return steps


def estimated_frame(make_job: Callable[[RenderOptions], FrameJob], options: RenderOptions,
                    spp: float) -> FrameJob:
    """The frame job ``make_job(options)`` with ``--estimator auto`` chosen for each frame
    (its media may move) before the frame's maps and renders, inside its time."""
    if options.estimator != "auto" or options.estimator_choice is not None:
        return make_job(options)

    def steps(scene) -> Steps[FrameResult]:
        chosen = with_estimator_choice(scene, options, spp)
        return (yield from make_job(chosen)(scene))

    return steps


def single_render_frame(render: Callable[[object], RenderOutcome], label: str) -> FrameJob:
    """A frame job for one ordinary render (gold, uniform, adaptive): ``render(scene)``."""

    def steps(scene) -> Steps[FrameResult]:
        yield 0.0, f"{label}: rendering"
        return FrameResult(scene.frame_current, render(scene))

    return steps


def stepped_render_frame(render_steps: Callable[[object], Steps[RenderOutcome]]) -> FrameJob:
    """A frame job from a render written as steps (e.g. the banded gold render)."""

    def steps(scene) -> Steps[FrameResult]:
        outcome = yield from render_steps(scene)
        return FrameResult(scene.frame_current, outcome)

    return steps


def maps_summary(maps: MapSet) -> dict:
    """What a frame's statistics record about its maps: seconds and the ray cache."""
    cache = maps.info["x"]["cache"]
    return {"frame": maps.info["frame"], "seconds": maps.info["seconds"],
            "ray_cache_hit": bool(cache["hit"]), "ray_cache": cache["path"],
            "warnings": maps.info["warnings"]}
