"""``xsl-render render ... --frames START-END --out 'out/frame_####.exr'``: an animation.

Each frame is written as soon as it is done (``frame_path`` numbers it as Blender would),
with its ``_spp.exr`` / ``_spp.png``; ``--stats`` gets one JSON for the whole run with every
frame's statistics; ``--save-maps DIR`` keeps each frame's maps in ``DIR/NNNN/`` and the
shared ray cache in ``DIR/zcache.npz`` (a temporary folder otherwise).

A rerun continues: a frame whose files are whole and were made from the same request (the
options, the scene's inputs: ``addon.scene.scene_inputs``, the frame, the Blender release;
``core.sampling.render_files.finished_frame``) is kept, and only the others are rendered.
Inside Blender (the batch entry) every frame is rendered: the open file may hold changes
that the file on disk, which the digest would be made of, does not.
"""
from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

from ...core.files import json_digest
from ...core.frames import frame_expression, frame_path
from ...core.sampling.render_files import finished_frame, write_render_outputs


def maps_folder(save_maps: str | Path, frame: int) -> Path:
    """Where --save-maps DIR keeps one frame's maps: DIR/NNNN."""
    return Path(save_maps) / f"{frame:04d}"


def frame_requests(request, inputs: dict | None, frames) -> dict:
    """Frame -> the digest of what it is made from (none where ``inputs`` is None)."""
    from ...core.farm.files import renderer_version

    if inputs is None:
        return {}
    made_of = {"request": request.to_dict(), "scene": inputs, "blender": renderer_version()}
    return {frame: json_digest(made_of | {"frame": frame}) for frame in frames}


def _kept_frames(args, requests: dict, out: Path) -> dict:
    """Frame -> its statistics, for the frames an earlier run of the same request finished
    (with --save-maps, their maps too)."""
    from ...core.maps.files import map_set_paths

    kept = {}
    for frame, request in requests.items():
        stats = finished_frame(frame_path(str(out), frame), request)
        if stats is None:
            continue
        if args.save_maps and stats.maps is not None and not all(
                path.is_file() for path in map_set_paths(maps_folder(args.save_maps, frame)).values()):
            continue
        kept[frame] = stats
    return kept


def render_frames(scene, args, request, frames: tuple[int, ...], out: Path) -> int:
    from ...addon.frame_jobs import frames_steps
    from ...addon.scene.scene_inputs import scene_inputs
    from ...addon.maps.director_maps import MapWarning
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
    requests = frame_requests(request, scene_inputs(scene, args.scene), frames)
    kept = _kept_frames(args, requests, out)
    for frame in kept:
        print(f"frame {frame}: kept {frame_path(str(out), frame)} (an earlier run of the same request "
              "finished it)", flush=True)
    todo = [frame for frame in frames if frame not in kept]
    if not todo:
        return _finish(args, [kept[frame] for frame in frames], out, 0.0)
    cache_dir = save_maps or Path(tempfile.mkdtemp(prefix="xsl-rays-"))

    # A guided range shares its time among its frames.
    sequence = SequenceBudget(request.guided.time_budget, len(todo)) if request.guided else None
    job = request_frame_job(request, cache_dir, sequence)

    def on_frame(result) -> dict:
        path = Path(frame_path(str(out), result.frame))
        stats = result.outcome.stats
        stats.frame, stats.file, stats.out = result.frame, str(args.scene), str(path)
        for warning in result.outcome.warnings:
            print(f"xsl-render: warning: frame {result.frame}: {warning}", file=sys.stderr)
        write_render_outputs(path, result.outcome.image, result.outcome.samples, stats,
                             spp_scale(request, result.outcome), request.options.seed,
                             request=requests.get(result.frame))
        if save_maps is not None and result.maps is not None:
            write_map_set(maps_folder(save_maps, result.frame), result.maps)
        print(f"frame {result.frame}: " + summary_line(args.mode, stats, path)
              + f" (Cycles synced the scene in {stats.cycles_sync_s or 0.0:.2f} s)", flush=True)
        return stats

    started = time.perf_counter()
    bar = None if args.quiet else ProgressBar(args.mode)
    try:
        with InterruptToCancel() as interrupt, warnings_as_lines(MapWarning, XMapWarning):
            done = run_steps(frames_steps(scene, todo, job, on_frame), interrupt.wrap(bar))
    finally:
        if bar is not None:
            bar.close()
        if save_maps is None:
            shutil.rmtree(cache_dir, ignore_errors=True)
    rendered = dict(zip(todo, done))
    return _finish(args, [kept.get(frame) or rendered[frame] for frame in frames], out,
                   time.perf_counter() - started)


def _finish(args, stats: list, out: Path, wall_s: float) -> int:
    """--stats for the whole range (the kept frames' statistics as first recorded) and the
    summary line."""
    from ...core.files import write_json
    from ...core.sampling.render_stats import sequence_stats

    hits = [frame.maps.ray_cache_hit for frame in stats if frame.maps is not None]
    if args.stats:
        write_json(args.stats, sequence_stats(stats, args.mode, str(args.scene), str(out),
                                              frame_expression(args.frames), wall_s))
    if hits:
        print(f"{len(stats)} frames; camera rays cast {hits.count(False)} time(s), reused "
              f"{hits.count(True)} time(s)")
    return 0
