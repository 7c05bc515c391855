"""Render windows of the frame with Cycles, many times in a row, with little fixed cost.

One ``CyclesWindowRenderer`` per run, inside ``preserved_scene``: persistent data on (the
scene synced once for all windows), a border cropped to each window, a plain EXR of the
Combined pass (multilayer where the count per pixel or the denoising guides are needed), a
fixed seed and no denoiser, compositor or stamp, so the pixels are Cycles' own estimate. The
sample count goes through the view layer's override, which Cycles reads at every render:
``scene.cycles.samples`` does not tag the scene, and tagging it would re-sync everything (the
volume octree again). The whole frame may also be rendered at a fraction of its resolution
(``reduce``) without a re-sync."""
from __future__ import annotations

import re
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ...core.camera import border_for_window
from ...core.errors import InputError
from ...core.sampling.sample_pattern import session_sequence
from ..scene.probe import render_size
from ..scene.shader_export import has_volume
from ..scene.state import (forget_session_counts, let_session_go, note_session_count, scene_changes,
                           session_largest_count)
from .own_renders import own_render
from .render import ensure_cycles, header_seconds, passes_from_channels, read_exr_parts

_SAMPLE_STATUS = re.compile(r"Sample (\d+)/(\d+)")
#: The volume estimator settings (and the sample pattern and light tree, which auto may set too) Cycles last
#: synced for a scene (its pointer) in this run's persistent session. They are add-on
#: properties, which do not tag the scene: without a tag Cycles keeps rendering with the ones
#: it synced first, also across a frame change (street: step rate 4 then 0.25 gave the same
#: pixels; a new pattern, the same pixels too). A render whose settings differ tags the
#: scene (a full sync: milliseconds for ray marching, Blender 5's octree for null scattering).
_synced_volumes: dict[int, tuple] = {}


def forget_synced_session() -> None:
    """A new run starts: what an earlier one synced, and the counts it rendered, are not known
    to hold (the artist may have rendered since), so each scene's first render tags it, and a
    session kept from before is let go (``CyclesWindowRenderer``)."""
    _synced_volumes.clear()
    forget_session_counts()


def volume_materials(scene) -> list:
    """The materials of the scene's objects that have a volume (whose step rate matters)."""
    found = {slot.material for ob in scene.objects for slot in ob.material_slots
             if slot.material is not None and hasattr(slot.material, "cycles")
             and slot.material.node_tree is not None and has_volume(slot.material.node_tree)}
    return sorted(found, key=lambda material: material.name_full)


def _changed_materials(scene) -> list:
    """The materials the open run changed (``scene_changes``): reached through instances or
    Geometry Nodes, they need not be in any object's slots."""
    import bpy

    try:
        return scene_changes(scene).datablocks(bpy.types.Material)
    except RuntimeError:                    # no block open: nothing of ours changed
        return []


def _volume_settings(scene, materials) -> tuple:
    """The scene's estimator and step rate, the world's step size and volume sampling, the
    volume ``materials``' own step rates and sampling (``--estimator auto`` may give some
    media coarser steps, or distance sampling), the sample
    pattern and the light tree (auto may set both: ``core.sampling.sample_pattern``,
    ``core.sampling.light_tree``)."""
    cycles = scene.cycles
    world = getattr(scene.world, "cycles", None)
    return (bool(cycles.volume_biased), round(float(cycles.volume_step_rate), 6),
            None if world is None else (round(float(world.volume_step_size), 6), world.volume_sampling),
            tuple((m.as_pointer(), round(float(m.cycles.volume_step_rate), 6), m.cycles.volume_sampling)
                  for m in materials),
            cycles.sampling_pattern, bool(cycles.use_light_tree))


