"""Cycles' ray marching predicted in numpy (``core.media.ray_marching``) and the choice of
``--estimator`` (``core.sampling.volume_estimator``): the step rules, the bias against what
Cycles itself renders when it ray-marches, and the choice."""
from __future__ import annotations

import math

import numpy as np
import pytest

from xsl_render.core.errors import InputError
from xsl_render.core.maps.camera_rays import CameraRays, MediumIntervals
from xsl_render.core.media.ray_marching import (MarchingPredictor, procedural_step, sample_pixels,
                                                voxel_step)
from xsl_render.core.sampling.render_options import RenderOptions
from xsl_render.core.sampling.volume_estimator import (check_estimator, choose_step_rate,
                                                       tolerated_bias, visible_bias)

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


class _Field:
    """A stand-in medium: a world-space extinction function and its Cycles step."""

    def __init__(self, extinction, step, key="m"):
        self.key, self._extinction = key, extinction
        self.extra = {"cycles_step": step}
        self.kind, self.name = "mesh", key

    def constant_extinction(self):
        return None if math.isfinite(self.extra["cycles_step"]) else self._extinction(np.zeros((1, 3)))[0]

    def extinction(self, points):
        return self._extinction(np.asarray(points))


def _rays(length: float = 10.0, count: int = 8) -> CameraRays:
    """``count`` parallel rays along +x, each through a medium from x = 0 to ``length``."""
    origins = np.zeros((1, count, 3))
    origins[0, :, 1] = np.arange(count)
    directions = np.zeros((1, count, 3))
    directions[..., 0] = 1.0
    intervals = {"m": MediumIntervals(ray=np.arange(count, dtype=np.int32),
                                      t0=np.zeros(count), t1=np.full(count, length))}
    return CameraRays(size=(1, count), window=(0, 1, 0, count), origins=origins,
                      directions=directions, t_near=np.zeros((1, count)),
                      t_far=np.full((1, count), length + 5.0), hit=np.ones((1, count), bool),
                      view_axis=np.array([1.0, 0.0, 0.0]), intervals=intervals)


def _predict(medium, rays, rates=(1.0,), runs=16):
    from xsl_render.core.maps.transmittance import medium_segments

    predictor = MarchingPredictor(rays, [medium], [medium_segments(rays, medium)],
                                  np.arange(rays.count), runs=runs)
    return {rate: predictor.error(rate) for rate in rates}


def test_cycles_step_rules():
    # A tenth of the mean bounds edge for a procedural volume; the smallest world-space
    # component of the voxel diagonal for a grid.
    assert procedural_step((0, 0, 0), (2, 4, 6)) == pytest.approx(0.4)
    assert voxel_step(np.diag([0.1, 0.2, 0.05, 1.0])) == pytest.approx(0.05)


def test_a_constant_medium_is_marched_without_bias():
    constant = _Field(lambda p: np.full((len(p), 3), 0.3), step=0.7)
    for error in _predict(constant, _rays(), rates=(0.5, 1.0, 4.0)).values():
        np.testing.assert_allclose(error.transmittance, math.exp(-3.0), rtol=1e-9)
        np.testing.assert_allclose(error.bias, 0.0, atol=1e-12)
        np.testing.assert_allclose(error.spread, 0.0, atol=1e-12)


def _cycles_marching_mean(sigma, length, step, pairs=4000, seed=1):
    """E[exp(-tau)] of Cycles' ray marching along one ray written as its kernel loop reads
    (``volume_ray_marching_advance``): random (u, v), step ends at (k + u) * step clipped to
    the end, each step shaded at v of its length."""
    rng = np.random.default_rng(seed)
    total = 0.0
    for u, v in rng.random((pairs, 2)):
        tau, t_max, k = 0.0, 0.0, 0
        while t_max < length:
            t_min, t_max = t_max, min(length, (k + u) * step)
            tau += sigma(t_min + v * (t_max - t_min)) * (t_max - t_min)
            k += 1
        total += math.exp(-tau)
    return total / pairs


