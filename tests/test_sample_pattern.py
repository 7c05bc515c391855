"""``--estimator auto`` renders a file that carries the legacy sample pattern with Blender 5's
blue noise (``core.sampling.sample_pattern``): chosen, kept through a time budget's settle,
reaching Cycles inside one persistent session, recorded, and the file's own pattern back
afterwards, also for the artist's next render."""
from __future__ import annotations

import pytest

from xsl_render.core.sampling.sample_pattern import BLENDER_DEFAULT, LEGACY, auto_sample_pattern
from xsl_render.core.sampling.volume_estimator import (choose_step_rate, provisional_choice,
                                                       settled_for)


@pytest.mark.parametrize("scene_pattern, chosen", [
    ("TABULATED_SOBOL", "AUTOMATIC"),      # what a file from before Blender 4.2 carries
    ("AUTOMATIC", None),                   # Blender 5's default: the scene's own
    ("BLUE_NOISE", None),                  # debug choices made on purpose stay
    ("SOBOL_BURLEY", None),
])
def test_auto_replaces_only_the_legacy_pattern(scene_pattern, chosen):
    assert auto_sample_pattern(scene_pattern) == chosen


def test_the_pattern_survives_the_provisional_choice_and_the_settle():
    from dataclasses import replace

    measures = {4.0: 0.16, 2.0: 0.11, 1.0: 0.04, 0.5: 0.008, 0.25: 0.0018}
    null = replace(choose_step_rate(measures.__getitem__, 1e6), sample_pattern=BLENDER_DEFAULT)
    assert null.biased is False
    provisional = provisional_choice(null)
    assert provisional.biased and provisional.sample_pattern == BLENDER_DEFAULT
    for spp in (4, 64, 1e6):
        assert settled_for(null, spp).sample_pattern == BLENDER_DEFAULT
    assert "blue noise" in null.describe() and null.to_dict()["sample_pattern"] == BLENDER_DEFAULT


W, H = 48, 27


@pytest.mark.blender
@pytest.mark.render
def test_an_auto_run_renders_a_legacy_file_with_blue_noise_and_puts_the_pattern_back(blender, monkeypatch):
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.addon.scene.state import settings_dump
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = build_fog_scene(blender, W, H)
    scene.cycles.sampling_pattern = LEGACY
    before = settings_dump(scene)
    seen = []
    real_render = CyclesWindowRenderer.render

    def spying(self, *args, **kwargs):
        seen.append(self.scene.cycles.sampling_pattern)
        return real_render(self, *args, **kwargs)

    monkeypatch.setattr(CyclesWindowRenderer, "render", spying)
    options = with_estimator_choice(scene, RenderOptions(max_spp=2, estimator="auto").check(), 2)
    outcome = sr.render_uniform(scene, options, spp=2)
    assert seen and set(seen) == {BLENDER_DEFAULT}
    assert outcome.stats.estimator["sample_pattern"] == BLENDER_DEFAULT
    assert settings_dump(scene) == before

    seen.clear()
    sr.render_uniform(scene, RenderOptions(max_spp=2, estimator="scene").check(), spp=2)
    assert set(seen) == {LEGACY}                             # other estimators: the file's own

    scene.cycles.sampling_pattern = BLENDER_DEFAULT          # a Blender 5 file: nothing to change
    options = with_estimator_choice(scene, RenderOptions(max_spp=2, estimator="auto").check(), 2)
    assert options.estimator_choice.sample_pattern is None


@pytest.mark.blender
@pytest.mark.render
def test_a_new_pattern_reaches_cycles_in_one_persistent_session_and_the_artists_next_render(
        blender, tmp_path):
    """The pattern is an add-on property, which does not tag the scene: without the tag
    Cycles kept rendering the pattern it synced first (the same pixels), and with the
    artist's persistent data on, their next render would keep ours."""
    from support.artist_render import artists_f12
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_volumes
    from xsl_render.addon.scene.state import preserved_scene

    scene = build_fog_scene(blender, W, H)
    forget_synced_volumes()
    with preserved_scene(scene):
        scene.cycles.sampling_pattern = LEGACY
        with CyclesWindowRenderer(scene, 0) as renderer:
            legacy = renderer.render(None, 2).pixels
            scene.cycles.sampling_pattern = BLENDER_DEFAULT
            blue = renderer.render(None, 2).pixels
    assert not (legacy == blue).all()

    scene.cycles.sampling_pattern = LEGACY
    artists_render = artists_f12(blender, scene, tmp_path)
    first = artists_render()
    with preserved_scene(scene):
        scene.cycles.sampling_pattern = BLENDER_DEFAULT
        with CyclesWindowRenderer(scene, 0) as renderer:
            renderer.render(None, 2)
    assert scene.cycles.sampling_pattern == LEGACY
    assert (artists_render() == first).all()
