"""``--estimator auto`` for a scene: predict ray marching's bias from the media and choose.

The camera rays are cast at a reduced size (about ``PREDICTION_PIXELS`` rays over the
frame) and the media scanned as the X map scans them; ``core.media.light_paths`` predicts
the picture's error along the light's whole path (camera and shadow rays marched as Cycles
marches them at each candidate step rate) and ``core.sampling.volume_estimator`` picks the
rate. Where the prediction cannot be trusted (media only Cycles can evaluate, lights it
cannot model, strong multiple scattering, light gathered mostly in homogeneous media, a
textured world medium) the scene's own settings are kept and the reason said. The seconds
it takes are the run's (a phase of its statistics).
"""
from __future__ import annotations

import math
import time
from dataclasses import replace

from ...core.maps.transmittance import medium_segments
from ...core.media.ray_marching import medium_step, sample_pixels
from ...core.sampling.render_options import RenderOptions
from ...core.sampling.light_tree import auto_light_tree
from ...core.sampling.sample_pattern import auto_sample_pattern
from ...core.sampling.volume_estimator import (CANDIDATE_RATES, EstimatorChoice, choose_step_rate,
                                               fixed_choice, homogeneous_choice,
                                               kept_scene_settings, per_medium_rates)
from ..scene.geometry import kept_carriers, media_by_carrier, scan_scene, step_setting
from ..scene.light_sampling import links_lights, sampled_lights
from ..scene.probe import camera_model, render_size
from .light_paths import light_path_predictor, scene_emitters
from .scatter_choice import scatter_sampling
from .zbuffer import cast_camera_rays

#: Camera rays the prediction marches: its 95th percentile needs a few hundred; each costs
#: RUNS marches of up to 4 / rate steps per medium crossing (balls_b: 0.3 s in all).
PREDICTION_PIXELS = 600
#: Auto keeps the scene's settings where more than this share of the media's single-scattered
#: light is gathered in homogeneous media, where Cycles' ray marching is the noisier estimator
#: and saves no octree (a thin fog box holding a thin smoke under a lamp: 1.5-2.8x null
#: scattering's pixel variance at equal samples, at every step rate).
HOMOGENEOUS_LIGHT_SHARE = 0.3
#: With volume bounces, the scattering optical depth (95th percentile over the frame) above
#: which auto keeps the scene's settings: multiple scattering is then a real part of the
#: light, and marching overestimates every bounce's transmittance (a sun-lit cloud with 8
#: bounces: 3.5-5x the single-scattering error; docs/light_paths.md).
MULTIPLE_SCATTERING_DEPTH = 0.3


def choose_estimator(scene, options: RenderOptions, spp: float) -> EstimatorChoice:
    """The volume estimator a run of ``spp`` samples per pixel renders with, and for auto the
    sample pattern (blue noise, its sequence rounded up to a power of two, where the file
    carries the legacy pattern or plain blue noise: ``core.sampling.sample_pattern``), the
    light tree (off where the scene has one light: ``core.sampling.light_tree``) and each
    medium's volume sampling while it ray-marches (``core.media.scatter_sampling``).

    ``options.estimator`` other than auto is taken as given; auto predicts (``_volumes``),
    never trying a step rate above ``options.step_rate`` when one is given. A range takes
    one choice per shot (``shot_choice``).
    """
    if options.estimator != "auto":
        return fixed_choice(options.estimator, options.step_rate)
    return replace(_volumes(scene, options, spp),
                   sample_pattern=auto_sample_pattern(scene.cycles.sampling_pattern),
                   light_tree=_light_tree(scene))


def _light_tree(scene) -> bool | None:
    """Auto's light tree: off where Cycles samples one light (``core.sampling.light_tree``)."""
    import bpy

    if not scene.cycles.use_light_tree:
        return None
    return auto_light_tree(True, sampled_lights(scene, bpy.context.evaluated_depsgraph_get()),
                           links_lights(scene))


