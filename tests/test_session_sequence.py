"""A persistent Cycles session lays blue noise out by the largest sample count it has rendered
(``core.sampling.sample_pattern.session_sequence``): a render of fewer samples after one of
more draws them from the longer sequence and gets other pixels than a fresh session gives.
Checked against Cycles itself: what it does, that a run never inherits a longer sequence from
the artist's kept session, that the artist's next render never inherits ours, that a
selective render's rectangles each get a fresh session's pixels, and the counts a guided run
chooses where the session already rendered more."""
from __future__ import annotations

import numpy as np
import pytest

from xsl_render.core.sampling.sample_counts import column_count, sobol_friendly, still_count
from xsl_render.core.sampling.sample_pattern import (BLENDER_DEFAULT, LEGACY, PURE, ROUND,
                                                    session_sequence)
from xsl_render.core.sampling.sequence_budget import SequenceBudget

W, H = 48, 27


@pytest.mark.parametrize("pattern, shared", [
    (BLENDER_DEFAULT, True), (PURE, True), (ROUND, True), ("BLUE_NOISE_FIRST", True),
    (LEGACY, False), ("SOBOL_BURLEY", False),
])
def test_session_sequence_follows_the_pattern(pattern, shared):
    assert session_sequence(pattern, 32) == (32 if shared else 0)
    assert session_sequence(pattern, 0) == 0


@pytest.mark.parametrize("count, sequence, expected", [
    (11, 0, 8),          # a fresh session: the power of two below, within the slack
    (11, 8, 8),          # the session's sequence is 8 long: 8 is its own pattern
    (11, 16, 11),        # 8 would be the first 8 of 16-sample sequences: keep all 11
    (20, 16, 16),        # rounding down to the session's own length is still a power of two's
    (24, 32, 24),        # 16 of a 32-sample sequence is not 16's pattern
    (40, 64, 40),        # above POWER_OF_TWO_LARGEST's range nothing is rounded anyway
    (1, 64, 1),
])
def test_a_count_below_the_sessions_is_not_rounded_down(count, sequence, expected):
    assert sobol_friendly(count, sequence) == expected


def test_guided_counts_keep_a_count_below_the_sessions_whole():
    # A later column that can no longer hold 16: 11, not 8 of a 16-long sequence.
    assert column_count(16, 11.4, 30.0) == 8
    assert column_count(16, 11.4, 30.0, sequence=16) == 11
    # A still whose pilot rendered 16 samples (a long budget) and can afford 11 at full size.
    assert still_count(11.2, 0.1, 64) == 8
    assert still_count(11.2, 0.1, 64, sequence=16) == 11
    # A range's frame that cannot hold the frame before's 16.
    budget = SequenceBudget(per_frame=10.0, frames=4)
    budget.spp = 16
    assert budget.steady_count(11.3, 64, 0.5) == 8
    assert budget.steady_count(11.3, 64, 0.5, sequence=16) == 11


def _fresh(scene, pattern, spp, window=None):
    from xsl_render.addon.cycles.sample_pattern import apply_sample_pattern
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene

    forget_synced_session()
    with preserved_scene(scene):
        apply_sample_pattern(scene, pattern)
        with CyclesWindowRenderer(scene, 0) as renderer:
            return renderer.render(window, spp).pixels


@pytest.mark.blender
@pytest.mark.render
@pytest.mark.parametrize("pattern, shared", [(ROUND, True), (BLENDER_DEFAULT, True), (LEGACY, False)])
def test_cycles_renders_fewer_samples_after_more_from_the_longer_sequence(blender, pattern, shared):
    """What Cycles does (Blender 5.0): the reason for everything below. If this starts to fail
    for the blue noises, Cycles resets the count now, and the rules built on it can go."""
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles.sample_pattern import apply_sample_pattern
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene

    scene = build_fog_scene(blender, W, H)
    fresh = _fresh(scene, pattern, 4)
    forget_synced_session()
    with preserved_scene(scene):
        apply_sample_pattern(scene, pattern)
        with CyclesWindowRenderer(scene, 0) as renderer:
            assert renderer.sequence() == 0
            renderer.render(None, 16)
            assert renderer.sequence() == (16 if shared else 0)
            after = renderer.render(None, 4).pixels
            again = renderer.render(None, 16).pixels
    assert (not np.array_equal(after, fresh)) == shared
    np.testing.assert_array_equal(again, _fresh(scene, pattern, 16))     # more is always fresh


