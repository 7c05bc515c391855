"""The pixels where a volume's face coincides with a surface or another volume's face
(``CameraRays.ties``): what share of Cycles' samples stops there.

Where the one coincidence is the first surface with a face a mesh volume is left by, and
nothing lies behind it (a fog box resting on the floor), the share is worked out in numpy
(``core.maps.embree_ties``), times the share of exact ties Embree resolves in the volume's
favour, which depends on Embree's tree and so is measured by at most ``PROBE_MAX`` small
probe renders. Every other tie is measured by a Cycles render of the box around those
pixels. Against the oracle: docs/performance.md, "The paper's maps"."""
from __future__ import annotations

import numpy as np

from ...core.maps.camera_rays import CameraRays, fit_ray_model
from ...core.maps.embree_ties import exact_tie_fractions
from ...core.maps.xmap import luminance

#: Work out the ties that can be (True), or have Cycles measure every tie as the X map did
#: before (False: ``bench/bench_xmap_ties.py`` times both).
WORK_OUT = True
#: The Cycles render that measures the ties not worked out here: this many pixel-samples
#: over the box around them, but no fewer than TIE_MIN_SAMPLES and no more than
#: TIE_MAX_SAMPLES per pixel. Each sample stops there or passes, so the answer has binomial
#: noise: at most 0.5 / sqrt(samples) of the difference between the outcomes (0.011 at
#: 2048 samples, 0.06 at 64). A 64x36 frame gets 2048, a 512x288 one 64.
TIE_SAMPLE_BUDGET = 5_000_000
TIE_MIN_SAMPLES = 64
TIE_MAX_SAMPLES = 2048
#: Its sampling seed: not the oracle's 0, so tests against the oracle see independent noise.
TIE_SEED = 1
#: Rays replayed for the exact-tie fractions: enough that each pixel's estimate rests on
#: REPLAY_RAYS rays, its own or pooled from its band in cells of at most 1/POOL_WIDTH of
#: the frame's width (``core.maps.embree_ties``), no more than REPLAY_BUDGET in all, and
#: from REPLAY_MIN to REPLAY_MAX a pixel: 2048 a pixel on a 32x18 frame, 512 on 64x36, 8
#: on 384x216 (0.3 us a ray).
REPLAY_RAYS = 2048
POOL_WIDTH = 24
REPLAY_BUDGET = 2_000_000
REPLAY_MIN, REPLAY_MAX = 2, 2048
#: The probe renders that measure which face wins an exact tie: squares of PROBE_SIDE
#: pixels, PROBE_SAMPLES samples a pixel, placed greedily so that each holds at least
#: PROBE_MIN_PIXELS pixels of as many pairs of triangles as it can (at most PROBE_MAX
#: probes; a pair none holds takes the probes' pooled share). Their pixels' fractions are
#: replayed with PROBE_REPLAY rays each.
PROBE_SIDE = 16
PROBE_SAMPLES = 64
PROBE_MIN_PIXELS = 16
PROBE_MAX = 4
PROBE_REPLAY = 128
_REPLAY_SEED = 2


def resolve_ties(scene, camera, geometry, rays: CameraRays, transmittance: np.ndarray,
                 step_rate: float, tie_samples: int | None = None):
    """What Cycles renders at the tie pixels of ``rays``.

    Parameters
    ----------
    scene : bpy.types.Scene
    camera : CameraModel
    geometry : SceneGeometry
        The scene's triangles (``addon.scene.geometry``), with Cycles' own vertices.
    rays : CameraRays
    transmittance : (h, w, 3) array
        exp(-tau) to the first surface as if no tie let anything through.
    step_rate : float
        Volume step rate of the Cycles renders (the probes' and the measurement's).
    tie_samples : int, optional
        Samples per pixel of the measurement of the other ties (default from the budget).

    Returns
    -------
    passing : (h, w) float array or None
        The share of samples that pass the surface (worked out), 0 elsewhere.
    measured : ((h, w) bool, (h, w, 3)) or None
        The pixels Cycles measured and their transmittance.
    info : dict
    """
    ties = rays.ties
    modelled = (rays.tie_exit >= 0) & ties & WORK_OUT & _replayable(scene, camera, geometry)
    info = {"pixels": int(ties.sum()), "worked_out": 0, "probes": [], "measured": None}
    passing = None
    if modelled.any():
        passing, modelled, details = _work_out(scene, camera, geometry, rays, transmittance,
                                               modelled, step_rate)
        info.update(details)
    measured = None
    rest = ties & ~modelled
    if rest.any():
        measured, info["measured"] = _measure(scene, rays, rest, tie_samples, step_rate)
    info["warning"] = (
        f"{info['pixels']} pixels see a volume's face lying on a surface or on another "
        "volume's face: Cycles renders those with noise (each sample stops there or passes "
        f"by its rounding); the X map worked out {info['worked_out']} of them (small probe "
        f"renders: {len(info['probes'])}) and measured {int(rest.sum())} with a Cycles "
        "render; move such faces apart by a hair to avoid both")
    return passing, measured, info


