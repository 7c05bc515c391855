"""Which object volumes a camera ray is inside, decided the way Cycles decides it: its volume
stack (``scene/camera.cpp``, ``integrator/intersect_volume_stack.h``, ``volume_stack.h``),
each rule checked against renders (``tests/test_xmap_coincident.py``).

Gate: a camera counts as possibly inside a volume only when the box around its near plane
overlaps some volume's bounding box. Probe: each ray's start then sends a probe straight up
through every face of every object with a volume; a face seen from behind whose material has
a volume puts the object on the stack unless it was entered first. Along the ray, volume
faces enter and leave, surfaces stop it. Ties: a face at exactly the same float distance as
the last hit is skipped, so coincident faces depend on Embree's rounding
(:func:`coincident_events`; ``core.maps.embree_ties`` replays the fog-box-on-the-floor case)."""
from __future__ import annotations

import numpy as np

from ..camera import CameraModel

#: Two events along a ray (volume faces, the first surface) closer than this, relative to
#: max(1, distance), count as coincident. Faces that coincide in a scene's single-precision
#: coordinates lie within about 1e-6 of each other; a wider net costs only a Cycles
#: measurement of pixels whose answer then agrees with ours anyway.
TIE_TOLERANCE = 1e-5


def near_plane_bounds(camera: CameraModel) -> tuple[np.ndarray, np.ndarray]:
    """Cycles' box around the camera's near plane (``Camera::viewplane_bounds_get``):
    the four corners and the centre of the whole frame at the clip start, grown by the
    clip start in every direction (no depth of field)."""
    xmin, xmax, ymin, ymax, _ = camera.view_plane()
    near = camera.clip_start
    xs = np.array([xmin, xmin, xmax, xmax, 0.5 * (xmin + xmax)])
    ys = np.array([ymin, ymax, ymax, ymin, 0.5 * (ymin + ymax)])
    if camera.kind == "PERSP":
        local = np.stack([xs * near, ys * near, np.full(5, -near)], axis=1)
    else:
        local = np.stack([xs, ys, np.full(5, -near)], axis=1)
    matrix = np.asarray(camera.matrix_world, dtype=np.float64)
    axes = matrix[:3, :3] / np.linalg.norm(matrix[:3, :3], axis=0, keepdims=True)
    points = local @ axes.T + matrix[:3, 3]
    return points.min(axis=0) - near, points.max(axis=0) + near


def camera_may_be_inside(camera: CameraModel, bounds: list[tuple[np.ndarray, np.ndarray]]) -> bool:
    """Cycles' gate: does the near-plane box overlap any of these (lo, hi) object boxes?"""
    lo, hi = near_plane_bounds(camera)
    return any(bool(np.all(lo <= b_hi) and np.all(b_lo <= hi)) for b_lo, b_hi in bounds)


def probe_inside(count: int, ray: np.ndarray, t: np.ndarray, front: np.ndarray,
                 has_volume: np.ndarray) -> np.ndarray:
    """Whether each of ``count`` rays starts inside one object, from its probe's hits.

    Parameters
    ----------
    count : int
        Number of rays.
    ray, t, front, has_volume : (K,) arrays
        The probe hits on the object's faces: which ray's probe, distance along +Z,
        whether the face was seen from the front, whether its material has a volume.

    Returns
    -------
    (count,) bool: the first hit that decides, a front face (entered: outside) or a back
    face with a volume (inside), is a back face; rays without one start outside.
    """
    inside = np.zeros(count, dtype=bool)
    decides = front | has_volume
    if not decides.any():
        return inside
    ray, t, front = ray[decides], t[decides], front[decides]
    order = np.lexsort((t, ray))
    ray, front = ray[order], front[order]
    first = np.ones(len(ray), dtype=bool)
    first[1:] = ray[1:] != ray[:-1]
    inside[ray[first]] = ~front[first]
    return inside


def coincident_events(count: int, ray: np.ndarray, t: np.ndarray, owner: np.ndarray,
                      tolerance: float = TIE_TOLERANCE) -> np.ndarray:
    """Rays along which two events of different owners coincide: (count,) bool.

    ``ray``, ``t``, ``owner`` (K,) list every event along every ray: each crossing of an
    object's volume faces (owner: that medium) and the first surface (owner: the medium
    whose volume face it also is, or a number of its own when it has none). Crossings of
    one owner at one distance (a ray through an edge shared by two of its faces) are one
    event, as they are for Cycles.
    """
    ties = np.zeros(count, dtype=bool)
    if len(ray) < 2:
        return ties
    order = np.lexsort((t, ray))
    ray, t, owner = ray[order], t[order], owner[order]
    same_ray = ray[1:] == ray[:-1]
    close = (t[1:] - t[:-1]) <= tolerance * np.maximum(1.0, np.abs(t[1:]))
    ties[ray[1:][same_ray & close & (owner[1:] != owner[:-1])]] = True
    return ties


#: Kinds of events along a ray (``surface_exit_ties``).
SURFACE, ENTERING, LEAVING = 0, 1, 2


def surface_exit_ties(count: int, ray: np.ndarray, t: np.ndarray, owner: np.ndarray,
                      kind: np.ndarray, tolerance: float = TIE_TOLERANCE) -> np.ndarray:
    """Rays whose one coincidence is their first surface with a face where they leave a
    mesh volume (a fog box resting on the floor, seen from inside or through the box).

    Parameters
    ----------
    count : int
        Number of rays.
    ray, t, owner : (K,) arrays
        Every event along every ray, as for :func:`coincident_events`; a surface that is
        also a volume's face has that medium as owner (and is never such a tie).
    kind : (K,) array
        ``SURFACE``, ``ENTERING`` or ``LEAVING`` (a volume face seen from behind).

    Returns
    -------
    (count,) int32: the owner of the face left there, -1 for every other ray (no tie, or
    another one: two volume faces, a face entered on the surface, three events at once).
    """
    medium = np.full(count, -1, dtype=np.int32)
    if len(ray) < 2:
        return medium
    order = np.lexsort((t, ray))
    ray, t, owner, kind = ray[order], t[order], owner[order], kind[order]
    close = ((ray[1:] == ray[:-1]) & (owner[1:] != owner[:-1])
             & ((t[1:] - t[:-1]) <= tolerance * np.maximum(1.0, np.abs(t[1:]))))
    pairs = np.bincount(ray[1:][close], minlength=count)
    first, second = np.flatnonzero(close), np.flatnonzero(close) + 1
    kinds = np.sort(np.stack([kind[first], kind[second]], axis=1), axis=1)
    plain = np.where(kind[first] == SURFACE, owner[first], owner[second]) == -1
    simple = (kinds[:, 0] == SURFACE) & (kinds[:, 1] == LEAVING) & plain
    simple &= pairs[ray[first]] == 1
    medium[ray[first][simple]] = np.where(kind[first] == LEAVING, owner[first],
                                          owner[second])[simple]
    return medium
