"""Frame jobs: how one frame is rendered (maps, estimator, render), for a still and for a frame
range alike, as steps (``core.progress``) the command line drives in one go and the panel one
step per timer tick.

A range renders in one Cycles session and shares one ray cache keyed by the camera and the
geometry, so while only the medium is animated later frames reuse the first frame's camera
rays (the paper's "instant recomputation", 4.1). The guided render's frame job computes its
importance map inside the frame's own time budget."""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Sequence

from ..core.maps.files import MapSet
from ..core.maps.options import MapOptions
from ..core.progress import Steps, scaled_steps, timed_steps
from ..core.sampling.guided_plan import GuidedOptions
from ..core.sampling.sequence_budget import SequenceBudget
from ..core.sampling.shot_plan import shot_of
from ..core.sampling.render_options import RenderOptions
from ..core.sampling.render_stats import FrameMaps
from .cycles.guided_render import guided_steps
from .cycles.selective_render import RenderOutcome, selective_steps
from .cycles.tile_render import forget_synced_session
from .maps.director_maps import map_steps, named_map_steps
from .maps.shot_choice import choose_for_shot, shot_range
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


@dataclass(frozen=True)
class FrameJob:
    """How to render one frame, in two parts so that a frame range keeps one Cycles session.

    ``prepare(scene)`` (optional) is everything that is not the frame's own rendering: its
    maps, the estimator's choice. The maps render with Cycles too (the snapshot, with the
    media switched off on temporary copies of their materials), and creating or removing a
    datablock makes Cycles sync the whole scene again at its next render (3.4 s of
    heterogeneous fog's octree on balls_b, every frame). ``frames_steps`` therefore prepares
    up to ``FRAMES_AHEAD`` frames first and then renders them back to back in one session.
    ``render(scene, prepared)`` renders the frame from what ``prepare`` returned. Both are
    steps reporting their own progress from 0 to 1; ``share`` is the part of a frame's
    progress bar given to ``prepare``.

    Calling the job runs both for the scene's current frame (a still).
    """

    render: Callable[[object, object], Steps[FrameResult]]
    prepare: Callable[[object], Steps[object]] | None = None
    share: float = 0.0

    def __call__(self, scene) -> Steps[FrameResult]:
        forget_synced_session()
        prepared = None
        if self.prepare is not None:
            prepared = yield from scaled_steps(self.prepare(scene), 0.0, self.share)
        return (yield from scaled_steps(self.render(scene, prepared), self.share, 1.0))


#: Frames prepared (maps computed) before they are rendered in one go; a frame's maps take
#: about 15 float32 images, 1 GB for 8 frames at 1920x1080.
FRAMES_AHEAD = 8


def frames_steps(scene, frames: Sequence[int], job: FrameJob,
                 on_frame: Callable[[FrameResult], object], ahead: int = FRAMES_AHEAD) -> Steps[list]:
    """Render ``frames`` in order in one Cycles session; ``on_frame(result)`` (write files,
    show images) runs as soon as a frame is done, so a cancelled run keeps every finished
    frame. Returns the list of what ``on_frame`` returned. The scene's frame and settings
    (persistent data among them) are restored at the end.

    Persistent data stays on for the whole range: Cycles then syncs only what changed from
    one frame to the next (a moving camera, an animated object), not the whole scene. Jobs
    with a ``prepare`` part have it run for up to ``ahead`` frames before those frames
    render (see ``FrameJob``): one full sync per ``ahead`` frames instead of one per frame.

    Datablocks created inside are removed at the end (``preserved_scene``), so images
    shown by ``on_frame`` must exist before the run starts.
    """
    frames = list(frames)
    done = []
    count = len(frames)
    forget_synced_session()
    chunk = max(1, ahead) if job.prepare is not None else 1
    with preserved_scene(scene):
        scene.render.use_persistent_data = True
        for first in range(0, count, chunk):
            part = range(first, min(count, first + chunk))
            prepared = {}
            if job.prepare is not None:
                for index in part:
                    scene.frame_set(frames[index])
                    prepared[index] = yield from scaled_steps(
                        job.prepare(scene), index / count, (index + job.share) / count,
                        _label(frames, index))
            for index in part:
                scene.frame_set(frames[index])
                result = yield from scaled_steps(
                    job.render(scene, prepared.get(index)), (index + job.share) / count,
                    (index + 1) / count, _label(frames, index))
                done.append(on_frame(result))
    return done


def _label(frames: Sequence[int], index: int) -> str:
    return f"frame {frames[index]} ({index + 1}/{len(frames)}): "


def selective_frame(map_options: MapOptions, options: RenderOptions, mode: str,
                    cache_dir, label: str | None = None) -> FrameJob:
    """A frame job for xs / xsl: the frame's maps (rays cached in ``cache_dir``), then the
    selective render driven by the map named ``mode`` (its stats call it ``label``, default
    ``mode``)."""

    def prepare(scene) -> Steps[MapSet]:
        return (yield from scaled_steps(map_steps(scene, map_options, size=options.resolution,
                                                  cache_dir=cache_dir), 0.0, 1.0, "maps: "))

    def render(scene, maps: MapSet) -> Steps[FrameResult]:
        outcome = yield from selective_steps(scene, maps.director(mode), options, label or mode,
                                             maps.info["seconds"]["total"])
        outcome.stats.maps = maps_summary(maps)
        return FrameResult(scene.frame_current, outcome, maps)

    return FrameJob(render, prepare, MAP_SHARE)


