"""The X map and Z buffer of a scene's active camera: the addon API of paper section 4.1.

``compute_x_map(scene)`` scans the evaluated scene (reading the grids of OpenVDB volume
objects through geometry nodes), casts the camera rays (or reuses the ones cached next to
the maps when camera and geometry are unchanged), integrates the media numpy can evaluate
and asks Cycles for the transmittance of the others (unsupported shader nodes, grids that
cannot be read), and returns X, Z and what it did.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...core.maps.camera_rays import CACHE_NAME, CameraRays, load_rays, save_rays
from ...core.maps.guided_upsample import upsample_optical_depth
from ...core.maps.transmittance import DEFAULT_SAMPLES, DEFAULT_TOLERANCE
from ...core.maps.xmap import (XMapWarning, luminance, with_ties, x_from_transmittance,
                               x_map_from_cached_rays)
from ...core.media.volume_medium import VolumeMedium
from ..scene.geometry import geometry_digest, scan_scene
from ..scene.probe import camera_model
from .ties import resolve_ties
from .zbuffer import cast_camera_rays

#: Cycles fallback for media numpy cannot evaluate: fraction of the resolution, samples and
#: volume step rate. An absorption-only render that ray-marches is nearly noise-free, so
#: few samples do; a finer step than Cycles' own matters for mesh volumes (whose default
#: step follows the object's size). Measured with the example scenes forced through the
#: fallback, against numpy's X: balls_b (noise fog) 0.6 s, mean error 0.002, 99th
#: percentile 0.012; statue (OpenVDB smoke) 2.5 s, 0.002 and 0.011. Full resolution, 16
#: samples at Cycles' own step took 5.5 s (0.009 and 0.046) and 16.9 s (0.002 and 0.008).
ORACLE_SCALE = 0.5
ORACLE_SAMPLES = 2
ORACLE_STEP_RATE = 0.25
#: ... but never fewer pixels than this on the longer side (small frames render whole).
ORACLE_MIN_SIDE = 256
#: Transmittance below this counts as fully opaque when turning Cycles' answer into tau.
_MIN_TRANSMITTANCE = 1e-6


@dataclass
class XMapResult:
    """The X map and Z buffer plus what the other maps reuse: the rays and the media."""

    x: np.ndarray                   # (H, W) float32 in [0, 1]
    z: np.ndarray                   # (H, W) float32, distance along the ray, inf for sky
    info: dict
    rays: CameraRays
    media: list[VolumeMedium]       # all media; those numpy cannot evaluate came from Cycles
    x_without_minbound: np.ndarray  # (H, W): sky pixels 0 (the paper's value before MinBound)
    cycles_transmittance: np.ndarray | None = None  # (H, W) of the media only Cycles evaluated


def compute_x_map(scene, cache_dir: str | Path | None = None, minbound: bool = True,
                  depsgraph=None, samples: int = DEFAULT_SAMPLES,
                  oracle_scale: float | None = None, oracle_samples: int = ORACLE_SAMPLES,
                  tolerance: float | None = DEFAULT_TOLERANCE, tie_samples: int | None = None,
                  ) -> tuple[np.ndarray, np.ndarray, dict]:
    """X map and Z buffer of the scene's active camera: ``(x, z, info)``.

    See :func:`compute_x_map_detailed` for the parameters.
    """
    result = compute_x_map_detailed(scene, cache_dir, minbound, depsgraph, samples,
                                    oracle_scale, oracle_samples, tolerance, tie_samples)
    return result.x, result.z, result.info


def compute_x_map_detailed(scene, cache_dir: str | Path | None = None, minbound: bool = True,
                           depsgraph=None, samples: int = DEFAULT_SAMPLES,
                           oracle_scale: float | None = None, oracle_samples: int = ORACLE_SAMPLES,
                           tolerance: float | None = DEFAULT_TOLERANCE,
                           tie_samples: int | None = None,
                           ) -> XMapResult:
    """X map and Z buffer of the scene's active camera at the current frame.

    Parameters
    ----------
    scene : bpy.types.Scene
    cache_dir : path, optional
        Folder of the ray cache (``zcache.npz``). When its key (camera and geometry) still
        matches, no ray is cast; the file is (re)written otherwise.
    minbound : bool
        Give sky pixels the smallest X of the pixels with a surface (paper's MinBound).
    depsgraph : optional
        The evaluated depsgraph (default: the context's).
    samples : int
        Midpoint samples per ray interval for heterogeneous media when every ray is
        marched (``tolerance`` None).
    oracle_scale, oracle_samples
        Resolution fraction and samples of the Cycles render used for media numpy cannot
        evaluate (default scale: ``ORACLE_SCALE``, at least ``ORACLE_MIN_SIDE`` pixels).
    tolerance : float or None
        Transmittance tolerance of the adaptive ray grid for heterogeneous media
        (``core.maps.ray_grid_depth``); None marches every pixel's ray (slow, a reference).
    tie_samples : int, optional
        Samples per pixel of the Cycles render that measures the pixels where a volume
        face coincides with a surface or another volume's face (``CameraRays.ties``) and
        ``addon.maps.ties`` cannot work the answer out; default from its budget.

    Returns
    -------
    XMapResult: x (H, W) float32 in [0, 1]; z (H, W) float32, distance along the ray to
    the first surface, inf for sky; info (timings in seconds, cache use, media and how
    each was evaluated, MinBound value, warnings); the rays and media for reuse.
    """
    import bpy

    start = time.perf_counter()
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    camera = camera_model(scene)
    geometry, media = scan_scene(scene, depsgraph)
    timings = {"scan": time.perf_counter() - start}
    key = geometry_digest(camera, geometry)

    tick = time.perf_counter()
    cache_path = Path(cache_dir) / CACHE_NAME if cache_dir is not None else None
    rays = load_rays(cache_path, key) if cache_path is not None else None
    cache_hit = rays is not None
    if rays is None:
        rays = cast_camera_rays(camera, geometry, key=key)
        if cache_path is not None:
            save_rays(cache_path, rays)
    timings["rays"] = time.perf_counter() - tick

    tick = time.perf_counter()
    fallback = [m for m in media if not m.evaluable]
    extra_tau = None
    oracle = None
    if fallback:
        if oracle_scale is None:
            oracle_scale = max(ORACLE_SCALE, min(1.0, ORACLE_MIN_SIDE / max(rays.size)))
        transmittance, seconds = _oracle_transmittance(scene, fallback, oracle_scale, oracle_samples)
        tau = -np.log(np.maximum(transmittance, _MIN_TRANSMITTANCE).astype(np.float64))
        if tau.shape[:2] != rays.size:
            tau = upsample_optical_depth(tau, rays.full_frame(_path_length(rays, fallback), fill=0.0))
        row0, row1, col0, col1 = rays.window
        extra_tau = tau[row0:row1, col0:col1]
        oracle = {"media": [m.key for m in fallback], "seconds": seconds,
                  "scale": oracle_scale, "samples": oracle_samples,
                  "step_rate": ORACLE_STEP_RATE}
    timings["cycles_fallback"] = time.perf_counter() - tick

    tick = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", XMapWarning)
        x, transmittance, details = x_map_from_cached_rays(
            rays, [m for m in media if m.evaluable], minbound=minbound,
            extra_tau=extra_tau, samples=samples, tolerance=tolerance)
    timings["x"] = time.perf_counter() - tick

    tick = time.perf_counter()
    ties = None
    if rays.ties.any():
        passing, measured, ties = resolve_ties(scene, camera, geometry, rays, transmittance,
                                               ORACLE_STEP_RATE, tie_samples)
        transmittance = with_ties(transmittance, passing, measured)
        x, details["minbound"] = x_from_transmittance(rays, transmittance, minbound)
        details["warnings"].append(ties["warning"])
    timings["ties"] = time.perf_counter() - tick
    # Light sources and emissive surfaces need the transmittance without MinBound's fill.
    x_plain = x if not minbound else rays.full_frame(
        np.where(rays.hit, luminance(transmittance), 0.0), fill=0.0)
    for warning in caught:
        warnings.warn(str(warning.message), XMapWarning, stacklevel=2)
    if ties is not None:
        warnings.warn(ties["warning"], XMapWarning, stacklevel=2)
    z = rays.full_frame(rays.distance(), fill=np.inf)
    timings["total"] = time.perf_counter() - start
    info = {
        "frame": scene.frame_current,
        "size": list(rays.size),
        "window": list(rays.window),
        "z_holds": "distance along the camera ray from its origin (eye or ortho plane)",
        "cache": {"path": None if cache_path is None else str(cache_path), "hit": cache_hit,
                  "key": key},
        "media": [m.describe() for m in media],
        "integration": details["media"],
        "cycles_fallback": oracle,
        "ties": ties,
        "minbound": {"enabled": minbound, "value": details["minbound"]},
        "sky_pixels": details["sky_pixels"],
        "samples_per_interval": samples,
        "grid_tolerance": tolerance,
        "warnings": details["warnings"],
        "seconds": timings,
    }
    cycles_part = None if extra_tau is None else rays.full_frame(
        luminance(np.exp(-extra_tau)).astype(np.float32), fill=1.0)
    return XMapResult(x=x, z=z, info=info, rays=rays, media=media, x_without_minbound=x_plain,
                      cycles_transmittance=cycles_part)


def _oracle_transmittance(scene, media, scale, samples):
    from .transmittance_oracle import render_transmittance

    return render_transmittance(scene, include=media, samples=samples, scale=scale,
                                step_rate=ORACLE_STEP_RATE, sky=1.0, resize=False)


def _path_length(rays: CameraRays, media: list[VolumeMedium]) -> np.ndarray:
    """Length (h, w) of each ray inside ``media``: their intervals in the ray cache; the
    whole visible ray for the world and for volume objects (whose smoke fades out
    anyway, so the surfaces behind are the edges that matter)."""
    length = np.zeros(rays.count)
    whole = (rays.t_far - rays.t_near).ravel()
    for medium in media:
        intervals = rays.intervals.get(medium.key)
        if medium.kind == "mesh" and intervals is not None:
            length += intervals.lengths(rays.count)
        else:
            length += whole
    return length.reshape(rays.shape)
