"""Whether an ``--estimator auto`` run renders with Cycles' light tree.

With one light the tree has nothing to pick and only costs: the same estimate, in more time,
most where a volume step is cheap. With several it changes which light each sample takes and
pays for itself, so auto keeps it there, and where lights are linked (docs/performance.md,
"Cycles' light tree"). What Cycles samples as a light, checked against its own renders
(``tests/test_light_tree.py``): every lamp, every emissive surface whose emission sampling is
not None, and the world only where its background varies over directions."""
from __future__ import annotations


def auto_light_tree(scene_uses_tree: bool, sampled_lights: int, links_lights: bool = False) -> bool | None:
    """The light-tree setting auto renders with: False (off) where the scene has it on and
    Cycles samples at most one light (``sampled_lights``), without light linking
    (``links_lights``); None (the scene's own) otherwise."""
    if scene_uses_tree and sampled_lights <= 1 and not links_lights:
        return False
    return None
