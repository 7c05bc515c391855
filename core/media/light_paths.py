"""The picture's error of Cycles' ray marching, along the light's whole path.

Light reaches the eye from a medium along two legs, and ray marching steps both (Cycles'
``shade_volume.h``): the camera ray (steps offset by a random fraction) and the shadow ray
from each scattering point to a light (steps from its start, shaded at a random fraction).
exp(-sum sigma dt) overestimates exp(-tau) on average (Jensen), so in a dense, sun-lit
medium the camera ray's transmittance is near 0 and says little, while the shadow rays'
make the medium too bright. Per sampled camera ray this module computes single-scattered
light, the medium's emission and the first surface's direct light, once exactly (a fine
grid along every ray) and once as marched at a step rate (Cycles' stepping averaged over a
lattice of offsets, the density read from the same grid), and returns the difference
relative to the pixel, under every lighting the scene leaves open (``ImageError``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scene_model import luminance

#: Points along each camera ray where shadow rays start (``_scatter_points``): its entry
#: into the media and quantiles of where distance samples scatter, exactly and marched.
SCATTER_POINTS = 12
#: Points a step's scattering is spread over (quantiles of its exponential).
STEP_QUANTILES = 6
#: Offset pairs (u, v) a camera ray is marched with, and shade offsets of a shadow ray.
CAMERA_RUNS, SHADOW_RUNS = 16, 8
_GOLDEN = 0.6180339887498949
#: Grid cells per step of the finest rate asked for, and the most cells one piece of a
#: camera or a shadow ray is given (bounds the shader evaluations, not the result).
CELLS_PER_STEP = 2
MAX_CAMERA_CELLS, MAX_SHADOW_CELLS = 256, 48
#: A surface's reflectance is not known: the error is taken at the worst of black and this
#: bright a diffuse surface (the pixel's value moves either way with it).
BRIGHT_SURFACE = 0.8
#: Pixels darker than this share of the frame's bright level (its 90th percentile) count
#: as that dark: a relative error in a near-black pixel is not seen.
DARK_SHARE = 0.05
#: Directions a world light is sampled in (cube corners: four up, four down).
WORLD_DIRECTIONS = np.array([[x, y, z] for z in (1, -1) for y in (1, -1) for x in (1, -1)],
                            np.float64) / math.sqrt(3.0)
#: A light of known strength bringing a point less than this share of the known lights'
#: light there is left out at that point (``_ShadowRays``): leaving it out lowers the pixel's
#: value, not its error, so the relative error left is the larger.
FAINT_LIGHT = 0.02
#: Length of a shadow ray toward a distant light (a sun, the sky), in scene units.
DISTANT = 1e6
_ISOTROPIC = 1.0 / (4.0 * math.pi)
#: Light below this is none (its logarithm is interpolated).
_DARKEST = 1e-30


@dataclass
class Emitters:
    """The light a point receives before media and surfaces block it.

    Local lights: ``positions`` (L, 3), ``intensity`` (L, 3) radiant intensity along
    ``axes`` (L, 3), ``cone_cos`` (L,) a spot's half-angle cosine (-1: every way),
    ``cone_smooth`` (L,) the width of its soft edge in cosine, ``one_sided`` (L,) an area
    light's cosine falloff. Distant lights (suns, a world sampled in ``WORLD_DIRECTIONS``):
    ``toward`` (D, 3) unit directions to the light, ``irradiance`` (D, 3). ``group`` (L + D,)
    is 0 for a light of known strength and 1 for a world whose radiance is not known (its
    directions given irradiance 4 pi / 8 each, as if its radiance were 1): the error is
    then bounded over its unknown scale. ``background`` (3,) is what a ray that meets
    nothing sees (the known world's radiance; with an unknown world, 1 in group 1).
    """

    positions: np.ndarray
    intensity: np.ndarray
    axes: np.ndarray
    cone_cos: np.ndarray
    cone_smooth: np.ndarray
    one_sided: np.ndarray
    toward: np.ndarray
    irradiance: np.ndarray
    group: np.ndarray
    background: np.ndarray

    @property
    def count(self) -> int:
        return len(self.positions) + len(self.toward)

    def shadow_rays(self, points: np.ndarray):
        """For every light and point: (direction (L + D, n, 3), length (L + D, n), irradiance
        (L + D, n, 3) arriving unblocked, the share a diffuse surface facing the light gets
        of it being its cosine)."""
        n = len(points)
        local = self.positions[:, None, :] - points[None, :, :]                     # (L, n, 3)
        distance = np.maximum(np.linalg.norm(local, axis=2), 1e-6)
        direction = local / distance[..., None]
        out = -direction
        cosine = np.einsum("lnk,lk->ln", out, self.axes)
        spread = np.ones_like(distance)
        spread = np.where(self.one_sided[:, None], np.maximum(cosine, 0.0), spread)
        cone = self.cone_cos[:, None] > -1.0
        edge = np.clip((cosine - self.cone_cos[:, None]) / np.maximum(self.cone_smooth[:, None], 1e-6), 0.0, 1.0)
        spread = np.where(cone, spread * np.where(cosine > self.cone_cos[:, None],
                                                  edge * edge * (3.0 - 2.0 * edge), 0.0), spread)
        local_e = self.intensity[:, None, :] * (spread / distance ** 2)[..., None]
        far_dir = np.broadcast_to(self.toward[:, None, :], (len(self.toward), n, 3))
        far_e = np.broadcast_to(self.irradiance[:, None, :], (len(self.toward), n, 3))
        return (np.concatenate([direction, far_dir]),
                np.concatenate([distance, np.full((len(self.toward), n), DISTANT)]),
                np.concatenate([local_e, far_e]))


@dataclass
class Pieces:
    """Pieces of rays between media boundaries: ray index, [a, b) and the media active."""

    ray: np.ndarray
    a: np.ndarray
    b: np.ndarray
    active: list

    @staticmethod
    def split(near: np.ndarray, far: np.ndarray, segments) -> "Pieces":
        """The pieces of rays [near, far) inside media; ``segments`` per medium: (ray index,
        t0, t1) of where each ray is inside it. Sorted by ray, then along it."""
        rows, lo, hi, owner = [], [], [], []
        for m, (index, t0, t1) in enumerate(segments):
            index = np.asarray(index, np.int64)
            t0 = np.maximum(np.asarray(t0, np.float64), near[index])
            t1 = np.minimum(np.asarray(t1, np.float64), far[index])
            keep = t1 > t0
            rows.append(index[keep]), lo.append(t0[keep]), hi.append(t1[keep])
            owner.append(np.full(int(keep.sum()), m))
        if not rows or not sum(len(r) for r in rows):
            return Pieces(np.zeros(0, np.int64), np.zeros(0), np.zeros(0), [])
        rows, lo, hi, owner = (np.concatenate(x) for x in (rows, lo, hi, owner))
        order = np.lexsort((lo, rows))
        rows, lo, hi, owner = rows[order], lo[order], hi[order], owner[order]
        # Rays inside one medium at a time (most): their segments are the pieces.
        alone = np.ones(len(rows), bool)
        same = rows[1:] == rows[:-1]
        overlap = same & (lo[1:] < hi[:-1])
        alone[1:] &= ~overlap
        alone[:-1] &= ~overlap
        mixed_rays = np.unique(rows[~alone])
        simple = ~np.isin(rows, mixed_rays)
        out = [(rows[simple], lo[simple], hi[simple], [(int(m),) for m in owner[simple]])]
        for ray in mixed_rays:
            chosen = np.flatnonzero(rows == ray)
            edges = np.unique(np.concatenate([lo[chosen], hi[chosen]]))
            piece_ray, piece_a, piece_b, piece_active = [], [], [], []
            for a, b in zip(edges[:-1], edges[1:]):
                middle = 0.5 * (a + b)
                active = tuple(sorted({int(owner[i]) for i in chosen if lo[i] <= middle <= hi[i]}))
                if active:
                    piece_ray.append(ray), piece_a.append(a), piece_b.append(b), piece_active.append(active)
            out.append((np.asarray(piece_ray, np.int64), np.asarray(piece_a), np.asarray(piece_b), piece_active))
        ray = np.concatenate([o[0] for o in out]).astype(np.int64)
        a = np.concatenate([o[1] for o in out]).astype(np.float64)
        b = np.concatenate([o[2] for o in out]).astype(np.float64)
        active = [x for o in out for x in o[3]]
        order = np.lexsort((a, ray))
        return Pieces(ray[order], a[order], b[order], [active[i] for i in order])

    def __len__(self) -> int:
        return len(self.ray)


class _Grid:
    """The media's coefficients on a grid of cells along pieces of rays (cell midpoints),
    and their value anywhere along a piece, interpolated between the midpoints."""

    def __init__(self, pieces: Pieces, origins, directions, media, steps, cell: float,
                 most: int, parts: int):
        self.pieces = pieces
        length = pieces.b - pieces.a
        finest = np.array([min(steps[m] for m in active) for active in pieces.active]) if len(pieces) else np.zeros(0)
        count = np.where(np.isfinite(finest), np.ceil(length / np.maximum(finest * cell, 1e-9)), 1)
        self.count = np.clip(count, 1, most).astype(np.int64)
        self.width = length / self.count
        self.offset = np.concatenate([[0], np.cumsum(self.count)[:-1]]).astype(np.int64)
        total = int(self.count.sum())
        piece = np.repeat(np.arange(len(pieces)), self.count)
        local = np.arange(total) - self.offset[piece]
        t = pieces.a[piece] + (local + 0.5) * self.width[piece]
        points = origins[pieces.ray[piece]] + directions[pieces.ray[piece]] * t[:, None]
        # Shadow rays (``parts`` 1) keep the extinction's luminance only: a third of the work.
        self.values = np.zeros((parts, total, 3 if parts > 1 else 1))
        groups: dict = {}
        for p, active in enumerate(pieces.active):
            groups.setdefault(active, []).append(p)
        for active, members in groups.items():
            cells = np.concatenate([np.arange(self.offset[p], self.offset[p] + self.count[p]) for p in members])
            for m in active:
                if parts == 1:
                    self.values[0, cells, 0] += luminance(media[m].extinction(points[cells]).T)
                else:
                    for k, field in enumerate(media[m].coefficients(points[cells])):
                        self.values[k, cells] += field
        self.cell_piece = piece
        self.cell_t = t

    def at(self, part: int, piece: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The ``part`` (0 extinction, 1 scattering, 2 emission) at distances ``t`` of pieces
        ``piece`` (broadcast together), (..., 3)."""
        a, width, count = self.pieces.a[piece], self.width[piece], self.count[piece]
        x = (t - a) / width - 0.5
        j0 = np.clip(np.floor(x), 0, count - 1).astype(np.int64)
        j1 = np.minimum(j0 + 1, count - 1)
        f = np.clip(x - j0, 0.0, 1.0)[..., None]
        base = self.offset[piece]
        values = self.values[part]
        return values[base + j0] * (1.0 - f) + values[base + j1] * f


def _steps(a, b, step, u, v, max_steps):
    """Cycles' steps over pieces [a, b) with step ``step``: (start, length, shading point)
    arrays of shape (pieces, runs, count), the first step ending at a fraction ``u`` (runs,)
    of a step (1: shadow rays), each shaded at a fraction ``v`` (runs,) of it."""
    length = b - a
    step = np.maximum(np.minimum(step, length), length / max_steps)
    count = int(np.max(np.ceil(length / step))) + 1 if len(a) else 1
    k = np.arange(count)
    ends = np.minimum(b[:, None, None], a[:, None, None] + (k[None, None, :] + u[None, :, None]) * step[:, None, None])
    starts = np.concatenate([np.broadcast_to(a[:, None, None], ends.shape[:2] + (1,)), ends[..., :-1]], axis=2)
    dt = np.maximum(ends - starts, 0.0)
    return starts, dt, starts + v[None, :, None] * dt


def _batches(pieces: Pieces, steps, rates, max_steps: int, most: int = 1 << 14):
    """Pieces marched alike at ``rates``: (indices, step) with step inf for homogeneous
    media only (one exact step), grouped by their step count so that arrays stay small
    (at most ``most`` steps of pieces a batch)."""
    step = np.array([min(steps[m] * rates[m] for m in active) for active in pieces.active]) \
        if len(pieces) else np.zeros(0)
    finite = np.isfinite(step)
    length = pieces.b - pieces.a
    count = np.where(finite, np.ceil(length / np.maximum(np.where(finite, step, 1.0),
                                                         length / max_steps)), 0).astype(np.int64)
    # Powers of two of the count: few batches, each padded at most twice.
    bucket = np.where(count > 0, np.ceil(np.log2(np.maximum(count, 1))), -1)
    for value in np.unique(bucket):
        chosen = np.flatnonzero(bucket == value)
        size = max(1, most // (2 ** max(int(value), 0) + 1))
        for first in range(0, len(chosen), size):
            part = chosen[first:first + size]
            yield part, step[part]


@dataclass
class ImageError:
    """Per sampled pixel: its predicted value ``value`` (luminance, exact), the error of
    the marched estimate ``error`` (its mean minus the truth, luminance) and ``relative``,
    the worst over the scene's open lighting of |error| / max(value, dark floor); ``weight``
    the share of the frame each stands for."""

    value: np.ndarray
    error: np.ndarray
    relative: np.ndarray
    weight: np.ndarray

    def visible(self, q: float = 95.0) -> float:
        """The ``q``-th percentile of the relative error over the pixels ray marching changes
        (not over the frame: a small cloud made far too bright is a few per cent of the frame,
        beyond its 95th percentile, and still most of its MSE)."""
        return weighted_percentile(self.relative, self.weight, q)


def weighted_percentile(values: np.ndarray, weights: np.ndarray, q: float) -> float:
    """The ``q``-th percentile of ``values`` with ``weights``."""
    total = float(np.sum(weights))
    if total <= 0.0 or not len(values):
        return 0.0
    order = np.argsort(values)
    index = min(int(np.searchsorted(np.cumsum(weights[order]), q / 100.0 * total)), len(order) - 1)
    return float(values[order[index]])


class LightPathPredictor:
    """Single scattering, emission and direct surface light along sampled camera rays,
    exact and as Cycles ray-marches them at any step rates (``error``).

    Parameters
    ----------
    origins, directions : (n, 3) arrays
        The sampled camera rays.
    near, far : (n,) arrays
        Where each starts (the clip start) and stops (its first surface or the clip end).
    normals : (n, 3) array
        The first surface's normal (zeros where a ray meets none).
    weight : (n,) array
        The share of the frame each ray stands for.
    media : list of VolumeMedium
        The media, each with its Cycles step at rate 1 in ``extra["cycles_step"]`` (inf or
        absent: homogeneous, one exact step).
    segments : list of (index, t0, t1)
        Each medium's pieces of the camera rays.
    emitters : Emitters
    cast : callable
        ``cast(origins, directions, lengths) -> (visible, segments)``: whether a surface
        blocks each ray before its length, and each medium's pieces of the rays.
    rates : sequence of float
        The step rates that will be asked for: the grid follows the finest, and the light
        is known where each scatters (``_scatter_points``).
    max_steps : int
        Cycles' ``volume_max_steps``.
    clip : float
        Pixel values the display shows as white (inf: none); an error there is not seen.
    """

    def __init__(self, origins, directions, near, far, normals, weight, media, segments,
                 emitters: Emitters, cast, rates=(4.0, 2.0, 1.0, 0.5, 0.25), max_steps: int = 1024,
                 clip: float = math.inf):
        self.media, self.emitters, self.max_steps, self.clip = media, emitters, max_steps, clip
        self.origins, self.directions = np.asarray(origins, np.float64), np.asarray(directions, np.float64)
        self.near, self.far = np.asarray(near, np.float64), np.asarray(far, np.float64)
        self.weight = np.asarray(weight, np.float64)
        n = len(self.near)
        self.hit = np.linalg.norm(normals, axis=1) > 0
        self.steps = [float(m.extra.get("cycles_step", math.inf))
                      if m.constant_extinction() is None else math.inf for m in media]
        self.camera = Pieces.split(self.near, self.far, segments)
        finest = min(rates)
        self.grid = _Grid(self.camera, self.origins, self.directions, media, self.steps,
                          finest / CELLS_PER_STEP, MAX_CAMERA_CELLS, 3)
        # Shadow rays: from each ray's scatter points, and from its surface.
        points = self._scatter_points(rates)                  # (n, K, 3)
        normal = np.asarray(normals, np.float64)
        normal = normal * np.where(np.einsum("ij,ij->i", normal, self.directions) > 0, -1.0, 1.0)[:, None]
        # Shadow rays leave a surface from just above it (toward the camera's side).
        lift = 1e-4 * np.maximum(1.0, np.abs(self.far))[:, None]
        surface = self.origins + self.directions * self.far[:, None] + normal * lift
        starts = np.concatenate([points.reshape(-1, 3), surface[self.hit]])
        self.shadow = _ShadowRays(starts, emitters, media, self.steps, cast, finest, max_steps)
        k = SCATTER_POINTS
        self._scatter_rows = slice(0, n * k)
        self._surface_rows = slice(n * k, n * k + int(self.hit.sum()))
        # The surface's cosine toward each light (0 for the sky).
        direction = self.shadow.direction[:, self._surface_rows]              # (lights, h, 3)
        self._cosine = np.maximum(np.einsum("lhk,hk->lh", direction, normal[self.hit]), 0.0)
        self._cache: dict = {}
        self.truth = self._pixels(self.shadow.exact, None)

    def _scatter_points(self, rates) -> np.ndarray:
        """(n, K, 3): where each camera ray gathers light, sorted along it: its entry into the
        media, then the quantiles (at the grid's cells) of where distance samples scatter
        exactly, of that weighted by the lights' unshadowed light (a lamp's glow peaks
        where the ray passes it), and of where they scatter as marched at each of
        ``rates``, mixed evenly. The light is known there and interpolated between
        (``_interpolate_light``): a coarse step scatters both before the first dense part of
        a medium (in light not yet shadowed) and far behind it (where its shading points
        missed it), which the exact estimate never does."""
        n, grid = len(self.near), self.grid
        t = np.repeat(self.near[:, None], SCATTER_POINTS, axis=1)
        entry = np.searchsorted(self.camera.ray, np.arange(n))
        has = entry < len(self.camera)
        t[has] = self.camera.a[entry[has], None]
        ray = self.camera.ray[grid.cell_piece]
        mixed = np.zeros(len(ray))
        exact = self._scatter_mass(None)
        points = self.origins[ray] + self.directions[ray] * grid.cell_t[:, None]
        lit = luminance(self.emitters.shadow_rays(points)[2].sum(axis=0).T)        # unshadowed
        sources = [exact, exact * lit]
        sources += [self._scatter_mass((float(rate),) * len(self.media)) for rate in rates]
        for mass in sources:
            total = np.bincount(ray, mass, n)
            mixed += np.where(total[ray] > 0, mass / np.where(total[ray] > 0, total[ray], 1.0), 0.0)
        # Per ray, the mixture's cumulative share along its cells, offset by the ray's index
        # so that one sorted search finds every ray's quantiles.
        cumulative = np.cumsum(mixed)
        first = np.searchsorted(ray, np.arange(n))
        last = np.searchsorted(ray, np.arange(n), side="right")
        base = np.where(first > 0, cumulative[np.maximum(first - 1, 0)], 0.0)
        span = np.where(last > first, cumulative[np.maximum(last - 1, 0)] - base, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.where(span[ray] > 0, (cumulative - base[ray]) / span[ray], 1.0)
        share = np.minimum(share, 1.0) + ray
        quantile = (np.arange(SCATTER_POINTS - 1) + 0.5) / (SCATTER_POINTS - 1)
        gathers = np.flatnonzero(span > 0)
        index = np.searchsorted(share, (gathers[:, None] + quantile[None, :]).ravel())
        index = np.minimum(index.reshape(len(gathers), -1), (last[gathers] - 1)[:, None])
        t[gathers, 1:] = grid.cell_t[index]
        t = np.sort(t, axis=1)
        self._quantile_t = t
        return self.origins[:, None, :] + self.directions[:, None, :] * t[..., None]

    # --- pixels ---------------------------------------------------------------------------
    def _light_in(self, transmittance: np.ndarray, group: int) -> np.ndarray:
        """(n, K, 3) light arriving at the scatter points from ``group``'s lights (isotropic
        phase), with each shadow ray's ``transmittance`` (lights, rays, 3)."""
        chosen = self.emitters.group == group
        rows = self._scatter_rows
        value = (self.shadow.irradiance[chosen, rows] * self.shadow.visible[chosen, rows, None]
                 * transmittance[chosen, rows]).sum(axis=0) * _ISOTROPIC
        return value.reshape(len(self.near), SCATTER_POINTS, 3)

    def _surface_light(self, transmittance: np.ndarray, group: int) -> np.ndarray:
        """(n, 3) diffuse light (reflectance 1) the first surface of each ray sends back."""
        chosen = self.emitters.group == group
        rows = self._surface_rows
        value = (self.shadow.irradiance[chosen, rows] * self.shadow.visible[chosen, rows, None]
                 * transmittance[chosen, rows] * self._cosine[chosen, :, None]).sum(axis=0) / math.pi
        out = np.zeros((len(self.near), 3))
        out[self.hit] = value
        return out

    def _pixels(self, transmittance: np.ndarray, rates) -> dict:
        """Per group: (in-scattered + emitted light (n, 3), transmittance to the end (n, 3),
        surface light at reflectance 1 (n, 3), background (n, 3)); exact when ``rates`` is
        None, else the mean of the marched estimate."""
        out = {}
        for group in np.unique(self.emitters.group):
            light = self._light_in(transmittance, int(group))
            gathered, ends = self._march(light, rates, emission=group == 0)
            sky = np.where(self.hit[:, None], 0.0, self.emitters.background[int(group)][None, :])
            out[int(group)] = (gathered, ends, self._surface_light(transmittance, int(group)), sky)
        return out

    def _march(self, light: np.ndarray, rates, emission: bool):
        """(gathered (n, 3), transmittance to the end (n, 3)) along the camera rays: exactly
        (``rates`` None: every grid cell a step) or Cycles' marching at ``rates`` averaged
        over ``CAMERA_RUNS`` offset pairs."""
        walk = _CameraWalk(self, rates)
        gathered = np.zeros((len(self.near), walk.runs, 3))
        for step in walk:
            light_there = self._interpolate_light(step.ray, step.scatter_at, light).mean(axis=-2)
            with np.errstate(divide="ignore", invalid="ignore"):
                albedo = np.where(step.sigma > 0.0, step.scatter / step.sigma, 0.0)
                emitted = 0.0
                if emission:
                    emit = self.grid.at(2, step.piece, step.shade)
                    emitted = np.where(step.sigma > 0.0, emit * step.kept / step.sigma, emit * step.dt[..., None])
            contribution = step.carried * (albedo * step.kept * light_there + emitted)
            np.add.at(gathered, step.ray, contribution.sum(axis=2))
        return gathered.mean(axis=1), np.exp(-walk.depth).mean(axis=1)

    def _scatter_mass(self, rates) -> np.ndarray:
        """Per grid cell of the camera rays, how much of a distance sample scatters there,
        exactly (``rates`` None) or as marched at ``rates`` (the runs' mean); luminance."""
        grid = self.grid
        mass = np.zeros(len(grid.cell_t))
        walk = _CameraWalk(self, rates)
        for step in walk:
            share = luminance(np.moveaxis(step.carried * step.kept, -1, 0))[..., None] / (STEP_QUANTILES * walk.runs)
            piece = np.broadcast_to(step.piece[..., None], step.scatter_at.shape)
            local = np.floor((step.scatter_at - self.camera.a[piece]) / grid.width[piece])
            cell = grid.offset[piece] + np.clip(local, 0, grid.count[piece] - 1).astype(np.int64)
            np.add.at(mass, cell.ravel(), np.broadcast_to(share, cell.shape).ravel())
        return mass

    def _interpolate_light(self, ray, t, light) -> np.ndarray:
        """(pieces, runs, count, ..., 3): the light arriving along ``ray`` at distances ``t``,
        between the ray's scatter points linear in its logarithm (light into a medium falls
        off exponentially), constant beyond them."""
        knots = self._quantile_t[ray]                                     # (p, K)
        values = np.log(np.maximum(light[ray], _DARKEST))                 # (p, K, 3)
        flat = t.reshape(len(ray), -1)
        position = np.clip(np.sum(flat[:, :, None] >= knots[:, None, :], axis=2) - 1, 0, SCATTER_POINTS - 1)
        upper = np.minimum(position + 1, SCATTER_POINTS - 1)
        rows = np.arange(len(ray))[:, None]
        t0, t1 = knots[rows, position], knots[rows, upper]
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.where(t1 > t0, np.clip((flat - t0) / (t1 - t0), 0.0, 1.0), 0.0)
        out = np.exp(values[rows, position] * (1.0 - f[..., None]) + values[rows, upper] * f[..., None])
        return np.where(out <= _DARKEST * 1.0001, 0.0, out).reshape(t.shape + (3,))

    def scattering_depth(self, q: float = 95.0) -> float:
        """The ``q``-th percentile over the frame of the scattering optical depth the camera
        rays cross in media marched in steps (how much multiple scattering matters there)."""
        grid = self.grid
        stepped = np.array([any(math.isfinite(self.steps[m]) for m in active) for active in self.camera.active], bool)
        cells = stepped[grid.cell_piece] if len(grid.cell_piece) else np.zeros(0, bool)
        depth = np.zeros(len(self.near))
        np.add.at(depth, self.camera.ray[grid.cell_piece[cells]],
                  luminance(grid.values[1][cells].T) * grid.width[grid.cell_piece[cells]])
        return weighted_percentile(depth, self.weight, q)

    # --- the error ------------------------------------------------------------------------
    def error(self, rates) -> ImageError:
        """The marched estimate's error per sampled pixel at one scene step rate for every
        medium, or one rate per medium (a sequence in ``media``'s order)."""
        rates = tuple(float(r) for r in ((rates,) * len(self.media) if isinstance(rates, (int, float)) else rates))
        if rates not in self._cache:
            marched = self._pixels(self.shadow.marched(rates), rates)
            self._cache[rates] = self._compare(self.truth, marched)
        return self._cache[rates]

    def _compare(self, truth: dict, marched: dict) -> ImageError:
        """The worst relative error over the lighting the scene leaves open: surfaces black
        or bright, and a world of unknown strength alone beside the known lights alone."""
        worst = np.zeros(len(self.near))
        report = None
        for group in truth:
            for reflectance in (0.0, BRIGHT_SURFACE):
                def pixel(parts):
                    gathered, ends, surface, sky = parts[group]
                    return gathered + ends * (reflectance * surface + sky)
                value = luminance(pixel(truth).T)
                error = luminance((pixel(marched) - pixel(truth)).T)
                error = np.where(value > self.clip, 0.0, error)       # shown as white either way
                dark = max(DARK_SHARE * weighted_percentile(value, self.weight, 90.0), 1e-12)
                worst = np.maximum(worst, np.abs(error) / np.maximum(value, dark))
                if group == 0 and reflectance > 0.0:
                    report = (value, error)
        value, error = report if report is not None else (np.zeros(len(self.near)),) * 2
        return ImageError(value=value, error=error, relative=worst, weight=self.weight)


@dataclass
class _Step:
    """One batch of camera pieces' steps: each (pieces, runs, count) array, the media's
    coefficients at the shading points (..., 3), and ``scatter_at`` (..., STEP_QUANTILES)
    where a distance sample scatters inside each step (its exponential's quantiles)."""

    ray: np.ndarray
    piece: np.ndarray
    shade: np.ndarray
    dt: np.ndarray
    sigma: np.ndarray
    scatter: np.ndarray
    carried: np.ndarray
    kept: np.ndarray
    scatter_at: np.ndarray


class _CameraWalk:
    """Steps through the camera rays' pieces in order along each ray, exactly (every grid
    cell a step) or as Cycles marches them at ``rates`` over ``CAMERA_RUNS`` offset pairs,
    carrying each ray's optical depth so far (``depth`` (n, runs, 3) at the end)."""

    def __init__(self, predictor: "LightPathPredictor", rates):
        self.predictor, self.rates = predictor, rates
        if rates is None:
            self.u = self.v = np.array([0.5])
        else:
            index = np.arange(CAMERA_RUNS)
            self.u, self.v = (index + 0.5) / CAMERA_RUNS, np.mod(0.5 + index * _GOLDEN, 1.0)
        self.runs = len(self.u)
        self.depth = np.zeros((len(predictor.near), self.runs, 3))

    def __iter__(self):
        p = self.predictor
        pieces = p.camera
        # Pieces in order along each ray: the rank of each within its ray.
        rank = np.arange(len(pieces)) - np.searchsorted(pieces.ray, pieces.ray)
        for r in range(int(rank.max()) + 1 if len(pieces) else 0):
            at_rank = np.flatnonzero(rank == r)
            if self.rates is None:
                batches = [(at_rank, None)]
            else:
                sub = Pieces(pieces.ray[at_rank], pieces.a[at_rank], pieces.b[at_rank],
                             [pieces.active[i] for i in at_rank])
                batches = [(at_rank[chosen], step) for chosen, step in _batches(sub, p.steps, self.rates, p.max_steps)]
            for chosen, step in batches:
                yield self._step(chosen, step)

    def _step(self, chosen, step) -> _Step:
        grid, pieces = self.predictor.grid, self.predictor.camera
        ray = pieces.ray[chosen]
        a, b = pieces.a[chosen], pieces.b[chosen]
        if step is None or not np.all(np.isfinite(step)):
            # Every cell a step (the truth), or homogeneous media (one exact step: its cell).
            cells = np.arange(int(grid.count[chosen].max()))
            width = grid.width[chosen]
            valid = cells[None, :] < grid.count[chosen][:, None]
            starts = np.repeat((a[:, None] + cells[None, :] * width[:, None])[:, None, :], self.runs, axis=1)
            dt = np.repeat(np.where(valid, width[:, None], 0.0)[:, None, :], self.runs, axis=1)
            shade = starts + 0.5 * dt
        else:
            starts, dt, shade = _steps(a, b, step, self.u, self.v, self.predictor.max_steps)
        piece = np.broadcast_to(chosen[:, None, None], shade.shape)
        sigma = grid.at(0, piece, shade)
        depth_step = sigma * dt[..., None]
        before = self.depth[ray][:, :, None, :] + np.cumsum(depth_step, axis=2) - depth_step
        s = luminance(np.moveaxis(sigma, -1, 0))
        quantile = (np.arange(STEP_QUANTILES) + 0.5) / STEP_QUANTILES
        with np.errstate(divide="ignore", invalid="ignore"):
            share = -np.expm1(-s * dt)[..., None] * quantile
            offset = np.where(s[..., None] * dt[..., None] > 1e-6,
                              -np.log1p(-share) / np.where(s > 0, s, 1.0)[..., None], dt[..., None] * quantile)
        out = _Step(ray=ray, piece=piece, shade=shade, dt=dt, sigma=sigma, scatter=grid.at(1, piece, shade),
                    carried=np.exp(-before), kept=-np.expm1(-depth_step), scatter_at=starts[..., None] + offset)
        np.add.at(self.depth, ray, depth_step.sum(axis=2))
        return out


class _ShadowRays:
    """The shadow rays from a set of points to every light: whether a surface blocks each,
    the irradiance it brings unblocked, and the media's transmittance along it, exactly and
    as marched (``marched``)."""

    def __init__(self, starts, emitters: Emitters, media, steps, cast, finest, max_steps):
        self.media, self.steps, self.max_steps = media, steps, max_steps
        lights, n = emitters.count, len(starts)
        direction, length, self.irradiance = emitters.shadow_rays(starts)
        self.direction = direction
        self.shape = (lights, n)
        # Only the lights that matter at a point are followed there (``FAINT_LIGHT``); a
        # world of unknown strength always is.
        brought = luminance(np.moveaxis(self.irradiance, -1, 0))                  # (lights, n)
        known = (emitters.group == 0)[:, None]
        followed = ~known | (brought >= FAINT_LIGHT * np.where(known, brought, 0.0).sum(axis=0))
        followed &= brought > 0.0
        rows = np.flatnonzero(followed.ravel())
        origins = np.repeat(starts[None], lights, axis=0).reshape(-1, 3)[rows]
        visible, segments = cast(origins, direction.reshape(-1, 3)[rows], length.reshape(-1)[rows])
        self.visible = np.zeros(lights * n, bool)
        self.visible[rows] = np.asarray(visible, bool)
        self.visible = self.visible.reshape(lights, n)
        # Pieces and depths are indexed by the full (light, point) row.
        segments = [(rows[np.asarray(index, np.int64)], t0, t1) for index, t0, t1 in segments]
        # Cycles follows a shadow ray to a distant light (a sun, the sky) to infinity: through
        # a world medium none of its light arrives, whatever the estimator.
        self.extinguished = np.zeros(lights * n, bool)
        far = length.reshape(-1) >= 0.5 * DISTANT
        for medium, (index, _, _) in zip(media, segments):
            constant = medium.constant_extinction() if medium.kind == "world" else None
            if medium.kind == "world" and (constant is None or np.any(constant > 0.0)):
                self.extinguished[index[far[index]]] = True
        segments = [(index[~self.extinguished[index]], np.asarray(t0)[~self.extinguished[index]],
                     np.asarray(t1)[~self.extinguished[index]]) for index, t0, t1 in segments]
        self.pieces = Pieces.split(np.zeros(lights * n), length.reshape(-1), segments)
        all_origins = np.repeat(starts[None], lights, axis=0).reshape(-1, 3)
        self.grid = _Grid(self.pieces, all_origins, direction.reshape(-1, 3), media, steps,
                          finest / CELLS_PER_STEP, MAX_SHADOW_CELLS, 1)
        depth = np.zeros((lights * n, 1))
        np.add.at(depth, self.pieces.ray[self.grid.cell_piece],
                  self.grid.values[0] * self.grid.width[self.grid.cell_piece][:, None])
        self.exact = (np.exp(-depth) * ~self.extinguished[:, None]).reshape(lights, n, 1)
        self._cache: dict = {}

    def marched(self, rates) -> np.ndarray:
        """(lights, points, 1): the mean of Cycles' marched transmittance (luminance) along each shadow
        ray at ``rates`` (one per medium), its shade offset the same on every piece."""
        key = tuple(rates)
        if key not in self._cache:
            runs = SHADOW_RUNS
            v = (np.arange(runs) + 0.5) / runs
            u = np.ones(runs)
            depth = np.zeros((self.shape[0] * self.shape[1], runs, 1))
            for chosen, step in _batches(self.pieces, self.steps, rates, self.max_steps):
                ray = self.pieces.ray[chosen]
                if not np.all(np.isfinite(step)):
                    # Homogeneous: one exact step (its single cell).
                    exact = self.grid.values[0][self.grid.offset[chosen]] * (self.pieces.b - self.pieces.a)[chosen, None]
                    np.add.at(depth, ray, np.repeat(exact[:, None, :], runs, axis=1))
                    continue
                _, dt, shade = _steps(self.pieces.a[chosen], self.pieces.b[chosen], step, u, v, self.max_steps)
                piece = np.broadcast_to(chosen[:, None, None], shade.shape)
                sigma = self.grid.at(0, piece, shade)
                np.add.at(depth, ray, (sigma * dt[..., None]).sum(axis=2))
            self._cache[key] = (np.exp(-depth).mean(axis=1) * ~self.extinguished[:, None]).reshape(self.shape + (1,))
        return self._cache[key]
