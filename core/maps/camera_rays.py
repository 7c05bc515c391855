"""The Z buffer: every camera ray with where it starts, where it stops and which media it
crosses, cached on disk so a changed medium never needs the rays cast again.

Distances are measured along the ray from its origin (the eye for a perspective camera,
the point on the camera plane for an orthographic one), in scene units. ``t_near`` is the
clip start (media before it are not seen, as in Cycles), ``t_far`` the first visible
surface or, where nothing is hit, the clip end. Cycles' Depth pass holds *planar* depth
(distance along the view axis); ``planar_depth`` and ``ray_distance`` convert.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..files import atomic_path

#: What z.exr holds where no surface is hit: Cycles' own Depth-pass value for "nothing".
SKY_DEPTH = 1e10
_CACHE_VERSION = 3
#: The ray cache's name in a maps folder (``addon.maps.xmap``).
CACHE_NAME = "zcache.npz"


@dataclass
class MediumIntervals:
    """Where the rays are inside one object's volume: ray index and [t0, t1) per piece."""

    ray: np.ndarray          # (K,) int32, flat index into the window
    t0: np.ndarray           # (K,) float64
    t1: np.ndarray           # (K,) float64

    def lengths(self, count: int) -> np.ndarray:
        """Total distance inside the medium per ray, shape (count,)."""
        return np.bincount(self.ray, weights=self.t1 - self.t0, minlength=count)


@dataclass
class CameraRays:
    """The rays of one camera through the pixel centres of a window of the frame."""

    size: tuple[int, int]                    # (height, width) of the whole frame
    window: tuple[int, int, int, int]        # (row0, row1, col0, col1), half-open
    origins: np.ndarray                      # (h, w, 3)
    directions: np.ndarray                   # (h, w, 3) unit vectors
    t_near: np.ndarray                       # (h, w)
    t_far: np.ndarray                        # (h, w)
    hit: np.ndarray                          # (h, w) bool: a surface stops the ray
    view_axis: np.ndarray                    # (3,) unit vector the camera looks along
    intervals: dict[str, MediumIntervals] = field(default_factory=dict)
    key: str = ""
    #: (h, w) bool: rays along which a volume face coincides with the first surface or
    #: with another object's volume face; Cycles resolves those ties by its rounding
    #: (``core.maps.volume_stack``), which ``addon.maps.ties`` works out or measures.
    ties: np.ndarray | None = None
    #: (h, w) int32: for the tie rays whose one coincidence is the first surface with a face
    #: where they leave a mesh volume (``volume_stack.surface_exit_ties``), that volume's
    #: index in ``intervals``; -1 elsewhere.
    tie_exit: np.ndarray | None = None
    #: (h, w) int32: the surface triangle each ray stops at (index into the scene's surface
    #: triangles), -1 for none or where the scene has no volume to tie with.
    surface_face: np.ndarray | None = None

    def __post_init__(self):
        if self.ties is None:
            self.ties = np.zeros(self.t_far.shape, dtype=bool)
        if self.tie_exit is None:
            self.tie_exit = np.full(self.t_far.shape, -1, dtype=np.int32)
        if self.surface_face is None:
            self.surface_face = np.full(self.t_far.shape, -1, dtype=np.int32)

    @property
    def shape(self) -> tuple[int, int]:
        return self.t_far.shape

    @property
    def count(self) -> int:
        return int(self.t_far.size)

    def distance(self) -> np.ndarray:
        """Distance along each ray to the first surface; inf where the ray hits nothing."""
        return np.where(self.hit, self.t_far, np.inf)

    def planar(self) -> np.ndarray:
        """Planar depth (what Cycles' Depth pass holds) to the first surface; inf for sky."""
        return planar_depth(self.distance(), self.directions, self.view_axis)

    def full_frame(self, values: np.ndarray, fill: float) -> np.ndarray:
        """Place a window-sized map into the whole frame, ``fill`` outside the window."""
        height, width = self.size
        row0, row1, col0, col1 = self.window
        out = np.full((height, width) + values.shape[2:], fill, dtype=np.float32)
        out[row0:row1, col0:col1] = values
        return out


@dataclass(frozen=True)
class RayModel:
    """The rays of a camera at any, also fractional or outside, pixel position of a window.

    For perspective and orthographic cameras both the ray origin and the direction scaled
    to unit length along the view axis are affine functions of the pixel coordinates, so
    three coefficients each (value at pixel (0, 0), change per column, change per row)
    give every ray. Rows and columns count from the window's top-left pixel centre.
    """

    origin: np.ndarray      # (3, 3): value, d/dcol, d/drow
    plane: np.ndarray       # (3, 3): direction / (direction . view axis), same layout

    def rays(self, rows, cols) -> tuple[np.ndarray, np.ndarray]:
        """Origins and unit directions (N, 3) at pixel positions ``rows``, ``cols`` (N,)."""
        rows = np.asarray(rows, dtype=np.float64)[:, None]
        cols = np.asarray(cols, dtype=np.float64)[:, None]
        origins = self.origin[0] + cols * self.origin[1] + rows * self.origin[2]
        plane = self.plane[0] + cols * self.plane[1] + rows * self.plane[2]
        return origins, plane / np.linalg.norm(plane, axis=1, keepdims=True)


