"""Reading and writing images with OpenImageIO; every write is atomic.

Maps and renders are float32 OpenEXR. Arrays are ``[row, column, channel]`` with row 0 at
the top. A write goes to a temporary name in the same folder and is renamed into place,
so a crash or a cancel never leaves a half-written file under the real name.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from .errors import InputError
from .files import atomic_path


def read_image(path: str | os.PathLike) -> np.ndarray:
    """Read any image OpenImageIO understands as float32 ``(H, W, C)``.

    8- and 16-bit files come back in [0, 1] (their stored values, not linearised); float
    files as stored. Raises InputError for a missing, unreadable or empty image.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"no such image file: {path}")
    image = oiio.ImageInput.open(str(path))
    if image is None:
        reason = oiio.geterror().strip().splitlines()
        raise InputError(f"cannot read image {path}: {reason[0] if reason else 'unknown format'}")
    try:
        spec = image.spec()
        if spec.width < 1 or spec.height < 1 or spec.nchannels < 1:
            raise InputError(f"image {path} has no pixels")
        pixels = image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None:
            reason = image.geterror().strip().splitlines()
            raise InputError(f"cannot read image {path}: {reason[0] if reason else 'read failed'}")
    finally:
        image.close()
    pixels = np.asarray(pixels, dtype=np.float32)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    return pixels.reshape(spec.height, spec.width, spec.nchannels)


def image_channel_names(path: str | os.PathLike) -> list[str]:
    image = oiio.ImageInput.open(str(path))
    if image is None:
        raise InputError(f"cannot read image {path}")
    try:
        return list(image.spec().channelnames)
    finally:
        image.close()


def image_attributes(path: str | os.PathLike) -> dict[str, object]:
    """The header attributes of an image file (e.g. ``xsl_render:seed`` of a reference)."""
    image = oiio.ImageInput.open(str(path))
    if image is None:
        raise InputError(f"cannot read image {path}")
    try:
        return {attr.name: attr.value for attr in image.spec().extra_attribs}
    finally:
        image.close()


def image_is_float(path: str | os.PathLike) -> bool:
    """True when the file stores floating-point pixels (OpenEXR, float TIFF, Radiance HDR):
    by convention scene-linear, where 8- and 16-bit integer files are display-referred."""
    return image_header(path)[3]


def image_header(path: str | os.PathLike) -> tuple[int, int, int, bool]:
    """``(width, height, channels, floating-point pixels)`` of an image file, read from its
    header alone (no pixels): enough to check a sequence's frames before any work."""
    image = oiio.ImageInput.open(str(path))
    if image is None:
        reason = oiio.geterror().strip().splitlines()
        raise InputError(f"cannot read image {path}: {reason[0] if reason else 'unknown format'}")
    try:
        spec = image.spec()
        return (int(spec.width), int(spec.height), int(spec.nchannels),
                spec.format.basetype in (oiio.HALF, oiio.FLOAT, oiio.DOUBLE))
    finally:
        image.close()


def _as_hwc(array: np.ndarray) -> np.ndarray:
    array = np.asarray(array)
    if array.ndim == 2:
        array = array[:, :, None]
    if array.ndim != 3 or array.shape[0] < 1 or array.shape[1] < 1:
        raise ValueError(f"expected an (H, W) or (H, W, C) image, got shape {array.shape}")
    return array


def _default_channels(count: int) -> list[str]:
    return {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}.get(
        count, [f"C{i}" for i in range(count)])