def _tag_volume_changes(scene, materials) -> bool:
    """Whether the volume settings differ from what Cycles last synced for the scene; the
    materials and the world whose own step changed are tagged here (a scene tag alone does
    not make Cycles read a material's step rate again), the scene by the caller."""
    synced, now = _synced_volumes.get(scene.as_pointer()), _volume_settings(scene, materials)
    if synced == now:
        return False
    # Nothing known (a run's first render): Cycles may hold any steps, tag them all.
    if (synced is None or synced[2] != now[2]) and scene.world is not None:
        scene.world.update_tag()
    changed = {pointer for pointer, *_ in set(now[3]) - set(() if synced is None else synced[3])}
    for material in materials:
        if material.as_pointer() in changed:
            material.update_tag()
    return True


@dataclass
class RenderedWindow:
    """Pixels of one render and what it cost."""

    window: tuple[int, int, int, int] | None     # None: the whole frame
    pixels: np.ndarray                           # (h, w, 4) float32 RGBA, row 0 at the top
    samples: np.ndarray | int                    # samples per pixel: a number, or (h, w) counts
    samples_set: int                             # scene.cycles.samples for this render
    samples_rendered: int                        # passes Cycles completed (< set when stopped early)
    samples_reported: int | None                 # the count in the EXR header Cycles wrote
    seconds: float                               # wall time of the render call
    guides: np.ndarray | None = None             # (h, w, 6) denoising albedo RGB + normal XYZ
    sync_seconds: float = 0.0                    # Cycles' own scene synchronization time


def render_layer(scene):
    """The view layer we render: the active one when it is enabled, else the first enabled."""
    import bpy

    active = getattr(bpy.context, "view_layer", None)
    if active is not None and scene.view_layers.get(active.name) == active and active.use:
        return active
    for layer in scene.view_layers:
        if layer.use:
            return layer
    raise InputError(f"scene '{scene.name}' has no view layer enabled for rendering")


