"""What Cycles' biased volume estimator (ray marching) makes of a medium, predicted in numpy.

Cycles renders volumes one of two ways. By default (Blender 5) it uses null scattering:
unbiased, but it needs a majorant octree built at every scene sync and its noise grows with
how much the density varies under the majorant. With ``scene.cycles.volume_biased`` it ray
marches instead (``volume_step_init`` and ``volume_ray_marching_advance`` in Cycles'
``kernel/integrator/shade_volume.h``): every piece of a camera ray between two surface or
volume-boundary hits is cut into steps of one size, the first step ending at a random
fraction ``u`` of it; each step is shaded once, at a second random fraction ``v`` of the
step, and treated as homogeneous. Homogeneous media take the whole piece as one step (exact).

The step (``Object::compute_volume_step_size`` and ``VolumeManager::update_step_size`` in
Cycles' ``scene/``): for an OpenVDB volume object its voxel size in world space, for a mesh
volume a tenth of the mean edge of its world-space bounds, for the world volume the world's
``volume_step_size``; times the material's ``volume_step_rate`` (the world's own step size
has no material rate) and the scene's ``volume_step_rate``. Where several heterogeneous
media overlap the smallest step wins, and no piece takes more than ``volume_max_steps``.

The estimate of exp(-tau) along one ray, exp(-sum sigma(x_i) dt_i), is unbiased in tau
but not in transmittance (Jensen: its mean is above exp(-tau)), and it varies from sample
to sample with the offsets. Both are computed here per ray by averaging Cycles' own
stepping over a lattice of (u, v) offsets, against a fine midpoint integral of the same rays:
``bias`` (mean minus truth) and ``spread`` (one sample's standard deviation).

Auto's prediction is ``core.media.light_paths``, which marches the light's whole path with
the step rules here; ``MarchingPredictor`` (camera rays' transmittance alone) stays as the
check of those rules against Cycles' own transmittance (``tests/test_ray_marching.py``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scene_model import luminance
from .volume_medium import VolumeMedium

#: ``scene.cycles.volume_max_steps``' default.
CYCLES_MAX_STEPS = 1024
#: Cycles' step for a procedural (mesh) volume: this fraction of the mean bounds edge.
PROCEDURAL_STEP_FRACTION = 0.1
#: (u, v) offset pairs the marching is averaged over: a rank-1 lattice, u evenly spaced and
#: v stepping by the golden ratio, so that u + v (where interior steps shade) covers [0, 1)
#: evenly too; a square grid gives u + v few distinct values and aliases on periodic media.
RUNS = 16
_GOLDEN = 0.6180339887498949
#: Midpoint samples per Cycles step, at the finest rate asked for, of the true integral.
REFERENCE_REFINE = 4
#: Points evaluated at once (bounds memory, not results).
_CHUNK_POINTS = 1 << 18


def procedural_step(bounds_lo, bounds_hi) -> float:
    """Cycles' step (rate 1) of a mesh volume with these world-space bounds."""
    edges = np.asarray(bounds_hi, np.float64) - np.asarray(bounds_lo, np.float64)
    return PROCEDURAL_STEP_FRACTION * float(np.mean(edges))


def voxel_step(index_to_world) -> float:
    """Cycles' automatic step (rate 1) of an OpenVDB grid: the smallest world-space
    component of its index-space diagonal (1, 1, 1)."""
    diagonal = np.asarray(index_to_world, np.float64)[:3, :3] @ np.ones(3)
    return float(np.min(np.abs(diagonal)))


@dataclass
class MarchingError:
    """The ray-marching estimate's error on a sample of camera rays, per RGB channel.

    ``pixels`` are flat indices into the rays' window; ``transmittance`` the true
    exp(-tau) to the first surface; ``bias`` the mean estimate minus the truth; ``spread``
    the standard deviation of one sample's estimate; ``step_rate`` the scene rate used (or the
    rates per medium).
    """

    pixels: np.ndarray          # (n,) int64
    transmittance: np.ndarray   # (n, 3)
    bias: np.ndarray            # (n, 3)
    spread: np.ndarray          # (n, 3)
    step_rate: float | tuple       # the scene rate, or one per medium

    def luminance(self, values: np.ndarray) -> np.ndarray:
        """(n,) luminance of (n, 3) per-channel values (``scene_model.luminance``'s weights)."""
        return np.asarray(luminance(np.asarray(values, np.float64).T), np.float64)


