"""Maps and renders shown as Blender images ("XSL X map", "XSL Render", ...) and read back.

Arrays are ``[row, col, channel]`` with row 0 at the top; Blender stores image rows from the
bottom, so rows are flipped on the way in and out. Maps (data, not colour) are grey
"Non-Color" images shown as stored; renders are scene-linear float images that Blender
shows through the scene's view transform, as it shows its own Render Result.
"""
from __future__ import annotations

import numpy as np

from ...core.maps.camera_rays import depth_to_exr
from ...core.maps.files import MapSet

MAP_IMAGES = {"z": "XSL Z map", "x": "XSL X map", "snapshot": "XSL Snapshot", "s": "XSL S map",
              "l": "XSL L map", "xs": "XSL XS map", "xsl": "XSL XSL map"}
RENDER_IMAGE = "XSL Render"
SAMPLES_IMAGE = "XSL Samples"
GOLD_IMAGE = "XSL Gold"
GOLD_SAMPLES_IMAGE = "XSL Gold Samples"
HEATMAP_IMAGE = "XSL FLIP heatmap"
_LINEAR = "Linear Rec.709"
_DATA = "Non-Color"


def ensure_image(name: str, width: int, height: int, data: bool):
    """A float RGBA image called ``name`` of this size (made, or resized in place)."""
    import bpy

    image = bpy.data.images.get(name)
    if image is not None and not (image.source == "GENERATED" and image.is_float):
        # Someone else's image under our name (a file, a byte image): leave it alone.
        image.name = name + " (not XSL)"
        image = None
    if image is None:
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    elif tuple(image.size) != (width, height):
        image.scale(width, height)
    colorspace = _DATA if data else _LINEAR
    if image.colorspace_settings.name != colorspace:
        image.colorspace_settings.name = colorspace
    return image


def as_rgba(array: np.ndarray) -> np.ndarray:
    """(H, W) grey, (H, W, 1), (H, W, 3) or (H, W, 4) -> (H, W, 4) float32, alpha 1 if absent."""
    array = np.asarray(array, dtype=np.float32)
    if array.ndim == 2:
        array = array[:, :, None]
    height, width, channels = array.shape
    out = np.ones((height, width, 4), np.float32)
    if channels == 1:
        out[:, :, :3] = array
    elif channels in (3, 4):
        out[:, :, :channels] = array
    else:
        raise ValueError(f"cannot show an image with {channels} channels")
    return out


def set_pixels(image, array: np.ndarray) -> None:
    """Fill ``image`` (already of the array's size) with ``array``, top row first."""
    rgba = as_rgba(array)
    if rgba.shape[:2] != (image.size[1], image.size[0]):
        raise ValueError(f"image {image.name} is {image.size[0]}x{image.size[1]}, "
                         f"pixels are {rgba.shape[1]}x{rgba.shape[0]}")
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())
    image.update()


def show(name: str, array: np.ndarray, data: bool, info: dict | None = None):
    """Create or update the image ``name`` with ``array``; ``info`` becomes its custom
    properties (numbers a script can read: ``bpy.data.images[name]["mean_spp"]``)."""
    height, width = np.shape(array)[:2]
    image = ensure_image(name, width, height, data)
    set_pixels(image, array)
    for key, value in (info or {}).items():
        image[key] = value
    return image


def read_pixels(image) -> np.ndarray:
    """The image's pixels as (H, W, 4) float32, top row first."""
    width, height = image.size
    flat = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(flat)
    return flat.reshape(height, width, 4)[::-1].copy()


def show_maps(maps: MapSet) -> list:
    """Every map of ``maps`` as its image; Z as Cycles' Depth pass holds it (sky 1e10)."""
    shown = [show(MAP_IMAGES["z"], depth_to_exr(maps.z), data=True),
             show(MAP_IMAGES["snapshot"], maps.snapshot, data=False)]
    for key in ("x", "s", "l", "xs", "xsl"):
        shown.append(show(MAP_IMAGES[key], maps.director(key), data=True,
                          info={"mean": float(np.mean(maps.director(key)))}))
    return shown


def show_render(outcome, max_spp: int, gold: bool = False) -> tuple:
    """A RenderOutcome as the render image and its samples image (spp / max_spp: 1 = the
    ceiling; the counts themselves are in the custom property ``max_spp`` times it)."""
    stats = outcome.stats
    info = {"mode": stats.mode, "mean_spp": float(stats.mean_spp), "total_samples": int(stats.total_samples),
            "renders": int(stats.renders), "wall_s": float(stats.wall_s), "max_spp": int(max_spp)}
    names = (GOLD_IMAGE, GOLD_SAMPLES_IMAGE) if gold else (RENDER_IMAGE, SAMPLES_IMAGE)
    return (show(names[0], outcome.image, data=False, info=info),
            show(names[1], outcome.samples / float(max_spp), data=True, info=info))


def show_in_image_editors(screen, image) -> None:
    """Show ``image`` in every Image Editor of ``screen`` that is not pinned."""
    if screen is None:
        return
    for area in screen.areas:
        if area.type == "IMAGE_EDITOR":
            space = area.spaces.active
            if not getattr(space, "use_image_pin", False):
                space.image = image
            area.tag_redraw()