class CyclesWindowRenderer:
    """Cycles renders of windows (or the whole frame) with fixed, reproducible settings.

    Parameters
    ----------
    scene
        The scene; must be inside ``preserved_scene`` for the renderer's whole life.
    seed
        Cycles' seed for every render.
    guides
        Also render Cycles' denoising albedo and normal (for ``addon.cycles.denoise``).
    """

    def __init__(self, scene, seed: int, guides: bool = False):
        self.scene = scene
        self.layer = render_layer(scene)
        self.width, self.height = render_size(scene)
        ensure_cycles(scene)
        cycles, render = scene.cycles, scene.render
        if not render.use_persistent_data or session_largest_count(scene) is None:
            # No session kept (the first render creates one), or one kept from before the run
            # (the artist's persistent data), which may have rendered more samples than this
            # run will and with blue noise would leave every render of the run on that longer
            # sequence: let it go (one scene sync more, paid only where the artist kept one).
            let_session_go(scene)
        render.use_persistent_data = True
        cycles.use_denoising = False
        cycles.use_adaptive_sampling = False
        cycles.time_limit = 0.0
        cycles.use_layer_samples = "USE"       # see the module docstring
        cycles.use_sample_subset = False
        cycles.sample_offset = 0
        cycles.use_animated_seed = False
        cycles.seed = seed
        render.use_compositing = False
        render.use_sequencer = False
        render.use_stamp = False
        render.use_file_extension = True
        self.guides = guides
        # Looked up once: a render's check of the volume settings reads only these.
        self.volume_materials = volume_materials(scene)
        self.layer.cycles.denoising_store_passes = guides
        self.folder = Path(tempfile.mkdtemp(prefix="xsl-tiles-"))
        render.filepath = str(self.folder / "window")
        self._status_max = 0
        self._on_sample: Callable[[int, int], None] | None = None
        self._handler = self._render_status
        #: Seconds Cycles reported syncing the scene, over every render so far: near 0 once
        #: the scene is synced (persistent data), seconds where it syncs again.
        self.sync_seconds = 0.0

    def sequence(self) -> int:
        """The per-pixel sequence length a render of fewer samples than the session's largest
        so far draws from (0: its own count; ``core.sampling.sample_pattern.session_sequence``)."""
        return session_sequence(self.scene.cycles.sampling_pattern, session_largest_count(self.scene) or 0)

    # -- context manager -------------------------------------------------------------------
    def __enter__(self) -> "CyclesWindowRenderer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)

    def _render_status(self, status, *_):
        # Cycles reports "... | Sample 16/64" while it renders; the highest number is the
        # count it completed when a time limit or adaptive sampling stops it early.
        match = _SAMPLE_STATUS.search(str(status))
        if match:
            done, total = int(match.group(1)), int(match.group(2))
            self._status_max = max(self._status_max, done)
            if self._on_sample is not None:
                self._on_sample(done, total)

    # -- rendering -------------------------------------------------------------------------
    def _render_reduced(self, reduce: int, samples: int, adaptive_threshold, time_limit,
                        on_sample) -> RenderedWindow:
        if reduce < 1:
            raise ValueError(f"reduce must be at least 1 (got {reduce})")
        render = self.scene.render
        resolution, full = (render.resolution_x, render.resolution_y), (self.width, self.height)
        render.resolution_x, render.resolution_y = (max(1, side // reduce) for side in resolution)
        try:
            self.width, self.height = render_size(self.scene)
            return self.render(None, samples, adaptive_threshold, time_limit, on_sample)
        finally:
            render.resolution_x, render.resolution_y = resolution
            self.width, self.height = full

    def _volume_materials(self) -> list:
        """The scene's volume materials and those the open run changed (``scene_changes``)."""
        found = {m.as_pointer(): m for m in self.volume_materials + _changed_materials(self.scene)}
        return sorted(found.values(), key=lambda material: (material.name_full, material.as_pointer()))

    @staticmethod
    def _assign(struct, name: str, value) -> bool:
        """Set a property only when it changes (every assignment makes Cycles re-check that
        part of the scene); True when it changed."""
        if getattr(struct, name) == value:
            return False
        setattr(struct, name, value)
        return True

    def _set_output(self, multilayer: bool) -> None:
        settings = self.scene.render.image_settings
        if hasattr(settings, "media_type"):        # Blender 5.0+: the format follows the media type
            self._assign(settings, "media_type", "MULTI_LAYER_IMAGE" if multilayer else "IMAGE")
        self._assign(settings, "file_format", "OPEN_EXR_MULTILAYER" if multilayer else "OPEN_EXR")
        self._assign(settings, "color_mode", "RGBA")
        self._assign(settings, "color_depth", "32")
        self._assign(settings, "exr_codec", "NONE")    # small temporary files: skip compression

    def render(self, window: tuple[int, int, int, int] | None, samples: int,
               adaptive_threshold: float | None = None, time_limit: float = 0.0,
               on_sample: Callable[[int, int], None] | None = None,
               reduce: int = 1) -> RenderedWindow:
        """Render ``window`` (row0, row1, col0, col1; rows from the top) or the whole frame.

        ``samples`` is Cycles' sample count (the ceiling when ``adaptive_threshold`` or
        ``time_limit`` may stop it earlier; then the returned ``samples`` holds Cycles' own
        count per pixel). ``on_sample(done, total)`` is called as Cycles reports progress.
        ``reduce`` > 1 renders the whole frame at 1/reduce of its resolution (window None).
        """
        import bpy

        if reduce != 1:
            return self._render_reduced(reduce, samples, adaptive_threshold, time_limit, on_sample)
        scene, cycles, render = self.scene, self.scene.cycles, self.scene.render
        counted = adaptive_threshold is not None or time_limit > 0.0
        multilayer = counted or self.guides
        self._assign(cycles, "samples", samples)
        new_count = self._assign(self.layer, "samples", samples)   # read at every render, no re-sync
        new_limit = self._assign(cycles, "time_limit", time_limit)
        changed = [self._assign(cycles, "use_adaptive_sampling", adaptive_threshold is not None),
                   self._assign(self.layer.cycles, "pass_debug_sample_count", counted),
                   # A new sample count resets Cycles' session, which re-reads the time limit;
                   # only a new limit at the same count needs the (costly) re-sync.
                   new_limit and not new_count,
                   _tag_volume_changes(scene, self._volume_materials())]
        if adaptive_threshold is not None:
            # Cycles reads the threshold at every render; tagging for it would re-sync the
            # scene for each rectangle (3.7 s each on balls_b, see the module docstring).
            self._assign(cycles, "adaptive_threshold", adaptive_threshold)
        self._set_output(multilayer=multilayer)
        if window is None:
            self._assign(render, "use_border", False)
            shape = (self.height, self.width)
        else:
            border = border_for_window(window, self.width, self.height)
            for name, value in zip(("border_min_x", "border_min_y", "border_max_x", "border_max_y"), border):
                self._assign(render, name, value)
            self._assign(render, "use_border", True)
            self._assign(render, "use_crop_to_border", True)
            shape = (window[1] - window[0], window[3] - window[2])
        if any(changed):
            scene.update_tag()      # see the module docstring: add-on properties do not tag it
        for old in self.folder.glob("window*"):
            old.unlink()
        self._status_max, self._on_sample = 0, on_sample
        # Cycles' status lines cost ~2 ms per render through a Python handler: listen only
        # when the count it completed or the progress is wanted.
        listen = counted or on_sample is not None
        if listen:
            bpy.app.handlers.render_stats.append(self._handler)
        started = time.perf_counter()
        _synced_volumes[scene.as_pointer()] = _volume_settings(scene, self._volume_materials())
        # (Before the render: Cycles may have taken the count even where the render fails.)
        note_session_count(scene, samples)
        try:
            with own_render():
                result = bpy.ops.render.render(write_still=True, scene=scene.name, layer=self.layer.name)
        except BaseException:
            _synced_volumes.pop(scene.as_pointer(), None)
            raise
        finally:
            self._on_sample = None
            if listen:
                bpy.app.handlers.render_stats.remove(self._handler)
        seconds = time.perf_counter() - started
        if "FINISHED" not in result:
            raise RuntimeError(f"Cycles did not finish the render ({result})")
        files = sorted(self.folder.glob("window*.exr"))
        if not files:
            raise RuntimeError("Cycles wrote no image")
        channels, attributes = read_exr_parts(files[0], small=window is not None)
        wanted = ("Combined",) + (("Debug Sample Count",) if counted else ()) \
            + (("Denoising Albedo", "Denoising Normal") if self.guides else ())
        passes = passes_from_channels(channels, self.layer.name, wanted)
        guides = (np.concatenate([passes["Denoising Albedo"], passes["Denoising Normal"]], axis=2)
                  if self.guides else None)
        pixels = passes["Combined"]
        if pixels.shape[:2] != shape:
            raise RuntimeError(f"Cycles rendered {pixels.shape[1]}x{pixels.shape[0]} pixels "
                               f"for a {shape[1]}x{shape[0]} window {window}")
        reported = attributes.get(f"cycles.{self.layer.name}.samples")
        reported = None if reported is None else int(reported)
        synced = attributes.get(f"cycles.{self.layer.name}.synchronization_time")
        synced = 0.0 if synced is None else header_seconds(synced)
        self.sync_seconds += synced
        if reported is not None and reported != samples:
            raise RuntimeError(f"Cycles rendered with {reported} samples where {samples} were set")
        if counted:
            rendered = self._status_max or samples
            # The pass holds each pixel's samples divided by the samples the render completed.
            per_pixel = np.rint(passes["Debug Sample Count"][:, :, 0] * rendered).astype(np.float32)
            return RenderedWindow(window, pixels, per_pixel, samples, rendered, reported, seconds, guides,
                                  synced)
        return RenderedWindow(window, pixels, samples, samples, samples, reported, seconds, guides, synced)
