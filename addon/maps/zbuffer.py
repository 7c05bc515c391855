"""Cast the camera's rays into the scene: the Z buffer and the media intervals.

One ``mathutils`` BVH holds every surface triangle; each pixel-centre ray runs from the clip
start to its first surface. Each object volume has its own BVH, and rays through its bounding
box are walked through its boundary (entering across a face from the front, leaving from
behind); whether a ray starts inside is decided as Cycles decides it
(``core.maps.volume_stack``). Rays with two events of different objects at the same distance
are marked in ``ties``, where Cycles' answer depends on its rounding (``addon.maps.ties``)."""
from __future__ import annotations

import gc
from contextlib import contextmanager
from itertools import repeat

import numpy as np

from ...core.camera import CameraModel
from ...core.maps.camera_rays import CameraRays, MediumIntervals
from ...core.maps.volume_stack import (ENTERING, LEAVING, SURFACE, TIE_TOLERANCE,
                                       camera_may_be_inside, coincident_events, probe_inside,
                                       surface_exit_ties)
from ..scene.geometry import SceneGeometry, Triangles

#: Crossings followed per ray and volume before giving up (a closed mesh needs 2 each time
#: the ray passes through it).
_MAX_CROSSINGS = 256
_UP = (0.0, 0.0, 1.0)


def _bvh(tris: Triangles):
    from mathutils.bvhtree import BVHTree

    return BVHTree.FromPolygons(tris.vertices.tolist(), tris.triangles.tolist(),
                                all_triangles=True)


def _normals(tris: Triangles) -> np.ndarray:
    v = tris.vertices[tris.triangles]
    return np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])


def cast_camera_rays(camera: CameraModel, geometry: SceneGeometry, key: str = "") -> CameraRays:
    """The Z buffer of ``camera`` over its render window, with every volume's intervals
    and the rays whose events coincide (``CameraRays.ties``, ``tie_exit``)."""
    window = camera.pixel_window()
    origins, directions = camera.pixel_rays(window)
    t_near, t_clip = camera.clip_range(directions)
    shape = t_near.shape
    o = origins.reshape(-1, 3)
    d = directions.reshape(-1, 3)
    near, clip = t_near.ravel(), t_clip.ravel()
    t_far = clip.copy()
    hit = np.zeros(len(near), dtype=bool)
    surface_face = np.full(len(near), -1, dtype=np.int32)
    surface_tree = None
    events = [(np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64), np.zeros(0, np.int8))]
    if len(geometry.surfaces.triangles):
        # The face hit tells a surface that is also a volume's face (glass over water),
        # one event with it, and the triangle of a tie; it costs the casts 5 %, so it is
        # asked for only where there are volumes.
        faces_needed = bool(geometry.volumes)
        surface_tree = _bvh(geometry.surfaces)
        distances, faces = _first_hits(surface_tree, o, d, near, clip, faces_needed)
        hit = np.isfinite(distances)
        t_far[hit] = distances[hit]
        rows = np.flatnonzero(hit)
        if faces_needed:
            surface_face[rows] = faces[rows]
            owner = geometry.surface_medium[faces[rows]]
        else:
            owner = np.full(len(rows), -1)
        events.append((rows, t_far[rows], owner.astype(np.int64), np.full(len(rows), SURFACE, np.int8)))
    gate = camera_may_be_inside(camera, geometry.volume_bounds)
    intervals = {}
    for index, (name, tris) in enumerate(geometry.volumes.items()):
        shell = geometry.shells.get(name, Triangles.empty())
        intervals[name], (rows, ts, kinds) = _volume_intervals(tris, shell, o, d, near, t_far, gate)
        events.append((rows, ts, np.full(len(rows), index, dtype=np.int64), kinds))
    tie_exit = np.full(len(near), -1, dtype=np.int32)
    if intervals:
        ray, t, owner, kind = (np.concatenate(part) for part in zip(*events))
        ties = coincident_events(len(near), ray, t, owner)
        tie_exit = surface_exit_ties(len(near), ray, t, owner, kind)
        if surface_tree is not None:
            behind = _seen_behind(surface_tree, geometry.surfaces, surface_face, tie_exit >= 0,
                                  o, d, t_far, clip)
            tie_exit[behind] = -1
    else:                       # one event per ray at most (its surface): nothing can tie
        ties = np.zeros(len(near), dtype=bool)
    return CameraRays(size=(camera.height, camera.width), window=window, origins=origins,
                      directions=directions, t_near=t_near, t_far=t_far.reshape(shape),
                      hit=hit.reshape(shape), view_axis=camera.view_axis(),
                      intervals=intervals, key=key, ties=ties.reshape(shape),
                      tie_exit=tie_exit.reshape(shape), surface_face=surface_face.reshape(shape))


