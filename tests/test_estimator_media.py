"""Auto gives media that allow it their own coarser step (a material's ``volume_step_rate``,
the world's ``volume_step_size``) beside the scene rate.

The scene rate is chosen for the medium that needs the finest step; a smoother medium in the
same scene then marches at that step too, and a voxel-sized step through OpenVDB smoke costs
more than null scattering (statue at rate 0.5: 11.6 s against 4.9 s at 16 spp). Cycles
multiplies the material's rate into the medium's step, so the choice can be made per medium.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from test_ray_marching import _Field, _two_media_scene

from xsl_render.core.maps.camera_rays import CameraRays, MediumIntervals
from xsl_render.core.media.ray_marching import MarchingPredictor
from xsl_render.core.sampling.volume_estimator import (EstimatorChoice, settled_for,
                                                       choose_step_rate, per_medium_rates,
                                                       tolerated_bias)

W, H = 48, 27


#: The measures here are written against a tolerance of 0.05 / sqrt(spp) (conftest).
pytestmark = pytest.mark.usefixtures("tolerance_units")


# -- the predictor with a rate per medium ------------------------------------------------
def _two_fields():
    """Rays 0-3 cross medium "a" only, rays 4-7 medium "b" only (x from 0 to 10)."""
    count = 8
    origins = np.zeros((1, count, 3))
    origins[0, :, 1] = np.arange(count)
    directions = np.zeros((1, count, 3))
    directions[..., 0] = 1.0
    intervals = {key: MediumIntervals(ray=np.asarray(rays, np.int32), t0=np.zeros(4), t1=np.full(4, 10.0))
                 for key, rays in (("a", range(4)), ("b", range(4, 8)))}
    rays = CameraRays(size=(1, count), window=(0, 1, 0, count), origins=origins, directions=directions,
                      t_near=np.zeros((1, count)), t_far=np.full((1, count), 15.0),
                      hit=np.ones((1, count), bool), view_axis=np.array([1.0, 0.0, 0.0]),
                      intervals=intervals)
    wavy = [_Field(lambda p, k=k: np.repeat((0.3 + 0.25 * np.sin(k * p[:, :1])), 3, axis=1), 0.8, key)
            for k, key in ((3.0, "a"), (1.3, "b"))]
    from xsl_render.core.maps.transmittance import medium_segments

    return MarchingPredictor(rays, wavy, [medium_segments(rays, m) for m in wavy], np.arange(count))


def test_one_rate_per_medium_marches_each_medium_at_its_own():
    predictor = _two_fields()
    same = predictor.error((1.0, 1.0))
    np.testing.assert_array_equal(same.bias, predictor.error(1.0).bias)
    mixed = predictor.error((1.0, 4.0))
    # Each ray crosses one medium: its error is that medium's at its own rate.
    np.testing.assert_allclose(mixed.bias[:4], predictor.error(1.0).bias[:4], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(mixed.bias[4:], predictor.error(4.0).bias[4:], rtol=1e-12, atol=1e-15)
    assert np.abs(mixed.bias[4:]).max() > 1e-3 > np.abs(predictor.error(1.0).bias[4:]).max() / 10
    with pytest.raises(ValueError, match="2 media"):
        predictor.error((1.0, 2.0, 4.0))


# -- the choice ----------------------------------------------------------------------------
def _chosen(rate=0.5, measure=0.008, spp=16) -> EstimatorChoice:
    return EstimatorChoice("auto", biased=True, step_rate=rate, predicted_bias=measure,
                           tolerance=tolerated_bias(spp), tried={rate: measure}, reason="r")


#: The materials' and world's own step values.
OWN = {"material:fog": 1.0, "material:smoke": 1.5, "world:World": 0.2}


def _measure_of(allowed: dict):
    """A measure that passes while each medium's rate is at most ``allowed[m]`` (else 1)."""
    calls = []

    def measure(rates):
        calls.append(rates)
        return 0.01 if all(r <= allowed[m] for m, r in enumerate(rates)) else 1.0
    return measure, calls


@pytest.mark.parametrize("allowed, expected", [
    ({0: 0.5, 1: 4.0, 2: 0.5}, {"material:smoke": 4.0}),
    ({0: 0.5, 1: 1.0, 2: 2.0}, {"material:smoke": 1.0, "world:World": 2.0}),
    ({0: 0.5, 1: 0.5, 2: 0.5}, None),
])
def test_each_medium_takes_the_coarsest_rate_its_bias_allows(allowed, expected):
    measure, calls = _measure_of(allowed)
    groups = {"material:fog": (0,), "material:smoke": (1,), "world:World": (2,)}
    chosen = per_medium_rates(_chosen(), measure, groups, 3, OWN)
    assert chosen.medium_rates == expected
    assert chosen.step_rate == 0.5 and chosen.biased
    assert all(rates[m] >= 0.5 for rates in calls for m in range(3))       # never finer
    if expected:
        assert chosen.predicted_bias == 0.01 and "coarser, within" in chosen.reason
        assert "smoke at" in chosen.describe() or "World at" in chosen.describe()


