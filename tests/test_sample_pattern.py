"""``--estimator auto`` renders a file that carries the legacy sample pattern or Blender 5's
blue noise with blue noise whose sequence is rounded up to a power of two
(``core.sampling.sample_pattern``): chosen, kept through a time budget's settle, reaching
Cycles inside one persistent session (a debug pattern too, with the preferences it needs),
recorded, and the file's own pattern and the preferences back afterwards, also for the
artist's next render."""
from __future__ import annotations

import numpy as np
import pytest

from xsl_render.core.sampling.sample_pattern import (BLENDER_DEFAULT, LEGACY, PURE, ROUND, auto_sample_pattern,
                                                    needs_debug_options)
from xsl_render.core.sampling.volume_estimator import (choose_step_rate, provisional_choice,
                                                       settled_for)


@pytest.mark.parametrize("scene_pattern, chosen", [
    ("TABULATED_SOBOL", ROUND),            # what a file from before Blender 4.2 carries
    ("AUTOMATIC", ROUND),                  # Blender 5's default: pure blue noise in a final render
    ("BLUE_NOISE", ROUND),                 # the same, chosen by name
    ("SOBOL_BURLEY", None),                # debug choices made on purpose stay
    ("BLUE_NOISE_FIRST", None),
    ("BLUE_NOISE_ROUND", None),
])
def test_auto_rounds_the_plain_patterns_and_keeps_debug_choices(scene_pattern, chosen):
    assert auto_sample_pattern(scene_pattern) == chosen
    assert needs_debug_options(scene_pattern) == (chosen is None)


def test_the_pattern_survives_the_provisional_choice_and_the_settle():
    from dataclasses import replace

    measures = {4.0: 0.16, 2.0: 0.11, 1.0: 0.04, 0.5: 0.008, 0.25: 0.0018}
    null = replace(choose_step_rate(measures.__getitem__, 1e6), sample_pattern=ROUND)
    assert null.biased is False
    provisional = provisional_choice(null)
    assert provisional.biased and provisional.sample_pattern == ROUND
    for spp in (4, 64, 1e6):
        assert settled_for(null, spp).sample_pattern == ROUND
    assert "blue noise" in null.describe() and null.to_dict()["sample_pattern"] == ROUND


W, H = 48, 27


def _debug_options(blender) -> tuple[bool, bool, bool]:
    preferences = blender.context.preferences
    return (preferences.view.show_developer_ui, preferences.experimental.use_cycles_debug,
            preferences.is_dirty)


@pytest.mark.blender
@pytest.mark.render
def test_an_auto_run_renders_a_legacy_file_with_rounded_blue_noise_and_puts_everything_back(
        blender, monkeypatch):
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.addon.scene.state import settings_dump
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = build_fog_scene(blender, W, H)
    scene.cycles.sampling_pattern = LEGACY
    before, options_before = settings_dump(scene), _debug_options(blender)
    assert options_before[:2] == (False, False)              # Blender's defaults
    seen = []
    real_render = CyclesWindowRenderer.render

    def spying(self, *args, **kwargs):
        seen.append(self.scene.cycles.sampling_pattern)
        return real_render(self, *args, **kwargs)

    monkeypatch.setattr(CyclesWindowRenderer, "render", spying)
    options = with_estimator_choice(scene, RenderOptions(max_spp=2, estimator="auto").check(), 2)
    outcome = sr.render_uniform(scene, options, spp=2)
    assert seen and set(seen) == {ROUND}
    assert outcome.stats.estimator["sample_pattern"] == ROUND
    assert settings_dump(scene) == before
    assert _debug_options(blender) == options_before

    seen.clear()
    sr.render_uniform(scene, RenderOptions(max_spp=2, estimator="scene").check(), spp=2)
    assert set(seen) == {LEGACY}                             # other estimators: the file's own

    scene.cycles.sampling_pattern = BLENDER_DEFAULT          # a Blender 5 file: rounded too
    options = with_estimator_choice(scene, RenderOptions(max_spp=2, estimator="auto").check(), 2)
    assert options.estimator_choice.sample_pattern == ROUND


@pytest.mark.blender
@pytest.mark.render
@pytest.mark.parametrize("artists_session", [False, True])
def test_the_rounded_pattern_reaches_cycles_only_off_a_power_of_two(blender, tmp_path, artists_session):
    """Cycles renders the rounded pattern only with its debug options on, read when it creates
    its session: at 3 spp it must differ from the pure blue noise (a pattern Cycles did not
    honour would render that), at 4 it is the same pattern. ``artists_session``: the artist
    rendered first with persistent data on and the options off, and Cycles kept that session."""
    from support.artist_render import artists_f12
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles.sample_pattern import apply_sample_pattern
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.scene.state import preserved_scene, settings_dump

    scene = build_fog_scene(blender, W, H)
    if artists_session:
        artists_f12(blender, scene, tmp_path)()
    before, options_before = settings_dump(scene), _debug_options(blender)

    def render(pattern: str, spp: int):
        with preserved_scene(scene):
            apply_sample_pattern(scene, pattern)
            with CyclesWindowRenderer(scene, 0) as renderer:
                return renderer.render(None, spp).pixels

    rounded = render(ROUND, 3)
    assert _debug_options(blender) == options_before and settings_dump(scene) == before
    assert not (rounded == render(PURE, 3)).all()
    np.testing.assert_array_equal(render(ROUND, 4), render(PURE, 4))
    assert _debug_options(blender) == options_before and settings_dump(scene) == before


@pytest.mark.blender
@pytest.mark.render
def test_a_new_pattern_reaches_cycles_in_one_persistent_session_and_the_artists_next_render(
        blender, tmp_path):
    """The pattern is an add-on property, which does not tag the scene: without the tag
    Cycles kept rendering the pattern it synced first (the same pixels), and with the
    artist's persistent data on, their next render would keep ours."""
    from support.artist_render import artists_f12
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene

    scene = build_fog_scene(blender, W, H)
    forget_synced_session()
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
