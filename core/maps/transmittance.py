"""Optical depth along camera rays: exp(-tau) is the fraction of light that reaches the eye.

tau(ray) integrates the extinction from the clip start to the first surface; media add (the
world's fills every point, each object volume its intervals, as Cycles sums them). A constant
extinction takes the closed form kappa x length; over a window of camera rays any other
medium is integrated on an adaptive grid of node rays (``core.maps.ray_grid_depth``); the few
rays of the light map are marched one by one with the midpoint rule at about the same step
for every interval. Deterministic and per RGB channel throughout."""
from __future__ import annotations

import time

import numpy as np

from ..media.volume_medium import VolumeMedium
from .camera_rays import CameraRays, MediumIntervals, fit_ray_model
from .ray_grid_depth import DEFAULT_TOLERANCE, grid_optical_depth

__all__ = ["DEFAULT_SAMPLES", "DEFAULT_TOLERANCE", "medium_segments", "optical_depth",
           "transmittance_along_rays"]

#: Samples along the long intervals of a medium that varies in space, where rays are
#: marched one by one. The midpoint rule converges as 1/n^2 on smooth fields; on the
#: noise-fog test scene 32 samples left a mean error of 0.002 in X against 128, 64 keeps
#: it near 0.0005.
DEFAULT_SAMPLES = 64
_MIN_SAMPLES = 4
#: Points evaluated at once while marching (bounds memory, not results; chunks of this size
#: keep numpy's temporaries in cache).
_CHUNK_POINTS = 1 << 16


def medium_segments(rays: CameraRays, medium: VolumeMedium, only: np.ndarray | None = None):
    """(ray index, t0, t1) of the pieces of the rays inside ``medium`` (of the rays where
    ``only`` is True, if given)."""
    if medium.kind == "volume_object":
        # A volume object's box is found here, from the rays themselves: its voxels may
        # change (an animated simulation) without the cached rays going stale.
        index, t0, t1 = medium.region.intervals(
            rays.origins.reshape(-1, 3), rays.directions.reshape(-1, 3),
            rays.t_near.ravel(), rays.t_far.ravel())
        if only is not None:
            keep = only.ravel()[index]
            index, t0, t1 = index[keep], t0[keep], t1[keep]
        return index.astype(np.int64), t0, t1
    if medium.kind == "world":
        t0, t1 = rays.t_near.ravel(), rays.t_far.ravel()
        keep = t1 > t0
        if only is not None:
            keep &= only.ravel()
        index = np.flatnonzero(keep)
        return index.astype(np.int64), t0[index].astype(np.float64), t1[index].astype(np.float64)
    intervals = rays.intervals.get(medium.key)
    if intervals is None:
        raise KeyError(f"the ray cache has no intervals for medium {medium.key}")
    index = intervals.ray.astype(np.int64)
    keep = slice(None) if only is None else only.ravel()[index]
    return (index[keep], intervals.t0[keep].astype(np.float64),
            intervals.t1[keep].astype(np.float64))


def optical_depth(rays: CameraRays, media: list[VolumeMedium], samples: int = DEFAULT_SAMPLES,
                  only: np.ndarray | None = None, tolerance: float | None = DEFAULT_TOLERANCE,
                  ) -> tuple[np.ndarray, list[dict]]:
    """Optical depth (h, w, 3) of ``media`` along ``rays`` and what each medium took.

    Parameters
    ----------
    rays : CameraRays
        The Z buffer (with the interval lists of every object medium).
    media : list of VolumeMedium
        Media numpy can evaluate (``medium.evaluable``).
    samples : int
        Midpoint samples per interval for media that vary in space, where the rays are
        marched one by one.
    only : (h, w) bool array, optional
        Integrate these rays only (the others keep tau = 0).
    tolerance : float or None
        Transmittance tolerance of the adaptive ray grid for media that vary in space;
        None marches every ray with the midpoint rule instead.
    """
    count = rays.count
    tau = np.zeros((count, 3), dtype=np.float64)
    report = []
    origins = rays.origins.reshape(-1, 3)
    directions = rays.directions.reshape(-1, 3)
    model, fitted = None, False       # fitted once, when a medium first needs the ray grid
    for medium in media:
        start = time.perf_counter()
        index, t0, t1 = medium_segments(rays, medium, only)
        constant = medium.constant_extinction()
        if constant is not None:
            lengths = np.bincount(index, weights=t1 - t0, minlength=count)
            tau += lengths[:, None] * constant[None, :]
            method = "closed form"
        else:
            if tolerance is not None and not fitted:
                model, fitted = fit_ray_model(rays), True
            if model is not None:
                grid_tau, grid = grid_optical_depth(model, rays.shape, medium.extinction, index,
                                                    t0, t1, tolerance,
                                                    visible=_visible_core(rays, medium))
                tau += grid_tau
                method = grid.describe()
            else:
                counts = _sample_counts(t1 - t0, samples)
                for n in np.unique(counts):
                    pick = counts == n
                    _march(tau, medium, origins, directions, index[pick], t0[pick], t1[pick], int(n))
                method = f"midpoint rule, {_MIN_SAMPLES}..{samples} samples per interval"
        report.append({"medium": medium.key, "method": method, "intervals": int(len(index)),
                       "seconds": time.perf_counter() - start})
    return tau.reshape(rays.shape + (3,)), report