def test_no_medium_coarser_than_a_given_step_rate_nor_than_the_limit():
    measure, calls = _measure_of({0: 0.5, 1: 4.0})
    capped = per_medium_rates(_chosen(), measure, {"material:fog": (0,), "material:smoke": (1,)}, 2, OWN,
                              largest=2.0)
    assert capped.medium_rates == {"material:smoke": 2.0}
    # Chosen within the null-scattering margin (measure above the tolerance): the limit is
    # its own measure, not the tolerance.
    over = _chosen(measure=0.02)
    assert per_medium_rates(over, lambda rates: 0.015 if rates[1] <= 1 and rates[0] <= 0.5 else 0.03,
                            {"material:fog": (0,), "material:smoke": (1,)}, 2, OWN).medium_rates \
        == {"material:smoke": 1.0}


@pytest.mark.parametrize("choice", [
    _chosen(),                                                               # one carrier only
    EstimatorChoice("auto", biased=False, tolerance=0.01, tried={0.25: 0.5}),  # null scattering
    EstimatorChoice("biased", biased=True, step_rate=1.0),                   # asked for
])
def test_nothing_is_predicted_where_no_medium_could_take_its_own_step(choice):
    def never(rates):
        raise AssertionError("predicted")
    groups = {"material:fog": (0,)} if choice.estimator == "auto" and choice.biased else \
        {"material:fog": (0,), "material:smoke": (1,)}
    chosen = per_medium_rates(choice, never, groups, 2, OWN)
    if choice.estimator == "auto" and choice.biased is False:
        # Null scattering keeps what carries each step, for a settle that marches.
        assert chosen.medium_rates is None and chosen.media["tried"] == []
        assert chosen.media["groups"] == {"material:fog": [0], "material:smoke": [1]}
    else:
        assert chosen == choice


def test_a_settled_count_chooses_the_media_steps_again_from_the_ceilings_trials():
    """Guided learns its count after its pilot: with the same scene rate the media steps are
    chosen again for the larger tolerance from the trials made for the ceiling (no new
    prediction); with another scene rate the materials get their own values back."""
    tried = {4.0: 0.16, 2.0: 0.11, 1.0: 0.04, 0.5: 0.008}
    ceiling = choose_step_rate(tried.__getitem__, 32, rates=tuple(tried))   # 0.5: 0.8 % within 0.88 %
    # The limit is then 0.88 %: the smoke at 4 is just over it, at 2 within it.
    measures = {(0.5, 4.0): 0.0095, (0.5, 2.0): 0.0079, (4.0, 0.5): 0.5, (2.0, 0.5): 0.3, (1.0, 0.5): 0.05}
    groups = {"material:fog": (0,), "material:smoke": (1,)}
    chosen = per_medium_rates(ceiling, measures.__getitem__, groups, 2, OWN)
    assert chosen.step_rate == 0.5 and chosen.medium_rates == {"material:smoke": 2.0}
    assert chosen.medium_settings == {"material:smoke": pytest.approx(1.5 * 2.0 / 0.5)}
    assert chosen.to_dict()["media"]["tried"][0] == [[4.0, 0.5], 0.5]             # JSON-ready
    settled = settled_for(chosen, 16)                            # tolerance 1.25 %
    assert settled.step_rate == 0.5 and settled.medium_rates == {"material:smoke": 4.0}
    assert settled.medium_settings == {"material:smoke": pytest.approx(1.5 * 4.0 / 0.5)}
    assert settled.predicted_bias == 0.0095
    # Rate 1 passes at 1 spp: the media steps were not measured with it, and the smoke's
    # material gets its own value back (the pilot may have set the coarser one).
    moved = settled_for(chosen, 1)
    assert moved.step_rate == 1.0 and moved.medium_rates is None
    assert moved.medium_settings == {"material:fog": 1.0, "material:smoke": 1.5}


#: Visible bias of the fog (medium 0) and the smoke (medium 1) at each rate; a frame's is
#: their sum (each ray crosses one of them).
FOG = {4.0: 0.15, 2.0: 0.1, 1.0: 0.038, 0.5: 0.006, 0.25: 0.003}
SMOKE = {4.0: 0.004, 2.0: 0.002, 1.0: 0.001, 0.5: 0.001, 0.25: 0.001}


def _predicted():
    calls = []

    def measure(rates):
        calls.append(rates)
        fog, smoke = (rates, rates) if isinstance(rates, float) else rates
        return FOG[fog] + SMOKE[smoke]
    return measure, calls