def _replayable(scene, camera, geometry) -> bool:
    """Whether Cycles' camera rays are the ones ``embree_ties`` replays: a perspective
    camera, no depth of field, no motion blur."""
    data = scene.camera.data
    return (camera.kind == "PERSP" and not data.dof.use_dof
            and not scene.render.use_motion_blur and len(geometry.surfaces.triangles) > 0)


def _work_out(scene, camera, geometry, rays, transmittance, modelled, step_rate):
    model = fit_ray_model(rays)
    if model is None:
        return None, np.zeros_like(modelled), {}
    rows, cols = np.nonzero(modelled)
    surface = geometry.surfaces.exact[geometry.surfaces.triangles[rays.surface_face[rows, cols]]]
    volume = np.full_like(surface, np.nan)
    volume_face = np.full(len(rows), -1, dtype=np.int64)
    keys = list(geometry.volumes)
    exit_of = rays.tie_exit[rows, cols]
    for index in np.unique(exit_of):
        pick = exit_of == index
        tris = geometry.volumes[keys[index]]
        points = (rays.origins[rows[pick], cols[pick]]
                  + rays.directions[rows[pick], cols[pick]] * rays.t_far[rows[pick], cols[pick], None])
        face = _faces_at(tris, points)
        volume[pick] = tris.exact[tris.triangles[face]]
        volume_face[pick] = face + 1_000_000 * index
    usable = np.isfinite(surface).all(axis=(1, 2)) & np.isfinite(volume).all(axis=(1, 2))
    keep = np.zeros_like(modelled)
    keep[rows[usable], cols[usable]] = True
    rows, cols = rows[usable], cols[usable]
    surface, volume, volume_face = surface[usable], volume[usable], volume_face[usable]
    if not len(rows):
        return None, keep, {}
    pair = volume_face * 10_000_000 + rays.surface_face[rows, cols]
    side = max(1, camera.width // POOL_WIDTH)
    per_pixel = int(np.clip(min(REPLAY_RAYS // side ** 2, REPLAY_BUDGET // len(rows)),
                            REPLAY_MIN, REPLAY_MAX))
    fraction = exact_tie_fractions(model, rows, cols, rays.view_axis, camera.clip_start, volume,
                                   surface, pair, per_pixel, np.random.default_rng(_REPLAY_SEED),
                                   pool_side=side)
    stop = luminance(transmittance[rows, cols])
    replay = (model, rays.view_axis, camera.clip_start, volume, surface)
    share, probes, shares = _probe(scene, rays, rows, cols, pair, stop, step_rate, replay)
    passing = np.zeros(rays.shape)
    passing[rows, cols] = np.clip(share * fraction, 0.0, 1.0)
    return passing, keep, {"worked_out": int(len(rows)), "replayed_per_pixel": per_pixel,
                           "probes": probes, "shares": shares}


def _faces_at(tris, points: np.ndarray) -> np.ndarray:
    """Index of the triangle of ``tris`` each point (N, 3) lies on (of those whose plane
    passes nearest to it, one that holds it)."""
    v = tris.vertices[tris.triangles]                            # (T, 3, 3)
    normal = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    if len(v) > 256:
        from mathutils.bvhtree import BVHTree

        tree = BVHTree.FromPolygons(tris.vertices.tolist(), tris.triangles.tolist(),
                                    all_triangles=True)
        return np.array([tree.find_nearest(p)[2] for p in points.tolist()], dtype=np.int64)
    distance = np.abs(points @ normal.T - np.einsum("tk,tk->t", normal, v[:, 0]))   # (N, T)
    best = distance.min(axis=1, keepdims=True)
    score = np.where(distance <= best + 1e-6 * (1.0 + best), 1.0, np.inf)
    for t in np.flatnonzero(np.isfinite(score).any(axis=0)):
        near = np.flatnonzero(np.isfinite(score[:, t]))
        outside = np.zeros(len(near))
        for a, b in ((0, 1), (1, 2), (2, 0)):
            edge = np.cross(v[t, b] - v[t, a], normal[t])        # points out of the triangle
            outside = np.maximum(outside, (points[near] - v[t, a]) @ edge)
        score[near, t] = outside
    return np.argmin(score, axis=1).astype(np.int64)


def _probe_windows(rows, cols, pair, shape):
    """Probe squares (r0, r1, c0, c1) in window coordinates, greedily: each centred on a
    pixel of the largest pair not yet held, where it holds the most pairs."""
    height, width = shape
    values, index, counts = np.unique(pair, return_inverse=True, return_counts=True)
    which = np.full(shape, len(values), dtype=np.int64)          # pair of each pixel
    which[rows, cols] = index.ravel()
    waiting = set(np.argsort(-counts)[:PROBE_MAX * 4].tolist())
    windows = []
    while waiting and len(windows) < PROBE_MAX:
        largest = max(waiting, key=lambda k: counts[k])
        mine = np.flatnonzero(index.ravel() == largest)
        best, best_held = None, set()
        for pick in mine[np.linspace(0, len(mine) - 1, min(len(mine), 48)).astype(int)]:
            r0 = int(np.clip(rows[pick] - PROBE_SIDE // 2, 0, max(0, height - PROBE_SIDE)))
            c0 = int(np.clip(cols[pick] - PROBE_SIDE // 2, 0, max(0, width - PROBE_SIDE)))
            window = (r0, min(height, r0 + PROBE_SIDE), c0, min(width, c0 + PROBE_SIDE))
            held = np.bincount(which[window[0]:window[1], window[2]:window[3]].ravel(),
                               minlength=len(values) + 1)
            held = {k for k in waiting if held[k] >= min(PROBE_MIN_PIXELS, counts[k])}
            if best is None or len(held) > len(best_held):
                best, best_held = window, held
        windows.append(best)
        waiting -= best_held | {largest}
    return windows


def _probe(scene, rays, rows, cols, pair, stop, step_rate, replay):
    """Share of exact ties the volume's face wins, per pixel (its pair's, measured by
    probe renders), and what each probe did."""
    from .transmittance_oracle import render_transmittance

    model, view_axis, clip_start, volume, surface = replay
    num, den = {}, {}
    probes = []
    row0, _, col0, _ = rays.window
    for r0, r1, c0, c1 in _probe_windows(rows, cols, pair, rays.shape):
        window = (row0 + r0, row0 + r1, col0 + c0, col0 + c1)
        rendered, seconds = render_transmittance(scene, samples=PROBE_SAMPLES, step_rate=step_rate,
                                                 window=window, seed=TIE_SEED)
        inside = np.flatnonzero((rows >= r0) & (rows < r1) & (cols >= c0) & (cols < c1))
        fraction = exact_tie_fractions(model, rows[inside], cols[inside], view_axis, clip_start,
                                       volume[inside], surface[inside], pair[inside], PROBE_REPLAY,
                                       np.random.default_rng(_REPLAY_SEED + 1))
        seen = luminance(rendered[rows[inside] - r0, cols[inside] - c0])
        for value in np.unique(pair[inside]):
            mine = pair[inside] == value
            num[value] = num.get(value, 0.0) + float(np.sum(stop[inside][mine] - seen[mine]))
            den[value] = den.get(value, 0.0) + float(np.sum(stop[inside][mine] * fraction[mine]))
        probes.append({"window": list(window), "samples": PROBE_SAMPLES, "seconds": seconds})
    share = {value: float(np.clip(num[value] / den[value], 0.0, 1.0))
             for value in num if den[value] > 1e-3 * max(1.0, abs(num[value]))}
    total = sum(den.values())
    pooled = float(np.clip(sum(num.values()) / total, 0.0, 1.0)) if total > 0 else 1.0
    shares = {"pairs": {str(k): round(v, 4) for k, v in share.items()}, "pooled": round(pooled, 4)}
    return np.array([share.get(value, pooled) for value in pair]), probes, shares


def _measure(scene, rays: CameraRays, pixels: np.ndarray, samples: int | None, step_rate: float):
    """Cycles' own transmittance at ``pixels``: one render of the box around them (all
    media, absorption only, as the oracle), at full resolution."""
    from .transmittance_oracle import render_transmittance

    rows, cols = np.nonzero(pixels)
    r0, r1, c0, c1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
    row0, _, col0, _ = rays.window
    window = (int(row0 + r0), int(row0 + r1), int(col0 + c0), int(col0 + c1))
    if samples is None:
        area = int((r1 - r0) * (c1 - c0))
        samples = int(np.clip(TIE_SAMPLE_BUDGET // area, TIE_MIN_SAMPLES, TIE_MAX_SAMPLES))
    rendered, seconds = render_transmittance(scene, samples=samples, step_rate=step_rate,
                                             window=window, seed=TIE_SEED)
    values = np.ones(rays.shape + (3,), dtype=np.float32)
    values[r0:r1, c0:c1] = rendered
    return (pixels, values), {"pixels": int(pixels.sum()), "window": list(window),
                              "samples": samples, "seconds": seconds}
