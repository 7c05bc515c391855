"""The snapshot of section 4.2: a fast Cycles render with direct lighting only, no media, which
(with the inverted X map) feeds the saliency model.

Cycles with zero bounces, volumes off (the view layer's flag, the world's volume unplugged on
a temporary copy of the world), a few samples at a fixed seed, denoised: a few samples and a
denoise cost less than the many it takes for grain to stop reading as texture in the
saliency model's feature maps. The render's Emit pass holds the emissive surfaces the
0-LightMap uses. Everything runs inside ``preserved_scene``."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.sampling.finite_pixels import zero_non_finite
from ..cycles.render import render_passes
from ..scene.state import let_session_go, preserved_scene

#: Direct lighting from point-like lamps converges fast: a few samples, no denoiser needed.
SNAPSHOT_SAMPLES = 4
SNAPSHOT_SEED = 0


@dataclass
class Snapshot:
    """The direct-lighting render (scene-linear RGBA) and the emission of visible surfaces."""

    combined: np.ndarray     # (H, W, 4) float32, denoised unless asked otherwise
    emission: np.ndarray     # (H, W, 3) float32
    samples: int
    denoised: bool = True


def _has_volume(node_tree) -> bool:
    output = node_tree.get_output_node("CYCLES") if node_tree is not None else None
    return output is not None and "Volume" in output.inputs and output.inputs["Volume"].is_linked


def _without_volume(datablock):
    """A copy of a world or material whose Volume output is unplugged (the original is untouched)."""
    copy = datablock.copy()
    tree = copy.node_tree
    output = tree.get_output_node("CYCLES")
    for link in list(output.inputs["Volume"].links):
        tree.links.remove(link)
    return copy


def _switch_media_off(scene, state) -> None:
    """No participating media: the view layers' volume flag (volume objects) and every
    world or material Volume output unplugged on temporary copies (mesh volumes, which
    the flag does not reach)."""
    for layer in scene.view_layers:
        layer.use_volumes = False
    if scene.world is not None and _has_volume(scene.world.node_tree):
        scene.world = _without_volume(scene.world)
    copies = {}
    for ob in scene.objects:
        for index, slot in enumerate(ob.material_slots):
            material = slot.material
            if material is None or not _has_volume(material.node_tree):
                continue
            if material.name not in copies:
                copies[material.name] = _without_volume(material)
            state.swap_material(ob, index, copies[material.name])


def render_snapshot(scene, size: tuple[int, int] | None = None, samples: int = SNAPSHOT_SAMPLES,
                    frame: int | None = None, denoise: bool = True) -> Snapshot:
    """Render the snapshot of the current frame (or ``frame``) at the render size (or ``size``)."""
    with preserved_scene(scene) as state:
        if frame is not None:
            scene.frame_set(frame)
        render = scene.render
        if size is not None:
            render.resolution_x, render.resolution_y = size
            render.resolution_percentage = 100
        render.use_border = False
        let_session_go(scene)
        _switch_media_off(scene, state)
        cycles = scene.cycles
        render.engine = "CYCLES"
        cycles.samples = samples
        cycles.use_adaptive_sampling = False
        cycles.use_denoising = False
        cycles.seed = SNAPSHOT_SEED
        cycles.use_animated_seed = False
        cycles.max_bounces = 0
        cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transmission_bounces = 0
        cycles.volume_bounces = 0
        cycles.transparent_max_bounces = max(cycles.transparent_max_bounces, 8)
        wanted = ("Combined", "Emit") + (("Denoising Albedo", "Denoising Normal") if denoise else ())
        for layer in scene.view_layers:
            layer.cycles.denoising_store_passes = denoise
        passes = render_passes(scene, wanted)
    # Light too strong for 32-bit floats: as every frame's (core.sampling.finite_pixels).
    passes = {name: zero_non_finite(pixels, whole_frame=False)[0] for name, pixels in passes.items()}
    combined = passes["Combined"]
    if denoise:
        from ..cycles.denoise import denoise as run_denoiser

        combined = run_denoiser(combined, passes["Denoising Albedo"], passes["Denoising Normal"])
    return Snapshot(combined=combined, emission=passes["Emit"], samples=samples, denoised=denoise)