@pytest.mark.parametrize("ceiling, count, scene_rate, smoke", [
    (64, 1, 1.0, 4.0),         # 0.5 at the ceiling, 1 at 1 spp: the smoke at 4 beside it
    (4096, 16, 0.5, 4.0),      # null scattering at the ceiling, 0.5 at 16 spp
])
def test_a_settle_at_another_scene_rate_predicts_the_media_steps_there(ceiling, count, scene_rate, smoke):
    """While the choice keeps its prediction (a still's run), a settle that moves the scene
    rate (or leaves null scattering) tries the media's steps at the new rate; without it the
    materials keep their own values."""
    from dataclasses import replace

    measure, calls = _predicted()
    groups = {"material:fog": (0,), "material:smoke": (1,)}
    chosen = per_medium_rates(choose_step_rate(measure, ceiling), measure, groups, 2, OWN)
    assert chosen.step_rate != scene_rate
    kept = replace(chosen, remeasure=measure)
    assert kept == chosen and "remeasure" not in kept.to_dict()          # not part of the record
    json.dumps(kept.to_dict())
    calls.clear()
    settled = settled_for(kept, count)
    assert settled.step_rate == scene_rate and settled.medium_rates == {"material:smoke": smoke}
    assert settled.medium_settings == {"material:smoke": pytest.approx(OWN["material:smoke"] * smoke / scene_rate)}
    assert (scene_rate, smoke) in calls and all(min(rates) == scene_rate for rates in calls)   # none finer
    assert settled.predicted_bias == pytest.approx(FOG[scene_rate] + SMOKE[smoke])
    unkept = settled_for(chosen, count)
    assert unkept.step_rate == scene_rate and unkept.medium_rates is None
    assert unkept.medium_settings == {"material:fog": 1.0, "material:smoke": 1.5}


# -- in Blender ----------------------------------------------------------------------------
@pytest.mark.blender
@pytest.mark.render
def test_a_materials_step_rate_reaches_cycles_and_multiplies_the_scene_rate(blender):
    """In one persistent session a material's new step rate renders (it needs the material's
    own tag), and material rate 4 at scene rate 1 renders the same pixels as the reverse:
    on a scene with one marched medium, a sweep of material rates is the scene-rate sweep."""
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene, settings_dump

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    media = [blender.data.materials["noise fog"], blender.data.materials["smoke"]]
    before = settings_dump(scene)
    forget_synced_session()
    with preserved_scene(scene):
        scene.cycles.volume_biased, scene.cycles.volume_step_rate = True, 1.0
        with CyclesWindowRenderer(scene, 0) as renderer:
            fine = renderer.render(None, 2).pixels
            for material in media:
                material.cycles.volume_step_rate = 4.0
            coarse_materials = renderer.render(None, 2).pixels
            scene.cycles.volume_step_rate = 4.0
            for material in media:
                material.cycles.volume_step_rate = 1.0
            coarse_scene = renderer.render(None, 2).pixels
    assert np.abs(coarse_materials - fine).max() > 1e-3
    np.testing.assert_array_equal(coarse_materials, coarse_scene)
    assert settings_dump(scene) == before


@pytest.mark.blender
@pytest.mark.render
def test_auto_gives_the_smoke_its_own_step_and_the_scene_gets_its_materials_back(blender):
    """The two-media scene: a dense noise fog (which needs rate 0.5 at 16 spp) over an
    OpenVDB smoke (fine at 4): auto marches the scene at 0.5 and the smoke at 4, the stats say
    so, Cycles renders it (the image is the one the same settings made by hand give), and
    the scene's and materials' settings are back afterwards."""
    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.cycles.sample_pattern import apply_sample_pattern
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.addon.scene.state import preserved_scene, settings_dump
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    smoke_material = blender.data.materials["smoke"]
    smoke_material.cycles.volume_step_rate = 1.5                           # the artist's own
    before = settings_dump(scene)
    options = with_estimator_choice(scene, RenderOptions(max_spp=16, estimator="auto", denoise=False), 16)
    auto = sr.render_uniform(scene, options, spp=16)
    assert settings_dump(scene) == before
    estimator = auto.stats.estimator
    rate, smoke = estimator["step_rate"], estimator["medium_rates"]["material:smoke"]
    assert smoke > rate and "material:noise fog" not in estimator["medium_rates"]
    assert estimator["medium_settings"]["material:smoke"] == pytest.approx(1.5 * smoke / rate)
    assert estimator["predicted_bias"] <= max(estimator["tolerance"], estimator["tried"][f"{rate:g}"])
    assert "smoke at" in estimator["described"]
    # The same settings by hand, with the scene's own estimator (and the sample pattern auto
    # renders this legacy-pattern test scene with: core.sampling.sample_pattern).
    assert estimator["sample_pattern"] == "BLUE_NOISE_ROUND"
    with preserved_scene(scene):          # (the debug options the pattern needs come back off)
        apply_sample_pattern(scene, estimator["sample_pattern"])
        scene.cycles.volume_biased, scene.cycles.volume_step_rate = True, rate
        smoke_material.cycles.volume_step_rate = 1.5 * smoke / rate
        by_hand = sr.render_uniform(scene, RenderOptions(max_spp=16, denoise=False), spp=16)
        np.testing.assert_array_equal(auto.image, by_hand.image)
        smoke_material.cycles.volume_step_rate = 1.5
        scene.cycles.volume_step_rate = rate
        # The smoke's own step showed (the same settings render bit-identically, as above).
        assert np.abs(sr.render_uniform(scene, RenderOptions(max_spp=16, denoise=False), spp=16).image
                      - auto.image).max() > 1e-4


