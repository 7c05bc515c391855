"""Auto Volumes' choice for a frame: auto's choice (``estimator_choice.choose_estimator``) at
the sampled frames of the frame's shot, for each view layer the render renders at the
samples the file gives it, and the most cautious of them (``core.sampling.shot_plan``).

The scene is evaluated at each sampled frame with ``scene.frame_set`` and put back at its own
frame (and subframe) afterwards, so this runs where Blender may change the frame: on the
main thread, or in a render whose interface is locked.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

from ...core.sampling.render_options import RenderOptions
from ...core.sampling.shot_plan import estimator_samples, layer_samples, most_cautious, sampled_frames
from ...core.sampling.volume_estimator import EstimatorChoice
from ..scene.animation import scene_moves
from .estimator_choice import choose_estimator


#: (first, last) frame of each scene (its pointer) as its file was loaded or saved: farms
#: split a range with ``-s`` / ``-e``, which set the scene's range before the render.
_saved_ranges: dict[int, tuple[int, int]] = {}


@dataclass(frozen=True)
class ShotChoice:
    """What a shot renders with and where that came from."""

    shot: tuple[int, int]               # first and last frame
    choice: EstimatorChoice
    frame: int                          # the sampled frame whose choice it is
    layer: str                          # ... and view layer
    frames: tuple[int, ...]             # every frame predicted at
    spp: float                          # the samples its tolerance was taken at
    seconds: float                      # the predictions, frames evaluated included

    def describe(self) -> str:
        """One line: the choice, its reason and where it came from."""
        first, last = self.shot
        shot = f"frame {first}" if first == last else f"shot {first}-{last}"
        return (f"{applied(self.choice)}; {self.choice.reason or 'as chosen'} ({shot}, decided at "
                f"frame {self.frame} of {', '.join(map(str, self.frames))}, view layer '{self.layer}', "
                f"{self.spp:g} spp)")


def applied(choice: EstimatorChoice) -> str:
    """What a render with ``choice`` changes, in words (Blender's own denoiser denoises an
    Auto Volumes render as the file sets it)."""
    return replace(choice, estimator="auto volumes").describe()


def frame_spp(scene, layer) -> float:
    """The samples per pixel auto's tolerance is taken at for ``layer``: the file's samples
    for it (the view layer's own where the scene says so) and its adaptive sampling."""
    cycles = scene.cycles
    samples = layer_samples(int(cycles.samples), int(getattr(layer, "samples", 0)),
                            str(getattr(cycles, "use_layer_samples", "IGNORE")))
    return estimator_samples(samples, bool(cycles.use_adaptive_sampling),
                             float(cycles.adaptive_threshold), int(cycles.adaptive_min_samples))


def rendered_layers(scene) -> list:
    """The view layers a render of the scene renders (Render Single Layer: the active one)."""
    import bpy

    if scene.render.use_single_layer:
        active = getattr(bpy.context, "view_layer", None)
        if active is not None and scene.view_layers.get(active.name) == active:
            return [active]
    return [layer for layer in scene.view_layers if layer.use] or list(scene.view_layers[:1])


def shot_range(scene) -> tuple[int, int]:
    """The frame range a shot spans: in the interface the scene's own; in the background the
    range its file was loaded (or last saved) with, as a farm's ``-s`` / ``-e`` may have set
    another for the frames of one task (an unsaved scene's own range)."""
    import bpy

    live = (scene.frame_start, scene.frame_end)
    return _saved_ranges.get(scene.as_pointer(), live) if bpy.app.background else live


def remember_ranges() -> None:
    """Note every scene's frame range as the file has it now (loaded or saved)."""
    import bpy

    _saved_ranges.clear()
    for scene in bpy.data.scenes:
        _saved_ranges[scene.as_pointer()] = (scene.frame_start, scene.frame_end)


def choose_for_shot(scene, shot: tuple[int, int], run: RenderOptions | None = None,
                    run_spp: float | None = None) -> ShotChoice:
    """Auto's choice for ``shot`` (first, last frame) of ``scene``: for Blender's own render
    at the file's samples of each view layer, or for a run of this extension's (``run``, at
    ``run_spp`` samples per pixel). It depends on the shot alone, never on the frames
    rendered before, so a frame renders the same alone, in a chunk or in the whole range."""
    import bpy

    started = time.perf_counter()
    frames = sampled_frames(shot, scene_moves(scene))
    layers = rendered_layers(scene)
    own = (scene.frame_current, scene.frame_subframe)
    found = []
    try:
        for frame in frames:
            scene.frame_set(frame)
            for layer in layers:
                spp = frame_spp(scene, layer) if run_spp is None else float(run_spp)
                options = (RenderOptions(max_spp=max(1, round(spp)), estimator="auto") if run is None
                           else replace(run, estimator="auto", estimator_choice=None))
                with bpy.context.temp_override(view_layer=layer):
                    found.append((choose_estimator(scene, options, spp), frame, layer.name, spp))
    finally:
        scene.frame_set(own[0], subframe=own[1])
    best = most_cautious([choice for choice, *_ in found])
    choice, frame, layer, spp = found[best]
    if len(frames) > 1:
        # A still keeps its prediction (a time budget's settle asks it again); a shot's would
        # answer for one sampled frame only.
        choice = replace(choice, remeasure=None)
    return ShotChoice(shot, choice, frame, layer, frames, spp, time.perf_counter() - started)
