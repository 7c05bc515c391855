"""The guided render against what Cycles renders: passes of two seeds merge into an unbiased estimate with the noise of their summed samples,
the time budget is kept, the ceiling obeyed, the scene restored."""
from __future__ import annotations

import json

import numpy as np
import pytest
from support.fog_scene import build_fog_scene

from xsl_render.addon.cycles.guided_render import render_guided
from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
from xsl_render.addon.scene.state import preserved_scene, settings_dump
from xsl_render.core.sampling.guided_plan import GuidedOptions
from xsl_render.core.sampling.sample_counts import POWER_OF_TWO_SLACK
from xsl_render.core.sampling.pass_merge import PassAccumulator
from xsl_render.core.sampling.render_options import UNBOUNDED_SPP, RenderOptions

pytestmark = [pytest.mark.blender, pytest.mark.render]

W, H = 64, 36


@pytest.fixture
def fog(blender):
    return build_fog_scene(blender, W, H)


def _renders(scene, seed: int, *samples: int):
    """Whole-frame renders of one renderer (one seed), with guides."""
    with preserved_scene(scene), CyclesWindowRenderer(scene, seed, guides=True) as renderer:
        return [renderer.render(None, count) for count in samples]


def _merge(*pieces) -> tuple[np.ndarray, np.ndarray]:
    image, guides = PassAccumulator(W, H, 4), PassAccumulator(W, H, 6)
    for piece in pieces:
        image.add(None, piece.pixels, piece.samples)
        guides.add(None, piece.guides, piece.samples)
    return image.result(), guides.result()


