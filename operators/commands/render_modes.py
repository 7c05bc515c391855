"""What ``xsl-render render`` does around its request for a still (``render.py``) and a
frame range (``render_animation.py``) alike: the scene's own checks, and what both print and
scale their images by. (The mode becomes renders in ``addon.render_dispatch``.)
"""
from __future__ import annotations

from pathlib import Path


def check_scene(scene, options, mode: str, director_map=None) -> None:
    """What only the opened scene can tell about the inputs, before any work (auto's choice,
    maps, renders, a progress bar): it has a camera, and (xs, xsl) the tiles and a director
    map given fit its frame."""
    from ...addon.scene.probe import camera_model, render_size
    from ...core.sampling.render_request import MODE_TRAITS
    from ...core.sampling.tile_plan import check_director_map

    camera_model(scene)
    width, height = options.resolution or render_size(scene)
    if MODE_TRAITS[mode].director_map:
        options.check_frame(width, height)
        if director_map is not None:
            check_director_map(director_map, width, height)


def spp_scale(request, outcome) -> int:
    """The samples per pixel the _spp.png shows as white: the ceiling, or for guided without
    one, the most any pixel got."""
    from ...core.sampling.render_files import preview_scale

    return preview_scale(None if request.unbounded else request.options.max_spp, outcome.samples)


def summary_line(mode: str, stats, out: Path) -> str:
    """One run's line: size, mean samples, renders and wall time (``RenderStats``)."""
    width, height = stats.resolution
    return (f"{mode}: {width}x{height}, mean {stats.mean_spp:.2f} spp in {stats.renders} render(s), "
            f"{stats.wall_s:.2f} s -> {out}")
