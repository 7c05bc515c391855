"""Issue 46, point 1: what ``--estimator auto`` changes is put back wherever the media live.

Auto finds its media in the evaluated scene (collection instances, Geometry Nodes, linked
libraries); the scene's settings were saved from the objects' slots only, so a medium reached
another way kept auto's step and volume sampling, and each run built on the last (balls_b's
thin fog went 1 -> 8 -> 64 -> 512). A linked ``Fog`` beside a local ``Fog`` was looked up by
name, so auto changed the local one and the render did not follow its own stats.
"""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from conftest import EXAMPLES

from xsl_render.core.imageio import read_image

pytestmark = [pytest.mark.blender, pytest.mark.render]

#: Small enough to be quick; balls_b's fog at 16 spp makes auto march it at 0.5, the thin
#: copy at a coarser step of its own, and both by distance sampling.
RUN = ["render", "--mode", "uniform", "--spp", "16", "--max-spp", "16", "--estimator", "auto",
       "--resolution", "64x48", "--no-denoise", "--quiet"]


@pytest.fixture(scope="module")
def addon():
    import xsl_render

    xsl_render.register()
    yield xsl_render
    xsl_render.unregister()


def _open_balls_b(bpy, folder):
    copy = folder / "balls_b.blend"
    shutil.copy(EXAMPLES / "balls_b.blend", copy)
    bpy.ops.wm.open_mainfile(filepath=str(copy))
    scene = bpy.context.scene
    fog = bpy.data.objects["Fog"]
    thin = fog.material_slots[0].material.copy()
    thin.name = "Thin Fog"
    thin.node_tree.nodes["Fog Peak Density"].inputs[1].default_value = 0.05
    return scene, fog, thin


def instanced_fog(bpy, folder):
    """balls_b with its fog, and a second thinner fog, in a collection the scene shows only
    through an instancing empty: no object of the scene has either material in a slot."""
    scene, fog, thin = _open_balls_b(bpy, folder)
    hidden = bpy.data.collections.new("Fog Set")
    for collection in fog.users_collection:
        collection.objects.unlink(fog)
    hidden.objects.link(fog)
    smaller = fog.copy()
    smaller.data = fog.data.copy()
    smaller.material_slots[0].material = thin
    smaller.scale = (0.5, 0.5, 0.5)
    hidden.objects.link(smaller)
    empty = bpy.data.objects.new("Fog Instance", None)
    empty.instance_type, empty.instance_collection = "COLLECTION", hidden
    scene.collection.objects.link(empty)
    return scene


