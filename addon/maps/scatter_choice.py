"""``--estimator auto``'s volume sampling per medium (``core.media.scatter_sampling``): the
sampled camera rays auto's step prediction marches, the lights Cycles samples, and each
medium's own method (its material's or world's ``volume_sampling``)."""
from __future__ import annotations

import math

import numpy as np

from ...core.media.ray_marching import ray_pieces
from ...core.media.scatter_sampling import (MAX_PIECE_LENGTH, METHODS, POINTS_PER_PIECE, Lights, Segments,
                                            chosen_methods, segment_moments)
from ..scene.geometry import media_by_carrier, step_setting
from ..scene.light_sampling import emits_sampled_light
from ..scene.probe import find_lights

#: Of the camera rays auto's step prediction samples, the scatter prediction takes every
#: this-many-th: 200 of 600 kept each example scene's ratios within a few per cent of all
#: 600's, for a third of the time (0.15-0.36 s with all).
RAY_STRIDE = 3


def scatter_sampling(scene, depsgraph, rays, media, segments, pixels) -> tuple[dict, dict, dict, float]:
    """({carrier: the method auto sets}, {carrier: {method: predicted noise}}, {carrier: its
    own method}, the share of the media's single-scattered light gathered in homogeneous
    media only): the first and last for the carriers whose method auto changes
    (``chosen_methods``), the predictions for all; from every ``RAY_STRIDE``-th of the
    sampled ``pixels``, each ray's pieces between the media's boundaries taken as the
    segments Cycles integrates one by one."""
    pixels = pixels[::RAY_STRIDE]
    lights = _sampled_lights(scene, depsgraph)
    carriers = media_by_carrier(media)
    if not len(lights.power):
        return {}, {}, {}, 0.0
    origins = rays.origins.reshape(-1, 3)[pixels]
    directions = rays.directions.reshape(-1, 3)[pixels]
    pieces = [(ray, a, min(b, a + MAX_PIECE_LENGTH), active)
              for ray, a, b, active in ray_pieces(rays, media, segments, pixels)]
    if not pieces:
        return {}, {}, {}, 0.0
    # Every piece's quadrature points, then each medium evaluated once at all of its points.
    fraction = (np.arange(POINTS_PER_PIECE) + 0.5) / POINTS_PER_PIECE
    a = np.array([p[1] for p in pieces])[:, None]
    b = np.array([p[2] for p in pieces])[:, None]
    ray_of = np.array([p[0] for p in pieces])
    t = a + fraction[None, :] * (b - a)                                   # (P, K)
    dt = np.broadcast_to((b - a) / POINTS_PER_PIECE, t.shape)
    points = origins[ray_of][:, None, :] + t[..., None] * directions[ray_of][:, None, :]
    sigma_t = np.zeros(t.shape)
    sigma_s = np.zeros(t.shape)
    for m in range(len(media)):
        rows = [i for i, piece in enumerate(pieces) if m in piece[3]]
        if rows:
            where = points[rows].reshape(-1, 3)
            sigma_t[rows] += media[m].extinction(where).mean(axis=1).reshape(len(rows), -1)
            sigma_s[rows] += media[m].extinction(where, "scattering").mean(axis=1).reshape(len(rows), -1)
    keys = list(carriers)
    members = np.array([[any(m in carriers[key] for m in piece[3]) for key in keys] for piece in pieces])
    integral, moments = np.zeros(len(pieces)), np.zeros((len(pieces), len(METHODS)))
    depth, previous_ray = 0.0, None
    for i, ray in enumerate(ray_of):
        if ray != previous_ray:
            depth, previous_ray = 0.0, ray
        integral[i], moments[i] = segment_moments(t[i], dt[i], sigma_t[i], sigma_s[i], points[i],
                                                  lights, depth)
        depth += float((sigma_t[i] * dt[i]).sum())
    homogeneous = np.array([all(media[m].constant_extinction() is not None for m in piece[3]) for piece in pieces])
    share = float(integral[homogeneous].sum() / integral.sum()) if integral.sum() > 0.0 else 0.0
    if not keys:
        return {}, {}, {}, share
    own = {key: step_setting(key)[0].volume_sampling for key in keys}
    methods, noises = chosen_methods(Segments(keys, ray_of, integral, moments, members), own)
    return methods, noises, {key: own[key] for key in methods}, share


def _sampled_lights(scene, depsgraph) -> Lights:
    """The lights equiangular sampling aims at: lamps other than suns (spots with their cone,
    area lights one-sided), and emissive meshes whose emission Cycles samples (at their
    centre, every way)."""
    import bpy

    rows = []
    for light in find_lights(scene, depsgraph):
        if light.kind == "SUN":
            continue
        material = bpy.data.materials.get(light.extra.get("material", "")) if light.kind == "MESH" else None
        if light.kind == "MESH" and not emits_sampled_light(material):
            continue
        cone_cos, smooth = -1.0, 0.0
        if light.kind == "SPOT":
            cone_cos = math.cos(0.5 * light.spot_size)
            smooth = light.spot_blend * (1.0 - cone_cos)
        rows.append((light.location, max(float(light.energy) * max(light.color), 0.0), light.direction,
                     cone_cos, smooth, light.kind == "AREA"))
    if not rows:
        return Lights(np.zeros((0, 3)), np.zeros(0))
    columns = list(zip(*rows))
    return Lights(np.asarray(columns[0], float), np.asarray(columns[1], float), np.asarray(columns[2], float),
                  np.asarray(columns[3], float), np.asarray(columns[4], float), np.asarray(columns[5], bool))
