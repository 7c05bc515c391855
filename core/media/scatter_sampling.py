"""Where along a camera ray Cycles places the scattering that gathers direct light, per medium:
its ``volume_sampling`` (distance, equiangular, or both with multiple importance), predicted
from the media and the lights, for ``--estimator auto``.

Single scattering along a ray is the integral of f(t) = sigma_s(t) T(t) G(t) over the ray in
the medium, with T the transmittance from the eye and G = 1 / |x(t) - light|^2 (the light's
own attenuation and the phase function left out: both sampling methods ignore them).
Distance sampling draws t with density proportional to sigma_t T, equiangular with density
proportional to G toward the light it sampled, and multiple importance draws from either;
each estimate is f / pdf, with the light taken in proportion to its power. The relative noise
of one sample, sqrt(second moment / integral^2 - 1), is computed per sampled camera ray by
quadrature, and combined over the rays weighted by what each gathers. Distance sampling wins
where the medium is thick and uneven and the lights are far from the rays (then G hardly
varies and sigma_t T carries the integrand); equiangular where a lamp sits in thin fog near
the rays (G peaks).

Measured against Cycles (auto's ray marching, 16 spp, OIDN as auto denoises, medians of 3
seeds, mean FLIP against the converged references; ``bench/bench_scatter_sampling.py``,
``docs/bench_scatter_sampling.txt``), with the prediction for distance / both / equiangular:

- balls_b (noise fog lit by an area light from outside): distance 0.0430 in 7.53 s, the
  material's own multiple importance 0.0473 in 8.11 s, equiangular 0.0506; predicted 0.25 /
  0.60 / 1.19.
- statue (smoke, a spot and an area light beside it): 0.0403 in 7.65 s, 0.0409 in 8.59 s,
  0.0409; predicted 0.26 / 0.58 / 1.05.
- balls_a (the same room in thin homogeneous fog): 0.0310, 0.0274, 0.0295; predicted 0.31 /
  0.20 / 0.09.
- street (lamps inside noise fog): 0.0742, 0.0632, 0.0651; predicted 3.37 / 1.71 / 1.89.
- road (lamps in world fog; the world's own method is equiangular): 0.0571, 0.0434, 0.0392;
  predicted 4.56 / 1.57 / 1.22.

Distance sampling is also the cheapest per sample (one strategy instead of two). The
prediction ranks distance against the own method as Cycles does on all five, and all three
methods as Cycles does on four (balls_a: equiangular predicted first, measured second by 8 %).
So auto switches a medium to distance sampling only where that is predicted to leave less
than ``DISTANCE_MARGIN`` of its own method's noise (balls_b 0.41, statue 0.44; balls_a,
street and road keep theirs), and never to equiangular.
"""
from __future__ import annotations

import math

import numpy as np

#: Cycles' names for the three methods (a material's or a world's ``volume_sampling``).
DISTANCE, EQUIANGULAR, BOTH = "DISTANCE", "EQUIANGULAR", "MULTIPLE_IMPORTANCE"
METHODS = (DISTANCE, EQUIANGULAR, BOTH)
#: Distance sampling replaces a medium's own method where its predicted noise is below this
#: share of the own method's (see the module notes: measured 0.41 on balls_b, where it paid).
DISTANCE_MARGIN = 0.5
#: Quadrature points per piece of a ray inside the media.
POINTS_PER_PIECE = 64
#: A piece of a ray is integrated over this length at most, in metres (a world fog reaches
#: to the sky; so far out nothing the eye sees is left).
MAX_PIECE_LENGTH = 200.0


def ray_noise(t: np.ndarray, dt: np.ndarray, sigma_t: np.ndarray, sigma_s: np.ndarray,
              points: np.ndarray, light_positions: np.ndarray, light_power: np.ndarray) -> tuple[dict, float]:
    """({method: relative noise of one sample}, the integral) of single scattering along one
    ray: quadrature points ``t`` (sorted) with widths ``dt``, the total extinction
    ``sigma_t`` there (transmittance and distance sampling), the scattering of the medium
    asked about ``sigma_s``, their world ``points``; lights (N, 3) with their power (N,)."""
    tau = np.cumsum(sigma_t * dt) - 0.5 * sigma_t * dt
    transmittance = np.exp(-tau)
    p_distance = sigma_t * transmittance
    norm = float((p_distance * dt).sum())
    if norm <= 0.0 or not len(light_power):
        return {}, 0.0
    p_distance = p_distance / norm
    choose = light_power / light_power.sum()
    moments = dict.fromkeys(METHODS, 0.0)
    integral = 0.0
    for position, power, chance in zip(light_positions, light_power, choose):
        if chance <= 0.0:
            continue
        g = 1.0 / np.maximum(((points - position) ** 2).sum(axis=1), 1e-6)
        f = sigma_s * transmittance * g * power
        p_equiangular = g / float((g * dt).sum())
        integral += float((f * dt).sum())
        for method, pdf in ((DISTANCE, p_distance), (EQUIANGULAR, p_equiangular),
                            (BOTH, 0.5 * (p_distance + p_equiangular))):
            moments[method] += float((f * f / np.maximum(pdf, 1e-30) * dt).sum()) / chance
    if integral <= 0.0:
        return {}, 0.0
    return {m: math.sqrt(max(moments[m] / integral ** 2 - 1.0, 0.0)) for m in METHODS}, integral


def combined_noise(per_ray: list[tuple[dict, float]]) -> dict:
    """The rays' noises combined, each weighted by what it gathers (root mean square)."""
    rays = [(noise, weight) for noise, weight in per_ray if noise and weight > 0.0]
    total = sum(weight for _, weight in rays)
    if not rays or total <= 0.0:
        return {}
    return {m: math.sqrt(sum(weight * noise[m] ** 2 for noise, weight in rays) / total) for m in METHODS}


def chosen_method(noise: dict, own: str) -> str | None:
    """Distance sampling where ``noise`` (``combined_noise``) puts it below ``DISTANCE_MARGIN``
    of the medium's ``own`` method's; None (its own) otherwise."""
    if not noise or own == DISTANCE or own not in noise:
        return None
    return DISTANCE if noise[DISTANCE] < DISTANCE_MARGIN * noise[own] else None