def _seen_behind(tree, surfaces: Triangles, faces, rays: np.ndarray, o, d, t_far, clip) -> np.ndarray:
    """Which of ``rays`` (a mask) meet another surface behind their first one (triangle
    ``faces``), before the clip end: a sample that passes the first surface sees that one.
    Rays whose surface's plane has every surface vertex on the ray's side (a ground
    plane under the scene) are let off without a cast."""
    behind = np.zeros(len(rays), dtype=bool)
    index = np.flatnonzero(rays)
    if not len(index):
        return behind
    # Per distinct triangle and side of it the rays come from (few: a floor's two).
    face, inverse = np.unique(faces[index], return_inverse=True)
    tri = surfaces.vertices[surfaces.triangles[face]]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    inverse = inverse.ravel()
    side = np.einsum("ij,ij->i", normal[inverse], o[index] - tri[inverse, 0]) > 0
    kinds, which = np.unique(face.astype(np.int64)[inverse] * 2 + side, return_inverse=True)
    points = surfaces.vertices[np.unique(surfaces.triangles)]
    scale = TIE_TOLERANCE * max(1.0, float(np.abs(points).max(initial=0.0)))
    crossed = np.zeros(len(kinds), dtype=bool)
    for k, kind in enumerate(kinds):
        v = surfaces.vertices[surfaces.triangles[kind // 2]]
        n = np.cross(v[1] - v[0], v[2] - v[0])
        n *= (1.0 if kind % 2 else -1.0) / max(np.linalg.norm(n), 1e-300)
        crossed[k] = bool(np.any((points - v[0]) @ n < -scale))
    index = index[crossed[which.ravel()]]
    if not len(index):
        return behind
    skip = 4 * TIE_TOLERANCE * np.maximum(1.0, np.abs(t_far[index]))
    starts = o[index] + d[index] * (t_far[index] + skip)[:, None]
    distance, _ = _cast(tree, starts.tolist(), d[index].tolist(),
                        np.maximum(clip[index] - t_far[index] - skip, 0.0).tolist())
    behind[index] = np.isfinite(distance)
    return behind


@contextmanager
def _gc_paused():
    """Casting creates hundreds of thousands of short-lived tuples; the cyclic garbage
    collector would walk the heap again and again meanwhile (they hold no cycles)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


_MISS = (np.nan, -1.0)


def _cast(tree, starts, directions, spans, faces: bool = False):
    """Distance to the first hit of each ray (NaN for none) and, with ``faces``, the face
    hit (-1; else None); the arguments are lists or iterables of plain tuples, as the BVH
    takes them fastest. Each result is reduced as it comes (the BVH's vectors freed at
    once): holding them all, or a second pass over them, cost the road scene 30 %."""
    with _gc_paused():
        if not faces:
            return np.array([hit[3] if hit[3] is not None else np.nan
                             for hit in map(tree.ray_cast, starts, directions, spans)],
                            dtype=np.float64), None
        flat = []
        extend = flat.extend
        for hit in map(tree.ray_cast, starts, directions, spans):
            extend(_MISS if hit[3] is None else (hit[3], hit[2]))
    pairs = np.array(flat, dtype=np.float64).reshape(-1, 2)
    return pairs[:, 0].copy(), pairs[:, 1].astype(np.int64)


def _first_hits(tree, o, d, near, clip, faces: bool = False):
    """Distance along each ray from its origin to the first surface in [near, clip) (NaN
    where there is none) and, with ``faces``, the face it hits (-1; else None).
    Perspective rays share their origin (the eye): they are cast from there, and only
    the few that meet a surface before the clip start are cast again from it."""
    if np.all(o == o[0]):
        far = float(clip.max())
        distance, face = _cast(tree, repeat(tuple(o[0].tolist())), d.tolist(), repeat(far), faces)
        again = np.flatnonzero(distance < near)
        if len(again):
            starts = (o[again] + d[again] * near[again, None]).tolist()
            later, later_face = _cast(tree, starts, d[again].tolist(),
                                      (clip[again] - near[again]).tolist(), faces)
            distance[again] = near[again] + later
            if faces:
                face[again] = later_face
        missed = ~(distance < clip)
        distance[missed] = np.nan
        if faces:
            face[missed] = -1
        return distance, face
    starts = (o + d * near[:, None]).tolist()
    distance, face = _cast(tree, starts, d.tolist(), (clip - near).tolist(), faces)
    return near + distance, face


def _segment_hits_box(o, d, t0, t1, lo, hi):
    """Which rays' segments [t0, t1] touch the axis-aligned box [lo, hi] (slab test)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        a = (lo - o) * inv
        b = (hi - o) * inv
    near = np.nanmax(np.minimum(a, b), axis=1)
    far = np.nanmin(np.maximum(a, b), axis=1)
    pad = 1e-6 * np.maximum(1.0, np.abs(far))
    with np.errstate(invalid="ignore"):         # inf - inf where a ray never leaves the box
        return (near <= far + pad) & (far >= t0 - pad) & (near <= t1 + pad)


def _convex_crossings(tris: Triangles, normals, o, d):
    """Where rays enter and leave a convex closed mesh with outward faces (a box, a
    sphere: most fog containers), as the intersection of the faces' half-spaces: no ray
    cast at all. (enter, leave) per ray, enter > leave where a ray misses it; None when
    the mesh is not such a solid (then each ray is walked)."""
    length = np.linalg.norm(normals, axis=1)
    keep = length > 1e-12 * max(1.0, float(length.max(initial=0.0)))
    if keep.sum() < 4:
        return None
    n = normals[keep] / length[keep, None]
    anchor = tris.vertices[tris.triangles[keep, 0]]
    offset = np.einsum("ij,ij->i", n, anchor)
    used = tris.vertices[np.unique(tris.triangles)]
    size = max(1.0, float(np.abs(used).max()))
    if np.max(used @ n.T - offset[None, :]) > 1e-6 * size:
        return None                          # some vertex lies outside a face: not convex
    # Every edge shared by exactly two faces: a closed surface, no holes or open edges.
    edges = np.sort(tris.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    if not np.all(counts == 2):
        return None
    facing = d @ n.T                                    # (rays, faces)
    distance = offset[None, :] - o @ n.T                # signed distance of the origin, along n
    with np.errstate(divide="ignore", invalid="ignore"):
        t = distance / facing
    outside = np.any((np.abs(facing) <= 1e-15) & (distance < 0.0), axis=1)
    enter = np.max(np.where(facing < -1e-15, t, -np.inf), axis=1)
    leave = np.min(np.where(facing > 1e-15, t, np.inf), axis=1)
    leave[outside] = -np.inf
    return enter, leave


def _in_window(t, near, far):
    """Crossings that count as events: from the clip start to just past the surface
    (a face that coincides with the surface may round to either side of it)."""
    return (t >= near) & (t <= far + TIE_TOLERANCE * np.maximum(1.0, np.abs(far)))


def _volume_intervals(tris: Triangles, shell: Triangles, o, d, near, far, gate: bool):
    """Pieces [t0, t1) of each ray inside the volume bounded by ``tris``, within
    [near, far), and the crossings of its faces as events (ray index, distance, ENTERING
    or LEAVING by the face's winding).

    ``shell`` holds the object's other faces, which only the camera-in-volume probe sees;
    ``gate`` is Cycles' camera-in-volume gate (False: every ray starts outside). All
    candidate rays advance together, one boundary crossing per round: the casts of a
    round go through ``map`` (no Python loop body per ray) and the bookkeeping is numpy.
    Whether a crossing enters or leaves comes from the winding of the face hit (its
    normal against the ray), as Cycles' volume stack decides it."""
    empty = MediumIntervals(np.zeros(0, np.int32), np.zeros(0), np.zeros(0))
    no_events = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int8))
    if not len(tris.triangles):
        return empty, no_events
    lo, hi = tris.bounds()
    touching = _segment_hits_box(o, d, near, far, lo, hi)
    normals = _normals(tris)
    ray = np.flatnonzero(touching)
    convex = None
    if len(ray) and not len(shell.triangles):
        convex = _convex_crossings(tris, normals, o[ray], d[ray])
    if convex is not None:
        enter, leave = convex
        # A closed convex mesh: the probe says "inside" exactly where the ray starts
        # between entering and leaving; without the gate nothing starts inside, and a
        # ray that starts inside never enters again.
        starts_inside = (enter < near[ray]) & (leave > near[ray])
        keep_start = gate | ~starts_inside
        t0 = np.maximum(enter, near[ray])
        t1 = np.minimum(leave, far[ray])
        keep = keep_start & (t1 > t0)
        through = enter < leave                         # rays that really pass through it
        crossings = np.concatenate([enter[through], leave[through]])
        owner = np.concatenate([ray[through], ray[through]])
        kinds = np.repeat(np.array([ENTERING, LEAVING], np.int8), int(through.sum()))
        counted = _in_window(crossings, near[owner], far[owner]) & np.isfinite(crossings)
        return (MediumIntervals(ray[keep].astype(np.int32), t0[keep], t1[keep]),
                (owner[counted].astype(np.int64), crossings[counted], kinds[counted]))
    # Any mesh: the probe decides where each ray starts, and a ray that starts inside
    # an open mesh may never come near its faces.
    inside = _probe(tris, shell, o + d * near[:, None]) if gate else np.zeros(len(o), dtype=bool)
    ray = np.flatnonzero(touching | inside)
    if not len(ray):
        return empty, no_events
    return _walk(tris, normals, ray, inside[ray], o, d, near, far)


def _probe(tris: Triangles, shell: Triangles, points) -> np.ndarray:
    """Cycles' camera-in-volume probe from each of ``points`` straight up (+Z) through
    every face of the object: (len(points),) bool, see ``core.maps.volume_stack``."""
    inside = np.zeros(len(points), dtype=bool)
    faces = Triangles.concatenate([tris, shell])
    lo, hi = faces.bounds()
    # Only points under the object's box can meet its faces going up.
    below = np.flatnonzero(np.all((points[:, :2] >= lo[:2]) & (points[:, :2] <= hi[:2]), axis=1)
                           & (points[:, 2] <= hi[2]))
    if not len(below):
        return inside
    has_volume = np.arange(len(faces.triangles)) < len(tris.triangles)
    front_of = _normals(faces)[:, 2] < 0.0            # seen from below: the normal points down
    cast = _bvh(faces).ray_cast
    t = np.zeros(len(below))
    found_ray, found_t, found_front, found_volume = [], [], [], []
    active = np.arange(len(below))
    for _ in range(_MAX_CROSSINGS):
        if not len(active):
            break
        starts = points[below[active]] + np.array(_UP) * t[active, None]
        with _gc_paused():
            hits = list(map(cast, starts.tolist(), repeat(_UP)))
        face = np.array([-1 if h[2] is None else h[2] for h in hits], dtype=np.int64)
        distance = np.array([0.0 if h[3] is None else h[3] for h in hits], dtype=np.float64)
        got = face >= 0
        rows, face, at = active[got], face[got], t[active[got]] + distance[got]
        found_ray.append(rows)
        found_t.append(at)
        found_front.append(front_of[face])
        found_volume.append(has_volume[face])
        # A front face (entered) or a back face with a volume decides; go on past others.
        undecided = ~front_of[face] & ~has_volume[face]
        t[rows] = at + 1e-6 * np.maximum(1.0, np.abs(at))
        active = rows[undecided]
    decided = probe_inside(len(below), np.concatenate(found_ray), np.concatenate(found_t),
                           np.concatenate(found_front), np.concatenate(found_volume))
    inside[below] = decided
    return inside


def _walk(tris: Triangles, normals, ray, inside, o, d, near, far):
    """Intervals and events of ``ray`` through a mesh volume, crossing by crossing, each
    ray starting ``inside`` or not."""
    cast = _bvh(tris).ray_cast
    t = near[ray].astype(np.float64)
    end = far[ray].astype(np.float64)
    inside = inside.copy()
    entered_at = t.copy()
    found_ray, found_t0, found_t1 = [], [], []
    event_ray, event_t, event_kind = [], [], []
    active = np.arange(len(ray))
    for _ in range(_MAX_CROSSINGS):
        if not len(active):
            break
        rows = ray[active]
        starts = o[rows] + d[rows] * t[active, None]
        with _gc_paused():
            hits = list(map(cast, starts.tolist(), d[rows].tolist()))
        face = np.array([-1 if h[2] is None else h[2] for h in hits], dtype=np.int64)
        distance = np.array([np.nan if h[3] is None else h[3] for h in hits], dtype=np.float64)
        missed = face < 0
        crossing = t[active] + np.where(missed, 0.0, distance)
        entering = np.einsum("ij,ij->i", normals[np.maximum(face, 0)], d[rows]) < 0.0
        counted = ~missed & _in_window(crossing, near[rows], end[active])
        event_ray.append(rows[counted])
        event_t.append(crossing[counted])
        event_kind.append(np.where(entering[counted], ENTERING, LEAVING).astype(np.int8))
        go = ~missed & (crossing < end[active])
        now_inside = inside[active]
        enter = go & entering & ~now_inside
        leave = go & ~entering & now_inside
        inside[active[enter]] = True
        entered_at[active[enter]] = crossing[enter]
        inside[active[leave]] = False
        emit = leave & (crossing > entered_at[active])
        found_ray.append(rows[emit])
        found_t0.append(entered_at[active[emit]])
        found_t1.append(crossing[emit])
        t[active[go]] = crossing[go] + 1e-6 * np.maximum(1.0, np.abs(crossing[go]))
        active = active[go]
    last = inside & (end > entered_at)
    found_ray.append(ray[last])
    found_t0.append(entered_at[last])
    found_t1.append(end[last])
    rays_out = np.concatenate(found_ray).astype(np.int32)
    t0, t1 = np.concatenate(found_t0), np.concatenate(found_t1)
    order = np.lexsort((t0, rays_out))
    return (MediumIntervals(rays_out[order], t0[order], t1[order]),
            (np.concatenate(event_ray).astype(np.int64), np.concatenate(event_t),
             np.concatenate(event_kind)))