@pytest.mark.blender
@pytest.mark.parametrize("first, count", [(4096, 16), (4, 64)])
def test_settling_a_choice_gives_the_choice_made_for_the_count(blender, first, count):
    """On the two-media scene, auto's choice for one count settled for another is the choice
    made for that count directly: from a ceiling no rate passes at (null scattering) down to
    16 spp, the scene rate from the trials made, the smoke's own step predicted at it; from
    4 spp up to 64, the finer rates
    predicted then."""
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    options = RenderOptions(max_spp=4096, estimator="auto").check()
    chosen = choose_estimator(scene, options, first)
    direct = choose_estimator(scene, options, count)
    assert chosen.remeasure is not None and chosen.step_rate != direct.step_rate
    if first > count:
        assert chosen.biased is False and chosen.media["tried"] == []
    assert direct.biased and direct.medium_rates
    settled = settled_for(chosen, count)
    assert (settled.biased, settled.step_rate, settled.medium_rates, settled.medium_settings) \
        == (direct.biased, direct.step_rate, direct.medium_rates, direct.medium_settings)
    assert settled.predicted_bias == pytest.approx(direct.predicted_bias)
    assert settled.tolerance == pytest.approx(direct.tolerance)


@pytest.mark.blender
@pytest.mark.render
def test_the_artists_next_render_has_the_materials_own_steps_again(blender, tmp_path):
    """With the artist's persistent data on, a run that rendered a material with its own
    coarser step leaves a session that would keep it: the material needs its own tag when
    the run puts its value back (a scene tag does not make Cycles read it again)."""
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.imageio import read_image

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.render.use_persistent_data = True
    scene.cycles.volume_biased, scene.cycles.samples, scene.cycles.use_denoising = True, 2, False
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.filepath = str(tmp_path / "f12")
    smoke = blender.data.materials["smoke"]

    def artists_render():
        blender.ops.render.render(write_still=True, scene=scene.name)
        return read_image(tmp_path / "f12.exr")

    before = artists_render()
    with preserved_scene(scene):
        smoke.cycles.volume_step_rate = 8.0
        with CyclesWindowRenderer(scene, 0) as renderer:
            renderer.render(None, 2)
    assert smoke.cycles.volume_step_rate == 1.0
    np.testing.assert_array_equal(artists_render(), before)


@pytest.mark.blender
@pytest.mark.render
def test_guided_renders_the_media_steps_it_settles_on(blender, monkeypatch):
    """A settled choice with the same scene rate but other media steps (the smoke coarser
    for the budget's count) is what Cycles renders the final pass with, not the pilot's;
    the material's own value comes back afterwards."""
    from dataclasses import replace

    from xsl_render.addon.cycles import guided_render
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.core.sampling.guided_plan import GuidedOptions
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    smoke = blender.data.materials["smoke"]
    options = with_estimator_choice(scene, RenderOptions(max_spp=16, estimator="auto").check(), 16)
    chosen = options.estimator_choice
    pilot = chosen.medium_settings["material:smoke"]
    assert pilot > 2.0                                  # the smoke coarser than the scene rate
    settled = replace(chosen, medium_rates={"material:smoke": 1.0}, medium_settings={"material:smoke": 2.0})
    seen = []
    real_render = CyclesWindowRenderer.render

    def spying(self, *args, **kwargs):
        seen.append(smoke.cycles.volume_step_rate)
        return real_render(self, *args, **kwargs)

    monkeypatch.setattr(CyclesWindowRenderer, "render", spying)
    monkeypatch.setattr(guided_render, "settled_for", lambda choice, spp: settled)
    outcome = guided_render.render_guided(scene, options, GuidedOptions(time_budget=2.0))
    assert seen[0] == pilot and seen[-1] == 2.0
    assert outcome.stats.estimator["medium_settings"] == {"material:smoke": 2.0}
    assert smoke.cycles.volume_step_rate == 1.0
