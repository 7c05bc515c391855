"""Which device Cycles renders on: the scene's own setting, or the one a farm job names.

``scene.cycles.device`` alone does not reach a GPU: Cycles also needs a compute backend and
its devices enabled in the preferences, and Blender as a Python module starts with backend
NONE (so a GPU scene silently renders on the CPU). ``gpu_backend`` enables every GPU of the
first backend that has one, once per process; the preferences are the process's own (we
never save them). A scene set to GPU on a machine without one renders on the CPU, as in
Blender, with one warning; a farm task told ``--device GPU`` (its host requirements promised
a GPU) is refused instead, since a CPU render there would quietly take many times longer.
"""
from __future__ import annotations

import sys

from ...core.errors import SettingError

DEVICES = ("CPU", "GPU")
#: Tried in this order; OptiX before CUDA (both NVIDIA: OptiX is faster where it works).
GPU_BACKENDS = ("OPTIX", "CUDA", "HIP", "ONEAPI", "METAL")
_found: dict[str, str | None] = {}


def gpu_backend() -> str | None:
    """The compute backend with a GPU: the one chosen in the preferences when it has a GPU in
    use, else the first that has one, every GPU of it enabled; None without one."""
    if "backend" in _found:
        return _found["backend"]
    import bpy

    preferences = bpy.context.preferences.addons["cycles"].preferences
    chosen = preferences.compute_device_type
    if chosen != "NONE":                    # the user's choice in Blender's preferences stands
        preferences.refresh_devices()
        if any(device.use and device.type != "CPU" for device in preferences.devices):
            _found["backend"] = chosen
            return chosen
    backend = None
    for name in GPU_BACKENDS:
        try:
            preferences.compute_device_type = name
        except TypeError:                   # not built for this platform (METAL off macOS)
            continue
        preferences.refresh_devices()
        gpus = [device for device in preferences.devices if device.type != "CPU"]
        if gpus:
            for device in preferences.devices:
                device.use = device.type != "CPU"
            backend = name
            break
    if backend is None:
        preferences.compute_device_type = "NONE"
    _found["backend"] = backend
    return backend


def honour_scene_device(scene) -> str:
    """Render on the scene's device: its GPUs enabled when it asks for GPU and there is one,
    else the CPU (the scene's setting changed, so callers run inside ``preserved_scene``)."""
    if scene.cycles.device == "GPU" and gpu_backend() is None:
        if not _found.get("warned"):
            print(f"xsl-render: warning: scene '{scene.name}' asks for the GPU but Cycles finds "
                  "none on this machine; rendering on the CPU", file=sys.stderr)
            _found["warned"] = "yes"
        scene.cycles.device = "CPU"
    return scene.cycles.device


def use_device(scene, device: str) -> None:
    """Set ``scene`` (an opened copy: a farm task's) to render on ``device``; InputError for
    GPU on a machine without one."""
    if device not in DEVICES:
        raise SettingError(f"{{device.name}} must be one of {', '.join(DEVICES)} "
                           "(got '{device.value}')", device=device)
    if device == "GPU" and gpu_backend() is None:
        raise SettingError("{device}: Cycles finds no GPU on this machine (CUDA, OptiX, HIP, "
                           "oneAPI or Metal); the job's host requirements should have kept this "
                           "task off it", device=device)
    scene.cycles.device = device
