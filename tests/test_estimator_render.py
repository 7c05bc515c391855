"""``--estimator`` end to end: what each choice sets in Cycles, what auto predicts and records,
the scene's own volume settings back after success, cancel and error, bad values refused."""
from __future__ import annotations

import json

import pytest
from support.artist_render import artists_f12
from support.fog_scene import build_fog_scene
from test_cli_info import one_line_error
from test_ray_marching import _two_media_scene

from xsl_render.addon.cycles import selective_render as sr
from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
from xsl_render.addon.scene.state import settings_dump
from xsl_render.core.errors import Cancelled
from xsl_render.core.sampling.render_options import RenderOptions

pytestmark = [pytest.mark.blender, pytest.mark.render]

W, H = 48, 27


def _volume_settings(scene) -> tuple:
    return scene.cycles.volume_biased, scene.cycles.volume_step_rate


@pytest.mark.parametrize("estimator, rate, biased, step", [
    ("scene", None, False, 1.7),
    ("unbiased", None, False, 1.7),
    ("biased", None, True, 1.7),
    ("biased", 3.0, True, 3.0),
])
def test_each_estimator_reaches_cycles_and_the_scene_gets_its_settings_back(
        blender, monkeypatch, estimator, rate, biased, step):
    scene = build_fog_scene(blender, W, H)
    scene.cycles.volume_biased, scene.cycles.volume_step_rate = False, 1.7
    before = settings_dump(scene)
    seen = []
    real_render = CyclesWindowRenderer.render

    def spying(self, *args, **kwargs):
        seen.append(_volume_settings(self.scene))
        return real_render(self, *args, **kwargs)

    monkeypatch.setattr(CyclesWindowRenderer, "render", spying)
    options = RenderOptions(max_spp=2, estimator=estimator, step_rate=rate).check()
    outcome = sr.render_uniform(scene, options, spp=1)
    assert seen and all(s == (biased, pytest.approx(step)) for s in seen)
    assert outcome.stats.estimator["estimator"] == estimator
    assert settings_dump(scene) == before

    with pytest.raises(Cancelled):                                              # cancel
        sr.render_uniform(scene, options, spp=1, progress=lambda fraction, message: True)
    assert settings_dump(scene) == before

    def failing(self, *args, **kwargs):
        raise RuntimeError("render failed")

    monkeypatch.setattr(CyclesWindowRenderer, "render", failing)                # error
    with pytest.raises(RuntimeError, match="render failed"):
        sr.render_uniform(scene, options, spp=1)
    assert settings_dump(scene) == before


def test_auto_marches_where_the_bias_hides_in_the_noise(blender):
    """On a noise fog box over an OpenVDB smoke, few samples tolerate a coarse step; many
    samples ask for a finer one (or for null scattering). A homogeneous fog keeps the
    scene's estimator: both are exact there, and null scattering is the less noisy."""
    from xsl_render.addon.maps.estimator_choice import choose_estimator

    scene = _two_media_scene(blender)
    before = settings_dump(scene)
    options = RenderOptions(max_spp=4, estimator="auto").check()
    few = choose_estimator(scene, options, spp=1)
    many = choose_estimator(scene, options, spp=4096)
    assert few.biased and few.step_rate is not None
    assert few.predicted_bias <= few.tolerance
    assert not many.biased or many.step_rate < few.step_rate
    assert list(many.tried) == sorted(many.tried, reverse=True)
    capped = choose_estimator(scene, RenderOptions(max_spp=4, estimator="auto", step_rate=0.5), spp=1)
    assert max(capped.tried) <= 0.5
    assert few.seconds > 0.0
    assert settings_dump(scene) == before                   # predicting changes nothing

    fog = build_fog_scene(blender, W, H)                     # homogeneous world fog
    exact = choose_estimator(fog, options, spp=4096)
    assert exact.biased is None and "homogeneous" in exact.reason and "kept the scene's" in exact.reason


