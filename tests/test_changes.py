"""The change record (``addon.scene.changes``): what a run changes is put back by identity,
wherever the datablock was found, and linked data is never written."""
from __future__ import annotations

import pytest

pytestmark = pytest.mark.blender


def _linked_and_local_fog(bpy, folder):
    """A library holding material ``Fog``, linked into an empty file that also keeps a local
    ``Fog`` (fake user): the linked one and the local one."""
    bpy.data.materials.new("Fog").use_fake_user = True
    bpy.ops.wm.save_as_mainfile(filepath=str(folder / "lib.blend"))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with bpy.data.libraries.load(str(folder / "lib.blend"), link=True) as (_, linked):
        linked.materials = ["Fog"]
    local = bpy.data.materials.new("Fog")
    local.use_fake_user = True
    return linked.materials[0], local


def test_settings_are_put_back_newest_first_and_the_written_datablocks_named(blender):
    from xsl_render.addon.scene.changes import ChangeRecord

    material = blender.data.materials.new("Fog")
    world = blender.data.worlds.new("Sky")
    material.cycles.volume_step_rate = 1.5
    record = ChangeRecord()
    assert record.set(material.cycles, "volume_step_rate", 4.0) is True
    assert record.set(material.cycles, "volume_step_rate", 8.0) is True        # the first value is kept
    assert record.set(material.cycles, "volume_sampling", "DISTANCE") is True
    assert record.set(world.cycles, "volume_step_size", world.cycles.volume_step_size) is False
    assert record.set(world.cycles, "volume_step_size", 0.5) is True
    assert {d.name for d in record.datablocks()} == {"Fog", "Sky"}
    assert [d.name for d in record.datablocks(blender.types.Material)] == ["Fog"]
    assert {d.name for d in record.restore()} == {"Fog", "Sky"}
    assert world.cycles.volume_step_size == 1.0
    assert (material.cycles.volume_step_rate, material.cycles.volume_sampling) == (1.5, "MULTIPLE_IMPORTANCE")
    assert record.restore() == [] and record.datablocks() == []              # once only


def test_as_a_context_manager_it_restores_after_an_error(blender):
    from xsl_render.addon.scene.changes import ChangeRecord

    material = blender.data.materials.new("Fog")
    with pytest.raises(RuntimeError, match="boom"), ChangeRecord() as record:
        record.set(material.cycles, "volume_step_rate", 3.0)
        raise RuntimeError("boom")
    assert material.cycles.volume_step_rate == 1.0


def test_a_datablock_removed_meanwhile_does_not_stop_the_others(blender):
    from xsl_render.addon.scene.changes import ChangeRecord

    gone, kept = blender.data.materials.new("Gone"), blender.data.materials.new("Kept")
    record = ChangeRecord()
    record.set(kept.cycles, "volume_step_rate", 2.0)
    record.set(gone.cycles, "volume_step_rate", 2.0)
    blender.data.materials.remove(gone)
    assert [d.name for d in record.restore()] == ["Kept"]
    assert kept.cycles.volume_step_rate == 1.0


def test_linked_data_is_never_written_and_a_same_named_local_one_is_another(blender, tmp_path):
    from xsl_render.addon.scene.changes import ChangeRecord, LinkedDataError, writable

    linked, local = _linked_and_local_fog(blender, tmp_path)
    assert not writable(linked.cycles) and writable(local.cycles)
    record = ChangeRecord()
    with pytest.raises(LinkedDataError, match=r"Material 'Fog \[lib.blend\]' is linked from"):
        record.set(linked.cycles, "volume_sampling", "DISTANCE")
    record.set(local.cycles, "volume_sampling", "DISTANCE")
    assert linked.cycles.volume_sampling == "MULTIPLE_IMPORTANCE"
    record.restore()
    assert local.cycles.volume_sampling == "MULTIPLE_IMPORTANCE"


def test_a_struct_outside_every_datablock_is_put_back_too(blender):
    from xsl_render.addon.scene.changes import ChangeRecord

    preferences = blender.context.preferences
    shown, dirty = preferences.view.show_developer_ui, preferences.is_dirty
    with ChangeRecord() as record:
        record.set(preferences.view, "show_developer_ui", not shown)
        assert record.datablocks() == []
    assert preferences.view.show_developer_ui == shown
    preferences.is_dirty = dirty            # never saved on the test machine