def _visible_core(rays: CameraRays, medium: VolumeMedium) -> np.ndarray | None:
    """For a volume object, the rays that cross the box of its active voxels: the ray
    grid must not let all its node rays pass by that (the field is zero around it)."""
    if medium.kind != "volume_object" or medium.region is None:
        return None
    index, _, _ = medium.region.intervals(rays.origins.reshape(-1, 3), rays.directions.reshape(-1, 3),
                                          rays.t_near.ravel(), rays.t_far.ravel(), core=True)
    visible = np.zeros(rays.count, dtype=bool)
    visible[index] = True
    return visible


def _sample_counts(lengths: np.ndarray, samples: int) -> np.ndarray:
    """Samples per interval: ``samples`` for the long ones, fewer for short ones, powers
    of two so the intervals fall into a few vectorised batches."""
    samples = max(int(samples), 1)
    if len(lengths) == 0:
        return np.zeros(0, dtype=np.int64)
    reference = max(float(np.percentile(lengths, 95)), 1e-12)
    wanted = np.ceil(samples * lengths / reference)
    counts = 2 ** np.ceil(np.log2(np.maximum(wanted, 1.0)))
    return np.clip(counts, min(_MIN_SAMPLES, samples), samples).astype(np.int64)


def _march(tau, medium, origins, directions, index, t0, t1, samples):
    samples = max(int(samples), 1)
    offsets = (np.arange(samples, dtype=np.float64) + 0.5) / samples
    per_chunk = max(1, _CHUNK_POINTS // samples)
    for first in range(0, len(index), per_chunk):
        rows = index[first:first + per_chunk]
        a, b = t0[first:first + per_chunk], t1[first:first + per_chunk]
        ts = a[:, None] + (b - a)[:, None] * offsets[None, :]                  # (k, n)
        points = origins[rows][:, None, :] + directions[rows][:, None, :] * ts[..., None]
        extinction = medium.extinction(points.reshape(-1, 3)).reshape(len(rows), samples, 3)
        segment_tau = extinction.astype(np.float64).mean(axis=1) * (b - a)[:, None]
        for channel in range(3):
            tau[:, channel] += np.bincount(rows, weights=segment_tau[:, channel],
                                           minlength=len(tau))


def transmittance_along_rays(rays: CameraRays, media: list[VolumeMedium], pixels: np.ndarray,
                             distances: np.ndarray, samples: int = DEFAULT_SAMPLES) -> np.ndarray:
    """exp(-tau) per RGB channel from the eye to ``distances`` along chosen cached rays.

    Used for the light map: how much of a lamp's light survives the medium on its way to
    the eye, taken along the camera ray through the lamp's pixel. ``pixels`` are flat
    indices into the rays' window; a distance of ``inf`` (the sun) means the whole ray.
    Where a surface comes first, the ray still stops there (the lamp is hidden anyway).
    """
    pixels = np.asarray(pixels, dtype=np.int64).ravel()
    distances = np.asarray(distances, dtype=np.float64).ravel()
    if pixels.size == 0:
        return np.ones((0, 3))
    t_far = rays.t_far.reshape(-1)[pixels]
    t_far = np.where(np.isfinite(distances), np.minimum(t_far, distances), t_far)
    position = {int(p): i for i, p in enumerate(pixels)}
    intervals = {}
    for key, medium_intervals in rays.intervals.items():
        keep = np.isin(medium_intervals.ray, pixels)
        ray = np.array([position[int(r)] for r in medium_intervals.ray[keep]], dtype=np.int32)
        t0 = medium_intervals.t0[keep]
        t1 = np.minimum(medium_intervals.t1[keep], t_far[ray]) if ray.size else medium_intervals.t1[keep]
        nonempty = t1 > t0
        intervals[key] = MediumIntervals(ray=ray[nonempty], t0=t0[nonempty], t1=t1[nonempty])
    subset = CameraRays(
        size=(1, len(pixels)), window=(0, 1, 0, len(pixels)),
        origins=rays.origins.reshape(-1, 3)[pixels][None], directions=rays.directions.reshape(-1, 3)[pixels][None],
        t_near=rays.t_near.reshape(-1)[pixels][None], t_far=t_far[None],
        hit=np.ones((1, len(pixels)), dtype=bool), view_axis=rays.view_axis, intervals=intervals)
    tau, _ = optical_depth(subset, [m for m in media if m.evaluable], samples, tolerance=None)
    return np.exp(-tau[0])
