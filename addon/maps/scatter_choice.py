"""``--estimator auto``'s volume sampling per medium (``core.media.scatter_sampling``): the
sampled camera rays auto's step prediction marches, the lights Cycles samples, and each
medium's own method (its material's or world's ``volume_sampling``)."""
from __future__ import annotations

import numpy as np

from ...core.media.ray_marching import extinction_at, ray_pieces
from ...core.media.scatter_sampling import (MAX_PIECE_LENGTH, POINTS_PER_PIECE, chosen_method,
                                            combined_noise, ray_noise)
from ..scene.geometry import media_by_carrier, step_setting

#: Of the camera rays auto's step prediction samples, the scatter prediction takes every
#: this-many-th: 200 of 600 kept each example scene's ratios within a few per cent of all
#: 600's, for a third of the time (0.15-0.36 s with all).
RAY_STRIDE = 3
from ..scene.light_sampling import emits_sampled_light
from ..scene.probe import find_lights


def scatter_sampling(scene, depsgraph, rays, media, segments, pixels) -> tuple[dict, dict, dict]:
    """({carrier: the method auto sets}, {carrier: {method: predicted noise}}, {carrier: its
    own method}): the first and last for the media whose method auto changes, the predictions
    for all; from every ``RAY_STRIDE``-th of the sampled ``pixels``."""
    pixels = pixels[::RAY_STRIDE]
    positions, power = _sampled_point_lights(scene, depsgraph)
    carriers = media_by_carrier(media)
    if not carriers or not len(power):
        return {}, {}, {}
    origins = rays.origins.reshape(-1, 3)[pixels]
    directions = rays.directions.reshape(-1, 3)[pixels]
    by_ray: dict[int, list] = {}
    for ray, a, b, active in ray_pieces(rays, media, segments, pixels):
        by_ray.setdefault(ray, []).append((a, min(b, a + MAX_PIECE_LENGTH), active))
    # Every ray's quadrature points, then each medium evaluated once at all of its points.
    fraction = (np.arange(POINTS_PER_PIECE) + 0.5) / POINTS_PER_PIECE
    rays_t, rays_dt, rays_points, offsets = [], [], [], [0]
    inside: list[list[np.ndarray]] = [[] for _ in media]
    for ray, pieces in by_ray.items():
        rays_t.append(np.concatenate([a + fraction * (b - a) for a, b, _ in pieces]))
        rays_dt.append(np.concatenate([np.full(POINTS_PER_PIECE, (b - a) / POINTS_PER_PIECE)
                                       for a, b, _ in pieces]))
        rays_points.append(origins[ray] + rays_t[-1][:, None] * directions[ray])
        for p, (_, _, active) in enumerate(pieces):
            for m in active:
                inside[m].append(offsets[-1] + p * POINTS_PER_PIECE + np.arange(POINTS_PER_PIECE))
        offsets.append(offsets[-1] + len(rays_t[-1]))
    if not rays_t:
        return {}, {}, {}
    points = np.concatenate(rays_points)
    own = np.zeros((len(media), len(points)))
    for m, chunks in enumerate(inside):
        if chunks:
            where = np.concatenate(chunks)
            own[m, where] = extinction_at(media, (m,), points[where]).mean(axis=1)
    total = own.sum(axis=0)
    per_ray: dict[str, list] = {key: [] for key in carriers}
    for r, t in enumerate(rays_t):
        span = slice(offsets[r], offsets[r + 1])
        order = np.argsort(t, kind="stable")
        for key, members in carriers.items():
            per_ray[key].append(ray_noise(t[order], rays_dt[r][order], total[span][order],
                                          own[list(members), span].sum(axis=0)[order], points[span][order],
                                          positions, power))
    methods, noises, own = {}, {}, {}
    for key, rows in per_ray.items():
        noises[key] = combined_noise(rows)
        own[key] = step_setting(key)[0].volume_sampling
        method = chosen_method(noises[key], own[key])
        if method is not None:
            methods[key] = method
    return methods, noises, {key: own[key] for key in methods}


def _sampled_point_lights(scene, depsgraph) -> tuple[np.ndarray, np.ndarray]:
    """Positions (N, 3) and powers (N,) of the lights equiangular sampling aims at: lamps
    other than suns, and emissive meshes whose emission Cycles samples (at their centre)."""
    import bpy

    positions, power = [], []
    for light in find_lights(scene, depsgraph):
        if light.kind == "SUN":
            continue
        material = bpy.data.materials.get(light.extra.get("material", "")) if light.kind == "MESH" else None
        if light.kind == "MESH" and not emits_sampled_light(material):
            continue
        positions.append(light.location)
        power.append(max(float(light.energy) * max(light.color), 0.0))
    return np.asarray(positions, np.float64).reshape(-1, 3), np.asarray(power, np.float64)
