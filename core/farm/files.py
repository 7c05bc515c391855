"""What a farm job writes for one frame, and how a rerun tells finished work from missing work.

A task may die at any moment and is then run again, so each writes its results atomically
and after them a record of what they were made from (a digest of every input that decides
the pixels, the files the scene reads included, and the SHA-256 of the file written). A rerun
trusts a result only when its record names the same inputs and the file keeps its hash.
Under the job's output folder: ``frame_NNNN.exr``, ``_spp.exr/.png`` and ``.json`` (one set),
``work/frame_NNNN/`` (maps, plan.json, one file per rectangle) and ``.scene_inputs.json``. A
rectangle's record depends on its window and samples, not the map, so a new plan re-renders
only the rectangles that changed; a guided job has no work/ folder."""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import file_identity, file_sha256, json_digest, write_json
from ..imageio import read_image, write_exr
from ..sampling.render_options import RenderOptions
from ..sampling.tile_plan import Rect, TilePlan

RECORD_FORMAT = 1
TILE_CHANNELS = ["R", "G", "B", "A", "samples"]
#: With denoising, a rectangle also keeps Cycles' denoising albedo and normal for the composite.
GUIDE_CHANNELS = ["albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z"]


def scene_sha256(path: str | os.PathLike) -> str:
    """The .blend's content hash (InputError when it cannot be read)."""
    try:
        return file_sha256(path)
    except OSError as error:
        raise InputError(f"cannot read the scene {path}: {error.strerror or error}") from None


def scene_inputs_path(output: str | os.PathLike) -> Path:
    """Where a job records the files its scene reads (``write_scene_inputs``): hidden beside
    the frames, as a guided job has no work folder."""
    return Path(output) / ".scene_inputs.json"


def write_scene_inputs(output: str | os.PathLike, inputs: dict) -> Path:
    """Record what the job's scene is made from (``addon.scene.scene_inputs.blend_inputs``:
    the .blend's hash, the identities of the files it reads), so that later tasks know it
    without opening the scene."""
    return write_json(scene_inputs_path(output), {"format": RECORD_FORMAT, "kind": "xsl-render farm scene",
                                                  "inputs": inputs})


def known_scene_inputs(output: str | os.PathLike, blend_sha256: str) -> dict | None:
    """The recorded inputs of the job's scene when the .blend has the hash ``blend_sha256``
    and every file it reads still has its recorded identity; else None (a task then opens
    the scene to list them again)."""
    record = read_record(scene_inputs_path(output))
    if record is None or record.get("kind") != "xsl-render farm scene":
        return None
    inputs = record.get("inputs")
    try:
        if inputs["blend_sha256"] != blend_sha256 or \
                any(file_identity(entry[0]) != list(entry) for entry in inputs["files"]):
            return None
    except (KeyError, TypeError, IndexError):
        return None
    return inputs


def renderer_version() -> str:
    """The Blender (bpy module) release that renders: another release may render other pixels."""
    try:
        return metadata.version("bpy")
    except metadata.PackageNotFoundError:
        return "unknown"


