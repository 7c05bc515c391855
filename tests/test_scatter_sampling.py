"""``--estimator auto``'s volume sampling per medium (``core.media.scatter_sampling``): the
prediction on rays with a known answer, against the noise Cycles itself renders with each
method, and the choice reaching Cycles and put back."""
from __future__ import annotations

import numpy as np
import pytest

from xsl_render.core.media.scatter_sampling import (BOTH, DISTANCE, DISTANCE_MARGIN, EQUIANGULAR, METHODS, Lights,
                                                    Segments, chosen_methods, segment_moments, stack_method)


def _ray(sigma: np.ndarray, light: tuple[float, float, float], length: float = 10.0):
    """({method: relative noise of one sample}, the integral) along a ray on +x from the origin
    through ``sigma`` (per point), one segment, one light at ``light``."""
    n = len(sigma)
    t = (np.arange(n) + 0.5) / n * length
    dt = np.full(n, length / n)
    points = np.stack([t, np.zeros(n), np.zeros(n)], axis=1)
    integral, moments = segment_moments(t, dt, sigma, sigma, points,
                                        Lights(np.array([light], float), np.array([100.0])))
    noise = {m: np.sqrt(max(moments[i] / integral ** 2 - 1.0, 0.0)) for i, m in enumerate(METHODS)}
    return noise, integral


@pytest.mark.parametrize("sigma, light, best", [
    # Thick, uneven fog lit from far above: the transmittance carries the integrand.
    (1.5 * (1.0 + np.sin(np.linspace(0.0, 12.0, 256)) ** 2), (5.0, 0.0, 40.0), DISTANCE),
    # Thin fog with a lamp just beside the ray: 1 / r^2 carries it.
    (np.full(256, 0.02), (5.0, 0.3, 0.0), EQUIANGULAR),
], ids=["thick fog, far light", "thin fog, lamp by the ray"])
def test_the_prediction_ranks_the_method_whose_pdf_follows_the_integrand_first(sigma, light, best):
    noise, integral = _ray(sigma, light)
    assert integral > 0
    assert min(noise, key=noise.get) == best
    assert noise[BOTH] < max(noise[DISTANCE], noise[EQUIANGULAR])     # the mixture is never the worst


@pytest.mark.parametrize("methods, expected", [
    ((), None), ((DISTANCE,), DISTANCE), ((EQUIANGULAR, EQUIANGULAR), EQUIANGULAR),
    ((DISTANCE, EQUIANGULAR), BOTH), ((DISTANCE, BOTH), BOTH), ((DISTANCE, DISTANCE), DISTANCE),
])
def test_a_segment_samples_with_the_union_of_its_stacks_methods(methods, expected):
    assert stack_method(methods) == expected


def _segments(members, moments, integral=1.0, carriers=("material:Fog", "world:W")):
    """Synthetic segments: one per row of ``members``, each its own ray."""
    rows = len(members)
    return Segments(list(carriers), np.arange(rows), np.full(rows, integral),
                    np.asarray(moments, float).reshape(rows, 3), np.asarray(members, bool))


def test_a_fog_box_inside_world_fog_switches_only_with_the_world():
    """Inside a world fog sampled equiangular, a fog box's distance gives both (Cycles'
    union): its switch alone changes nothing, and auto switches the two together."""
    # distance / equiangular / both second moments: distance far the least noisy
    segments = _segments([[True, True]], [1.1, 5.0, 2.0])
    own = {"material:Fog": BOTH, "world:W": EQUIANGULAR}
    methods, noises = chosen_methods(segments, own)
    assert noises["material:Fog"][DISTANCE] == pytest.approx(noises["material:Fog"][BOTH])
    assert methods == {"material:Fog": DISTANCE, "world:W": DISTANCE}
    # The box alone (no world around it) switches alone.
    alone = _segments([[True, False]], [1.1, 5.0, 2.0])
    assert chosen_methods(alone, own)[0] == {"material:Fog": DISTANCE}