def test_a_reduced_render_is_the_frame_at_a_fraction_of_its_resolution(fog):
    before = settings_dump(fog)
    with preserved_scene(fog), CyclesWindowRenderer(fog, 3, guides=True) as renderer:
        small = renderer.render(None, 16, reduce=4)
        full = renderer.render(None, 16)
    assert small.pixels.shape == (H // 4, W // 4, 4) and small.guides.shape == (H // 4, W // 4, 6)
    assert full.pixels.shape == (H, W, 4)
    # The same picture: the full render box-filtered to the small size matches it to noise.
    pooled = full.pixels[:H // 4 * 4, :W // 4 * 4].reshape(H // 4, 4, W // 4, 4, 4).mean(axis=(1, 3))
    assert abs(pooled.mean() - small.pixels.mean()) < 0.1 * pooled.mean()
    assert np.corrcoef(pooled[..., :3].ravel(), small.pixels[..., :3].ravel())[0, 1] > 0.8
    assert settings_dump(fog) == before


def test_passes_of_two_seeds_merge_into_one_estimate(fog):
    # 2 samples of seed 1 and 14 of seed 2, merged by sample count, against 16-sample
    # renders of seeds 3 and 4: no bias, and the noise of 16 samples (an unweighted mean of
    # the two passes would have ~1.3x the deviation).
    (two,), (fourteen,) = _renders(fog, 1, 2), _renders(fog, 2, 14)
    merged, _ = _merge(two, fourteen)
    (reference,), (other,) = _renders(fog, 3, 16), _renders(fog, 4, 16)
    difference = (merged - reference.pixels)[..., :3].ravel()
    spread = np.std(difference) / np.sqrt(difference.size)
    assert abs(difference.mean()) < 4 * spread
    deviation = np.median(np.abs(difference))
    baseline = np.median(np.abs((other.pixels - reference.pixels)[..., :3]))
    assert 0.85 < deviation / baseline < 1.15
    unweighted = np.median(np.abs(((two.pixels + fourteen.pixels) / 2 - reference.pixels)[..., :3]))
    assert unweighted / baseline > 1.15                     # the test can tell the weighting


@pytest.mark.timing
@pytest.mark.parametrize("exponent", [0.0, 0.15])
def test_guided_render_keeps_its_time_budget(fog, exponent):
    budget = 4.0
    outcome = render_guided(fog, RenderOptions(max_spp=UNBOUNDED_SPP, tile_size=16, resolution=(96, 54)),
                            GuidedOptions(time_budget=budget, exponent=exponent))
    stats = outcome.stats
    # Over by 10 % at most; early by up to a third where a power of two's count is the
    # better frame (sobol_friendly, column_count).
    assert budget / POWER_OF_TWO_SLACK <= stats.wall_s <= 1.1 * budget
    assert stats.wall_s == pytest.approx(sum(stats.phases_s.values()))
    assert outcome.samples.min() >= 1 and stats.pilot_spp >= 1
    # The final pass is recorded as rendered (the pacer's counts), pixel-sample for pixel-sample.
    assert stats.final_pass["samples"] == stats.total_samples == int(outcome.samples.sum())
    if exponent == 0:
        # Nothing to score: the plan is flat, three columns of the frame (the later paced).
        assert stats.final_pass["flat"] and stats.final_pass["renders"] == 3
    else:
        assert stats.final_pass["renders"] >= 2
        assert outcome.samples.max() > outcome.samples.min()    # the samples went somewhere
    assert np.isfinite(outcome.image).all() and outcome.image.shape == (54, 96, 4)


@pytest.mark.timing
def test_guided_render_obeys_its_ceiling_and_restores_the_scene(fog):
    before = settings_dump(fog)
    outcome = render_guided(fog, RenderOptions(max_spp=8), GuidedOptions(time_budget=6.0))
    assert outcome.samples.max() <= 8
    assert outcome.stats.wall_s < 6.0                    # done when every pixel has its 8
    assert settings_dump(fog) == before


def test_guided_render_syncs_heterogeneous_fog_once(blender):
    """The pilot's scoring denoise sits between two renders of one Cycles session; it used to
    make Cycles sync the scene again (the octree of a noise fog, seconds) in the first
    rectangle of the final pass. Cycles' own sync times (its EXR headers) add up to one
    sync, with the pilot scored (denoised) and without."""
    import time

    import support.xmap_scenes as xs

    scene = xs.base_scene(blender, 32, 18)
    scene.render.engine = "CYCLES"
    xs.ground_and_props(blender)
    xs.add(blender, "primitive_cube_add", xs.noise_fog_material(blender), size=6.0, location=(0.0, 6.0, 1.0))
    options = RenderOptions(max_spp=16, tile_size=8, estimator="unbiased").check()
    # A budget of 2.5 syncs leaves the final pass room (the sync alone is measured first).
    with preserved_scene(scene), CyclesWindowRenderer(scene, 3) as renderer:
        started = time.perf_counter()
        renderer.render(None, 1)
        first_sync, cycles_sync = time.perf_counter() - started, renderer.sync_seconds
    assert cycles_sync > 0.3 * first_sync           # the test can see a sync in Cycles' reports
    for exponent in (0.0, 0.15):
        guided = GuidedOptions(time_budget=max(2.0, 2.5 * first_sync), exponent=exponent).check()
        outcome = render_guided(scene, options, guided)
        final = [tile["seconds"] for tile in outcome.stats.tiles if tile.get("pass") == "final"]
        assert final and outcome.stats.phases_s["sync"] > 0.3 * first_sync
        assert outcome.stats.cycles_sync_s < 1.5 * cycles_sync, (exponent, outcome.stats.cycles_sync_s)
        assert max(final) < 0.3 * outcome.stats.phases_s["sync"], (final, outcome.stats.phases_s)


@pytest.mark.parametrize("prefilter", ["ACCURATE", "NONE"])
def test_a_stills_budget_sets_the_files_prefilter_time_aside(cli, blender, tmp_path, prefilter):
    """A still's budget keeps back the time its final denoise will take, which is the file's
    own denoiser: its guides prefiltered (Accurate, Blender 5's default) cost
    ``PREFILTER_COST`` times the plain denoise. (A ceiling of 16 makes both reserves afford
    the same count, so the prefilter never costs a power of two on a loaded host.)"""
    from conftest import EXAMPLES

    from xsl_render.addon.cycles.denoise import PREFILTER_COST
    from xsl_render.addon.cycles.guided_render import _DENOISE_SECONDS_PER_PIXEL

    blender.ops.wm.open_mainfile(filepath=str(EXAMPLES / "road.blend"), load_ui=False)
    blender.context.scene.cycles.denoising_prefilter = prefilter
    path = tmp_path / "road.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    out = tmp_path / "still.exr"
    done = cli("render", path, "--mode", "guided", "--time-budget", "4", "--max-spp", "16",
               "--resolution", f"{W}x{H}", "--estimator", "auto", "--quiet", "--out", out,
               "--stats", tmp_path / "stats.json")
    assert done.returncode == 0, done.stderr
    stats = json.loads((tmp_path / "stats.json").read_text())
    accurate = prefilter == "ACCURATE"
    assert stats["denoise_guides"]["prefiltered"] is accurate
    plain = _DENOISE_SECONDS_PER_PIXEL * W * H
    assert stats["denoise_reserved_s"] == pytest.approx(PREFILTER_COST * plain if accurate else plain)