def read_record(path: Path) -> dict | None:
    """A JSON record of ours, or None when missing, unreadable or of another format."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != RECORD_FORMAT:
        return None
    return data


def recorded_file_intact(record: dict, key: str, path: Path) -> bool:
    """True when ``path`` exists and has the SHA-256 stored under ``key`` in ``record``."""
    try:
        return record.get(key) == file_sha256(path)
    except OSError:
        return False


@dataclass(frozen=True)
class FrameFiles:
    """Paths of one frame of a farm job under its output folder."""

    output: Path
    frame: int

    @property
    def stem(self) -> str:
        return f"frame_{self.frame:04d}"

    @property
    def work(self) -> Path:
        return self.output / "work" / self.stem

    @property
    def maps(self) -> Path:
        return self.work / "maps"

    @property
    def plan(self) -> Path:
        return self.work / "plan.json"

    @property
    def tiles(self) -> Path:
        return self.work / "tiles"

    @staticmethod
    def rect_name(rect: Rect) -> str:
        return f"r{rect.row0}-{rect.row1}_c{rect.col0}-{rect.col1}"

    def tile_image(self, rect: Rect) -> Path:
        return self.tiles / f"{self.rect_name(rect)}.exr"

    def tile_record(self, rect: Rect) -> Path:
        return self.tiles / f"{self.rect_name(rect)}.json"

    @property
    def image(self) -> Path:
        return self.output / f"{self.stem}.exr"

    @property
    def spp_image(self) -> Path:
        return self.output / f"{self.stem}_spp.exr"

    @property
    def spp_preview(self) -> Path:
        return self.output / f"{self.stem}_spp.png"

    @property
    def stats(self) -> Path:
        return self.output / f"{self.stem}.json"


# -- the maps step: director maps and the tile plan -----------------------------------------

def maps_inputs(scene_digest: str, scene_name: str, frame: int, mode: str, map_options: dict,
                options: RenderOptions) -> dict:
    """Everything the maps and the plan of a frame are made from (``scene_digest``: the
    scene's inputs, the files it reads among them)."""
    return {"scene_inputs": scene_digest, "scene_name": scene_name, "frame": frame, "mode": mode,
            "map_options": map_options, "options": options.to_dict(), "blender": renderer_version()}


def guided_inputs(scene_digest: str, scene_name: str, frame: int, guided: dict,
                  map_options: dict | None, options: RenderOptions) -> dict:
    """Everything a guided frame is rendered from: the time budget is one of them (a frame
    rendered with another budget is another frame); the map options only when the
    importance map uses them (``map_options`` None otherwise)."""
    return {"scene_inputs": scene_digest, "scene_name": scene_name, "frame": frame, "mode": "guided",
            "guided": guided, "map_options": map_options, "options": options.to_dict(),
            "blender": renderer_version()}


@dataclass
class PlanRecord:
    """``plan.json``: the tile plan of a frame and what it was made from."""

    data: dict

    @property
    def plan(self) -> TilePlan:
        return TilePlan.from_dict(self.data["plan"])

    @property
    def options(self) -> RenderOptions:
        return options_from_dict(self.data["inputs_detail"]["options"])

    @property
    def scene_digest(self) -> str:
        return self.data["inputs_detail"]["scene_inputs"]

    @property
    def scene_name(self) -> str:
        return self.data["inputs_detail"]["scene_name"]

    @property
    def mode(self) -> str:
        return self.data["inputs_detail"]["mode"]

    @property
    def blender(self) -> str:
        """The Blender release the frame was planned with; its rectangles render with it too."""
        return self.data["inputs_detail"]["blender"]


def options_from_dict(data: dict) -> RenderOptions:
    """``RenderOptions.to_dict()`` read back."""
    values = dict(data)
    if values.get("resolution") is not None:
        values["resolution"] = tuple(values["resolution"])
    try:
        return RenderOptions(**values).check()
    except TypeError as error:
        raise InputError(f"malformed render options in a plan: {error}") from None


def write_plan_record(files: FrameFiles, inputs: dict, plan: TilePlan, director_map: Path,
                      extra: dict) -> Path:
    """Write ``plan.json`` (after the maps it names: it is what marks the step done)."""
    record = {"format": RECORD_FORMAT, "kind": "xsl-render farm plan", "frame": files.frame,
              "inputs": json_digest(inputs), "inputs_detail": inputs,
              "director_map": director_map.name, "director_sha256": file_sha256(director_map),
              "plan": plan.to_dict(), **extra}
    return write_json(files.plan, record)


def valid_plan(files: FrameFiles, inputs: dict | None = None) -> PlanRecord | None:
    """The frame's plan when the maps step finished it (for ``inputs``, when given), else None."""
    record = read_record(files.plan)
    if record is None or record.get("kind") != "xsl-render farm plan":
        return None
    if inputs is not None and record.get("inputs") != json_digest(inputs):
        return None
    director = files.maps / str(record.get("director_map", ""))
    if not recorded_file_intact(record, "director_sha256", director):
        return None
    try:
        result = PlanRecord(record)
        result.plan, result.options           # both must parse
    except (InputError, KeyError, TypeError, ValueError):
        return None
    return result


def load_plan(files: FrameFiles) -> PlanRecord:
    """The frame's plan for the tile and composite steps; InputError when the maps step has
    not finished it."""
    record = valid_plan(files)
    if record is None:
        raise InputError(f"frame {files.frame} has no finished tile plan in {files.work} "
                         "(run the maps step first)")
    return record


# -- the tile steps: one image and one record per rectangle ---------------------------------

def tile_inputs(record: PlanRecord, rect: Rect) -> dict:
    """What decides a rectangle's pixels: the scene, frame, window, samples and the render
    settings (not the map: an unchanged rectangle of a new plan is still valid)."""
    from ..sampling.composite import render_window

    options = record.options
    width, height = record.plan.width, record.plan.height
    threshold = options.noise_threshold(rect.spp)
    return {"scene_inputs": record.scene_digest, "scene_name": record.scene_name,
            "frame": record.data["frame"], "resolution": [width, height], "rect": rect.to_dict(),
            "window": list(render_window(rect.window, options.margin, width, height)),
            "seed": options.seed, "adaptive_threshold": threshold, "blender": record.blender}


def valid_tile(files: FrameFiles, record: PlanRecord, rect: Rect) -> dict | None:
    """The rectangle's record when its image is finished and current, else None."""
    tile = read_record(files.tile_record(rect))
    if tile is None or tile.get("inputs") != json_digest(tile_inputs(record, rect)):
        return None
    if not recorded_file_intact(tile, "image_sha256", files.tile_image(rect)):
        return None
    return tile


def remove_partial_files(path: Path) -> None:
    """Delete what a killed writer of ``path`` left (``core.files.atomic_path`` temporaries)."""
    for stale in path.parent.glob(f".{path.stem}.*.partial{path.suffix}"):
        stale.unlink(missing_ok=True)


def write_tile(files: FrameFiles, record: PlanRecord, rect: Rect, pixels: np.ndarray,
               samples: np.ndarray | int, details: dict, guides: np.ndarray | None = None) -> dict:
    """Write a rectangle's image (RGBA + samples per pixel [+ denoising albedo and normal]),
    then its record; return the record."""
    image, record_path = files.tile_image(rect), files.tile_record(rect)
    for path in (image, record_path):
        remove_partial_files(path)
    counts = np.broadcast_to(np.asarray(samples, np.float32), pixels.shape[:2])
    layers = [pixels[:, :, :4], counts] + ([guides[:, :, :6]] if guides is not None else [])
    data = np.ascontiguousarray(np.dstack(layers), dtype=np.float32)
    write_exr(image, data, TILE_CHANNELS + (GUIDE_CHANNELS if guides is not None else []))
    inputs = tile_inputs(record, rect)
    tile = {"format": RECORD_FORMAT, "kind": "xsl-render farm tile", "inputs": json_digest(inputs),
            "inputs_detail": inputs, "image": image.name, "image_sha256": file_sha256(image),
            # The file hash guards the file; this one is what the composite depends on (a
            # rectangle rendered again to the same pixels, in a file of another date, changes
            # nothing downstream).
            "pixels_sha256": hashlib.sha256(data.tobytes()).hexdigest(), **details}
    write_json(record_path, tile)
    return tile


def read_tile(files: FrameFiles, rect: Rect) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(RGBA pixels (h, w, 4), samples per pixel (h, w), denoising guides (h, w, 6) or None)."""
    data = read_image(files.tile_image(rect))
    plain, guided = len(TILE_CHANNELS), len(TILE_CHANNELS) + len(GUIDE_CHANNELS)
    if data.shape[:2] != (rect.height, rect.width) or data.shape[2] not in (plain, guided):
        raise InputError(f"{files.tile_image(rect)} holds {data.shape} values, not the "
                         f"{rect.height}x{rect.width} rectangle")
    return data[:, :, :4], data[:, :, 4], (data[:, :, plain:] if data.shape[2] == guided else None)
