"""Where along a camera ray Cycles places the scattering that gathers direct light, per medium:
its ``volume_sampling`` (distance, equiangular, or both with multiple importance), predicted
from the media and the lights, for ``--estimator auto``.

Single scattering along a segment is the integral of f(t) = sigma_s(t) T(t) G(t) S(t), with
sigma_s the media's scattering coefficient (an absorbing medium gathers nothing), T the
transmittance from the eye, G = 1 / |x(t) - light|^2 and S the share the light sends that
way (a spot's cone, an area light's one side; ``Lights``); the phase function is left out.
Distance sampling draws t with density proportional to sigma_t T, equiangular with density
proportional to G toward the light it sampled (it knows where a light is, not where it
points), and multiple importance draws from either; each estimate is f / pdf, with the light
taken in proportion to its power. Cycles integrates a camera ray segment by segment between
surfaces (a fog box's faces among them), and samples each with the union of the methods of
the media on its volume stack (``stack_method``: a fog box set to distance inside a world
fog sampled equiangular is sampled with both). So the noise is computed per segment by
quadrature (``segment_moments``), summed over a ray's segments, combined over the rays
weighted by what each gathers (``Segments.noise``), and the carriers that switch are chosen
together (``chosen_methods``). Distance sampling wins where the medium is thick and uneven
and the lights are far from the rays (then G hardly varies and sigma_t T carries the
integrand); equiangular where a lamp sits in thin fog near the rays (G peaks).

Measured against Cycles (auto's ray marching, 16 spp, OIDN as auto denoises, medians of 3
seeds, mean FLIP against the converged references; ``bench/bench_scatter_sampling.py``,
``docs/bench_scatter_sampling.txt``), with the prediction for distance / both / equiangular:

- balls_b (noise fog lit by an area light from outside): distance 0.0430 in 7.53 s, the
  material's own multiple importance 0.0473 in 8.11 s, equiangular 0.0506; predicted 0.27 /
  0.62 / 1.21.
- statue (smoke, a spot and an area light beside it): 0.0403 in 7.65 s, 0.0409 in 8.59 s,
  0.0409; predicted 0.44 / 0.72 / 1.19.
- balls_a (the same room in thin homogeneous fog): 0.0310, 0.0274, 0.0295; predicted 0.37 /
  0.25 / 0.13.
- street (lamps inside noise fog): 0.0742, 0.0632, 0.0651; predicted 3.37 / 1.71 / 1.89.
- road (lamps and two headlights in world fog; the world's own method is equiangular):
  0.0571, 0.0434, 0.0392; predicted 5.60 / 2.05 / 1.70.

Distance sampling is also the cheapest per sample (one strategy instead of two: 7-11 % less
time above). The prediction ranks distance against the own method as Cycles does on all
five, and all three methods as Cycles does on four (balls_a: equiangular predicted first,
measured second by 8 %). So auto switches media to distance sampling only where that is
predicted to leave less than ``DISTANCE_MARGIN`` of the own methods' noise (balls_b 0.44,
statue 0.62; balls_a, street and road keep theirs, at 1.5-2.7), and never to equiangular.

On random lit scenes (``bench/bench_scatter_random.py``, 90 seeds, 84 with a medium that
could switch; ``docs/bench_scatter_random.txt``) the prediction is a poor judge of the gain
but a safe one: auto switched 5, where Cycles rendered 0.95-1.06 of the own methods' pixel
variance at equal samples (less than distance's cheaper sample pays back), and kept 7 where
every medium at distance would have rendered 0.36-0.60 of it (misses: there Cycles' own
"both" under ray marching, one strategy per sample weighed by twice the power heuristic
against distance's unnormalized density, renders 2-3x noisier than either strategy alone,
where the balance heuristic modelled here puts it between them; README). Before the volume stack, the
scattering part and the lights' spread were modelled, the same suite found a switched
absorbing box (nothing to gather) and switches inside world fog that Cycles overruled
(``docs/bench_scatter_random_before.txt``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Cycles' names for the three methods (a material's or a world's ``volume_sampling``).
DISTANCE, EQUIANGULAR, BOTH = "DISTANCE", "EQUIANGULAR", "MULTIPLE_IMPORTANCE"
METHODS = (DISTANCE, EQUIANGULAR, BOTH)
#: Distance sampling replaces the media's own methods where their predicted noise is below
#: this share of the own methods' (module notes: statue's 0.62 paid, the kept examples sit at
#: 1.5-2.7, and no random scene it switched rendered more than 1.06 of the own noise).
DISTANCE_MARGIN = 0.65
#: Quadrature points per piece of a ray inside the media.
POINTS_PER_PIECE = 64
#: A piece of a ray is integrated over this length at most, in metres (a world fog reaches
#: to the sky; so far out nothing the eye sees is left).
MAX_PIECE_LENGTH = 200.0


@dataclass
class Lights:
    """The lights equiangular sampling aims at: ``positions`` (N, 3), ``power`` (N,), and how
    each spreads its light: ``directions`` (N, 3) where it points, ``cone_cos`` (N,) the
    cosine of a spot's half angle (-1: every direction), ``cone_smooth`` (N,) the width of
    its soft edge in cosine (Cycles' ``spot_blend`` times one minus ``cone_cos``), and
    ``one_sided`` (N,) an area light's Lambertian side. Equiangular sampling knows only
    where a light is, so a spot aimed away from the ray or an area light facing away wastes
    its samples; the integrand sees it."""

    positions: np.ndarray
    power: np.ndarray
    directions: np.ndarray | None = None
    cone_cos: np.ndarray | None = None
    cone_smooth: np.ndarray | None = None
    one_sided: np.ndarray | None = None

    def spread(self, index: int, points: np.ndarray) -> np.ndarray | float:
        """The share of light ``index`` sends toward each of ``points`` (1 for a point lamp)."""
        if self.directions is None:
            return 1.0
        out = points - self.positions[index]
        cosine = out @ self.directions[index] / np.maximum(np.linalg.norm(out, axis=1), 1e-12)
        factor = np.ones(len(points))
        if self.one_sided[index]:
            factor = np.maximum(cosine, 0.0)
        if self.cone_cos[index] > -1.0:
            edge = (cosine - self.cone_cos[index]) / max(float(self.cone_smooth[index]), 1e-6)
            smooth = np.clip(edge, 0.0, 1.0)
            factor = factor * np.where(cosine > self.cone_cos[index], smooth * smooth * (3.0 - 2.0 * smooth), 0.0)
        return factor


def segment_moments(t: np.ndarray, dt: np.ndarray, sigma_t: np.ndarray, sigma_s: np.ndarray,
                    points: np.ndarray, lights: Lights, depth_before: float = 0.0) -> tuple[float, np.ndarray]:
    """(the integral, the second moment of one sample's estimate with each of ``METHODS``) of
    single scattering over one segment of a ray, as Cycles integrates a segment between two
    surfaces: quadrature points ``t`` (sorted) with widths ``dt``, the total extinction
    ``sigma_t`` there, the scattering ``sigma_s`` whose light is gathered, their world
    ``points``; the ``lights``; ``depth_before`` the optical depth from the eye to the
    segment's start.

    Distance sampling draws with density sigma_t T normalized over the segment. Cycles' own
    is not normalized (a sample that crosses a thin segment without scattering gathers no
    fog light there), but then it carries the surface behind instead, which this model does
    not see; with the unnormalized density the model ranked distance last on balls_b and
    statue, where Cycles renders it best, and with the normalized one it ranks every example
    as Cycles does (module notes). Equiangular sampling draws over the segment toward the
    light it took; both mixes the two halves of the samples (one-sample multiple importance,
    balance heuristic)."""
    local = np.cumsum(sigma_t * dt) - 0.5 * sigma_t * dt
    transmittance = np.exp(-(depth_before + local))
    p_distance = sigma_t * np.exp(-local)
    norm = float((p_distance * dt).sum())
    moments = np.zeros(len(METHODS))
    if not len(lights.power) or lights.power.sum() <= 0.0 or norm <= 0.0:
        return 0.0, moments
    p_distance = p_distance / norm
    choose = lights.power / lights.power.sum()
    integral = 0.0
    for index, (position, power, chance) in enumerate(zip(lights.positions, lights.power, choose)):
        if chance <= 0.0:
            continue
        g = 1.0 / np.maximum(((points - position) ** 2).sum(axis=1), 1e-6)
        f = sigma_s * transmittance * g * power * lights.spread(index, points)
        p_equiangular = g / float((g * dt).sum())
        integral += float((f * dt).sum())
        for column, pdf in enumerate((p_distance, p_equiangular, 0.5 * (p_distance + p_equiangular))):
            moments[column] += float((f * f / np.maximum(pdf, 1e-30) * dt).sum()) / chance
    return integral, moments


#: Cycles' method bits (``VolumeSampleMethod``): a segment inside several media samples with
#: the union of their methods, so distance and equiangular together give both.
METHOD_BITS = {DISTANCE: 1, EQUIANGULAR: 2, BOTH: 3}
#: The column of ``METHODS`` (and of ``segment_moments``' moments) for each union of bits (a
#: segment with no medium on its stack gathers nothing; any column does).
_COLUMN_OF_BITS = np.array([2, 0, 1, 2])


def stack_method(methods) -> str | None:
    """The method Cycles samples a segment with, from its volume stack's media's methods
    (``volume_stack_sample_method``): one asking for both, or distance beside equiangular,
    gives both."""
    bits = 0
    for method in methods:
        bits |= METHOD_BITS[method]
    return METHODS[_COLUMN_OF_BITS[bits]] if bits else None


@dataclass
class Segments:
    """The segments of the sampled camera rays inside media, as Cycles integrates them.

    ``ray`` (S,) the ray of each, ``integral`` (S,) and ``moments`` (S, 3) from
    ``segment_moments``, ``members`` (S, C) whether each of the ``carriers`` (the materials
    and world whose ``volume_sampling`` Cycles reads) has a medium on the stack there."""

    carriers: list[str]
    ray: np.ndarray
    integral: np.ndarray
    moments: np.ndarray
    members: np.ndarray

    def noise(self, methods: dict) -> float:
        """The relative noise of one sample with each carrier at ``methods[carrier]``: per ray
        the segments' variances summed over what the ray gathers squared, combined over the
        rays weighted by what each gathers (root mean square)."""
        if not len(self.ray):
            return 0.0
        bits = np.array([METHOD_BITS[methods[c]] for c in self.carriers], np.int64)
        stacked = np.bitwise_or.reduce(np.where(self.members, bits[None, :], 0), axis=1)
        column = _COLUMN_OF_BITS[stacked]
        variance = self.moments[np.arange(len(self.ray)), column] - self.integral ** 2
        rays, where = np.unique(self.ray, return_inverse=True)
        gathered = np.bincount(where, self.integral, len(rays))
        spread = np.bincount(where, np.maximum(variance, 0.0), len(rays))
        keep = gathered > 0.0
        if not keep.any():
            return 0.0
        relative = spread[keep] / gathered[keep] ** 2
        return float(math.sqrt((gathered[keep] * relative).sum() / gathered[keep].sum()))


#: Every subset of the carriers that may switch is tried up to this many carriers; beyond,
#: one carrier at a time.
MAX_ENUMERATED = 6


def chosen_methods(segments: Segments, own: dict) -> tuple[dict, dict]:
    """({carrier: DISTANCE} for the carriers auto switches, {carrier: {method: predicted
    noise of the frame with that carrier alone at it}}).

    The carriers switched together are the subset whose frame is predicted least noisy, kept
    only where that is below ``DISTANCE_MARGIN`` of the noise with every carrier at its own
    method: a medium's switch takes effect only where no medium beside it on the stack asks
    for equiangular or both (a world fog's equiangular overrules a fog box's distance inside
    it), so carriers are judged together, not one by one."""
    carriers = segments.carriers
    noises = {c: {m: segments.noise({**own, c: m}) for m in METHODS} for c in carriers}
    base = segments.noise(own)
    switchable = [c for c in carriers if own[c] != DISTANCE]
    if base <= 0.0 or not switchable:
        return {}, noises
    if len(switchable) <= MAX_ENUMERATED:
        subsets = [[c for bit, c in enumerate(switchable) if mask >> bit & 1]
                   for mask in range(1, 1 << len(switchable))]
    else:
        subsets = [[c] for c in switchable] + [switchable]
    best, best_noise = [], base
    for subset in sorted(subsets, key=len):
        value = segments.noise({**own, **dict.fromkeys(subset, DISTANCE)})
        if value < best_noise * (1.0 - 1e-9):
            best, best_noise = subset, value
    if not best or best_noise >= DISTANCE_MARGIN * base:
        return {}, noises
    return dict.fromkeys(best, DISTANCE), noises