def test_distance_is_taken_only_by_the_margin_and_never_for_nothing():
    own = {"material:Fog": BOTH, "world:W": EQUIANGULAR}
    # distance predicted at 0.7 / 0.6 of both's noise (relative variance 0.5): kept / switched
    kept = _segments([[True, False]], [1.0 + 0.49 * 0.5, 3.0, 1.5])
    assert chosen_methods(kept, own)[0] == {} and 0.6 < DISTANCE_MARGIN < 0.7
    assert chosen_methods(_segments([[True, False]], [1.0 + 0.36 * 0.5, 3.0, 1.5]), own)[0] == {"material:Fog": DISTANCE}
    # a medium that gathers no light (absorption only) gives no reason to switch
    dark = _segments([[True, False]], [0.0, 0.0, 0.0], integral=0.0)
    assert chosen_methods(dark, own)[0] == {}
    # own methods at distance already: nothing to switch
    assert chosen_methods(_segments([[True, False]], [1.1, 5.0, 2.0]),
                          {"material:Fog": DISTANCE, "world:W": DISTANCE})[0] == {}


def test_the_frame_noise_sums_a_rays_segments_variances():
    # one ray of two segments (each gathering 1) against two rays of one
    two = Segments(["material:Fog"], np.array([0, 0]), np.ones(2), np.array([[2.0, 2.0, 2.0]] * 2),
                   np.ones((2, 1), bool))
    assert two.noise({"material:Fog": DISTANCE}) == pytest.approx(np.sqrt(2.0 / 4.0))
    apart = Segments(["material:Fog"], np.array([0, 1]), np.ones(2), np.array([[2.0, 2.0, 2.0]] * 2),
                     np.ones((2, 1), bool))
    assert apart.noise({"material:Fog": DISTANCE}) == pytest.approx(1.0)


@pytest.mark.parametrize("node_type, color, scattering", [
    ("VOLUME_SCATTER", (0.8, 0.8, 0.8), 0.8),
    ("VOLUME_ABSORPTION", (0.2, 0.2, 0.2), 0.0),
    ("PRINCIPLED_VOLUME", (0.5, 0.5, 0.5), 0.5),
])
def test_only_the_scattering_part_gathers_light(node_type, color, scattering):
    """The prediction's integrand is a medium's scattering coefficient: an absorbing medium
    gathers no light whatever its extinction."""
    from xsl_render.core.media.shader_graph import Node, ShaderGraph
    from xsl_render.core.media.shader_link import Link
    from xsl_render.core.media.volume_medium import VolumeMedium

    node = Node(type=node_type, name="v", inputs={"Density": 1.0, "Color": color, "Absorption Color": (0, 0, 0)},
                input_kinds={"Density": "VALUE", "Color": "RGBA", "Absorption Color": "RGBA"})
    medium = VolumeMedium(key="m", name="m", kind="mesh", material="m",
                          graph=ShaderGraph(nodes={"v": node}, root=Link("v", "Volume", "SHADER")))
    points = np.zeros((4, 3))
    assert np.allclose(medium.extinction(points, "scattering"), scattering)
    assert medium.extinction(points).mean() >= scattering


W, H = 40, 24


def _thick_box(blender):
    """A dense fog box filling the frame, lit by a lamp far above it: distance's case."""
    from support.xmap_scenes import add, base_scene

    scene = base_scene(blender, W, H, lens=50.0, location=(0.0, -6.0, 2.0), rotation=(90.0, 0.0, 0.0))
    fog = blender.data.materials.new("Fog")
    tree = fog.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    volume = tree.nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Density"].default_value = 1.5
    tree.links.new(volume.outputs[0], tree.nodes["Material Output"].inputs["Volume"])
    add(blender, "primitive_cube_add", fog, size=4.0, location=(0.0, 0.0, 2.0))
    lamp = blender.data.objects.new("Key", blender.data.lights.new("Key", "POINT"))
    lamp.data.energy = 200000.0
    lamp.location = (2.0, 0.0, 30.0)
    scene.collection.objects.link(lamp)
    return scene, "material:Fog"


