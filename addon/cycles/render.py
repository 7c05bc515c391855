"""One Cycles render of the scene as it is set up now, returned as numpy arrays.

The render result of a background session cannot be read from Python directly, so the
frame goes through a temporary multilayer EXR. Callers change settings inside
``addon.scene.state.preserved_scene``; this module only sets the output it needs (and that
is put back by the same block).
"""
from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from ...core.errors import InputError
from .device import honour_scene_device
from .own_renders import own_render

#: Our pass name -> (view-layer flag enabling it, its name in the EXR, channels).
PASSES = {
    "Combined": (None, "Combined", "RGBA"),
    "Depth": ("use_pass_z", "Depth", "Z"),
    "Normal": ("use_pass_normal", "Normal", "XYZ"),
    "Emit": ("use_pass_emit", "Emission", "RGB"),
    "Object Index": ("use_pass_object_index", "Object Index", "X"),
    # Samples taken per pixel / samples rendered (view_layer.cycles.pass_debug_sample_count).
    "Debug Sample Count": (None, "Debug Sample Count", "X"),
    # Cycles' denoising data (view_layer.cycles.denoising_store_passes).
    "Denoising Albedo": (None, "Denoising Albedo", "RGB"),
    "Denoising Normal": (None, "Denoising Normal", "XYZ"),
}


def ensure_cycles(scene) -> None:
    """Cycles as the engine, on the scene's own device (``addon.cycles.device``: its GPUs
    enabled, or the CPU when it asks for none or the machine has none). Both are scene
    settings, so this runs inside ``preserved_scene`` and the user's scene gets them back."""
    if scene.render.engine != "CYCLES":
        scene.render.engine = "CYCLES"
    honour_scene_device(scene)


def render_passes(scene, passes: tuple[str, ...] = ("Combined",), view_layer=None) -> dict[str, np.ndarray]:
    """Render with Cycles and return the requested passes as float32 ``(H, W, C)`` arrays.

    Row 0 is the top of the image. With a render border and crop on, the arrays have the
    border's size. Must run inside ``preserved_scene`` (it changes the output settings).
    """
    import bpy

    ensure_cycles(scene)
    layer = view_layer or scene.view_layers[0]
    for name in passes:
        flag = PASSES[name][0]
        if flag and not getattr(layer, flag):
            setattr(layer, flag, True)
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):          # Blender 5.0+: the format follows the media type
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    scene.render.use_file_extension = True
    folder = Path(tempfile.mkdtemp(prefix="xsl-render-"))
    try:
        scene.render.filepath = str(folder / "frame")
        with own_render():
            result = bpy.ops.render.render(write_still=True, scene=scene.name, layer=layer.name)
        if "FINISHED" not in result:
            raise RuntimeError(f"Cycles did not finish the render ({result})")
        files = sorted(folder.glob("frame*.exr"))
        if not files:
            raise RuntimeError("Cycles wrote no image")
        return read_multilayer(files[0], layer.name, passes)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def header_seconds(text) -> float:
    """Seconds of a duration as Blender writes it in an EXR header ("00:10.68", "01:02:03.5").

    Cycles records its render statistics this way (``cycles.<layer>.synchronization_time``)."""
    seconds = 0.0
    for part in str(text).strip().split(":"):
        seconds = seconds * 60.0 + float(part)
    return seconds


def read_exr_parts(path: str | os.PathLike, small: bool = False) -> tuple[dict[str, np.ndarray], dict[str, object]]:
    """Every channel of every part of an EXR by name, and the first part's header attributes.

    Blender 5 writes each pass of a multilayer EXR as its own part (subimage); older versions
    put all channels in one part. Cycles puts its render statistics in the header
    (``cycles.<view layer>.samples``, ``...render_time``). ``small``: a tile of a few
    thousand pixels, read on one thread (OpenEXR's thread pool costs ~3 ms per file, ten
    times the read itself; a frame read gains from the threads).
    """
    threads = oiio.get_int_attribute("exr_threads")
    if small:
        oiio.attribute("exr_threads", 1)
    try:
        return _read_exr_parts(path)
    finally:
        oiio.attribute("exr_threads", threads)


def _read_exr_parts(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict[str, object]]:
    image = oiio.ImageInput.open(str(path))
    if image is None:
        raise InputError(f"cannot read {path}: {oiio.geterror()}")
    channels: dict[str, np.ndarray] = {}
    attributes: dict[str, object] = {}
    try:
        subimage = 0
        while image.seek_subimage(subimage, 0):
            spec = image.spec()
            if subimage == 0:
                attributes = {attr.name: attr.value for attr in spec.extra_attribs}
            pixels = image.read_image(subimage, 0, 0, spec.nchannels, oiio.FLOAT)
            pixels = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
            for i, name in enumerate(spec.channelnames):
                channels[name] = pixels[:, :, i]
            subimage += 1
    finally:
        image.close()
    return channels, attributes


def read_multilayer(path: str | os.PathLike, layer: str, passes: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Read named passes of one view layer from a Blender multilayer EXR (or a plain EXR of
    the Combined pass, whose channels are just R, G, B, A)."""
    channels, _ = read_exr_parts(path)
    return passes_from_channels(channels, layer, passes)


def passes_from_channels(channels: dict[str, np.ndarray], layer: str,
                         passes: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Named passes as (H, W, C) float32 arrays from the channels ``read_exr_parts`` found."""
    out = {}
    for name in passes:
        _, exr_name, wanted = PASSES.get(name, (None, name, "RGBA"))
        found = []
        for c in wanted:
            for candidate in ((f"{layer}.{exr_name}.{c}", f"{exr_name}.{c}")
                              + ((c,) if name == "Combined" else ())):
                if candidate in channels:
                    found.append(channels[candidate])
                    break
        if not found:
            raise RuntimeError(f"pass {name} missing from the render (has: {sorted(channels)[:8]})")
        out[name] = np.ascontiguousarray(np.stack(found, axis=-1), dtype=np.float32)
    return out
