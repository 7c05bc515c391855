"""All director maps of one frame: Z and X (4.1), snapshot and S (4.2), L (4.4), XS (4.3)
and XSL (4.5). The Blender side of ``xsl-render maps``, the panel and the renderer.

Data flows one way: the scene is read into plain data (camera, media, lights, rays,
snapshot), the maps are computed by ``core`` functions, and nothing is written back. The
frame and resolution are set inside ``preserved_scene`` and restored afterwards. ``map_steps`` is the same computation as steps, so that the
Blender panel can run it from a modal operator one map at a time.
"""
from __future__ import annotations

import time
import warnings
from typing import Callable

import numpy as np

from ...core.camera import CameraModel
from ...core.maps.director import xs_map, xsl_map
from ...core.maps.files import MapSet
from ...core.maps.light_map import auto_parameters
from ...core.maps.light_map import light_map as glow_map
from ...core.maps.light_raster import emission_footprints, lamp_footprints, merge_footprints
from ...core.maps.options import MapOptions
from ...core.maps.saliency_input import modulated_saliency_map
from ...core.maps.transmittance import transmittance_along_rays
from ...core.media.scene_model import luminance
from ...core.progress import ProgressCallback, Steps, run_steps
from ..scene.probe import camera_model, find_lights
from ..scene.state import preserved_scene
from .snapshot import render_snapshot
from .xmap import XMapResult, compute_x_map_detailed

NO_LIGHTS_WARNING = "no light source shows in the frame: the L map is 0 everywhere"


class MapWarning(UserWarning):
    """Something the user should know about the maps (shown as a one-line warning)."""


def compute_maps(scene, options: MapOptions | None = None, size: tuple[int, int] | None = None,
                 frame: int | None = None, cache_dir=None, progress: ProgressCallback | None = None,
                 depsgraph=None) -> MapSet:
    """Compute every map for the scene's active camera.

    Parameters
    ----------
    scene : bpy.types.Scene (left exactly as it was)
    options : MapOptions (the paper's defaults if None)
    size : (width, height) to compute at instead of the render resolution
    frame : frame to evaluate instead of the current one
    cache_dir : folder for the ray cache (instant X recomputation when only media change)
    progress : called with (fraction done, message); returning True cancels between maps
    """
    return run_steps(map_steps(scene, options, size, frame, cache_dir, depsgraph), progress)


def map_steps(scene, options: MapOptions | None = None, size: tuple[int, int] | None = None,
              frame: int | None = None, cache_dir=None, depsgraph=None) -> Steps[MapSet]:
    """``compute_maps`` as steps (``core.progress``): yields before each map, returns the
    ``MapSet``. Closing it between two steps restores the scene."""
    import bpy

    options = (options or MapOptions()).validate()
    seconds: dict[str, float] = {}
    notes: list[str] = []
    with preserved_scene(scene):
        if frame is not None:
            scene.frame_set(frame)
        if size is not None:
            scene.render.resolution_x, scene.render.resolution_y = size
            scene.render.resolution_percentage = 100
        depsgraph = bpy.context.evaluated_depsgraph_get() if depsgraph is None or frame is not None else depsgraph
        camera = camera_model(scene)

        yield 0.0, "X map and Z buffer"
        tick = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            xres = compute_x_map_detailed(scene, cache_dir=cache_dir, minbound=options.minbound,
                                          depsgraph=depsgraph)
        notes += [str(w.message) for w in caught]
        seconds["x"] = time.perf_counter() - tick

        yield 0.3, "snapshot (direct light, no media)"
        tick = time.perf_counter()
        snapshot = render_snapshot(scene)
        seconds["snapshot"] = time.perf_counter() - tick

        yield 0.6, "S map (saliency)"
        tick = time.perf_counter()
        s = modulated_saliency_map(snapshot.combined[..., :3], xres.x)
        seconds["s"] = time.perf_counter() - tick

        yield 0.75, "L map (lights)"
        tick = time.perf_counter()
        lights = [light for light in find_lights(scene, depsgraph, camera) if light.in_frame]
        l_map, light_info = light_map(camera, lights, xres, snapshot.emission, options)
        if not light_info["lights"]:
            notes.append(NO_LIGHTS_WARNING)
        seconds["l"] = time.perf_counter() - tick

        tick = time.perf_counter()
        xs = xs_map(xres.x, s, options.wx, options.ws, options.xs_op)
        seconds["xs"] = time.perf_counter() - tick
        tick = time.perf_counter()
        xsl = xsl_map(xs, l_map, options.wxs, options.wl, options.xsl_op)
        seconds["xsl"] = time.perf_counter() - tick
        frame_done = scene.frame_current
    yield 1.0, "maps done"
    for note in dict.fromkeys(notes):
        warnings.warn(note, MapWarning, stacklevel=2)
    seconds["total"] = sum(seconds.values())
    info = {
        "scene": scene.name, "frame": frame_done, "size": [camera.width, camera.height],
        "camera": scene.camera.name, "options": options.to_dict(), "seconds": seconds,
        "x": xres.info, "snapshot": {"samples": snapshot.samples, "seed": 0, "bounces": 0,
                                     "volumes": False, "denoised": snapshot.denoised},
        "s": {"model": "Itti, Koch and Niebur 1998 on the tone-mapped snapshot plus 1 - X"},
        "l": light_info, "warnings": list(dict.fromkeys(notes)),
    }
    return MapSet(z=xres.z, x=xres.x, snapshot=snapshot.combined, s=s, l=l_map, xs=xs, xsl=xsl, info=info)


