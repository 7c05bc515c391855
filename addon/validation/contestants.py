"""The renders of ``xsl-render curves``: one function per kind of contestant
(``core.validation.contestants``), each timed as a whole.

Equal fixed costs
-----------------
Every contestant pays the same fixed costs, and all of its own:

- Cycles' one-time start-up in the process (kernels, the denoiser's first call) is paid
  before any timed run, by ``warm_up``;
- every run pays its own scene sync (BVH, the heterogeneous volumes' octree): each render
  function runs inside ``preserved_scene``, which puts ``use_persistent_data`` back when it
  ends and so frees Cycles' synced scene (measured on balls_b: a second identical render
  takes as long as the first), and a time-budgeted render syncs inside its budget;
- a selective run computes its maps from the scene as ``xsl-render render --mode xs/xsl``
  does (no ray cache), and their time is part of its time.

The time of a run (``run_contestant``) is the wall time of everything it does: maps, scene
sync, renders, compositing, denoising; writing its files afterwards is not counted.

Adding a kind: a function ``(scene, contestant, options, budget_s, progress) ->
RenderOutcome`` in ``RENDERERS`` (``budget_s`` is the time budget of a contestant with
``time_of``, else None), as ``_guided`` is.

Over frames (``curves --frames``)
---------------------------------
``run_contestant_frames`` renders a contestant over a list of frames as ``xsl-render render
--frames`` does: the same frame jobs (``addon.frame_jobs``) through ``frames_steps``, one
Cycles session for the whole range (persistent data on, so the run pays one scene sync, not
one per frame), xs and xsl with their camera rays cast once and reused while camera and
geometry stay still, guided sharing the run's budget among its frames (``SequenceBudget``),
the volume estimator ``auto`` chosen per frame. A kind renders over frames when it has a
maker in ``FRAME_JOBS``: ``(contestant, options, budget_s, frame_count, cache_dir, shared)
-> (FrameJob, setup)``, ``setup(scene)`` run once before the frames (path guiding switches
guiding on there); a maker may be called once per frame (the estimator ``auto`` makes each
frame's job with that frame's choice), so what the frames share lives in ``shared``, a dict
of the run (guided keeps its ``SequenceBudget`` there). Writing the frames' files (``on_frame``) is not counted in the time.
"""
from __future__ import annotations

import shutil
import tempfile
import time
import warnings
from dataclasses import replace
from typing import Callable, Sequence

from ...core.errors import InputError
from ...core.maps.options import MapOptions
from ...core.progress import ProgressCallback
from ...core.sampling.render_options import RenderOptions
from ...core.progress import run_steps
from ...core.validation.contestants import Contestant
from ..frame_jobs import (FrameJob, FrameResult, estimated_frame, frames_steps, guided_frame,
                         selective_frame, single_render_frame)
from ..cycles import selective_render as sr
from ..scene.state import preserved_scene

Renderer = Callable[[object, Contestant, RenderOptions, "float | None", "ProgressCallback | None"],
                    sr.RenderOutcome]


def warm_up(scene) -> None:
    """One tiny render, denoised, so that no timed run pays Cycles' or the denoiser's
    one-time start-up in this process (the scene's own sync is paid again by every run)."""
    sr.render_uniform(scene, RenderOptions(max_spp=1, resolution=(8, 8)), spp=1)


def _uniform(scene, contestant: Contestant, options: RenderOptions, budget_s, progress):
    return sr.render_uniform(scene, options, spp=int(contestant.params["spp"]), progress=progress)


def _adaptive(scene, contestant: Contestant, options: RenderOptions, budget_s, progress):
    options = replace(options, max_spp=int(contestant.params["max_spp"])).check()
    return sr.render_adaptive(scene, options, None, float(contestant.params["noise_threshold"]),
                              progress=progress)


def _guiding(scene, contestant: Contestant, options: RenderOptions, budget_s, progress):
    """Uniform sampling with Cycles' path guiding on (surface and volume guiding as the
    scene has them, Blender's defaults: both on). Whether Cycles really used it shows in
    the image: the curves job compares it with the uniform run of the same samples and seed."""
    with preserved_scene(scene):
        scene.cycles.use_guiding = True
        outcome = sr.render_uniform(scene, options, spp=int(contestant.params["spp"]), progress=progress)
        outcome.stats["path_guiding"] = _guiding_settings(scene)
    return outcome


