"""Denoising the finished frame with Blender's Open Image Denoise (addon.cycles.denoise)."""
from __future__ import annotations

import numpy as np
import pytest

from support.fog_scene import build_fog_scene, radial_map

pytestmark = [pytest.mark.blender, pytest.mark.render]


@pytest.fixture
def fog(blender):
    return build_fog_scene(blender, 96, 54, density=0.08)


def render(scene, spp, **options):
    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.core.sampling.render_options import RenderOptions

    return sr.render_gold(scene, RenderOptions(max_spp=spp, **options))


def error(image, reference):
    return float(np.mean((image[..., :3] - reference[..., :3]) ** 2))


def test_denoising_takes_most_of_the_noise_away_and_leaves_nothing_behind(blender, fog):
    from xsl_render.addon.scene.state import settings_dump

    reference = render(fog, 128, denoise=False, seed=9).image
    before = settings_dump(fog)
    counts = {name: len(getattr(blender.data, name)) for name in ("scenes", "images", "node_groups", "objects")}
    raw = render(fog, 4, denoise=False)
    denoised = render(fog, 4)
    assert error(denoised.image, reference) < 0.5 * error(raw.image, reference)
    assert denoised.stats.phases_s["denoise"] > 0 and denoised.stats.options["denoise"]
    np.testing.assert_array_equal(denoised.image[..., 3], raw.image[..., 3])      # alpha as rendered
    assert settings_dump(fog) == before
    assert counts == {name: len(getattr(blender.data, name)) for name in counts}


def test_selective_frames_are_denoised_whole_with_composited_guides(fog):
    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.core.sampling.render_options import RenderOptions

    director = radial_map(96, 54, 0.3)
    raw = sr.render_selective(fog, director, RenderOptions(max_spp=16, tile_size=16, denoise=False))
    denoised = sr.render_selective(fog, director, RenderOptions(max_spp=16, tile_size=16))
    reference = render(fog, 128, denoise=False, seed=9).image
    assert np.isfinite(denoised.image).all()
    assert error(denoised.image, reference) < 0.5 * error(raw.image, reference)
    # The same samples went in: denoising changes pixels, not the plan.
    np.testing.assert_array_equal(denoised.samples, raw.samples)


def test_direct_oidn_is_the_compositors_denoise_bit_for_bit(blender):
    """The library call and the compositor's Denoise node (Fast, High, HDR) on one noisy frame
    with guides, and on one without: identical pixels, so the converged references stay valid."""
    from xsl_render.addon.cycles import denoise as module
    from xsl_render.addon.cycles.oidn_library import load

    assert load() is not None, "Blender's Open Image Denoise library was not found"
    rng = np.random.default_rng(3)
    rows, cols = np.mgrid[0:40, 0:56]
    clean = np.stack([0.5 + 0.4 * np.sin(cols / 7), 0.3 + 0.2 * np.cos(rows / 5),
                      0.2 + 0.1 * np.sin((cols + rows) / 9)], axis=-1)
    noisy = (clean * rng.gamma(2.0, 0.5, size=clean.shape)).astype(np.float32)
    rgba = np.concatenate([noisy, rng.random((40, 56, 1), dtype=np.float32)], axis=-1)
    albedo = (0.8 * clean).astype(np.float32)
    normal = np.zeros_like(albedo)
    normal[..., 2] = 1.0
    for guides in ((albedo, normal), (None, None)):
        direct = module.denoise(rgba, *guides)
        through = module._compositor_denoise(rgba, *guides)
        np.testing.assert_array_equal(direct[..., :3], np.maximum(through, 0.0))
        np.testing.assert_array_equal(direct[..., 3], rgba[..., 3])


def test_prefiltered_guides_leave_less_error_in_fog(fog):
    """In fog Cycles writes the albedo and normal at the first scattering event, as noisy as
    the image: denoised first (the Accurate prefilter), they let OIDN come closer to the converged
    frame, on mean FLIP as the benches measure it, than the guides as rendered."""
    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.validation.metrics import flip_metric

    reference = render(fog, 256, denoise=False, seed=9).image[..., :3]
    with preserved_scene(fog), CyclesWindowRenderer(fog, 0, guides=True) as renderer:
        noisy = renderer.render(None, 4)
    albedo, normal = noisy.guides[..., :3], noisy.guides[..., 3:6]
    plain = denoise(noisy.pixels, albedo, normal)
    prefiltered = denoise(noisy.pixels, albedo, normal, prefilter_guides=True)
    assert np.isfinite(prefiltered).all() and prefiltered.min() >= 0.0
    np.testing.assert_array_equal(prefiltered[..., 3], noisy.pixels[..., 3])
    flip = {name: flip_metric(reference, image[..., :3], hdr=True).extra["mean_flip"]
            for name, image in (("plain", plain), ("prefiltered", prefiltered))}
    assert flip["prefiltered"] < flip["plain"], flip


def test_the_guide_prefilter_takes_albedo_or_normal_only(blender):
    from xsl_render.addon.cycles.oidn_library import load

    with pytest.raises(ValueError, match="albedo"):
        load().prefilter(np.zeros((8, 8, 3), np.float32), "color")


def test_a_denoise_between_renders_keeps_the_synced_scene(blender):
    """Cycles keeps a scene synced between renders (persistent data) unless Blender renders
    another scene or a datablock comes or goes: a denoise in the middle of a run (the guided
    pilot's) must not make the next render sync heterogeneous fog again (its octree)."""
    import time

    import support.xmap_scenes as xs

    from xsl_render.addon.cycles.denoise import denoise
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.scene.state import preserved_scene

    scene = xs.base_scene(blender, 32, 18)
    scene.render.engine = "CYCLES"
    xs.ground_and_props(blender)
    xs.add(blender, "primitive_cube_add", xs.noise_fog_material(blender), size=6.0, location=(0.0, 6.0, 1.0))
    with preserved_scene(scene), CyclesWindowRenderer(scene, 0, guides=True) as renderer:
        started = time.perf_counter()
        first = renderer.render(None, 1)                # syncs the scene, octree and all
        sync = time.perf_counter() - started
        denoise(first.pixels, first.guides[..., :3], first.guides[..., 3:])
        started = time.perf_counter()
        renderer.render((0, 8, 0, 8), 2)
        again = time.perf_counter() - started
    assert again < 0.25 * sync, (again, sync)


@pytest.mark.parametrize("prefilter, prefiltered", [("ACCURATE", True), ("FAST", False), ("NONE", False)])
@pytest.mark.parametrize("estimator", ["scene", "auto"])
def test_every_run_denoises_as_the_files_own_denoiser(fog, prefilter, prefiltered, estimator):
    """The guides are prefiltered where the file's denoiser prefilters them (Blender 5's
    default, Accurate) and only there, whatever the estimator: a comparison with the file
    measures the estimator, not a denoise of its own."""
    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.core.sampling.render_options import RenderOptions

    fog.cycles.denoising_prefilter = prefilter
    options = with_estimator_choice(fog, RenderOptions(max_spp=2, estimator=estimator).check(), 2)
    stats = sr.render_uniform(fog, options, spp=2).stats
    assert stats.denoise_guides["prefiltered"] is prefiltered
    assert fog.cycles.denoising_prefilter == prefilter