def medium_step(medium: VolumeMedium) -> float:
    """The medium's Cycles step at scene rate 1; inf for a homogeneous medium (one step)."""
    if medium.constant_extinction() is not None:
        return math.inf
    return float(medium.extra.get("cycles_step", math.inf))


def sample_pixels(shape: tuple[int, int], count: int) -> np.ndarray:
    """About ``count`` flat pixel indices on a regular grid over a window of ``shape``."""
    height, width = shape
    stride = max(1, int(math.sqrt(height * width / max(count, 1))))
    rows = np.arange(stride // 2, height, stride)
    cols = np.arange(stride // 2, width, stride)
    return (rows[:, None] * width + cols[None, :]).ravel().astype(np.int64)


def ray_pieces(rays, media, segments, pixels):
    """Per sampled ray, its pieces between boundaries with the media active in each:
    lists (ray position, a, b, active-medium tuple)."""
    position = {int(p): i for i, p in enumerate(pixels)}
    bounds: list[list[float]] = [[] for _ in pixels]
    inside: list[list[tuple[int, float, float]]] = [[] for _ in pixels]
    near, far = rays.t_near.ravel()[pixels], rays.t_far.ravel()[pixels]
    for i in range(len(pixels)):
        bounds[i] += [float(near[i]), float(far[i])]
    for m, (index, t0, t1) in enumerate(segments):
        for r, a, b in zip(index, t0, t1):
            i = position.get(int(r))
            if i is not None and b > a:
                bounds[i] += [float(a), float(b)]
                inside[i].append((m, float(a), float(b)))
    pieces = []
    for i in range(len(pixels)):
        edges = np.unique(np.clip(bounds[i], near[i], far[i]))
        for a, b in zip(edges[:-1], edges[1:]):
            middle = 0.5 * (a + b)
            active = tuple(sorted({m for m, lo, hi in inside[i] if lo <= middle <= hi}))
            if active:
                pieces.append((i, float(a), float(b), active))
    return pieces


def extinction_at(media, active, points) -> np.ndarray:
    total = np.zeros((len(points), 3))
    for m in active:
        total += media[m].extinction(points)
    return total


class MarchingPredictor:
    """The error of Cycles' ray marching along sampled camera rays, at any scene step rate.

    The rays' pieces are found once; ``error(rate)`` then marches them as Cycles would at
    that rate, against their true optical depth (cached per rate).

    Parameters
    ----------
    rays : core.maps.camera_rays.CameraRays
        The cast camera rays of the frame.
    media : list of VolumeMedium
        The media numpy can evaluate, each with its Cycles step in ``extra["cycles_step"]``
        (material rate included; absent or inf: marched in one step).
    segments : list of (index, t0, t1)
        Each medium's pieces of the rays (``core.maps.transmittance.medium_segments``).
    pixels : (n,) int array
        Flat indices of the rays to evaluate.
    runs : int
        The number of (u, v) offset pairs (``RUNS``).
    max_steps : int
        Cycles' ``volume_max_steps``.
    """

    def __init__(self, rays, media: list[VolumeMedium], segments, pixels: np.ndarray,
                 runs: int = RUNS, max_steps: int = CYCLES_MAX_STEPS):
        self.media = media
        self.pixels = np.asarray(pixels, np.int64)
        self.origins = rays.origins.reshape(-1, 3)[self.pixels]
        self.directions = rays.directions.reshape(-1, 3)[self.pixels]
        self.steps = [medium_step(m) for m in media]
        self.max_steps = max_steps
        index = np.arange(runs)
        self.u = (index + 0.5) / runs
        self.v = np.mod(0.5 + index * _GOLDEN, 1.0)
        self.pieces = ray_pieces(rays, media, segments, self.pixels)
        # Pieces by the media active in them; pieces in homogeneous media only are marched in
        # one exact step at every rate.
        by_active: dict = {}
        for ray, a, b, active in self.pieces:
            by_active.setdefault(active, []).append((ray, a, b))
        self._by_active = {active: tuple(np.array(column) for column in zip(*pieces))
                           for active, pieces in by_active.items()}
        self.tau_exact = np.zeros((len(self.pixels), 3))
        with _Evaluator(media) as evaluate:
            for active, rows, a, b, count in self._batches(self._rates(1.0)):
                if count == 0:
                    self._integrate(evaluate, self.tau_exact, active, rows, a, b, 1)
        # Per (active media, their step): the marched depths (rays, runs, 3) and the true
        # ones (rays, 3) of those pieces. A rate for one medium changes only the pieces where
        # it sets the step, so per-medium choices re-march only those.
        self._pieces_cache: dict = {}
        self._cache: dict = {}

    @property
    def heterogeneous(self) -> bool:
        """Some piece of some sampled ray is marched in steps (else every rate is exact)."""
        return any(math.isfinite(min(self.steps[m] for m in active)) for *_, active in self.pieces)

    def _rates(self, rate) -> tuple[float, ...]:
        """One scene rate for every medium, or a rate per medium (in ``media``'s order)."""
        if isinstance(rate, (int, float)):
            return (float(rate),) * len(self.media)
        rates = tuple(float(r) for r in rate)
        if len(rates) != len(self.media):
            raise ValueError(f"{len(rates)} step rates for {len(self.media)} media")
        return rates

    def _integrate(self, evaluate, tau, active, rows, a, b, samples: int) -> None:
        """Midpoint rule with ``samples`` points per piece, added into ``tau``."""
        per_chunk = max(1, _CHUNK_POINTS // samples)
        for first in range(0, len(rows), per_chunk):
            part = slice(first, first + per_chunk)
            r, lo, hi = rows[part], a[part], b[part]
            t = lo[:, None] + (np.arange(samples)[None, :] + 0.5) / samples * (hi - lo)[:, None]
            points = self.origins[r][:, None, :] + self.directions[r][:, None, :] * t[..., None]

            def done(sigma, r=r, lo=lo, hi=hi):
                _add(tau, r, sigma.reshape(len(r), samples, 3).mean(axis=1) * (hi - lo)[:, None])
            evaluate(active, points.reshape(-1, 3), done)

    def _step(self, active, rates) -> float:
        """Cycles' step where ``active`` media overlap: the smallest of theirs (inf: homogeneous
        media only, one exact step)."""
        return min(self.steps[m] * rates[m] for m in active)

    def _batches(self, rates, only=None):
        """(active media, rows, a, b, padded step count) of pieces marched alike; a count of
        0 means homogeneous media only (one exact step). ``only``: those active media's."""
        for active, (rays, a_all, b_all) in self._by_active.items():
            if only is not None and active != only:
                continue
            step = self._step(active, rates)
            counts = np.zeros(len(rays), np.int64)
            if math.isfinite(step):
                length = b_all - a_all
                steps = np.maximum(np.minimum(step, length), length / self.max_steps)
                # Steps a piece can take (its first is a fraction u of one), rounded up to
                # even so that the pieces fall into fewer vectorised batches.
                counts = np.ceil(length / steps).astype(np.int64) + 1
                counts += counts % 2
            for count in np.unique(counts):
                chosen = counts == count
                yield (active, rays[chosen].astype(np.int64), a_all[chosen].astype(np.float64),
                       b_all[chosen].astype(np.float64), int(count))

    def _stepped_pieces(self, active, rates):
        """The marched (rays, runs, 3) and true (rays, 3) optical depth of the pieces where
        ``active`` media are, at ``rates`` (cached per step: where media overlap the finest
        step wins, so a coarser rate for another of them changes nothing here)."""
        key = (active, self._step(active, rates))
        if key not in self._pieces_cache:
            runs = len(self.u)
            marched = np.zeros((len(self.pixels), runs, 3))
            true = np.zeros((len(self.pixels), 3))
            with _Evaluator(self.media) as evaluate:
                for _, rows, a, b, count in self._batches(rates, only=active):
                    if count == 0:
                        continue
                    # The truth: a midpoint integral REFERENCE_REFINE times finer than the steps.
                    self._integrate(evaluate, true, active, rows, a, b, max(count * REFERENCE_REFINE, 16))
                    step = np.maximum(np.minimum(self._step(active, rates), b - a), (b - a) / self.max_steps)
                    per_chunk = max(1, _CHUNK_POINTS // (runs * count))
                    for first in range(0, len(rows), per_chunk):
                        part = slice(first, first + per_chunk)
                        self._march(evaluate, marched, active, rows[part], a[part], b[part],
                                    step[part], count)
            self._pieces_cache[key] = (marched, true)
        return self._pieces_cache[key]

    def error(self, rate) -> MarchingError:
        """The marching's bias and one-sample spread in exp(-tau) at scene step ``rate``, or
        at one rate per medium (a sequence in ``media``'s order: a material's own rate)."""
        rates = self._rates(rate)
        if rates not in self._cache:
            runs = len(self.u)
            tau_runs = np.repeat(self.tau_exact[:, None, :], runs, axis=1)
            tau_true = self.tau_exact.copy()
            for active in self._by_active:
                if math.isfinite(self._step(active, rates)):
                    marched, true = self._stepped_pieces(active, rates)
                    tau_runs += marched
                    tau_true += true
            truth = np.exp(-tau_true)
            estimates = np.exp(-tau_runs)
            self._cache[rates] = MarchingError(
                pixels=self.pixels, transmittance=truth, bias=estimates.mean(axis=1) - truth,
                spread=estimates.std(axis=1), step_rate=rate if isinstance(rate, (int, float)) else rates)
        return self._cache[rates]

    def _march(self, evaluate, tau_runs, active, rows, a, b, step, count) -> None:
        """Cycles' stepping over pieces: their optical depth per offset pair added into
        ``tau_runs`` (rays, runs, 3)."""
        u, v = self.u, self.v
        runs, n = len(u), len(a)
        o, d = self.origins[rows], self.directions[rows]
        k = np.arange(count)
        # (n, runs, count): the end of each step, the first one at a fraction u of a step;
        # steps past the piece's end have zero length.
        ends = np.minimum(b[:, None, None], a[:, None, None]
                          + (k[None, None, :] + u[None, :, None]) * step[:, None, None])
        starts = np.concatenate([np.broadcast_to(a[:, None, None], (n, runs, 1)), ends[..., :-1]],
                                axis=2)
        dt = ends - starts
        shade = starts + v[None, :, None] * dt
        points = o[:, None, None, :] + d[:, None, None, :] * shade[..., None]

        def done(sigma):
            _add(tau_runs, rows, (sigma.reshape(n, runs, count, 3) * dt[..., None]).sum(axis=2))
        evaluate(active, points.reshape(-1, 3), done)


class _Evaluator:
    """Evaluates the media's extinction for many small sets of points in few calls.

    A medium's shader costs a fixed few milliseconds per call (a noise texture is hundreds
    of numpy operations) on top of its cost per point, and a rate's pieces fall into dozens
    of batches of a few thousand points (street at rate 0.25: 25). Points asked for with the
    same active media are therefore gathered up to ``_CHUNK_POINTS`` and evaluated at once;
    each set's ``done`` gets its (k, 3) extinction. Leaving the ``with`` block evaluates the
    rest.
    """

    def __init__(self, media):
        self.media = media
        self._waiting: dict = {}

    def __enter__(self):
        return self

    def __call__(self, active, points: np.ndarray, done) -> None:
        waiting = self._waiting.setdefault(active, [])
        waiting.append((points, done))
        if sum(len(p) for p, _ in waiting) >= _CHUNK_POINTS:
            self._flush(active)

    def _flush(self, active) -> None:
        waiting = self._waiting.pop(active, [])
        if not waiting:
            return
        sigma = extinction_at(self.media, active, np.concatenate([p for p, _ in waiting]))
        first = 0
        for points, done in waiting:
            done(sigma[first:first + len(points)])
            first += len(points)

    def __exit__(self, kind, value, traceback):
        if kind is None:
            for active in list(self._waiting):
                self._flush(active)
        return False


def _add(target: np.ndarray, rows: np.ndarray, values: np.ndarray) -> None:
    """target[rows] += values, rows may repeat (a ray crosses several pieces)."""
    np.add.at(target, rows, values)
