"""The settings Auto Volumes changes for a render, recorded first and put back after.

The one place Auto Volumes saves and restores (``addon.cycles.auto_volumes`` calls nothing
else for it): ``FrameRecord`` holds what ``selective_render.apply_estimator`` may set for a
frame (Cycles' volume estimator, step rate, sample pattern and light tree; every material's
and world's own step and volume sampling; persistent data, which a debug sample pattern lets
go) and the stamp note the frame's record is written into; ``JobRecord`` what lasts the
whole render (Blender's preferences a debug sample pattern turns on, persistent data where
Auto Volumes turns it on). Each datablock is held by identity, not by name, so a rename
during the render cannot misdirect a restore.
"""
from __future__ import annotations

from ..scene.state import DEBUG_PATTERN_PREFERENCES

#: What ``apply_estimator`` may set on the scene's Cycles settings.
SCENE_CYCLES = ("volume_biased", "volume_step_rate", "sampling_pattern", "use_light_tree")
#: ... on each material's and world's own Cycles settings.
MATERIAL_CYCLES = ("volume_step_rate", "volume_sampling")
WORLD_CYCLES = ("volume_step_size", "volume_sampling")
#: The render settings a frame's record note uses.
STAMP_NOTE = ("use_stamp_note", "stamp_note_text")
#: The volume settings Blender must have for auto's choice (Blender 5: ray marching per scene,
#: a step per material and per world).
NEEDED_SETTINGS = (("scene", "volume_biased"), ("scene", "volume_step_rate"),
                   ("material", "volume_step_rate"), ("world", "volume_step_size"))


def unsupported() -> str:
    """Why this Blender cannot render with auto's choice ("" where it can)."""
    import bpy

    owners = {"scene": bpy.types.Scene, "material": bpy.types.Material, "world": bpy.types.World}
    for owner, name in NEEDED_SETTINGS:
        cycles = owners[owner].bl_rna.properties.get("cycles")
        if cycles is None:
            return "Cycles is not enabled"
        if name not in cycles.fixed_type.properties:
            return f"this Blender's Cycles has no {owner} setting '{name}' (it needs Blender 5.0 or newer)"
    return ""


class _Values:
    """Named values of RNA structs, each struct with the datablock that owns it."""

    def __init__(self):
        self._entries: list[tuple[object, object, str, object]] = []    # (owner, struct, name, value)

    def add(self, owner, struct, names) -> None:
        for name in names:
            if hasattr(struct, name):
                self._entries.append((owner, struct, name, getattr(struct, name)))

    def changed(self) -> list:
        """The datablocks (once each) whose recorded values differ from their values now."""
        owners = []
        for owner, struct, name, value in self._entries:
            if getattr(struct, name) != value and all(owner is not seen for seen in owners):
                owners.append(owner)
        return owners

    def restore(self) -> list:
        """Put every value back (twice: some settings depend on others); the datablocks
        that had changed."""
        owners = self.changed()
        for _ in range(2):
            for _owner, struct, name, value in self._entries:
                if getattr(struct, name) != value:
                    setattr(struct, name, value)
        return owners


class FrameRecord:
    """A frame's settings as the artist has them, before auto's choice is applied."""

    def __init__(self, scene):
        import bpy

        self._values = _Values()
        self._values.add(scene, scene.cycles, SCENE_CYCLES)
        self._values.add(scene, scene.render, ("use_persistent_data",) + STAMP_NOTE)
        for material in bpy.data.materials:
            if hasattr(material, "cycles"):
                self._values.add(material, material.cycles, MATERIAL_CYCLES)
        for world in bpy.data.worlds:
            if hasattr(world, "cycles"):
                self._values.add(world, world.cycles, WORLD_CYCLES)

    def changed(self) -> list:
        """The datablocks whose settings differ from the record now (to tag for a kept session)."""
        return self._values.changed()

    def restore(self) -> list:
        """Every recorded setting back; the datablocks that had changed."""
        return self._values.restore()


class JobRecord:
    """What a whole render keeps changed: Blender's debug preferences (a debug sample
    pattern needs them while Cycles creates its session, so they stay on from frame to
    frame) and the scene's persistent data (where Auto Volumes turns it on)."""

    def __init__(self, scene):
        import bpy

        preferences = bpy.context.preferences
        self._values = _Values()
        for path, name in DEBUG_PATTERN_PREFERENCES:
            self._values.add(None, getattr(preferences, path), (name,))
        self._dirty = preferences.is_dirty
        self._values.add(scene, scene.render, ("use_persistent_data",))

    def restore(self) -> list:
        """Everything back, the preferences' unsaved-changes flag last (Blender would else
        save them on quit); the datablocks that had changed."""
        import bpy

        owners = [owner for owner in self._values.restore() if owner is not None]
        if bpy.context.preferences.is_dirty != self._dirty:
            bpy.context.preferences.is_dirty = self._dirty
        return owners
