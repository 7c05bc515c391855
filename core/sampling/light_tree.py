"""Whether an ``--estimator auto`` run renders with Cycles' light tree.

Cycles picks the light a shading point (or a volume segment) samples with its light tree by
default: an estimate of each light's importance from where the point is, which pays where a
scene has many lights. With one light there is nothing to pick, and the tree only costs: the
same estimate (the renders differ by rounding, 0.01-0.05 % of what another seed changes, and
score the same mean FLIP, p95 region FLIP and MSE to the digits printed) in more time. In fog
the cost comes with every scatter event (a volume segment's importance), so it grows with
the samples and weighs most where a step is cheap. Measured (``bench/bench_light_tree.py``,
``docs/bench_light_tree.txt``: auto's choice with and without the file's tree, the whole
frame in a fresh session, medians of 4 seeds): balls_a (one area light, homogeneous fog)
1.16 / 1.38 / 1.23x faster at 4 / 16 / 32 spp; balls_b (the same light, noise fog marched at
rate 0.5) 0.99 / 1.15 / 0.98x, within its spread. With two lights or more the tree changes
which light each sample takes, and on the example scenes that have several it is worth its
time: without it statue (a spot and an area light) rendered 16 spp in 0.82x the time at mean
FLIP 0.0441 against 0.0405, 0.94x the time the tree's curve needs for that FLIP (0.83x at 32
spp); road (eight lamps) 0.95x and 0.77x. So auto keeps it there.

What Cycles samples as a light (checked against Cycles' own renders, tree against no tree:
``tests/test_light_tree.py``): every lamp, every emissive surface whose material's emission
sampling is not None, and the world only where its background varies over directions (a
constant colour is not sampled, whatever its sampling method, nor any world whose sampling
method is None). A scene that links lights (Blender's light and shadow linking, which Cycles
resolves in its tree) keeps it: not measured here.
"""
from __future__ import annotations


def auto_light_tree(scene_uses_tree: bool, sampled_lights: int, links_lights: bool = False) -> bool | None:
    """The light-tree setting auto renders with: False (off) where the scene has it on and
    Cycles samples at most one light (``sampled_lights``), without light linking
    (``links_lights``); None (the scene's own) otherwise."""
    if scene_uses_tree and sampled_lights <= 1 and not links_lights:
        return False
    return None
