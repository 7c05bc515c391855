"""``--estimator auto`` turns Cycles' light tree off where the scene has one light
(``core.sampling.light_tree``): what Cycles samples as a light is counted as Cycles counts it
(checked against Cycles' own renders, tree against no tree, in one persistent session), the
choice reaches Cycles, is recorded, and the scene's own setting is back afterwards."""
from __future__ import annotations

import numpy as np
import pytest

from xsl_render.core.sampling.light_tree import auto_light_tree


@pytest.mark.parametrize("uses_tree, lights, links, chosen", [
    (True, 1, False, False),        # one light: the tree has nothing to choose
    (True, 0, False, False),        # no light at all (emission seen directly only)
    (True, 2, False, None),         # several: the tree picks among them, it stays
    (True, 1, True, None),          # light linking chooses through the tree
    (False, 1, False, None),        # off already: the scene's own
    (False, 3, False, None),
])
def test_auto_turns_the_tree_off_only_for_one_light(uses_tree, lights, links, chosen):
    assert auto_light_tree(uses_tree, lights, links) is chosen


def test_the_tree_survives_the_provisional_choice_and_the_settle():
    from dataclasses import replace

    from xsl_render.core.sampling.volume_estimator import choose_step_rate, provisional_choice, settled_for

    measures = {4.0: 0.16, 2.0: 0.11, 1.0: 0.04, 0.5: 0.008, 0.25: 0.0018}
    null = replace(choose_step_rate(measures.__getitem__, 1e6), light_tree=False)
    assert provisional_choice(null).light_tree is False
    for spp in (4, 64, 1e6):
        assert settled_for(null, spp).light_tree is False
    assert "light tree off" in null.describe() and null.to_dict()["light_tree"] is False


W, H = 40, 24


def _scene(blender, lamps: tuple[str, ...] = ("POINT",), world: str = "constant",
           world_sampling: str = "AUTOMATIC", emitter: str = ""):
    """The fog scene with ``lamps`` (types) in place of its two, a ``world`` background
    ("constant" or "textured") and an emissive sphere (``emitter``: "", "sampled",
    "not sampled", "hidden from the camera")."""
    from support.fog_scene import build_fog_scene

    scene = build_fog_scene(blender, W, H, density=0.1)
    for ob in [ob for ob in scene.objects if ob.type == "LIGHT"]:
        blender.data.objects.remove(ob)
    for index, kind in enumerate(lamps):
        lamp = blender.data.objects.new(f"Lamp{index}", blender.data.lights.new(f"Lamp{index}", kind))
        lamp.data.energy = 3.0 if kind == "SUN" else 400.0 + 150.0 * index
        lamp.location = (1.5 - 3.0 * index, 1.0, 3.0)
        scene.collection.objects.link(lamp)
    tree = scene.world.node_tree
    background = next(node for node in tree.nodes if node.type == "BACKGROUND")
    background.inputs["Color"].default_value = (0.3, 0.35, 0.45, 1.0)
    if world == "textured":
        tree.links.new(tree.nodes.new("ShaderNodeTexNoise").outputs["Color"], background.inputs["Color"])
    scene.world.cycles.sampling_method = world_sampling
    if emitter:
        blender.ops.mesh.primitive_uv_sphere_add(radius=0.4, location=(-1.0, 0.0, 2.5), segments=8, ring_count=4)
        sphere = blender.context.object
        material = blender.data.materials.new("Glow")
        principled = material.node_tree.nodes["Principled BSDF"]
        principled.inputs["Emission Strength"].default_value = 20.0
        principled.inputs["Emission Color"].default_value = (1.0, 0.5, 0.2, 1.0)
        material.cycles.emission_sampling = "NONE" if emitter == "not sampled" else "AUTO"
        sphere.data.materials.append(material)
        sphere.visible_camera = emitter != "hidden from the camera"
    return scene