def _guiding_settings(scene) -> dict:
    """What the stats record about path guiding: the scene's switches and whether this
    Cycles was built with it."""
    import _cycles

    return {"use_guiding": bool(scene.cycles.use_guiding),
            "use_surface_guiding": bool(scene.cycles.use_surface_guiding),
            "use_volume_guiding": bool(scene.cycles.use_volume_guiding),
            "built_with_path_guiding": bool(getattr(_cycles, "with_path_guiding", False)),
            "device": scene.cycles.device}


def _selective(scene, contestant: Contestant, options: RenderOptions, budget_s, progress):
    """XS or XSL with the paper's map options, the maps computed here (their time counted),
    as ``xsl-render render --mode xs/xsl`` does."""
    from ..maps.director_maps import compute_maps

    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        maps = compute_maps(scene, MapOptions(), size=options.resolution)
    map_seconds = time.perf_counter() - started
    options = replace(options, max_spp=int(contestant.params["max_spp"])).check()
    outcome = sr.render_selective(scene, maps.director(contestant.kind), options, progress=progress,
                                  mode=contestant.kind, map_seconds=map_seconds)
    outcome.warnings += [str(w.message) for w in caught]
    return outcome


def _guided(scene, contestant: Contestant, options: RenderOptions, budget_s, progress):
    """The guided render in ``budget_s`` seconds, its importance map (when it has one)
    computed here inside the budget, as ``xsl-render render --mode guided`` does."""
    from ...core.sampling.guided_plan import GuidedOptions
    from ..cycles.guided_render import render_guided
    from ..maps.director_maps import named_map

    guided = GuidedOptions(time_budget=float(budget_s),
                           importance=contestant.params.get("importance", "none")).check()
    importance, map_seconds = None, 0.0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if guided.importance != "none":
            started = time.perf_counter()
            importance = named_map(scene, guided.importance, MapOptions(), options.resolution)
            map_seconds = time.perf_counter() - started
        outcome = render_guided(scene, options, guided, importance, map_seconds, progress)
    outcome.warnings += [str(w.message) for w in caught]
    return outcome


RENDERERS: dict[str, Renderer] = {
    "uniform": _uniform,
    "adaptive": _adaptive,
    "guiding": _guiding,
    "xs": _selective,
    "xsl": _selective,
    "guided": _guided,
}


def run_contestant(scene, contestant: Contestant, options: RenderOptions, budget_s: float | None = None,
                   progress: ProgressCallback | None = None) -> tuple[sr.RenderOutcome, float]:
    """Render one contestant; returns its outcome and its wall time in seconds (everything
    the run does, see the module notes)."""
    renderer = RENDERERS.get(contestant.kind)
    if renderer is None:
        raise InputError(f"no renderer for contestants of kind '{contestant.kind}' "
                         f"(known: {', '.join(RENDERERS)})")
    if contestant.time_of is not None and not (budget_s and budget_s > 0):
        raise InputError(f"{contestant.name} needs a positive time budget (from {contestant.time_of})")
    started = time.perf_counter()
    options = _with_estimator(scene, contestant, options)
    outcome = renderer(scene, contestant, options, budget_s, progress)
    return outcome, time.perf_counter() - started


def _with_estimator(scene, contestant: Contestant, options: RenderOptions) -> RenderOptions:
    """A contestant's ``estimator`` (and ``step_rate``) parameters, auto chosen here: inside
    the run's time, as ``xsl-render render --estimator auto`` chooses it."""
    from ..maps.estimator_choice import estimator_spp, with_estimator_choice

    if "estimator" not in contestant.params:
        return options
    options = replace(options, estimator=contestant.params["estimator"],
                      step_rate=contestant.params.get("step_rate")).check()
    budget = {"spp": contestant.params.get("spp")}
    return with_estimator_choice(scene, options, estimator_spp(contestant.kind, options, budget))


# -- over frames -------------------------------------------------------------------------
FrameJobMaker = Callable[[Contestant, RenderOptions, "float | None", int, str, dict],
                         "tuple[FrameJob, Callable[[object], None] | None]"]


def _uniform_frames(contestant: Contestant, options: RenderOptions, budget_s, count, cache_dir, shared):
    spp = int(contestant.params["spp"])
    return single_render_frame(lambda scene: sr.render_uniform(scene, options, spp=spp), "uniform"), None


def _adaptive_frames(contestant: Contestant, options: RenderOptions, budget_s, count, cache_dir, shared):
    threshold = float(contestant.params["noise_threshold"])
    return single_render_frame(lambda scene: sr.render_adaptive(scene, options, None, threshold), "adaptive"), None


