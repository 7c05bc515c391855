"""Auto's volume sampling per medium against the noise Cycles itself renders: the oracle of
``test_scatter_sampling.py``, ``test_scatter_random.py`` and ``bench/bench_scatter_random.py``."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Renders per setting: 4 samples each, seeds 0 .. SEEDS - 1.
SEEDS = 6


def cycles_noise(blender, scene, methods: dict, seeds: int = SEEDS) -> float:
    """Cycles' own relative noise with each medium carrier in ``methods`` ("material:<name>"
    or "world:<name>") at its method, the others as the file has them: the pixels' variance
    over seeds (4 spp, ray marching at the scene's rate, no denoising) over their mean
    squared."""
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.geometry import step_setting
    from xsl_render.addon.scene.state import preserved_scene

    renders = []
    for seed in range(seeds):
        forget_synced_session()
        with preserved_scene(scene):
            scene.cycles.volume_biased = True
            for key, method in methods.items():
                step_setting(key)[0].volume_sampling = method
            with CyclesWindowRenderer(scene, seed) as renderer:
                renders.append(renderer.render(None, 4).pixels[..., :3].mean(axis=2))
    stack = np.stack(renders)
    return float(stack.var(axis=0).mean() / max(stack.mean() ** 2, 1e-12))


@dataclass
class SceneVerdict:
    """Auto's volume sampling on one scene beside Cycles' noise: with auto's methods and with
    every carrier at distance, each over the noise with every carrier at its own method."""

    switched: dict            # {carrier: method} auto sets
    predicted: dict           # {carrier: {method: predicted noise}}
    own: dict                 # {carrier: own method} of the carriers that could switch
    auto_ratio: float | None  # Cycles: auto's methods over the own (None: nothing switched)
    distance_ratio: float     # Cycles: every carrier at distance over the own

    def describe(self) -> str:
        singles = "; ".join(f"{key} ({self.own[key][:4].lower()}): " + (
            f"distance/own {noise['DISTANCE'] / noise[self.own[key]]:.2f}" if noise[self.own[key]] > 0
            else "no noise predicted") for key, noise in sorted(self.predicted.items()) if key in self.own)
        auto = (f"switched {', '.join(sorted(self.switched))}, Cycles {self.auto_ratio:.2f}"
                if self.switched else "kept")
        return f"predicted {singles}; {auto}; Cycles all at distance {self.distance_ratio:.2f}"


def auto_scatter(scene, spp: int = 16):
    """(auto's estimator choice on ``scene``, {carrier: its own method} of the carriers that
    could switch to distance, those not at distance already)."""
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.addon.scene.geometry import step_setting
    from xsl_render.core.media.scatter_sampling import DISTANCE
    from xsl_render.core.sampling.render_options import RenderOptions

    choice = choose_estimator(scene, RenderOptions(max_spp=spp, estimator="auto").check(), spp)
    own = {key: step_setting(key)[0].volume_sampling for key in choice.scatter_noise or {}}
    return choice, {key: method for key, method in own.items() if method != DISTANCE}


def scene_verdict(blender, scene, spp: int = 16) -> SceneVerdict | None:
    """Auto's choice on ``scene`` judged by Cycles (None where no carrier could switch)."""
    from xsl_render.core.media.scatter_sampling import DISTANCE

    choice, own = auto_scatter(scene, spp)
    predicted = choice.scatter_noise or {}
    if not own:
        return None
    base = max(cycles_noise(blender, scene, {}), 1e-12)
    switched = choice.scatter_sampling or {}
    auto_ratio = cycles_noise(blender, scene, switched) / base if switched else None
    distance_ratio = cycles_noise(blender, scene, dict.fromkeys(own, DISTANCE)) / base
    return SceneVerdict(switched, predicted, own, auto_ratio, distance_ratio)