@pytest.mark.blender
@pytest.mark.render
@pytest.mark.parametrize("setup, one_light", [
    (dict(), True),
    (dict(lamps=("SPOT",)), True),
    (dict(lamps=("AREA",), world_sampling="MANUAL"), True),     # a constant world is never sampled
    (dict(world="textured"), False),
    (dict(world="textured", world_sampling="NONE"), True),
    (dict(lamps=("POINT", "SPOT")), False),
    (dict(emitter="sampled"), False),
    (dict(emitter="not sampled"), True),
    (dict(emitter="hidden from the camera"), False),                 # it still lights the fog
    (dict(lamps=(), emitter="sampled"), False),                      # a mesh light: one per triangle
], ids=["point", "spot", "area, manual world", "textured world", "textured world not sampled",
        "two lamps", "emissive sphere", "emission not sampled", "emitter hidden", "emitter alone"])
def test_one_light_as_cycles_counts_it_renders_the_same_estimate_without_the_tree(blender, setup, one_light):
    """Where the count says one light, Cycles' renders with and without the tree differ by
    rounding only (measured: 0.01-0.05 % of what another seed changes); where it says
    several, the tree changes which light each sample takes, and the renders differ by a
    third of that or more. The second render is in the same persistent session, so this also
    shows that a new setting reaches it."""
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer, forget_synced_session
    from xsl_render.addon.scene.light_sampling import sampled_lights
    from xsl_render.addon.scene.state import preserved_scene

    scene = _scene(blender, **setup)
    assert (sampled_lights(scene, blender.context.evaluated_depsgraph_get()) <= 1) is one_light
    forget_synced_session()
    pixels = {}
    with preserved_scene(scene), CyclesWindowRenderer(scene, 0) as renderer:
        for tree in (True, False):
            scene.cycles.use_light_tree = tree
            pixels[tree] = renderer.render(None, 4).pixels[..., :3]
    with preserved_scene(scene), CyclesWindowRenderer(scene, 1) as renderer:
        other_seed = renderer.render(None, 4).pixels[..., :3]
    assert scene.cycles.use_light_tree
    noise = np.abs(pixels[True] - other_seed).mean()
    change = np.abs(pixels[True] - pixels[False]).mean()
    assert noise > 0
    if one_light:
        assert change < 0.01 * noise
    else:
        assert change > 0.2 * noise


@pytest.mark.blender
@pytest.mark.render
@pytest.mark.parametrize("lamps, linked, tree_in_render", [
    (("POINT",), False, False),
    (("POINT", "POINT"), False, True),
    (("POINT",), True, True),
], ids=["one lamp", "two lamps", "one lamp, linked"])
def test_an_auto_run_renders_without_the_tree_where_it_may_and_puts_it_back(
        blender, monkeypatch, lamps, linked, tree_in_render):
    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.cycles.tile_render import CyclesWindowRenderer
    from xsl_render.addon.maps.estimator_choice import with_estimator_choice
    from xsl_render.addon.scene.state import settings_dump
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = _scene(blender, lamps=lamps)
    if linked:
        receivers = blender.data.collections.new("Lit")
        scene.objects["Lamp0"].light_linking.receiver_collection = receivers
    before = settings_dump(scene)
    seen = []
    real_render = CyclesWindowRenderer.render

    def spying(self, *args, **kwargs):
        seen.append(self.scene.cycles.use_light_tree)
        return real_render(self, *args, **kwargs)

    monkeypatch.setattr(CyclesWindowRenderer, "render", spying)
    options = with_estimator_choice(scene, RenderOptions(max_spp=2, estimator="auto").check(), 2)
    outcome = sr.render_uniform(scene, options, spp=2)
    assert seen and set(seen) == {tree_in_render}
    assert outcome.stats.estimator["light_tree"] == (None if tree_in_render else False)
    assert settings_dump(scene) == before and scene.cycles.use_light_tree

    seen.clear()
    sr.render_uniform(scene, RenderOptions(max_spp=2, estimator="scene").check(), spp=2)
    assert set(seen) == {True}                               # other estimators: the file's own
