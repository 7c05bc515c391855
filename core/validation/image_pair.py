"""A reference and a test image, read and checked so that every metric can compare them.

The metrics compare like with like: two scene-linear HDR renders or two display-referred LDR
images. Which is which is read from the file's pixels, not its name: floating-point pixels
(OpenEXR, Radiance HDR, float TIFF) hold scene-linear radiance, integer pixels (PNG, JPEG,
8- and 16-bit TIFF) display values. Anything that would make a comparison meaningless
(different sizes or channel layouts, NaN or Inf pixels, a missing file, an HDR image against
an LDR one) is bad input and raises :class:`~.errors.InputError` with one line.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..imageio import image_is_float, read_image


@dataclass(frozen=True)
class ImagePair:
    """Two RGB images of one size, ``(H, W, 3)`` float32, row 0 at the top.

    ``hdr`` is True for scene-linear renders (values >= 0, unbounded) and False for
    display-encoded sRGB images (values in [0, 1]).
    """

    reference: np.ndarray
    test: np.ndarray
    hdr: bool

    @property
    def height(self) -> int:
        return self.reference.shape[0]

    @property
    def width(self) -> int:
        return self.reference.shape[1]


def dynamic_range_of(path: str | os.PathLike) -> bool:
    """True for an HDR file (floating-point pixels: scene-linear), False for an LDR one
    (integer pixels: display-encoded), whatever its name says; InputError for a file that is
    not an image."""
    return image_is_float(Path(path))


def as_rgb(image: np.ndarray, name: str = "image") -> np.ndarray:
    """``(H, W, C)`` -> ``(H, W, 3)`` float32.

    One channel (grey) or grey + alpha is repeated into RGB; RGBA drops alpha, so a render
    is compared as its colour channels hold it (Cycles stores premultiplied colour, i.e.
    over black). Other channel counts raise InputError.
    """
    image = np.asarray(image, dtype=np.float32)
    if image.ndim == 2:
        image = image[:, :, None]
    if image.ndim != 3:
        raise InputError(f"{name} is not an image (array of shape {image.shape})")
    channels = image.shape[2]
    if channels in (1, 2):
        return np.ascontiguousarray(np.repeat(image[:, :, :1], 3, axis=2))
    if channels in (3, 4):
        return np.ascontiguousarray(image[:, :, :3])
    raise InputError(f"{name} has {channels} channels; expected grey, grey+alpha, RGB or RGBA")


def check_pair(reference: np.ndarray, test: np.ndarray, hdr: bool,
               names: tuple[str, str] = ("reference", "test")) -> ImagePair:
    """Validate two arrays and return them as an :class:`ImagePair`.

    Raises InputError when sizes or channel counts differ, when any pixel is NaN or Inf,
    or when an LDR image holds values outside [0, 1].
    """
    reference = np.asarray(reference, dtype=np.float32)
    test = np.asarray(test, dtype=np.float32)
    ref_shape, test_shape = _hwc(reference.shape), _hwc(test.shape)
    if ref_shape[:2] != test_shape[:2]:
        raise InputError(f"images differ in size: {names[0]} is {ref_shape[1]}x{ref_shape[0]}, "
                         f"{names[1]} is {test_shape[1]}x{test_shape[0]}")
    if ref_shape[2] != test_shape[2]:
        raise InputError(f"images differ in channel count: {names[0]} has {ref_shape[2]}, "
                         f"{names[1]} has {test_shape[2]}")
    for image, name in ((reference, names[0]), (test, names[1])):
        bad = int(np.count_nonzero(~np.isfinite(image)))
        if bad:
            raise InputError(f"{name} has {bad} NaN or Inf values; a metric cannot compare them")
        if not hdr and (image.min() < 0.0 or image.max() > 1.0):
            raise InputError(f"{name} is an LDR image with values outside [0, 1]")
    return ImagePair(as_rgb(reference, names[0]), as_rgb(test, names[1]), hdr)


def read_pair(reference_path: str | os.PathLike, test_path: str | os.PathLike) -> ImagePair:
    """Read and check a reference and a test image file (both HDR or both LDR)."""
    ref_hdr, test_hdr = dynamic_range_of(reference_path), dynamic_range_of(test_path)
    if ref_hdr != test_hdr:
        kinds = {True: "HDR (floating-point pixels)", False: "LDR (integer pixels)"}
        raise InputError(f"cannot compare {kinds[ref_hdr]} {reference_path} with "
                         f"{kinds[test_hdr]} {test_path}: use two images of the same kind")
    reference, test = read_image(reference_path), read_image(test_path)
    return check_pair(reference, test, ref_hdr, names=(str(reference_path), str(test_path)))


def _hwc(shape: tuple[int, ...]) -> tuple[int, int, int]:
    if len(shape) == 2:
        return shape[0], shape[1], 1
    if len(shape) == 3:
        return shape[0], shape[1], shape[2]
    raise InputError(f"not an image: array of shape {shape}")
