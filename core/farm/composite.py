"""The farm job's last step for one frame: put the rendered rectangles together.

Reads the frame's plan and every rectangle the tile steps wrote, checks each against its
record (``core.farm.files``), and writes the frame EXR, its samples-per-pixel EXR and PNG
and the statistics JSON, the same files ``xsl-render render`` writes. The statistics carry
the composite's own record: a rerun whose plan and rectangles are unchanged does nothing.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from ..errors import InputError
from ..sampling.composite import Compositor
from ..sampling.render_files import frame_attributes
from .files import RECORD_FORMAT, FrameFiles, json_digest, load_plan, read_tile, valid_tile
from .frame_outputs import FRAME_KIND, valid_frame_outputs, write_frame_outputs
from .task_groups import group_plan


@dataclass
class CompositeResult:
    stats: dict             # the frame's record (``core.farm.frame_outputs``)
    skipped: bool           # the outputs were already there and current


def composite_frame(files: FrameFiles, groups: int | None = None,
                    denoiser=None) -> CompositeResult:
    """Assemble ``files.frame`` from its rectangles; InputError naming what is missing.

    ``groups`` (the job's tile tasks per frame) only adds how evenly they shared the work
    to the statistics. ``denoiser(rgba, albedo, normal, prefilter_guides)`` denoises the frame
    when the plan's options ask for it, its guides prefiltered where the file's denoiser
    prefilters them (the plan's record says; ``addon.cycles.denoise.denoise``, passed in so
    this module needs no Blender).
    """
    started = time.perf_counter()
    record = load_plan(files)
    plan, options = record.plan, record.options
    tiles, missing = [], []
    for rect in plan.rects:
        tile = valid_tile(files, record, rect)
        if tile is None:
            missing.append(files.rect_name(rect))
        tiles.append(tile)
    if missing:
        shown = ", ".join(missing[:4]) + (", ..." if len(missing) > 4 else "")
        raise InputError(f"frame {files.frame}: {len(missing)} of {len(plan.rects)} rectangles have "
                         f"no finished render ({shown}); run the tile step first")
    inputs_digest = json_digest({"plan": record.data["inputs"],
                                 "tiles": [tile.get("pixels_sha256") for tile in tiles]})
    previous = valid_frame_outputs(files, inputs_digest)
    if previous is not None:
        return CompositeResult(previous, skipped=True)

    compositor = Compositor(plan.width, plan.height)
    guides = Compositor(plan.width, plan.height, channels=6) if options.denoise else None
    for rect in plan.rects:
        pixels, samples, tile_guides = read_tile(files, rect)
        compositor.add(rect.window, pixels, samples)
        if guides is not None:
            if tile_guides is None:
                raise InputError(f"{files.tile_image(rect)} has no denoising passes; rerun the tile step")
            guides.add(rect.window, tile_guides, samples)
    image, samples = compositor.result()
    denoise_seconds = 0.0
    if guides is not None:
        if denoiser is None:
            raise InputError("this frame is to be denoised, which needs Blender's denoiser")
        albedo_normal = guides.result()[0]
        tick = time.perf_counter()
        prefilter = bool(record.data.get("denoise_prefilter", True))
        image = denoiser(image, albedo_normal[..., :3], albedo_normal[..., 3:], prefilter)
        denoise_seconds = time.perf_counter() - tick
    mode = record.mode
    attributes = frame_attributes(mode, options.max_spp, options.seed, samples.mean(dtype="float64"))
    total = float(samples.sum(dtype="float64"))
    render_seconds = sum(float(tile.get("seconds", 0.0)) for tile in tiles)
    record_json = {
        "format": RECORD_FORMAT, "kind": FRAME_KIND,
        "inputs": inputs_digest, "image_sha256": None, "spp_sha256": None,
        "mode": mode, "frame": files.frame, "scene": record.scene_name,
        "resolution": [plan.width, plan.height], "max_spp": options.max_spp, "seed": options.seed,
        "total_samples": int(round(total)), "mean_spp": total / plan.pixels,
        "gold_samples": plan.gold_samples, "ideal_speedup": plan.ideal_speedup,
        "renders": len(plan.rects), "render_s": render_seconds,
        # Cycles' scene sync over the frame's rectangles: paid by the first render of each
        # tile task's session (a later frame of a chunk syncs only what moved).
        "cycles_sync_s": sum(float(tile.get("cycles_sync_s") or 0.0) for tile in tiles),
        "phases_s": {"maps": float(record.data.get("seconds", {}).get("total", 0.0)),
                     "renders": render_seconds, "composite": 0.0, "denoise": denoise_seconds},
        "tiles": [{**rect.to_dict(), "seconds": tile.get("seconds"), "group": tile.get("group"),
                   "samples_rendered": tile.get("samples_rendered"),
                   "cycles_sync_s": tile.get("cycles_sync_s")}
                  for rect, tile in zip(plan.rects, tiles)],
        "grouping": None if groups is None else group_plan(plan.rects, groups, options.render_cost).to_dict(),
        "options": options.to_dict(), "map_options": record.data["inputs_detail"]["map_options"],
        "out": str(files.image),
    }
    record_json["phases_s"]["composite"] = time.perf_counter() - started
    # wall_s: the compute the frame cost across its tasks (what --budget-from compares
    # against), not the elapsed time of the job, which depends on how many machines ran it.
    write_frame_outputs(files, image, samples, options.max_spp, attributes, record_json)
    return CompositeResult(record_json, skipped=False)
