"""The randomized X-map oracle suite (issue 14): for each seed, a small scene from
``random_scenes`` and its X map against the Cycles oracle at 64x36: mean absolute error <= 0.01
and 99th percentile <= 0.05 over the non-silhouette pixels with a surface.

A handful of seeds runs with the suite; all 50 with ``-m slow`` (``bench/bench_xmap_oracle.py``
prints the worst seed's figures). A seed that fails becomes a named test in
``test_xmap_coincident.py`` (or next to the code at fault) before it is fixed."""
from __future__ import annotations

import pytest

from support.random_scenes import build_random_scene
from support.xmap_scenes import OracleComparison

pytestmark = [pytest.mark.blender, pytest.mark.render]

#: Seeds of the everyday suite, a few seconds each, between them: an OpenVDB grid, the
#: clip start inside a box, the eye on a box's face, a torus (not convex), the camera
#: inside with a nested sphere, orthographic with shift, noise and gradient densities,
#: world volumes, generated coordinates. Ties are exercised by test_xmap_coincident.py.
SEEDS = (7, 8, 9, 10, 11, 12)
SLOW_SEEDS = tuple(range(50))


def _check(blender, seed):
    built = build_random_scene(blender, seed)
    compared = OracleComparison(blender, built.scene)
    assert compared.mae <= 0.01 and compared.p99 <= 0.05, \
        f"{compared.describe()}; {built.describe()}"


@pytest.mark.parametrize("seed", SEEDS)
def test_x_matches_cycles_on_a_random_scene(blender, seed):
    _check(blender, seed)


@pytest.mark.slow
@pytest.mark.parametrize("seed", SLOW_SEEDS)
def test_x_matches_cycles_on_fifty_random_scenes(blender, seed):
    _check(blender, seed)