def write_exr(path: str | os.PathLike, array: np.ndarray, channel_names: list[str] | None = None,
              attributes: dict[str, object] | None = None, atomic: bool = True) -> Path:
    """Write a float32 OpenEXR (ZIP compressed) atomically.

    A 2-D array becomes one channel named ``Y``. Refuses NaN and Inf: a map with them
    is a bug upstream and must not reach a file; and a name without ``.exr``, under which
    OpenImageIO would write another format. ``atomic=False`` writes ``path`` itself: only for
    a path that is already a temporary (``core.files.atomic_paths``).
    """
    if Path(path).suffix.lower() != ".exr":
        raise ValueError(f"write_exr writes OpenEXR files; {path} does not end in .exr")
    data = np.ascontiguousarray(_as_hwc(array), dtype=np.float32)
    if not np.isfinite(data).all():
        raise ValueError(f"refusing to write NaN or Inf to {path}")
    names = channel_names or _default_channels(data.shape[2])
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], data.shape[2], oiio.FLOAT)
    spec.channelnames = tuple(names)
    spec.attribute("compression", "zip")
    for key, value in (attributes or {}).items():
        spec.attribute(key, value if isinstance(value, (int, float)) else str(value))
    return _write(path, data, spec, atomic)


def write_png(path: str | os.PathLike, array: np.ndarray, encode_srgb: bool = False,
              atomic: bool = True) -> Path:
    """Write an 8-bit PNG preview of values in [0, 1] (clipped) atomically (``atomic`` as
    in ``write_exr``).

    ``encode_srgb`` applies the sRGB transfer curve first (for linear images); maps are
    written as they are, so a grey level in the PNG is the map value.
    """
    data = np.clip(np.nan_to_num(_as_hwc(array).astype(np.float32)), 0.0, 1.0)
    if encode_srgb:
        data = linear_to_srgb(data)
    data = np.round(data * 255.0).astype(np.uint8)
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], data.shape[2], oiio.UINT8)
    spec.channelnames = tuple(_default_channels(data.shape[2]))
    return _write(path, np.ascontiguousarray(data), spec, atomic)


def _write(path: str | os.PathLike, data: np.ndarray, spec: "oiio.ImageSpec", atomic: bool = True) -> Path:
    path = Path(path)
    if not atomic:
        _write_to(path, path, data, spec)
        return path
    with atomic_path(path) as tmp:
        _write_to(path, tmp, data, spec)
    return path


def _write_to(path: Path, target: Path, data: np.ndarray, spec: "oiio.ImageSpec") -> None:
    """Write ``data`` to ``target`` (``path`` or its temporary; errors name ``path``).

    OpenImageIO does not always say when a write fails: a PNG's short writes only leave a
    message behind, and an OpenEXR file small enough to sit in a buffer until ``close``
    loses a full disk's error there. So every message counts as a failure, and the file
    is read back whole before it may take the real name."""
    out = oiio.ImageOutput.create(str(target))
    if out is None:
        raise InputError(f"cannot write {path}: {oiio.geterror().strip() or 'unknown format'}")
    try:
        if not out.open(str(target), spec):
            raise InputError(f"cannot write {path}: {_first_line(out.geterror())}")
        if not out.write_image(data) or out.has_error:
            raise InputError(f"cannot write {path}: {_first_line(out.geterror())}")
    finally:
        closed = out.close()
    if not closed or out.has_error:
        raise InputError(f"cannot write {path}: {_first_line(out.geterror())}")
    _read_back(path, target, spec)


def _first_line(message: str) -> str:
    lines = message.strip().splitlines()
    return lines[0] if lines else "write failed"


def _read_back(path: Path, target: Path, spec: "oiio.ImageSpec") -> None:
    """InputError unless ``target`` reads back whole as the image of ``spec``."""
    image = oiio.ImageInput.open(str(target))
    problem = None
    if image is None:
        problem = _first_line(oiio.geterror())
    else:
        try:
            pixels = image.read_image(0, 0, 0, spec.nchannels, spec.format)
            if pixels is None or image.has_error:
                problem = _first_line(image.geterror())
        finally:
            image.close()
    if problem is not None:
        # OpenImageIO's words name the temporary file; the user knows the real one.
        raise InputError(f"cannot write {path}: the file came out incomplete (is the disk full?)")


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on values in [0, 1]."""
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear,
                    1.055 * np.power(linear, 1.0 / 2.4) - 0.055).astype(np.float32)
