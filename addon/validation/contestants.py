"""The renders of ``xsl-render curves``: one request maker per kind of contestant
(``core.validation.contestants``), each run timed as a whole.

Every contestant pays the same fixed costs, all of its own: Cycles' one-time start-up is
paid before any timed run (``warm_up``); every run syncs the scene itself (``preserved_scene``
frees Cycles' session when it ends; a time budget syncs inside itself); a selective run
computes its maps. A run's time is everything but writing its files. A contestant renders as
``xsl-render render`` does: ``contestant_request`` makes a ``RenderRequest`` for the dispatcher,
for a still or over frames (one session for the range, as ``render --frames``). A new kind: a
request maker in ``REQUESTS``, and a scene setup in ``SETUPS`` where a Cycles switch is turned on."""
from __future__ import annotations

import shutil
import tempfile
import time
import warnings
from dataclasses import replace
from typing import Callable, Sequence

from ...core.errors import InputError
from ...core.maps.options import MapOptions
from ...core.progress import ProgressCallback, run_steps
from ...core.sampling.guided_plan import GuidedOptions
from ...core.sampling.sequence_budget import SequenceBudget
from ...core.sampling.render_options import UNBOUNDED_SPP, RenderOptions
from ...core.sampling.render_request import RenderRequest
from ...core.validation.contestants import Contestant
from ..cycles import selective_render as sr
from ..frame_jobs import FrameResult, frames_steps
from ..render_dispatch import request_frame_job
from ..scene.state import preserved_scene

RequestMaker = Callable[[Contestant, RenderOptions, "float | None"], RenderRequest]
#: How many times the ceiling a time-limited contestant may render (its clock stops it first).
TIME_LIMIT_CEILINGS = 16


def warm_up(scene) -> None:
    """One tiny render, denoised, so that no timed run pays Cycles' or the denoiser's
    one-time start-up in this process (the scene's own sync is paid again by every run)."""
    sr.render_uniform(scene, RenderOptions(max_spp=1, resolution=(8, 8)), spp=1)


def _uniform(contestant: Contestant, options: RenderOptions, budget_s) -> RenderRequest:
    """Uniform sampling at the contestant's count; a count above the curves' ceiling (a
    biased curve's bias floor at 256 spp) raises the ceiling for that run."""
    spp = int(contestant.params["spp"])
    return RenderRequest("uniform", replace(options, max_spp=max(options.max_spp, spp)), spp=spp)


def _adaptive(contestant: Contestant, options: RenderOptions, budget_s) -> RenderRequest:
    """Cycles' adaptive sampling up to the contestant's ceiling, at its noise threshold."""
    return RenderRequest("adaptive", replace(options, max_spp=int(contestant.params["max_spp"])),
                         noise_threshold=float(contestant.params["noise_threshold"]))


def _selective(contestant: Contestant, options: RenderOptions, budget_s) -> RenderRequest:
    """XS or XSL with the paper's map options, the maps computed in the run (their time
    counted)."""
    return RenderRequest(contestant.kind, replace(options, max_spp=int(contestant.params["max_spp"])),
                         map_options=MapOptions())


def _guided(contestant: Contestant, options: RenderOptions, budget_s) -> RenderRequest:
    """The guided render in ``budget_s`` seconds, its importance map (when it has one)
    computed inside the budget, with no ceiling (as ``render --mode guided`` without
    --max-spp: the budget alone decides)."""
    defaults = GuidedOptions(time_budget=1.0)
    guided = GuidedOptions(time_budget=float(budget_s),
                           importance=contestant.params.get("importance", defaults.importance),
                           exponent=float(contestant.params.get("exponent", defaults.exponent)))
    return RenderRequest("guided", replace(options, max_spp=UNBOUNDED_SPP), guided=guided,
                         map_options=MapOptions())


def _time_limited(contestant: Contestant, options: RenderOptions, budget_s) -> RenderRequest:
    """Uniform sampling stopped by Cycles' own time limit at ``budget_s`` seconds (the scene's
    sync and auto's prediction inside it, the denoise after it), as Blender's Time Limit
    renders for an artist; up to ``TIME_LIMIT_CEILINGS`` times the ceiling, so that the clock,
    not the count, stops it."""
    ceiling = TIME_LIMIT_CEILINGS * options.max_spp
    return RenderRequest("uniform", replace(options, max_spp=ceiling), seconds=float(budget_s))


def _switch_guiding_on(scene) -> None:
    """Cycles' path guiding (surface and volume guiding as the scene has them, Blender's
    defaults: both on). Whether Cycles really used it shows in the image: the curves job
    compares it with the uniform run of the same samples and seed."""
    scene.cycles.use_guiding = True


