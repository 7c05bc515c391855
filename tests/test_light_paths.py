"""The light-path prediction of ray marching's error in the picture (``core.media.light_paths``),
without Blender: its marched estimate against a brute-force Monte Carlo of Cycles' own
stepping on a medium whose density is known in closed form, and its bookkeeping."""
from __future__ import annotations

import math

import numpy as np
import pytest

from xsl_render.core.media.light_paths import (Emitters, LightPathPredictor, Pieces,
                                               weighted_percentile)

#: A slab of fog between z = 0 and z = TOP, lit by a sun straight above.
TOP = 2.0


class Slab:
    """A duck-typed medium: density ``base * (1 + wave * sin(2 pi x / period))`` for
    0 <= z <= TOP, albedo ``albedo``; ``step`` its Cycles step at rate 1 (inf: one step)."""

    def __init__(self, base=3.0, wave=0.9, period=0.9, albedo=0.9, step=0.4):
        self.base, self.wave, self.period, self.albedo = base, wave, period, albedo
        self.extra = {"cycles_step": step}
        self.kind = "mesh"
        self.step = step

    def density(self, points):
        points = np.asarray(points, np.float64)
        inside = (points[:, 2] >= 0.0) & (points[:, 2] <= TOP)
        return np.where(inside, self.base * (1.0 + self.wave * np.sin(2 * math.pi * (points[:, 0] + 0.3 * points[:, 2]) / self.period)), 0.0)

    def extinction(self, points, part="extinction"):
        sigma = self.density(points)[:, None].repeat(3, axis=1)
        return sigma * (self.albedo if part == "scattering" else 1.0)

    def coefficients(self, points):
        sigma = self.extinction(points)
        return sigma, sigma * self.albedo, np.zeros_like(sigma)

    def constant_extinction(self):
        return np.full(3, self.base) if self.wave == 0.0 else None


def sun_above(strength=3.0) -> Emitters:
    none = np.zeros((0, 3))
    return Emitters(positions=none, intensity=none, axes=none, cone_cos=np.zeros(0), cone_smooth=np.zeros(0),
                    one_sided=np.zeros(0, bool), toward=np.array([[0.0, 0.0, 1.0]]),
                    irradiance=np.full((1, 3), strength), group=np.zeros(1, np.int64), background=np.zeros((2, 3)))


def slab_cast(origins, directions, lengths):
    """No surfaces; each ray's piece inside 0 <= z <= TOP."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t_bottom = (0.0 - origins[:, 2]) / directions[:, 2]
        t_top = (TOP - origins[:, 2]) / directions[:, 2]
    flat = np.abs(directions[:, 2]) < 1e-12
    lo = np.where(flat, np.where((origins[:, 2] >= 0) & (origins[:, 2] <= TOP), 0.0, np.inf), np.minimum(t_bottom, t_top))
    hi = np.where(flat, np.where((origins[:, 2] >= 0) & (origins[:, 2] <= TOP), np.inf, -np.inf), np.maximum(t_bottom, t_top))
    t0, t1 = np.maximum(lo, 0.0), np.minimum(hi, lengths)
    keep = np.flatnonzero(t1 > t0)
    return np.ones(len(lengths), bool), [(keep, t0[keep], t1[keep])]


def slab_predictor(medium, rays=4):
    """Camera rays slanting down into the slab from above, ending on its floor (no surface)."""
    origins = np.array([[0.05 * i, 0.0, 3.0] for i in range(rays)])
    directions = np.array([[0.6, 0.0, -0.8]] * rays)
    near, far = np.zeros(rays), np.full(rays, 3.0 / 0.8)
    _, segments = slab_cast(origins, directions, far)
    return LightPathPredictor(origins, directions, near, far, np.zeros((rays, 3)), np.ones(rays), [medium],
                              segments, sun_above(), slab_cast)


def cycles_marching(medium, origin, direction, a, b, rate, samples, rng, strength=3.0):
    """Cycles' ray marching of single scattering along one ray, sampled: the camera ray's
    steps offset by u and shaded at v, a distance sample through them, and the sun's shadow
    ray marched from the scatter point (steps from its start, shaded at its own v)."""
    step = medium.step * rate
    total = 0.0
    for _ in range(samples):
        u, v, r = rng.random(3)
        count = int(math.ceil((b - a) / step)) + 1
        ends = np.minimum(b, a + (np.arange(count) + u) * step)
        starts = np.concatenate([[a], ends[:-1]])
        sigma = medium.density(origin + direction * (starts + v * (ends - starts))[:, None])
        target, depth = -math.log(1.0 - r), 0.0
        for start, length, s in zip(starts, ends - starts, sigma):
            if depth + s * length >= target:
                point = origin + direction * (start + (target - depth) / s)
                height = TOP - point[2]
                shadow = max(min(step, height), height / 1024)
                n = int(math.ceil(height / shadow))
                edges = np.minimum(height, (np.arange(n) + 1) * shadow)
                lows = np.concatenate([[0.0], edges[:-1]])
                w = rng.random()
                tau = (medium.density(point + np.array([0, 0, 1.0]) * (lows + w * (edges - lows))[:, None])
                       * (edges - lows)).sum()
                total += medium.albedo * strength * math.exp(-tau) / (4 * math.pi)
                break
            depth += s * length
    return total / samples


def test_the_marched_estimate_is_cycles_stepping_averaged():
    """On a medium of known density, the predictor's mean marched pixel (truth + error) is
    what Cycles' stepping gives on average, to a few per cent; its error at a coarse rate
    is Cycles' to within the light's resolution along the ray (``SCATTER_POINTS``), and far
    from the fine rate's."""
    medium = Slab()
    predictor = slab_predictor(medium)
    rng = np.random.default_rng(7)
    origin, direction = predictor.origins[0], predictor.directions[0]
    a = (TOP - origin[2]) / direction[2]
    b = predictor.far[0]
    exact = cycles_marching(medium, origin, direction, a, b, 0.01, 4000, rng)
    sampled = {rate: cycles_marching(medium, origin, direction, a, b, rate, 8000, rng) for rate in (4.0, 1.0)}
    for rate, value in sampled.items():
        error = predictor.error(rate)
        assert error.value[0] + error.error[0] == pytest.approx(value, rel=0.04)
    coarse = predictor.error(4.0).error[0]
    assert 0.6 < coarse / (sampled[4.0] - exact) < 1.3
    assert abs(coarse) > 5 * abs(predictor.error(0.25).error[0])


