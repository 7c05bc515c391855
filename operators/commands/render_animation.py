"""``xsl-render render ... --frames START-END --out 'out/frame_####.exr'``: an animation.

Each frame is written as soon as it is done (``frame_path`` numbers it as Blender would),
with its ``_spp.exr`` / ``_spp.png``; ``--stats`` gets one JSON for the whole run with every
frame's statistics; ``--save-maps DIR`` keeps each frame's maps in ``DIR/NNNN/`` and the
shared ray cache in ``DIR/zcache.npz`` (a temporary folder otherwise).
"""
from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

from ...core.frames import frame_expression, frame_path
from ...core.sampling.render_files import write_render_outputs


def maps_folder(save_maps: str | Path, frame: int) -> Path:
    """Where --save-maps DIR keeps one frame's maps: DIR/NNNN."""
    return Path(save_maps) / f"{frame:04d}"


def render_frames(scene, args, request, frames: tuple[int, ...], out: Path) -> int:
    from ...addon.frame_jobs import frames_steps
    from ...addon.maps.director_maps import MapWarning
    from ...core.files import write_json
    from ...core.sampling.render_stats import sequence_stats
    from ...core.sampling.sequence_budget import SequenceBudget
    from ...core.maps.files import write_map_set
    from ...core.maps.xmap import XMapWarning
    from ...core.progress import run_steps
    from ..interrupt import InterruptToCancel
    from ..progress_bar import ProgressBar
    from .common import warnings_as_lines
    from ...addon.render_dispatch import request_frame_job
    from .render_modes import spp_scale, summary_line

    save_maps = Path(args.save_maps) if args.save_maps else None
    cache_dir = save_maps or Path(tempfile.mkdtemp(prefix="xsl-rays-"))

    # A guided range shares its time among its frames.
    sequence = SequenceBudget(request.guided.time_budget, len(frames)) if request.guided else None
    job = request_frame_job(request, cache_dir, sequence)

    def on_frame(result) -> dict:
        path = Path(frame_path(str(out), result.frame))
        stats = result.outcome.stats
        stats.frame, stats.file, stats.out = result.frame, str(args.scene), str(path)
        for warning in result.outcome.warnings:
            print(f"xsl-render: warning: frame {result.frame}: {warning}", file=sys.stderr)
        write_render_outputs(path, result.outcome.image, result.outcome.samples, stats,
                             spp_scale(request, result.outcome), request.options.seed)
        if save_maps is not None and result.maps is not None:
            write_map_set(maps_folder(save_maps, result.frame), result.maps)
        print(f"frame {result.frame}: " + summary_line(args.mode, stats, path)
              + f" (Cycles synced the scene in {stats.cycles_sync_s or 0.0:.2f} s)", flush=True)
        return stats

    started = time.perf_counter()
    bar = None if args.quiet else ProgressBar(args.mode)
    try:
        with InterruptToCancel() as interrupt, warnings_as_lines(MapWarning, XMapWarning):
            done = run_steps(frames_steps(scene, frames, job, on_frame), interrupt.wrap(bar))
    finally:
        if bar is not None:
            bar.close()
        if save_maps is None:
            shutil.rmtree(cache_dir, ignore_errors=True)
    hits = [stats.maps.ray_cache_hit for stats in done if stats.maps is not None]
    if args.stats:
        write_json(args.stats, sequence_stats(done, args.mode, str(args.scene), str(out),
                                              frame_expression(args.frames), time.perf_counter() - started))
    if hits:
        print(f"{len(done)} frames; camera rays cast {hits.count(False)} time(s), reused "
              f"{hits.count(True)} time(s)")
    return 0