def test_cli_records_the_choice(cli, blender, tmp_path):
    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    path = tmp_path / "two.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    stats_path = tmp_path / "out.json"
    result = cli("render", path, "--mode", "uniform", "--spp", "2", "--max-spp", "4",
                 "--estimator", "auto", "--out", tmp_path / "out.exr", "--stats", stats_path,
                 "--quiet")
    assert result.returncode == 0, result.stderr
    stats = json.loads(stats_path.read_text())
    chosen = stats["estimator"]
    assert chosen["estimator"] == "auto" and chosen["tried"]
    assert stats["phases_s"]["estimator"] == pytest.approx(chosen["seconds"])
    assert stats["wall_s"] >= chosen["seconds"]
    # (uniform's --spp alone is its ceiling too: no --max-spp needed.)
    frames = cli("render", path, "--mode", "uniform", "--spp", "1",
                 "--estimator", "biased", "--step-rate", "2", "--frames", "1-2",
                 "--out", tmp_path / "f_#.exr", "--stats", tmp_path / "f.json", "--quiet")
    assert frames.returncode == 0, frames.stderr
    done = json.loads((tmp_path / "f.json").read_text())["frames"]
    assert [f["estimator"]["step_rate"] for f in done] == [2.0, 2.0]
    assert [f["mean_spp"] for f in done] == [1.0, 1.0]


@pytest.mark.parametrize("extra, message", [
    (["--estimator", "scene", "--step-rate", "2"], "does not march"),
    (["--estimator", "biased", "--step-rate", "0"], "--step-rate"),
    (["--estimator", "biased", "--step-rate", "nan"], "--step-rate"),
    (["--estimator", "fast"], "--estimator"),
])
def test_bad_estimator_options_exit_2_before_blender(cli, blender, tmp_path, extra, message):
    build_fog_scene(blender, W, H)
    blender.ops.wm.save_as_mainfile(filepath=str(tmp_path / "fog.blend"))
    result = cli("render", tmp_path / "fog.blend", "--mode", "gold",
                 "--max-spp", "4", "--out", tmp_path / "o.exr", *extra)
    assert result.returncode == 2
    assert message in one_line_error(result)
    assert not (tmp_path / "o.exr").exists()


def test_a_changed_estimator_reaches_cycles_in_one_persistent_session(blender):
    """Cycles' volume settings are add-on properties, which do not tag the scene: with
    persistent data Cycles kept rendering the step it synced first, even across a frame
    change, while the stats recorded the new one. The renderer tags the scene when they
    differ from what it synced last (and only then: the same settings render bit-identically)."""
    from test_ray_marching import _two_media_scene

    from xsl_render.addon.cycles.tile_render import forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    forget_synced_session()
    with preserved_scene(scene):
        scene.cycles.volume_biased, scene.cycles.volume_step_rate = True, 4.0
        with CyclesWindowRenderer(scene, 0) as renderer:
            coarse = renderer.render(None, 2).pixels
            scene.cycles.volume_step_rate = 0.25
            fine = renderer.render(None, 2).pixels
        scene.cycles.volume_step_rate = 4.0
        with CyclesWindowRenderer(scene, 0) as renderer:         # the next frame's renderer
            again = renderer.render(None, 2).pixels
            same = renderer.render(None, 2)
    assert abs(float(fine.mean()) - float(coarse.mean())) > 1e-4
    assert (again == coarse).all() and (same.pixels == coarse).all()
    assert same.sync_seconds < 0.5


def test_an_equal_time_run_counts_autos_prediction_inside_its_time(blender):
    """``uniform --equal-time S --estimator auto`` took S plus the prediction (street: 12.2 s
    for 10 s): the time Cycles may render for is what the prediction left."""
    from dataclasses import replace

    from xsl_render.core.sampling.volume_estimator import fixed_choice

    scene = build_fog_scene(blender, W, H)
    predicted = replace(fixed_choice("biased", 1.0), estimator="auto", seconds=1.5)
    options = RenderOptions(max_spp=4096, estimator="auto", estimator_choice=predicted).check()
    outcome = sr.render_uniform(scene, options, seconds=2.5)
    assert outcome.stats.time_limit_s <= 2.5 - 1.5
    assert outcome.stats.phases_s["estimator"] == 1.5


def test_the_artists_next_render_after_a_run_uses_the_artists_volume_settings(blender, tmp_path):
    """With the artist's own persistent data on, Cycles' session outlives our run into their
    next F12. Our run's volume settings are put back, but untagged add-on properties do not
    reach a persistent session; ``preserved_scene`` tags the scene when the block changed them
    (restoring other settings tags it too today, so this guards against losing both)."""
    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.cycles.volume_biased, scene.cycles.volume_step_rate = True, 0.25
    artists_render = artists_f12(blender, scene, tmp_path, seed=3)

    before = artists_render()
    options = RenderOptions(max_spp=2, estimator="biased", step_rate=4.0).check()
    coarse = sr.render_uniform(scene, options, spp=2).image
    assert abs(float(coarse.mean()) - float(before.mean())) > 1e-4      # our run did march coarser
    after = artists_render()
    assert _volume_settings(scene) == (True, 0.25)
    assert (after == before).all()
