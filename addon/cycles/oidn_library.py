"""Open Image Denoise called directly, from the library Blender itself ships and denoises with.

Not the compositor: a Blender render of another scene (the compositor's Denoise node runs in
one) and any datablock created or removed make Cycles sync the rendering scene from scratch
at its next render (the volume octree again, on heterogeneous fog). A denoise between two
renders of one session (a pilot, an animation's frames) must not touch Blender. The library
is OIDN 2's C API, loaded from Blender's own lib folder; ``load()`` returns None where it
cannot be found, and the caller falls back to the compositor. ``addon.cycles.denoise`` sets
it up exactly as the compositor's Denoise node (a test compares the two)."""
from __future__ import annotations

import ctypes
import os
import sys
from pathlib import Path

import numpy as np

#: OIDNDeviceType, OIDNFormat and OIDNQuality values of OIDN 2's C header.
DEVICE_CPU = 1
FORMAT_FLOAT3 = 3
QUALITY_FAST, QUALITY_BALANCED, QUALITY_HIGH = 4, 5, 6
_NAMES = {"linux": ("libOpenImageDenoise.so.2", "libOpenImageDenoise.so"),
          "darwin": ("libOpenImageDenoise.2.dylib", "libOpenImageDenoise.dylib"),
          "win32": ("OpenImageDenoise.dll",)}


def _candidates() -> list[Path]:
    """Where Blender keeps its libraries, from its version folder (``bpy.utils.resource_path
    ("LOCAL")``, e.g. ``.../5.0``): ``lib`` beside it (the bpy module, Linux, macOS'
    ``Resources``), or the folder itself and ``blender.shared`` beside it (Windows)."""
    try:
        import bpy

        base = Path(bpy.utils.resource_path("LOCAL")).resolve().parent
    except Exception:       # no Blender: nothing to load
        return []
    names = _NAMES.get(sys.platform, _NAMES["linux"])
    return [folder / name for folder in (base / "lib", base, base / "blender.shared") for name in names]


class OIDN:
    """The C functions this module needs, with their argument types."""

    def __init__(self, library: ctypes.CDLL):
        self.lib = lib = library
        handle, text = ctypes.c_void_p, ctypes.c_char_p
        signatures = {
            "oidnNewDevice": (handle, [ctypes.c_int]),
            "oidnCommitDevice": (None, [handle]),
            "oidnReleaseDevice": (None, [handle]),
            "oidnGetDeviceError": (ctypes.c_int, [handle, ctypes.POINTER(text)]),
            "oidnNewFilter": (handle, [handle, text]),
            "oidnSetSharedFilterImage": (None, [handle, text, handle, ctypes.c_int, ctypes.c_size_t,
                                                ctypes.c_size_t, ctypes.c_size_t, ctypes.c_size_t,
                                                ctypes.c_size_t]),
            "oidnSetFilterBool": (None, [handle, text, ctypes.c_bool]),
            "oidnSetFilterInt": (None, [handle, text, ctypes.c_int]),
            "oidnCommitFilter": (None, [handle]),
            "oidnExecuteFilter": (None, [handle]),
            "oidnReleaseFilter": (None, [handle]),
        }
        for name, (result, arguments) in signatures.items():
            function = getattr(lib, name)
            function.restype, function.argtypes = result, arguments

    def check(self, device) -> None:
        message = ctypes.c_char_p()
        if self.lib.oidnGetDeviceError(device, ctypes.byref(message)):
            raise RuntimeError(f"Open Image Denoise: {(message.value or b'').decode(errors='replace')}")

    def denoise(self, color: np.ndarray, albedo: np.ndarray | None, normal: np.ndarray | None,
                hdr: bool = True, clean_aux: bool = True, quality: int = QUALITY_HIGH) -> np.ndarray:
        """The RT filter on (H, W, 3) float32 images; returns the denoised (H, W, 3)."""
        images = {"color": color}
        if albedo is not None:
            images["albedo"] = albedo
            if normal is not None:
                images["normal"] = normal
        flags = {"hdr": hdr} | ({"cleanAux": clean_aux} if albedo is not None else {})
        return self._filter(images, flags, quality)

    def prefilter(self, guide: np.ndarray, kind: str, quality: int = QUALITY_HIGH) -> np.ndarray:
        """A denoising guide (``kind`` "albedo" or "normal", (H, W, 3)) denoised by the RT
        filter on its own, as OIDN's documentation prefilters noisy guides (then passed to
        ``denoise`` with ``clean_aux``)."""
        if kind not in ("albedo", "normal"):
            raise ValueError(f"a guide is 'albedo' or 'normal' (got {kind!r})")
        return self._filter({kind: guide}, {}, quality)

    def _filter(self, inputs: dict[str, np.ndarray], flags: dict[str, bool], quality: int) -> np.ndarray:
        lib = self.lib
        height, width = next(iter(inputs.values())).shape[:2]
        images = {name: np.ascontiguousarray(pixels[..., :3], np.float32) for name, pixels in inputs.items()}
        images["output"] = np.zeros((height, width, 3), np.float32)
        device = lib.oidnNewDevice(DEVICE_CPU)
        if not device:
            raise RuntimeError("Open Image Denoise: no CPU device")
        try:
            lib.oidnCommitDevice(device)
            self.check(device)
            filter_ = lib.oidnNewFilter(device, b"RT")
            try:
                for name, pixels in images.items():
                    lib.oidnSetSharedFilterImage(filter_, name.encode(), pixels.ctypes.data, FORMAT_FLOAT3,
                                                 width, height, 0, 0, 0)
                for name, value in flags.items():
                    lib.oidnSetFilterBool(filter_, name.encode(), value)
                lib.oidnSetFilterInt(filter_, b"quality", quality)
                lib.oidnCommitFilter(filter_)
                self.check(device)
                lib.oidnExecuteFilter(filter_)
                self.check(device)
            finally:
                lib.oidnReleaseFilter(filter_)
        finally:
            lib.oidnReleaseDevice(device)
        return images["output"]


_LOADED: list = []


def load() -> OIDN | None:
    """Blender's OIDN library, loaded once; None where it cannot be found or loaded (set
    ``XSL_RENDER_NO_DIRECT_OIDN=1`` to force the compositor)."""
    if os.environ.get("XSL_RENDER_NO_DIRECT_OIDN"):
        return None
    if not _LOADED:
        found = None
        for path in _candidates():
            if path.is_file():
                try:
                    found = OIDN(ctypes.CDLL(str(path)))
                    break
                except (OSError, AttributeError):
                    continue
        _LOADED.append(found)
    return _LOADED[0]