def named_map(scene, name: str, options: MapOptions | None = None,
              size: tuple[int, int] | None = None, cache_dir=None) -> np.ndarray:
    """One director map, "x", "xs" or "xsl", at ``size`` (the render size if None), computing
    no more than it needs: X alone costs a fraction of the snapshot that S and L need."""
    return run_steps(named_map_steps(scene, name, options, size, cache_dir))


def named_map_steps(scene, name: str, options: MapOptions | None = None,
                    size: tuple[int, int] | None = None, cache_dir=None) -> Steps[np.ndarray]:
    """``named_map`` as steps (``core.progress``); ``cache_dir`` keeps the camera rays for
    the next frame, as ``map_steps`` does."""
    if name not in ("x", "xs", "xsl"):
        raise ValueError(f"no director map named {name!r}")
    options = (options or MapOptions()).validate()
    if name != "x":
        maps = yield from map_steps(scene, options, size=size, cache_dir=cache_dir)
        return maps.director(name)
    yield 0.0, "X map and Z buffer"
    with preserved_scene(scene):
        if size is not None:
            scene.render.resolution_x, scene.render.resolution_y = size
            scene.render.resolution_percentage = 100
        x = compute_x_map_detailed(scene, cache_dir=cache_dir, minbound=options.minbound).x
    return np.asarray(x, np.float32)


def light_transmittance(camera: CameraModel, xres: XMapResult) -> Callable[[np.ndarray], np.ndarray]:
    """exp(-tau) from the eye to world points, along the camera ray through each point's pixel."""
    rays = xres.rays
    row0, row1, col0, col1 = rays.window

    def transmittance_to(points: np.ndarray) -> np.ndarray:
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        col, row, _ = camera.project(points)
        rows = np.clip(np.nan_to_num(row, nan=0).astype(int), row0, row1 - 1) - row0
        cols = np.clip(np.nan_to_num(col, nan=0).astype(int), col0, col1 - 1) - col0
        pixels = rows * (col1 - col0) + cols
        distances = np.linalg.norm(points - camera.eye, axis=1)
        distances = np.where(distances >= 0.99 * camera.clip_end, np.inf, distances)
        t = luminance(np.moveaxis(transmittance_along_rays(rays, xres.media, pixels, distances), -1, 0))
        if xres.cycles_transmittance is not None:
            # Media only Cycles could evaluate: their transmittance to the first surface.
            t = t * xres.cycles_transmittance[rows + row0, cols + col0]
        return np.asarray(t, dtype=np.float64)

    return transmittance_to


def light_map(camera: CameraModel, lights, xres: XMapResult, emission: np.ndarray,
              options: MapOptions) -> tuple[np.ndarray, dict]:
    """The L map in [0, 1] and what was drawn, with n and sigma_base fixed or per light (auto)."""
    footprints, drawn = lamp_footprints(camera, lights, xres.z, light_transmittance(camera, xres))
    footprints = merge_footprints(footprints, emission_footprints(camera, emission, xres.x_without_minbound))
    parameters = {}
    for footprint in footprints:
        auto_n, auto_sigma = auto_parameters(footprint.optical_depth)
        parameters[footprint.name] = (
            auto_n if options.light_n is None else int(options.light_n),
            auto_sigma if options.light_sigma_base is None else float(options.light_sigma_base))
    l_map, per_light = glow_map(footprints, (camera.height, camera.width), parameters)
    info = {
        "drawn": [d.__dict__ for d in drawn if d.drawn],
        "emissive_surfaces": sum(1 for f in footprints if f.name.startswith("emissive surface")),
        "not_drawn": [{"name": d.name, "kind": d.kind, "reason": d.reason} for d in drawn if not d.drawn],
        "lights": per_light,
        "sigma_unit": "pixels at 512 px on the longer side",
    }
    return l_map, info
