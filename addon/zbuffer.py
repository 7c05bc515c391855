"""Cast the camera's rays into the scene: the Z buffer and the media intervals.

One ``mathutils`` BVH tree holds every surface triangle in world space; each pixel-centre
ray is cast from its clip start (Cycles starts camera rays there) up to its clip end, and
stops at the first surface. Each object volume gets its own BVH; rays that reach its
bounding box are walked through its boundary, entering where they cross a face from the
front and leaving where they cross one from behind (Cycles' volume stack does the same
with face orientation), which gives the intervals inside the medium up to the surface.
The first boundary crossing also tells whether the ray starts inside (camera in the fog).
"""
from __future__ import annotations

import numpy as np

from ..core.camera import CameraModel
from ..core.camera_rays import CameraRays, MediumIntervals
from .scene_geometry import SceneGeometry, Triangles

#: Crossings followed per ray and volume before giving up (a closed mesh needs 2 each time
#: the ray passes through it).
_MAX_CROSSINGS = 256


def _bvh(tris: Triangles):
    from mathutils.bvhtree import BVHTree

    return BVHTree.FromPolygons(tris.vertices.tolist(), tris.triangles.tolist(),
                                all_triangles=True)


def cast_camera_rays(camera: CameraModel, geometry: SceneGeometry, key: str = "") -> CameraRays:
    """The Z buffer of ``camera`` over its render window, with every volume's intervals."""
    window = camera.pixel_window()
    origins, directions = camera.pixel_rays(window)
    t_near, t_clip = camera.clip_range(directions)
    shape = t_near.shape
    o = origins.reshape(-1, 3)
    d = directions.reshape(-1, 3)
    near, clip = t_near.ravel(), t_clip.ravel()
    t_far = clip.copy()
    hit = np.zeros(len(near), dtype=bool)
    if len(geometry.surfaces.triangles):
        tree = _bvh(geometry.surfaces)
        starts = (o + d * near[:, None]).tolist()
        dirs = d.tolist()
        spans = (clip - near).tolist()
        cast = tree.ray_cast
        distances = np.array([result[3] if result[3] is not None else np.nan
                              for result in map(cast, starts, dirs, spans)], dtype=np.float64)
        hit = np.isfinite(distances)
        t_far[hit] = near[hit] + distances[hit]
    intervals = {name: _volume_intervals(tris, o, d, near, t_far)
                 for name, tris in geometry.volumes.items()}
    return CameraRays(size=(camera.height, camera.width), window=window, origins=origins,
                      directions=directions, t_near=t_near, t_far=t_far.reshape(shape),
                      hit=hit.reshape(shape), view_axis=camera.view_axis(),
                      intervals=intervals, key=key)


def _segment_hits_box(o, d, t0, t1, lo, hi):
    """Which rays' segments [t0, t1] touch the axis-aligned box [lo, hi] (slab test)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        a = (lo - o) * inv
        b = (hi - o) * inv
    near = np.nanmax(np.minimum(a, b), axis=1)
    far = np.nanmin(np.maximum(a, b), axis=1)
    pad = 1e-6 * np.maximum(1.0, np.abs(far))
    return (near <= far + pad) & (far >= t0 - pad) & (near <= t1 + pad)


def _volume_intervals(tris: Triangles, o, d, near, far) -> MediumIntervals:
    """Pieces [t0, t1) of each ray inside the closed mesh ``tris``, within [near, far)."""
    if not len(tris.triangles):
        return MediumIntervals(np.zeros(0, np.int32), np.zeros(0), np.zeros(0))
    lo, hi = tris.bounds()
    # A ray may start inside the box; its first crossing (possibly beyond ``far``) says
    # whether it starts inside the medium, so test the ray to infinity for candidates.
    candidates = np.flatnonzero(_segment_hits_box(o, d, near, far, lo, hi))
    tree = _bvh(tris)
    cast = tree.ray_cast
    rays, starts, ends = [], [], []
    for i in candidates.tolist():
        origin, direction = o[i], d[i]
        t, end = float(near[i]), float(far[i])
        inside = None
        entered_at = t
        for _ in range(_MAX_CROSSINGS):
            location, normal, _, distance = cast((origin + direction * t).tolist(), direction.tolist())
            if location is None:
                break
            crossing = t + distance
            entering = (normal[0] * direction[0] + normal[1] * direction[1]
                        + normal[2] * direction[2]) < 0.0
            if inside is None:
                inside = not entering
                entered_at = near[i]
            if crossing >= end:
                break
            if entering and not inside:
                inside, entered_at = True, crossing
            elif not entering and inside:
                inside = False
                if crossing > entered_at:
                    rays.append(i), starts.append(entered_at), ends.append(crossing)
            t = crossing + 1e-6 * max(1.0, abs(crossing))
        if inside and end > entered_at:
            rays.append(i), starts.append(entered_at), ends.append(end)
    return MediumIntervals(np.asarray(rays, dtype=np.int32), np.asarray(starts, dtype=np.float64),
                           np.asarray(ends, dtype=np.float64))
