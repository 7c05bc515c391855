"""How ``xsl-render render``'s ``--mode`` becomes a frame job (``addon.frame_jobs``): the one
place the command switches on the mode, for a still (``render.py``) and a frame range
(``render_animation.py``) alike, and what both print and scale their images by.
"""
from __future__ import annotations

from pathlib import Path


def mode_frame_job(args, options, budget: dict, cache_dir=None, sequence=None, director_map=None,
                   map_seconds: float = 0.0, progress=None):
    """The frame job of ``args.mode`` with ``--estimator auto`` chosen per frame.

    ``budget`` is what ``render._budget`` checked; ``cache_dir`` keeps the camera rays between
    frames; ``sequence`` shares a guided range's time (``SequenceBudget``); ``director_map``
    (xs, xsl) is a map given as a file, read in ``map_seconds``. ``progress`` hears the
    samples of a gold, uniform or adaptive render (one Cycles render, no steps inside)."""
    from ...addon.frame_jobs import (estimated_frame, guided_frame, map_frame, selective_frame,
                                     single_render_frame)
    from ...addon.maps.estimator_choice import estimator_spp

    def make(chosen):
        if args.mode in ("xs", "xsl"):
            if director_map is not None:
                return map_frame(director_map, chosen, args.mode, map_seconds)
            return selective_frame(budget["compute_maps"], chosen, args.mode, cache_dir)
        if args.mode == "guided":
            return guided_frame(budget["guided"], budget["map_options"], chosen, cache_dir, sequence)
        return single_render_frame(lambda scene: _baseline(scene, args, chosen, budget, progress),
                                   args.mode, announce=progress is None)

    return estimated_frame(make, options, estimator_spp(args.mode, options, budget))


def check_scene(scene, options, mode: str) -> None:
    """What only the opened scene can tell about the inputs, before any work (maps, renders,
    a progress bar): it has a camera, and (xs, xsl) the tiles fit its frame."""
    from ...addon.scene.probe import camera_model, render_size

    camera_model(scene)
    width, height = options.resolution or render_size(scene)
    if mode in ("xs", "xsl"):
        options.check_frame(width, height)


def _baseline(scene, args, options, budget: dict, progress=None):
    """One gold, uniform or adaptive render of the scene at its current frame."""
    from ...addon.cycles import selective_render as sr

    if args.mode == "gold":
        return sr.render_gold(scene, options, progress=progress)
    if args.mode == "uniform":
        return sr.render_uniform(scene, options, spp=budget.get("spp"), seconds=budget.get("seconds"),
                                 progress=progress)
    threshold = args.noise_threshold if args.noise_threshold is not None \
        else sr.CYCLES_DEFAULT_NOISE_THRESHOLD
    return sr.render_adaptive(scene, options, budget["seconds"], threshold, progress=progress)


def spp_scale(args, options, outcome) -> int:
    """The samples per pixel the _spp.png shows as white: the ceiling, or for guided without
    one, the most any pixel got."""
    from ...core.sampling.render_files import preview_scale

    unbounded = args.mode == "guided" and args.max_spp is None
    return preview_scale(None if unbounded else options.max_spp, outcome.samples)


def summary_line(mode: str, stats: dict, out: Path) -> str:
    return (f"{mode}: {stats['resolution'][0]}x{stats['resolution'][1]}, mean "
            f"{stats['mean_spp']:.2f} spp in {stats['renders']} render(s), {stats['wall_s']:.2f} s -> {out}")
