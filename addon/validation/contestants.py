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
"""
from __future__ import annotations

import time
import warnings
from dataclasses import replace
from typing import Callable

from ...core.errors import InputError
from ...core.maps.options import MapOptions
from ...core.progress import ProgressCallback
from ...core.sampling.render_options import RenderOptions
from ...core.validation.contestants import Contestant
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
    import _cycles

    with preserved_scene(scene):
        scene.cycles.use_guiding = True
        outcome = sr.render_uniform(scene, options, spp=int(contestant.params["spp"]), progress=progress)
        outcome.stats["path_guiding"] = {
            "use_guiding": bool(scene.cycles.use_guiding),
            "use_surface_guiding": bool(scene.cycles.use_surface_guiding),
            "use_volume_guiding": bool(scene.cycles.use_volume_guiding),
            "built_with_path_guiding": bool(getattr(_cycles, "with_path_guiding", False)),
            "device": scene.cycles.device}
    return outcome


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