def test_the_bias_of_a_varying_medium_is_jensens_and_grows_with_the_step():
    # Density striped at 1 m along the rays (a phase per ray): steps finer than the stripes
    # barely miss exp(-tau); coarser ones shade the stripes at random, so the mean estimate
    # lies above the truth (Jensen) and one sample's estimate varies with the offsets.
    def stripes(points):
        return np.repeat((0.4 * (1.0 + np.sin(2.0 * np.pi * points[:, :1] + points[:, 1:2]))), 3, axis=1)

    rates = (0.125, 0.25, 0.5, 1.0)
    errors = _predict(_Field(stripes, step=1.0), _rays(), rates=rates, runs=256)
    truth = errors[1.0].transmittance
    np.testing.assert_allclose(truth, math.exp(-4.0), rtol=2e-3)   # 0.4 per metre over 10 m
    biases = [float(np.mean(errors[rate].bias)) for rate in rates]
    assert 0.0 <= biases[0] < biases[1] < biases[2] < biases[3]
    assert biases[0] < 1e-3 * truth.mean()
    assert np.mean(errors[1.0].spread) > 10 * np.mean(errors[0.125].spread)
    for ray in (0, 3):
        mean = _cycles_marching_mean(lambda t: 0.4 * (1.0 + math.sin(2.0 * math.pi * t + ray)), 10.0, 1.0)
        assert errors[1.0].bias[ray, 0] + truth[ray, 0] == pytest.approx(mean, rel=0.03)


def test_sample_pixels_cover_the_window_evenly():
    pixels = sample_pixels((36, 64), 500)
    rows, cols = np.divmod(pixels, 64)
    assert 300 <= len(pixels) <= 700
    assert rows.min() < 4 and rows.max() > 31 and cols.min() < 4 and cols.max() > 59


def test_auto_takes_the_largest_rate_within_the_noise():
    from xsl_render.core.sampling.volume_estimator import NOISE_AT_ONE_SPP

    tolerance = tolerated_bias(16)
    assert tolerance == pytest.approx(NOISE_AT_ONE_SPP / 4)        # the noise of 16 spp
    # Rate 1 is within 16 spp's tolerance, rate 0.5 only within 64 spp's (half of it).
    measures = {4.0: 24 * tolerance, 2.0: 4 * tolerance, 1.0: 0.8 * tolerance, 0.5: 0.32 * tolerance,
                0.25: 0.08 * tolerance}
    asked = []

    def measure(rate):
        asked.append(rate)
        return measures[rate]

    choice = choose_step_rate(measure, spp=16)
    assert (choice.biased, choice.step_rate) == (True, 1.0)
    assert asked == [4.0, 2.0, 1.0]                     # stops at the first that passes
    assert choose_step_rate(measures.get, spp=64).step_rate == 0.5
    assert choose_step_rate(measures.get, spp=16, largest=0.5).step_rate == 0.5
    never = choose_step_rate(lambda rate: 1.0, spp=16)
    assert never.biased is False and "within" in never.reason
    assert set(never.to_dict()["tried"]) == {"4", "2", "1", "0.5", "0.25"}


def test_no_rate_within_the_tolerance_is_null_scattering():
    """Where even the finest rate's error is over the tolerance, auto takes null scattering:
    unbiased, whatever it costs (an error a little over the noise made lit seed 5 1.42x the
    file's p95-tile FLIP, docs/bench_auto_rates.txt)."""
    tolerance = tolerated_bias(16)
    measures = {4.0: 40.0, 2.0: 20.0, 1.0: 10.0, 0.5: 3.0, 0.25: 1.01}
    choice = choose_step_rate(lambda rate: measures[rate] * tolerance, spp=16)
    assert choice.biased is False and choice.step_rate is None
    assert set(choice.tried) == set(measures)


