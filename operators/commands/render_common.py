"""What a single-frame render (``render.py``) and an animation (``render_animation.py``) share:
the baseline render of one frame and the summary line each render prints.

Its own module so that ``render`` can hand an animation to ``render_animation`` without the
two importing each other.
"""
from __future__ import annotations

from pathlib import Path


def render_baseline(scene, args, options, budget: dict, progress=None):
    """One gold, uniform, adaptive or guided render of the scene at its current frame."""
    from ...addon.cycles import selective_render as sr

    if args.mode == "guided":
        return guided_render(scene, options, budget, progress)
    if args.mode == "gold":
        return sr.render_gold(scene, options, progress=progress)
    if args.mode == "uniform":
        return sr.render_uniform(scene, options, spp=budget.get("spp"), seconds=budget.get("seconds"),
                                 progress=progress)
    threshold = args.noise_threshold if args.noise_threshold is not None \
        else sr.CYCLES_DEFAULT_NOISE_THRESHOLD
    return sr.render_adaptive(scene, options, budget["seconds"], threshold, progress=progress)


def guided_render(scene, options, budget: dict, progress=None):
    """A guided render of the scene at its current frame: the frame job the panel and the
    farm run (``addon.frame_jobs.guided_frame``), the importance map inside the budget."""
    from ...addon.frame_jobs import guided_frame
    from ...addon.maps.director_maps import MapWarning
    from ...core.maps.xmap import XMapWarning
    from ...core.progress import run_steps
    from .common import warnings_as_lines

    job = guided_frame(budget["guided"], budget["map_options"], options)
    with warnings_as_lines(MapWarning, XMapWarning):
        return run_steps(job(scene), progress).outcome


def spp_scale(args, options, outcome) -> int:
    """The samples per pixel the _spp.png shows as white: the ceiling, or for guided without
    one, the most any pixel got."""
    from ...core.sampling.render_files import preview_scale

    unbounded = args.mode == "guided" and args.max_spp is None
    return preview_scale(None if unbounded else options.max_spp, outcome.samples)


def summary_line(mode: str, stats: dict, out: Path) -> str:
    return (f"{mode}: {stats['resolution'][0]}x{stats['resolution'][1]}, mean "
            f"{stats['mean_spp']:.2f} spp in {stats['renders']} render(s), {stats['wall_s']:.2f} s -> {out}")