def fit_ray_model(rays: CameraRays) -> RayModel | None:
    """The affine :class:`RayModel` of ``rays``, or None when the rays are not such a grid
    (a window narrower than 2 pixels, or rays picked from here and there)."""
    height, width = rays.shape
    if height < 2 or width < 2:
        return None
    cos = rays.directions @ np.asarray(rays.view_axis, dtype=np.float64)
    if not np.all(cos > 1e-9):
        return None
    plane = rays.directions / cos[..., None]

    def affine(field):
        return np.stack([field[0, 0], (field[0, -1] - field[0, 0]) / (width - 1),
                         (field[-1, 0] - field[0, 0]) / (height - 1)])

    model = RayModel(origin=affine(rays.origins), plane=affine(plane))
    rows, cols = np.divmod(np.arange(rays.count), width)
    origins, directions = model.rays(rows, cols)
    scale = max(1.0, float(np.abs(rays.origins).max()))
    if (np.abs(origins - rays.origins.reshape(-1, 3)).max() > 1e-7 * scale
            or np.abs(directions - rays.directions.reshape(-1, 3)).max() > 1e-7):
        return None
    return model


def planar_depth(distance: np.ndarray, directions: np.ndarray, view_axis: np.ndarray) -> np.ndarray:
    """Distance along rays -> depth along the view axis (Cycles' Depth pass)."""
    return distance * (directions @ np.asarray(view_axis, dtype=np.float64))


def ray_distance(planar: np.ndarray, directions: np.ndarray, view_axis: np.ndarray) -> np.ndarray:
    """Depth along the view axis -> distance along the rays (inverse of planar_depth)."""
    return planar / (directions @ np.asarray(view_axis, dtype=np.float64))


def depth_to_exr(distance: np.ndarray) -> np.ndarray:
    """Distances with inf for sky -> the finite float32 array z.exr holds (sky = SKY_DEPTH)."""
    return np.where(np.isfinite(distance), distance, SKY_DEPTH).astype(np.float32)


def depth_from_exr(stored: np.ndarray) -> np.ndarray:
    """z.exr values -> distances with inf for sky."""
    stored = np.asarray(stored, dtype=np.float64)
    return np.where(stored >= SKY_DEPTH * 0.5, np.inf, stored)


# ---------------------------------------------------------------------------------------
# Cache on disk

def save_rays(path: str | os.PathLike, rays: CameraRays) -> Path:
    """Write the rays to an .npz (atomically); ``load_rays`` reads it back."""
    arrays = {
        "version": np.array(_CACHE_VERSION), "key": np.array(rays.key),
        "size": np.array(rays.size), "window": np.array(rays.window),
        "origins": rays.origins, "directions": rays.directions, "t_near": rays.t_near,
        "t_far": rays.t_far, "hit": rays.hit, "view_axis": rays.view_axis,
        "medium_keys": np.array(list(rays.intervals), dtype=str), "ties": rays.ties,
        "tie_exit": rays.tie_exit, "surface_face": rays.surface_face,
    }
    for i, item in enumerate(rays.intervals.values()):
        arrays[f"ray_{i}"], arrays[f"t0_{i}"], arrays[f"t1_{i}"] = item.ray, item.t0, item.t1
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)
    return Path(path)


def load_rays(path: str | os.PathLike, key: str | None = None) -> CameraRays | None:
    """The cached rays at ``path``, or None if missing, unreadable or for another ``key``."""
    path = Path(path)
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            if int(data["version"]) != _CACHE_VERSION:
                return None
            if key is not None and str(data["key"]) != key:
                return None
            intervals = {str(k): MediumIntervals(data[f"ray_{i}"], data[f"t0_{i}"], data[f"t1_{i}"])
                         for i, k in enumerate(data["medium_keys"])}
            return CameraRays(
                size=tuple(int(v) for v in data["size"]),
                window=tuple(int(v) for v in data["window"]),
                origins=data["origins"], directions=data["directions"], t_near=data["t_near"],
                t_far=data["t_far"], hit=data["hit"], view_axis=data["view_axis"],
                intervals=intervals, key=str(data["key"]), ties=data["ties"],
                tie_exit=data["tie_exit"], surface_face=data["surface_face"])
    except (OSError, ValueError, KeyError):
        return None
