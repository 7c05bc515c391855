"""Denoise a whole frame with the denoiser Cycles itself uses (Intel Open Image Denoise).

After compositing, never per tile: OIDN looks at a neighbourhood of every pixel, so
rectangles denoised one by one would seam. Every mode goes through this one function, so
comparisons stay fair. OIDN is called directly from the library Blender ships
(``oidn_library``), set up as the compositor's Denoise node (Quality High, HDR, the file's
prefilter), bit for bit the same; going through the compositor would make Cycles sync the
scene again at its next render. The guides' prefilter follows the file's own denoiser in every
mode and in the converged reference (``selective_render.guide_prefilter``: Accurate, Blender
5's default, denoises the albedo and normal guides first, which in fog are as noisy as the
image), so a comparison with the file measures the estimator, not the denoise. Non-finite
values are set to 0 first, and a frame too bright for OIDN's 32-bit auto-exposure is scaled by
a power of two before and back after (``OIDN_PEAK``).
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np

from ...core.sampling.finite_pixels import zero_non_finite
from .oidn_library import QUALITY_HIGH
from .oidn_library import load as load_oidn
from .render import read_exr_parts

_SCENE = "xsl_render denoise"
#: What prefiltered guides cost over the plain denoise, as a multiple of it (measured: 4x at
#: 256x192 and 512x288, the prefilter's two filters beside the main one).
PREFILTER_COST = 4.0
#: The denoising procedure's version: part of the converged reference's cache key
#: (``core.validation.reference``). Bump it with any change to what ``denoise`` does
#: (settings, prefilter, guides), then regenerate the shipped reference
#: (tools/regenerate_reference.py); a test compares the shipped entry's key.
DENOISE_VERSION = "oidn-hdr-file-prefilter-2"
#: The largest value a frame goes to OIDN with (2^100; a frame up to 2^120 denoised within
#: 2e-6 of itself at 1 in a test, 1e37 came back black). Frames below it are untouched.
OIDN_PEAK = 2.0 ** 100


def _image(bpy, name: str, pixels: np.ndarray, non_color: bool):
    """A float image datablock holding ``pixels`` (H, W, C), row 0 at the top."""
    height, width = pixels.shape[:2]
    rgba = np.ones((height, width, 4), np.float32)
    rgba[..., :min(pixels.shape[2], 4)] = pixels[..., :4]
    image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    if non_color:
        image.colorspace_settings.name = "Non-Color"
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())   # Blender: bottom row first
    return image


def _set_input(node, name: str, value) -> None:
    if name in node.inputs:
        try:
            node.inputs[name].default_value = value
        except (TypeError, AttributeError):
            pass


def denoise(rgba: np.ndarray, albedo: np.ndarray | None = None,
            normal: np.ndarray | None = None, prefilter_guides: bool = False) -> np.ndarray:
    """The frame denoised by OIDN (HDR, guided by albedo and normal when given).

    ``rgba`` is (H, W, 4) scene-linear; alpha passes through unchanged. Returns float32
    (H, W, 4). ``prefilter_guides``: the guides are denoised first, each by OIDN's filter on
    its own, and then taken as clean (OIDN's and Blender's "Accurate" prefilter, the file's
    choice: ``selective_render.guide_prefilter``).
    """
    rgba = zero_non_finite(rgba)[0]
    albedo = None if albedo is None else zero_non_finite(albedo, whole_frame=False)[0]
    normal = None if normal is None else zero_non_finite(normal, whole_frame=False)[0]
    alpha = rgba[..., 3:]
    scale = _scale_into_range(rgba)
    if scale != 1.0:
        rgba = rgba[..., :3] * np.float32(scale)
    library = load_oidn()
    if library is not None:
        # Rows bottom first, as the compositor hands Blender's images to OIDN: its network is
        # not symmetric under a flip, and this is what makes the two bit-identical.
        albedo = None if albedo is None else albedo[::-1]
        normal = None if normal is None else normal[::-1]
        clean = prefilter_guides and albedo is not None
        if clean:
            albedo = library.prefilter(albedo, "albedo", QUALITY_HIGH)
            normal = None if normal is None else library.prefilter(normal, "normal", QUALITY_HIGH)
        out = library.denoise(rgba[::-1], albedo, normal, hdr=True, clean_aux=clean,
                              quality=QUALITY_HIGH)[::-1]
    else:
        out = _compositor_denoise(rgba, albedo, normal, "Accurate" if prefilter_guides else "Fast")
    denoised = np.empty(alpha.shape[:2] + (3 + alpha.shape[2],), dtype=np.float32)
    denoised[..., :3] = np.maximum(out, 0.0)       # OIDN may undershoot slightly below zero
    if scale != 1.0:
        denoised[..., :3] = np.minimum(denoised[..., :3] / np.float64(scale), np.finfo(np.float32).max)
    denoised[..., 3:] = alpha
    return denoised


def _scale_into_range(rgba: np.ndarray) -> float:
    """The power of two that brings the frame's largest colour value to at most ``OIDN_PEAK``
    (1 where it is there already)."""
    peak = float(np.max(rgba[..., :3])) if rgba.size else 0.0
    if peak <= OIDN_PEAK:
        return 1.0
    return 2.0 ** (np.frexp(OIDN_PEAK)[1] - 1 - np.frexp(peak)[1])


def _compositor_denoise(rgba: np.ndarray, albedo: np.ndarray | None,
                        normal: np.ndarray | None, prefilter: str = "Fast") -> np.ndarray:
    """The denoised RGB (H, W, 3) through the compositor's Denoise node in a temporary scene
    (Prefilter ``prefilter``, Quality High, HDR)."""
    import bpy

    height, width = rgba.shape[:2]
    scene = bpy.data.scenes.new(_SCENE)
    created_images, tree, folder = [], None, Path(tempfile.mkdtemp(prefix="xsl-denoise-"))
    try:
        render = scene.render
        render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100
        render.engine = "BLENDER_WORKBENCH"          # nothing to render: only the compositor runs
        render.use_compositing, render.use_sequencer = True, False
        camera = bpy.data.objects.new(_SCENE, bpy.data.cameras.new(_SCENE))
        scene.collection.objects.link(camera)
        scene.camera = camera
        settings = render.image_settings
        if hasattr(settings, "media_type"):
            settings.media_type = "IMAGE"
        settings.file_format, settings.color_depth, settings.color_mode = "OPEN_EXR", "32", "RGBA"
        scene.view_settings.view_transform = "Standard"

        if hasattr(scene, "compositing_node_group"):          # Blender 5.0+
            tree = bpy.data.node_groups.new(_SCENE, "CompositorNodeTree")
            scene.compositing_node_group = tree
            output = tree.nodes.new("NodeGroupOutput")
            tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
        else:                                                  # Blender 4.2-4.5
            scene.use_nodes = True
            tree = scene.node_tree
            tree.nodes.clear()
            output = tree.nodes.new("CompositorNodeComposite")
        denoiser = tree.nodes.new("CompositorNodeDenoise")
        _set_input(denoiser, "HDR", True)
        _set_input(denoiser, "Prefilter", prefilter)
        _set_input(denoiser, "Quality", "High")
        if hasattr(denoiser, "use_hdr"):
            denoiser.use_hdr = True
        if hasattr(denoiser, "prefilter"):
            denoiser.prefilter = prefilter.upper()
        for socket, pixels, non_color in (("Image", rgba, False), ("Albedo", albedo, False),
                                          ("Normal", normal, True)):
            if pixels is None:
                continue
            image = _image(bpy, f"{_SCENE} {socket}", np.asarray(pixels, np.float32), non_color)
            created_images.append(image)
            node = tree.nodes.new("CompositorNodeImage")
            node.image = image
            tree.links.new(node.outputs["Image"], denoiser.inputs[socket])
        tree.links.new(denoiser.outputs["Image"], output.inputs[0])
        render.filepath = str(folder / "denoised")
        render.use_file_extension = True
        result = bpy.ops.render.render(write_still=True, scene=scene.name)
        if "FINISHED" not in result:
            raise RuntimeError(f"the denoiser did not finish ({result})")
        files = sorted(folder.glob("denoised*.exr"))
        if not files:
            raise RuntimeError("the denoiser wrote no image")
        channels, _ = read_exr_parts(files[0])
        out = np.stack([channels[c] for c in "RGB"], axis=-1)
    finally:
        for image in created_images:
            bpy.data.images.remove(image)
        if tree is not None and tree.name in bpy.data.node_groups:
            bpy.data.node_groups.remove(tree)
        camera_data = scene.camera.data if scene.camera else None
        for ob in list(scene.collection.objects):
            bpy.data.objects.remove(ob)
        if camera_data is not None:
            bpy.data.cameras.remove(camera_data)
        bpy.data.scenes.remove(scene)
        shutil.rmtree(folder, ignore_errors=True)
    return out