def map_frame(director_map, options: RenderOptions, mode: str, map_seconds: float = 0.0) -> FrameJob:
    """A frame job for xs / xsl from a director map given (read from a file): the selective
    render it drives; ``map_seconds`` (reading it) recorded as the "maps" phase."""

    def render(scene, _prepared=None) -> Steps[FrameResult]:
        outcome = yield from selective_steps(scene, director_map, options, mode, map_seconds)
        return FrameResult(scene.frame_current, outcome)

    return FrameJob(render)


def guided_frame(guided: GuidedOptions, map_options: MapOptions | None, options: RenderOptions,
                 cache_dir=None, sequence: SequenceBudget | None = None) -> FrameJob:
    """A frame job for the guided render within ``guided.time_budget``: the importance map
    it asks for first (rays cached in ``cache_dir``), inside the budget (its seconds, not the
    time spent waiting between steps, are passed on as spent), then the guided render. The
    command line, the farm and the panel all render guided frames through this job.

    ``sequence``: the frames of one run share its time (``SequenceBudget``: each frame gets
    what the range has left per frame still to render, the scene sync outside it)."""

    def prepare(scene) -> Steps[tuple]:
        maps = named_map_steps(scene, guided.importance, map_options, options.resolution, cache_dir)
        return (yield from scaled_steps(timed_steps(maps), 0.0, 1.0,
                                        f"{guided.importance.upper()} map: "))

    def render(scene, prepared) -> Steps[FrameResult]:
        importance, map_seconds = prepared if prepared is not None else (None, 0.0)
        frame_guided = guided if sequence is None else replace(guided, time_budget=sequence.next_budget())
        outcome = yield from guided_steps(scene, options, frame_guided, importance, map_seconds,
                                          pace=sequence)
        if sequence is not None:
            sequence.record(outcome.stats.wall_s)
            outcome.stats.sequence_budget = sequence.to_dict()
        return FrameResult(scene.frame_current, outcome)

    if guided.importance == "none":
        return FrameJob(render)
    return FrameJob(render, prepare, IMPORTANCE_SHARE)


def estimated_frame(make_job: Callable[[RenderOptions], FrameJob], options: RenderOptions,
                    spp: float) -> FrameJob:
    """The frame job ``make_job(options)`` with ``--estimator auto`` chosen for each frame's
    shot (``shot_choice``, as Auto Volumes chooses in Blender's own render) before the
    frame's maps and renders, inside its time: one choice per shot, so the step, and the
    bias with it, does not switch within a shot, and frame N's choice is the same whichever
    frames the run renders."""
    if options.estimator != "auto" or options.estimator_choice is not None:
        return make_job(options)
    share = make_job(options).share
    shots: dict = {}

    def prepare(scene) -> Steps[tuple]:
        yield 0.0, "choosing the volume estimator"
        shot = shot_of(scene.frame_current, *shot_range(scene))
        if shot in shots:           # chosen for an earlier frame: this one spends no time on it
            choice = replace(shots[shot].choice, seconds=0.0)
        else:
            shots[shot] = choose_for_shot(scene, shot, options, spp)
            choice = replace(shots[shot].choice, seconds=shots[shot].seconds)
        chosen = replace(options, estimator_choice=choice)
        job = make_job(chosen)
        inner = None
        if job.prepare is not None:
            inner = yield from job.prepare(scene)
        return job, inner

    def render(scene, prepared) -> Steps[FrameResult]:
        job, inner = prepared
        return (yield from job.render(scene, inner))

    return FrameJob(render, prepare, share)


def single_render_frame(render: Callable[[object], RenderOutcome], label: str,
                        announce: bool = True) -> FrameJob:
    """A frame job for one ordinary render (gold, uniform, adaptive): ``render(scene)``.
    ``announce``: a step saying so before it (not when ``render`` reports its own progress,
    so that a scene found wrong ends the command before any progress is shown)."""

    def steps(scene, _prepared=None) -> Steps[FrameResult]:
        if announce:
            yield 0.0, f"{label}: rendering"
        return FrameResult(scene.frame_current, render(scene))

    return FrameJob(steps)


def stepped_render_frame(render_steps: Callable[[object], Steps[RenderOutcome]]) -> FrameJob:
    """A frame job from a render written as steps (e.g. the banded gold render)."""

    def steps(scene, _prepared=None) -> Steps[FrameResult]:
        outcome = yield from render_steps(scene)
        return FrameResult(scene.frame_current, outcome)

    return FrameJob(steps)


def maps_summary(maps: MapSet) -> FrameMaps:
    """What a frame's statistics record about its maps: seconds and the ray cache."""
    cache = maps.info["x"]["cache"]
    return FrameMaps(frame=maps.info["frame"], seconds=maps.info["seconds"],
                     ray_cache_hit=bool(cache["hit"]), ray_cache=cache["path"],
                     warnings=maps.info["warnings"])