#: Each kind's request; path guiding is uniform sampling with Cycles' guiding on (``SETUPS``).
REQUESTS: dict[str, RequestMaker] = {
    "uniform": _uniform,
    "adaptive": _adaptive,
    "guiding": _uniform,
    "xs": _selective,
    "xsl": _selective,
    "guided": _guided,
    "time_limit": _time_limited,
}
#: Kinds whose scene is set up before they render (inside the run's ``preserved_scene``).
SETUPS: dict[str, Callable[[object], None]] = {"guiding": _switch_guiding_on}


def _guiding_settings(scene) -> dict:
    """What the stats record about path guiding: the scene's switches and whether this
    Cycles was built with it."""
    import _cycles

    return {"use_guiding": bool(scene.cycles.use_guiding),
            "use_surface_guiding": bool(scene.cycles.use_surface_guiding),
            "use_volume_guiding": bool(scene.cycles.use_volume_guiding),
            "built_with_path_guiding": bool(getattr(_cycles, "with_path_guiding", False)),
            "device": scene.cycles.device}


def contestant_request(contestant: Contestant, options: RenderOptions,
                       budget_s: float | None = None) -> RenderRequest:
    """The ``RenderRequest`` a contestant renders (checked): its kind's, with its
    ``estimator`` and ``step_rate`` parameters when it has them."""
    maker = REQUESTS.get(contestant.kind)
    if maker is None:
        raise InputError(f"no renderer for contestants of kind '{contestant.kind}' "
                         f"(known: {', '.join(REQUESTS)})")
    if contestant.time_of is not None and not (budget_s and budget_s > 0):
        raise InputError(f"{contestant.name} needs a positive time budget (from {contestant.time_of})")
    if "estimator" in contestant.params:
        options = replace(options, estimator=contestant.params["estimator"],
                          step_rate=contestant.params.get("step_rate"))
    return maker(contestant, options, budget_s).check()


def run_contestant(scene, contestant: Contestant, options: RenderOptions, budget_s: float | None = None,
                   progress: ProgressCallback | None = None) -> tuple[sr.RenderOutcome, float]:
    """Render one contestant; returns its outcome and its wall time in seconds (everything
    the run does, see the module notes)."""
    request = contestant_request(contestant, options, budget_s)
    setup = SETUPS.get(contestant.kind)
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught, preserved_scene(scene):
        warnings.simplefilter("always")
        if setup is not None:
            setup(scene)
        job = request_frame_job(request, progress=progress)
        outcome = run_steps(job(scene), progress).outcome
        if setup is not None:
            outcome.stats.path_guiding = _guiding_settings(scene)
    seconds = time.perf_counter() - started
    outcome.warnings += [str(w.message) for w in caught]
    return outcome, seconds


def run_contestant_frames(scene, contestant: Contestant, options: RenderOptions, frames: Sequence[int],
                          budget_s: float | None = None, on_frame: Callable | None = None,
                          progress: ProgressCallback | None = None) -> tuple[list, float]:
    """Render one contestant over ``frames`` in one Cycles session (module notes); returns
    what ``on_frame(FrameResult)`` returned for each frame (the results themselves without
    it) and the run's wall time in seconds, the time spent in ``on_frame`` (writing files)
    left out. The scene is left as it was found."""
    frames = list(frames)
    # A time budget is the whole run's; each frame gets its share (guided: what the range
    # has left, ``SequenceBudget``).
    per_frame = None if budget_s is None else float(budget_s) / max(1, len(frames))
    request = contestant_request(contestant, options, per_frame)
    sequence = None if request.guided is None else SequenceBudget(request.guided.time_budget, len(frames))
    setup = SETUPS.get(contestant.kind)
    cache_dir = tempfile.mkdtemp(prefix="xsl-curves-rays-")
    outside = [0.0]

    def done(result: FrameResult):
        began = time.perf_counter()
        try:
            if setup is not None:
                result.outcome.stats.path_guiding = _guiding_settings(scene)
            return result if on_frame is None else on_frame(result)
        finally:
            outside[0] += time.perf_counter() - began

    try:
        with preserved_scene(scene):
            started = time.perf_counter()
            if setup is not None:
                setup(scene)
            job = request_frame_job(request, cache_dir, sequence)
            results = run_steps(frames_steps(scene, frames, job, done), progress)
            seconds = time.perf_counter() - started - outside[0]
    finally:
        shutil.rmtree(cache_dir, ignore_errors=True)
    return results, seconds


def without_frames(contestants: Sequence[Contestant]) -> list[str]:
    """Names of the contestants whose kind cannot render over frames (every kind can now:
    kept for the curves runner's check of unknown kinds)."""
    return [c.name for c in contestants if c.kind not in REQUESTS]