def geometry_nodes_fog(bpy, folder):
    """balls_b with its fog box's material set by a Geometry Nodes modifier, not a slot."""
    scene, fog, _ = _open_balls_b(bpy, folder)
    material = fog.material_slots[0].material
    fog.data.materials.clear()
    tree = bpy.data.node_groups.new("Set Fog", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    given, result = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    setter = tree.nodes.new("GeometryNodeSetMaterial")
    setter.inputs["Material"].default_value = material
    tree.links.new(given.outputs[0], setter.inputs["Geometry"])
    tree.links.new(setter.outputs[0], result.inputs[0])
    fog.modifiers.new("Set Fog", "NODES").node_group = tree
    return scene


def volume_settings(bpy) -> dict:
    """Every material's and world's volume settings, by full name."""
    return {item.name_full: (item.cycles.volume_step_rate if hasattr(item.cycles, "volume_step_rate")
                             else item.cycles.volume_step_size, item.cycles.volume_sampling)
            for collection in (bpy.data.materials, bpy.data.worlds) for item in collection}


@pytest.mark.parametrize("build", [instanced_fog, geometry_nodes_fog], ids=["instanced", "geometry-nodes"])
def test_three_auto_runs_leave_every_medium_as_it_was(blender, addon, tmp_path, capfd, build):
    from xsl_render.addon.scene.state import settings_dump

    scene = build(blender, tmp_path)
    before, dump = volume_settings(blender), settings_dump(scene)
    images, choices = [], []
    for run in range(3):
        out = tmp_path / f"run{run}.exr"
        assert addon.batch([*RUN, "--out", str(out), "--stats", str(tmp_path / f"run{run}.json")]) == 0
        assert volume_settings(blender) == before
        images.append(read_image(out))
        estimator = json.loads((tmp_path / f"run{run}.json").read_text())["estimator"]
        choices.append((estimator["step_rate"], estimator["medium_settings"], estimator["scatter_sampling"]))
    capfd.readouterr()
    # Auto did change the media (else the test shows nothing): the same each time, and
    # Cycles rendered what it chose each time.
    assert choices[0][2] and "material:Fog" in choices[0][2]
    assert choices[0] == choices[1] == choices[2]
    np.testing.assert_array_equal(images[0], images[2])
    assert settings_dump(scene) == dump
    # The panel's render too.
    scene.xsl_render.max_spp = 4
    assert blender.ops.xsl.render_gold(filepath=str(tmp_path / "gold.exr")) == {"FINISHED"}
    assert volume_settings(blender) == before


def linked_fog(bpy, folder, local_copy: bool):
    """balls_b whose fog box's material ``Fog`` is linked from a library; ``local_copy``: the
    file also keeps an unused local material named ``Fog`` (fake user)."""
    scene, fog, _ = _open_balls_b(bpy, folder)
    own = fog.material_slots[0].material
    library = folder / "fog_library.blend"
    bpy.data.libraries.write(str(library), {own}, fake_user=True)
    own.name = "Unused"
    with bpy.data.libraries.load(str(library), link=True) as (_, linked):
        linked.materials = ["Fog"]
    fog.material_slots[0].material = linked.materials[0]
    if local_copy:
        own.name = "Fog"
        own.use_fake_user = True
    else:
        bpy.data.materials.remove(own)
    return scene, linked.materials[0]


def test_a_linked_medium_keeps_its_settings_and_a_same_named_local_one_is_left_alone(blender, addon, tmp_path,
                                                                                     capfd):
    images = {}
    for local_copy in (True, False):
        folder = tmp_path / ("with" if local_copy else "without")
        folder.mkdir()
        scene, linked = linked_fog(blender, folder, local_copy)
        if local_copy:
            local = blender.data.materials[("Fog", None)]
            assert local.library is None and linked.library is not None
        before = volume_settings(blender)
        assert addon.batch([*RUN, "--out", str(folder / "r.exr"), "--stats", str(folder / "r.json")]) == 0
        assert volume_settings(blender) == before
        estimator = json.loads((folder / "r.json").read_text())["estimator"]
        # The linked fog is not changed, and the stats say so (and claim no change of it).
        assert "Fog" not in json.dumps([estimator["scatter_sampling"], estimator["medium_settings"]])
        assert "material 'Fog' is linked from" in estimator["reason"], estimator["reason"]
        assert "its media keep their own volume settings" in estimator["reason"]
        images[local_copy] = read_image(folder / "r.exr")
    capfd.readouterr()
    # The same file renders the same with or without an unused local material of that name.
    np.testing.assert_array_equal(images[True], images[False])


def test_a_record_used_outside_every_block_puts_back_all_that_auto_set(blender, addon, tmp_path):
    """What a render handler does (apply at render start, restore at its end, in two calls):
    auto's whole choice through an explicit record, no ``preserved_scene`` open; the debug
    preferences its sample pattern needs and the persistent data it lets go come back too."""
    from xsl_render.addon.cycles.selective_render import apply_estimator
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.addon.scene.changes import ChangeRecord
    from xsl_render.addon.scene.state import settings_dump
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = instanced_fog(blender, tmp_path)
    scene.render.use_persistent_data = True
    preferences = blender.context.preferences
    preferences.view.show_developer_ui = preferences.experimental.use_cycles_debug = False
    debug = (preferences.view.show_developer_ui, preferences.experimental.use_cycles_debug,
             preferences.is_dirty)
    before, media = settings_dump(scene), volume_settings(blender)
    choice = choose_estimator(scene, RenderOptions(max_spp=16, estimator="auto", resolution=(64, 48)), 16)
    assert choice.sample_pattern == "BLUE_NOISE_ROUND" and choice.scatter_sampling
    record = ChangeRecord()
    assert apply_estimator(scene, choice, record) == []
    assert blender.data.materials["Fog"].cycles.volume_sampling == "DISTANCE"
    assert preferences.experimental.use_cycles_debug and not scene.render.use_persistent_data
    record.restore()
    assert settings_dump(scene) == before and volume_settings(blender) == media
    assert (preferences.view.show_developer_ui, preferences.experimental.use_cycles_debug,
            preferences.is_dirty) == debug