def test_the_exact_value_is_single_scattering_integrated_finely():
    medium = Slab()
    predictor = slab_predictor(medium)
    origin, direction = predictor.origins[0], predictor.directions[0]
    a, b = (TOP - origin[2]) / direction[2], predictor.far[0]
    t = a + (np.arange(4000) + 0.5) / 4000 * (b - a)
    points = origin + direction * t[:, None]
    sigma = medium.density(points)
    camera = np.exp(-np.cumsum(sigma) * (b - a) / 4000 + sigma * (b - a) / 8000)
    shadow = []
    for point in points[::40]:
        z = point[2] + (np.arange(400) + 0.5) / 400 * (TOP - point[2])
        up = np.column_stack([np.full(400, point[0]), np.full(400, point[1]), z])
        shadow.append(math.exp(-medium.density(up).sum() * (TOP - point[2]) / 400))
    shadow = np.repeat(shadow, 40)
    exact = (camera * sigma * medium.albedo * shadow).sum() * (b - a) / 4000 * 3.0 / (4 * math.pi)
    assert predictor.error(1.0).value[0] == pytest.approx(exact, rel=0.03)


def test_a_homogeneous_medium_is_marched_exactly_at_every_rate():
    predictor = slab_predictor(Slab(wave=0.0, step=math.inf))
    for rate in (4.0, 1.0, 0.25):
        error = predictor.error(rate)
        assert np.all(error.value > 0)
        np.testing.assert_allclose(error.error, 0.0, atol=1e-12)


def test_an_unknown_world_bounds_the_error_over_its_strength():
    """A world whose radiance is not known is a group of its own: the relative error is the
    worst of the known lights alone and that world alone, so never below the known one's."""
    medium = Slab()
    known = slab_predictor(medium).error(2.0)
    emitters = sun_above()
    sky = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    both = Emitters(positions=emitters.positions, intensity=emitters.intensity, axes=emitters.axes,
                    cone_cos=emitters.cone_cos, cone_smooth=emitters.cone_smooth, one_sided=emitters.one_sided,
                    toward=np.concatenate([emitters.toward, sky]),
                    irradiance=np.concatenate([emitters.irradiance, np.full((2, 3), 2 * math.pi)]),
                    group=np.array([0, 1, 1]), background=np.array([[0.0] * 3, [1.0] * 3]))
    p = slab_predictor(medium)
    bounded = LightPathPredictor(p.origins, p.directions, p.near, p.far, np.zeros((4, 3)), np.ones(4), [medium],
                                 slab_cast(p.origins, p.directions, p.far)[1], both, slab_cast).error(2.0)
    assert np.all(bounded.relative >= known.relative - 1e-12)


def test_pieces_split_where_media_overlap():
    near, far = np.zeros(2), np.full(2, 10.0)
    pieces = Pieces.split(near, far, [(np.array([0, 1]), np.array([1.0, 2.0]), np.array([5.0, 3.0])),
                                      (np.array([0]), np.array([4.0]), np.array([12.0]))])
    assert pieces.ray.tolist() == [0, 0, 0, 1]
    assert pieces.a.tolist() == [1.0, 4.0, 5.0, 2.0]
    assert pieces.b.tolist() == [4.0, 5.0, 10.0, 3.0]
    assert pieces.active == [(0,), (0, 1), (1,), (0,)]


@pytest.mark.parametrize("values, weights, q, expected", [
    ([1.0, 2.0, 3.0, 4.0], [1, 1, 1, 1], 50, 2.0),
    ([1.0, 2.0, 3.0, 4.0], [1, 1, 1, 1], 95, 4.0),
    ([5.0, 1.0], [3, 1], 50, 5.0),
    ([], [], 95, 0.0),
])
def test_weighted_percentile(values, weights, q, expected):
    assert weighted_percentile(np.array(values), np.array(weights, float), q) == expected