def test_visible_bias_is_relative_to_what_the_transmittance_can_move():
    t = np.array([0.5, 0.9, 0.01])
    bias = np.array([0.01, 0.01, 0.001])
    # |dT| / max(min(T, 1 - T), 0.05): 0.02, 0.1 and 0.02
    assert visible_bias(np.repeat(t, 20), np.repeat(bias, 20)) == pytest.approx(0.1)


@pytest.mark.parametrize("estimator, rate, message", [
    ("magic", None, "estimator must be one of"),
    ("scene", 2.0, "does not march"),
    ("unbiased", 1.0, "does not march"),
    ("biased", 0.0, "from 0.01 to 100"),
    ("biased", float("nan"), "from 0.01 to 100"),
    ("auto", 1000.0, "from 0.01 to 100"),
])
def test_bad_estimator_settings_are_refused(estimator, rate, message):
    with pytest.raises(InputError, match=message):
        check_estimator(estimator, rate)
    with pytest.raises(InputError, match=message):
        RenderOptions(max_spp=4, estimator=estimator, step_rate=rate).check()


def test_auto_must_be_chosen_before_rendering():
    with pytest.raises(ValueError, match="chosen for the scene"):
        RenderOptions(max_spp=4, estimator="auto").volume_estimator()
    assert RenderOptions(max_spp=4, estimator="biased", step_rate=2.0).volume_estimator().step_rate == 2.0


def _two_media_scene(bpy):
    """A noise-textured fog box (a mesh volume, step from its bounds) overlapping an
    OpenVDB smoke (step from its voxels) over a ground with props."""
    import support.xmap_scenes as xs

    scene = xs.base_scene(bpy)
    scene.render.engine = "CYCLES"
    xs.ground_and_props(bpy)
    material = xs.noise_fog_material(bpy)
    for node in material.node_tree.nodes:
        if node.type == "MATH":
            node.inputs[1].default_value = 2.4          # dense enough for a measurable bias
    xs.add(bpy, "primitive_cube_add", material, size=6.0, location=(0.0, 6.0, 1.0))
    xs.smoke_volume_object(bpy, scene, density=2.0)
    return scene


@pytest.mark.blender
@pytest.mark.render
def test_predicted_bias_matches_cycles_ray_marching(blender):
    """Cycles ray-marches an absorption-only copy of the scene (the transmittance oracle) at
    step rates 2 and 4; the difference from its fine-step render is the bias it makes. The
    prediction must follow it pixel by pixel."""
    from xsl_render.addon.maps.transmittance_oracle import render_transmittance
    from xsl_render.addon.maps.xmap import compute_x_map_detailed
    from xsl_render.core.maps.transmittance import medium_segments

    scene = _two_media_scene(blender)
    result = compute_x_map_detailed(scene)
    media = [m for m in result.media if m.evaluable]
    assert {m.kind for m in media} == {"mesh", "volume_object"}
    assert all(math.isfinite(m.extra["cycles_step"]) for m in media)
    predictor = MarchingPredictor(result.rays, media, [medium_segments(result.rays, m) for m in media],
                                  np.arange(result.rays.count), runs=36)
    truth, _ = render_transmittance(scene, samples=64, step_rate=0.05)
    truth = truth.reshape(-1, 3)
    hit = result.rays.hit.ravel()               # the oracle's sky is black, not exp(-tau)
    assert np.abs(predictor.error(2.0).transmittance - truth)[hit].mean() < 2e-3
    for rate in (2.0, 4.0):
        marched, _ = render_transmittance(scene, samples=512, step_rate=rate)
        measured = ((marched.reshape(-1, 3) - truth) @ LUMINANCE)[hit]
        predicted = (predictor.error(rate).bias @ LUMINANCE)[hit]
        assert measured.mean() > 1e-3                       # a bias worth predicting
        assert np.corrcoef(measured, predicted)[0, 1] > 0.85
        assert 0.7 < predicted.mean() / measured.mean() < 1.3