def _guiding_frames(contestant: Contestant, options: RenderOptions, budget_s, count, cache_dir, shared):
    """Uniform frames with path guiding switched on once for the whole run (``_guiding``)."""
    spp = int(contestant.params["spp"])

    def setup(scene) -> None:
        scene.cycles.use_guiding = True

    def render(scene) -> sr.RenderOutcome:
        outcome = sr.render_uniform(scene, options, spp=spp)
        outcome.stats["path_guiding"] = _guiding_settings(scene)
        return outcome

    return single_render_frame(render, "path guiding"), setup


def _selective_frames(contestant: Contestant, options: RenderOptions, budget_s, count, cache_dir, shared):
    """XS or XSL as ``render --mode xs/xsl --frames`` renders them: each frame's maps with
    the paper's options, the camera rays cast once into ``cache_dir``."""
    return selective_frame(MapOptions(), options, contestant.kind, cache_dir), None


def _guided_frames(contestant: Contestant, options: RenderOptions, budget_s, count, cache_dir, shared):
    """The guided frames of ``render --mode guided --frames``: the run's budget (the time
    its uniform run took over every frame) shared among the frames (``SequenceBudget``)."""
    from ...core.sampling.guided_plan import GuidedOptions, SequenceBudget

    per_frame = float(budget_s) / count
    guided = GuidedOptions(time_budget=per_frame,
                           importance=contestant.params.get("importance", "none")).check()
    sequence = shared.setdefault("sequence", SequenceBudget(per_frame, count))
    return guided_frame(guided, MapOptions(), options, cache_dir, sequence), None


FRAME_JOBS: dict[str, FrameJobMaker] = {
    "uniform": _uniform_frames,
    "adaptive": _adaptive_frames,
    "guiding": _guiding_frames,
    "xs": _selective_frames,
    "xsl": _selective_frames,
    "guided": _guided_frames,
}


def without_frames(contestants: Sequence[Contestant]) -> list[str]:
    """Names of the contestants whose kind cannot render over frames (no ``FRAME_JOBS``)."""
    return [c.name for c in contestants if c.kind not in FRAME_JOBS]


def run_contestant_frames(scene, contestant: Contestant, options: RenderOptions, frames: Sequence[int],
                          budget_s: float | None = None, on_frame: Callable | None = None,
                          progress: ProgressCallback | None = None) -> tuple[list, float]:
    """Render one contestant over ``frames`` in one Cycles session (module notes); returns
    what ``on_frame(FrameResult)`` returned for each frame (the results themselves without
    it) and the run's wall time in seconds, the time spent in ``on_frame`` (writing files)
    left out. The scene is left as it was found."""
    from ..maps.estimator_choice import estimator_spp

    maker = FRAME_JOBS.get(contestant.kind)
    if maker is None:
        raise InputError(f"{contestant.name}: contestants of kind '{contestant.kind}' do not render "
                         f"over frames (those that do: {', '.join(FRAME_JOBS)})")
    if contestant.time_of is not None and not (budget_s and budget_s > 0):
        raise InputError(f"{contestant.name} needs a positive time budget (from {contestant.time_of})")
    frames = list(frames)
    if "max_spp" in contestant.params:
        options = replace(options, max_spp=int(contestant.params["max_spp"])).check()
    if "estimator" in contestant.params:
        options = replace(options, estimator=contestant.params["estimator"],
                          step_rate=contestant.params.get("step_rate")).check()
    cache_dir = tempfile.mkdtemp(prefix="xsl-curves-rays-")
    outside = [0.0]
    setups, shared = [], {}

    def make_job(frame_options: RenderOptions) -> FrameJob:
        job, setup = maker(contestant, frame_options, budget_s, len(frames), cache_dir, shared)
        setups[:] = [setup] if setup is not None else []
        return job

    def done(result: FrameResult):
        began = time.perf_counter()
        try:
            return result if on_frame is None else on_frame(result)
        finally:
            outside[0] += time.perf_counter() - began

    try:
        with preserved_scene(scene):
            started = time.perf_counter()
            job = estimated_frame(make_job, options, estimator_spp(
                contestant.kind, options, {"spp": contestant.params.get("spp")}))
            for setup in setups:
                setup(scene)
            results = run_steps(frames_steps(scene, frames, job, done), progress)
            seconds = time.perf_counter() - started - outside[0]
    finally:
        shutil.rmtree(cache_dir, ignore_errors=True)
    return results, seconds