def _volumes(scene, options: RenderOptions, spp: float) -> EstimatorChoice:
    """Auto's volume estimator: the prediction of the module notes."""
    import bpy

    started = time.perf_counter()

    def done(choice: EstimatorChoice) -> EstimatorChoice:
        return replace(choice, seconds=time.perf_counter() - started)

    depsgraph = bpy.context.evaluated_depsgraph_get()
    geometry, media = scan_scene(scene, depsgraph)
    opaque = [m.name for m in media if not m.evaluable]
    if opaque:
        return done(kept_scene_settings(f"medium '{opaque[0]}' is evaluated only by Cycles, so ray "
                                         "marching's error in it cannot be predicted"))
    if not media:
        return done(replace(fixed_choice("scene", None), estimator="auto", reason="no participating media"))
    width, height = options.resolution or render_size(scene)
    count = PREDICTION_PIXELS
    scale = min(1.0, math.sqrt(count / (width * height)))
    camera = camera_model(scene, size=(max(4, round(width * scale)), max(4, round(height * scale))))
    rays = cast_camera_rays(camera, geometry)
    segments = [medium_segments(rays, m) for m in media]
    pixels = sample_pixels(rays.shape, count)
    methods, noises, own, homogeneous = scatter_sampling(scene, depsgraph, rays, media, segments, pixels)
    scatter = dict(scatter_sampling=methods or None, scatter_noise=noises or None, scatter_own=own or None)
    if not any(math.isfinite(medium_step(m)) for m in media):
        return done(replace(homogeneous_choice(), **scatter))
    if homogeneous > HOMOGENEOUS_LIGHT_SHARE:
        return done(replace(homogeneous_choice(f"{homogeneous:.0%} of the media's light is gathered in "
                                               "homogeneous media"), **scatter))
    varying_world = [m.name for m in media if m.kind == "world" and math.isfinite(medium_step(m))]
    if varying_world:
        # Outside what the prediction was checked on: it fell short of Cycles there (lit suite,
        # docs/light_paths.md).
        return done(replace(kept_scene_settings(
            f"the world's medium ('{varying_world[0]}') varies in space, where auto's prediction of ray "
            "marching's error is not yet validated"), **scatter))
    emitters, unmodelled = scene_emitters(scene, depsgraph)
    if unmodelled:
        return done(replace(kept_scene_settings(f"{unmodelled}, so the light through the media cannot be "
                                                "modelled"), **scatter))
    predictor = light_path_predictor(scene, depsgraph, rays, geometry, media, segments, pixels,
                                     emitters, rates=CANDIDATE_RATES)
    bounces = int(scene.cycles.volume_bounces)
    if predictor is not None and bounces > 0 and predictor.scattering_depth() > MULTIPLE_SCATTERING_DEPTH:
        return done(replace(kept_scene_settings(
            f"light scatters up to {bounces} times in the media (volume bounces), where ray marching's "
            "error grows with every bounce; auto predicts it for single scattering"), **scatter))

    def measure(rate) -> float:
        return 0.0 if predictor is None else predictor.error(rate).visible()

    choice = choose_step_rate(measure, spp, largest=options.step_rate)
    choice = _per_medium(choice, media, measure, options.step_rate)
    # Kept for a time-budgeted still's settle, which may need finer rates or the media's
    # steps at another scene rate (``settled_for``).
    choice = replace(choice, remeasure=measure)
    kept = "".join(f"; {reason}" for reason in kept_carriers(media).values())
    return done(replace(choice, reason=choice.reason + kept, **scatter))


def step_carriers(media) -> dict:
    """What carries each heterogeneous medium's step in Blender -> its media's indices:
    "material:<name>" (``volume_step_rate``, shared by the material's users) or
    "world:<name>" (``volume_step_size``). Homogeneous media take one exact step."""
    return media_by_carrier(media, keep=lambda medium: math.isfinite(medium_step(medium)))


def _per_medium(choice: EstimatorChoice, media, measure, largest) -> EstimatorChoice:
    """``per_medium_rates``: coarser steps for the media whose error allows them."""
    groups = step_carriers(media)
    own = {key: float(getattr(*step_setting(key))) for key in groups}
    return per_medium_rates(choice, measure, groups, len(media), own, CANDIDATE_RATES, largest)


def with_estimator_choice(scene, options: RenderOptions, spp: float) -> RenderOptions:
    """``options`` with auto's choice for the scene at its current frame (unchanged for the
    other estimators, or when chosen already)."""
    if options.estimator != "auto" or options.estimator_choice is not None:
        return options
    return replace(options, estimator_choice=choose_estimator(scene, options, spp))