@pytest.mark.blender
@pytest.mark.render
def test_a_run_never_draws_from_the_artists_longer_sequence_nor_leaves_them_ours(blender, tmp_path):
    """The artist rendered 16 samples with persistent data on (Blender 5's blue noise): our
    4-sample run must get a fresh session's pixels, and their next render after our 16-sample
    run must be what it was."""
    from support.artist_render import artists_f12
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene

    scene = build_fog_scene(blender, W, H)
    scene.cycles.sampling_pattern = BLENDER_DEFAULT
    fresh = _fresh(scene, BLENDER_DEFAULT, 4)
    artists_render = artists_f12(blender, scene, tmp_path, samples=4)
    first = artists_render()
    scene.cycles.samples = 16
    artists_render()                                  # their kept session now holds 16
    forget_synced_session()                           # (what every run starts with)
    with preserved_scene(scene):
        with CyclesWindowRenderer(scene, 0) as renderer:
            ours = renderer.render(None, 4).pixels
            renderer.render(None, 16)
    np.testing.assert_array_equal(ours, fresh)
    assert scene.render.use_persistent_data
    scene.cycles.samples = 4
    np.testing.assert_array_equal(artists_render()[..., :3], first[..., :3])


@pytest.mark.blender
@pytest.mark.render
def test_a_selective_render_gives_every_rectangle_a_fresh_sessions_pixels(blender):
    """Tiles of 2 and 8 samples, the 8s first in the frame: each rectangle must have the
    pixels a fresh session renders for its window (``render_order``: fewest samples first)."""
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles.selective_render import render_selective
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = build_fog_scene(blender, W, H)
    scene.cycles.sampling_pattern = BLENDER_DEFAULT
    director = np.zeros((H, W), np.float32)
    director[:, :16] = 1.0                              # the left tile wants the most samples
    options = RenderOptions(max_spp=8, min_spp=2, tile_size=16, denoise=False, seed=0).check()
    outcome = render_selective(scene, director, options, mode="xs")
    rects = outcome.stats.plan["rects"]
    assert len({rect["spp"] for rect in rects}) == 2
    assert [rect["spp"] for rect in rects] == sorted(rect["spp"] for rect in rects)
    for rect in rects:
        window = (rect["row0"], rect["row1"], rect["col0"], rect["col1"])
        expected = _fresh(scene, BLENDER_DEFAULT, rect["spp"], window)
        got = outcome.image[window[0]:window[1], window[2]:window[3]]
        np.testing.assert_allclose(got[..., :3], expected[..., :3], rtol=1e-5, atol=1e-6)


@pytest.mark.blender
@pytest.mark.render
def test_a_session_let_go_forgets_its_count(blender):
    """Persistent data turned off frees the session (a debug pattern's first use does): the
    next renderer starts from a fresh session's count, not the one before's."""
    from support.fog_scene import build_fog_scene

    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.state import preserved_scene

    scene = build_fog_scene(blender, W, H)
    scene.cycles.sampling_pattern = BLENDER_DEFAULT
    forget_synced_session()
    with preserved_scene(scene):
        with CyclesWindowRenderer(scene, 0) as renderer:
            renderer.render(None, 8)
            assert renderer.sequence() == 8
        scene.render.use_persistent_data = False
        with CyclesWindowRenderer(scene, 0) as renderer:
            assert renderer.sequence() == 0