def _thin_world(blender):
    """The fog scene: thin world fog with lamps among the rays: equiangular's case."""
    from support.fog_scene import build_fog_scene

    scene = build_fog_scene(blender, W, H, density=0.03)
    return scene, f"world:{scene.world.name}"


@pytest.mark.blender
@pytest.mark.render
@pytest.mark.parametrize("build, chosen", [(_thick_box, DISTANCE), (_thin_world, None)],
                         ids=["thick box, far light", "thin world fog, lamps"])
def test_auto_takes_distance_sampling_where_cycles_renders_it_with_less_noise(blender, build, chosen):
    from support.scatter_oracle import cycles_noise
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.core.sampling.render_options import RenderOptions

    scene, key = build(blender)
    choice = choose_estimator(scene, RenderOptions(max_spp=16, estimator="auto").check(), 16)
    assert (choice.scatter_sampling or {}).get(key) == chosen
    noise = choice.scatter_noise[key]
    # Cycles ranks the three methods as the prediction does (measured: thick box 0.008 /
    # 0.034 / 0.114 for distance / both / equiangular, predicted 0.006 / 0.57 / 1.34; thin
    # world fog 0.39 / 0.16 / 0.09, predicted 3.6 / 1.2 / 0.75).
    rendered = {method: cycles_noise(blender, scene, {key: method}) for method in (DISTANCE, EQUIANGULAR, BOTH)}
    assert sorted(rendered, key=rendered.get) == sorted(noise, key=noise.get)


@pytest.mark.blender
@pytest.mark.render
def test_the_chosen_sampling_reaches_cycles_and_is_put_back(blender, monkeypatch):
    from dataclasses import replace

    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.addon.scene.state import settings_dump
    from xsl_render.core.sampling.render_options import RenderOptions

    scene, _ = _thick_box(blender)
    fog = blender.data.materials["Fog"]
    before = settings_dump(scene)
    seen = []
    real_render = CyclesWindowRenderer.render

    def spying(self, *args, **kwargs):
        seen.append((self.scene.cycles.volume_biased, fog.cycles.volume_sampling))
        return real_render(self, *args, **kwargs)

    monkeypatch.setattr(CyclesWindowRenderer, "render", spying)
    options = with_estimator_choice(scene, RenderOptions(max_spp=2, estimator="auto").check(), 2)
    # A homogeneous box alone keeps the scene's estimator (nothing to save): march it as auto
    # marches elsewhere, with the sampling auto chose for it.
    assert options.estimator_choice.biased is None
    options = replace(options, estimator_choice=replace(options.estimator_choice, biased=True, step_rate=1.0))
    outcome = sr.render_uniform(scene, options, spp=2)
    assert set(seen) == {(True, DISTANCE)}
    assert outcome.stats.estimator["scatter_sampling"] == {"material:Fog": DISTANCE}
    assert "Fog sampled by distance" in options.volume_estimator().describe()
    assert settings_dump(scene) == before and fog.cycles.volume_sampling == BOTH

    seen.clear()
    sr.render_uniform(scene, RenderOptions(max_spp=2, estimator="biased").check(), spp=2)
    assert set(seen) == {(True, BOTH)}                       # other estimators: the file's own


@pytest.mark.blender
def test_a_settle_to_null_scattering_puts_the_own_method_back(blender):
    """A time budget's pilot ray-marches with distance sampling; where its count then settles
    on null scattering, the medium renders with its own method again."""
    from dataclasses import replace

    from xsl_render.addon.cycles.selective_render import apply_estimator
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.addon.scene.state import preserved_scene
    from xsl_render.core.sampling.render_options import RenderOptions

    scene, _ = _thick_box(blender)
    fog = blender.data.materials["Fog"]
    choice = choose_estimator(scene, RenderOptions(max_spp=16, estimator="auto").check(), 16)
    assert choice.scatter_own == {"material:Fog": BOTH}
    with preserved_scene(scene):
        apply_estimator(scene, replace(choice, biased=True))
        assert fog.cycles.volume_sampling == DISTANCE
        apply_estimator(scene, replace(choice, biased=False))
        assert fog.cycles.volume_sampling == BOTH and not scene.cycles.volume_biased
