"""Leave the user's scene exactly as we found it.

Every render xsl_render makes changes settings (engine, samples, border, output, view layer,
materials); all of it happens inside ``preserved_scene(scene)``, which records them first and
puts them back whether the block finishes, raises or is cancelled. Materials and worlds are
never edited in place: copies are assigned (``swap_material``), datablocks created inside are
removed at the end unless kept, and a setting of a datablock found elsewhere (a medium's
material through an instance) goes through the block's change record, put back by identity
(``addon.scene.changes``)."""
from __future__ import annotations

from contextlib import contextmanager

from .changes import ChangeRecord, plain

# RNA property types we record and restore by value.
_VALUE_TYPES = {"BOOLEAN", "INT", "FLOAT", "STRING", "ENUM"}
# Collections of bpy.data whose new members are removed at the end of a block.
_DATA_COLLECTIONS = ("materials", "worlds", "images", "node_groups", "objects", "meshes",
                     "lights", "cameras", "textures", "collections", "volumes")


def rna_values(struct, skip: tuple[str, ...] = ()) -> dict:
    """The editable value properties (and ID pointers) of an RNA struct, as plain data.

    A datablock's ``name`` is its identity, not a setting, and is left out; other structs'
    ``name`` is a setting (a colour space's, say) and is kept."""
    values = {}
    identity = ("name",) if _is_id(struct) else ()
    for prop in struct.bl_rna.properties:
        name = prop.identifier
        if name == "rna_type" or name in identity or name in skip or prop.is_readonly:
            continue
        if getattr(prop, "is_deprecated", False):   # kept only for old scripts; we never set them
            continue
        if prop.type in _VALUE_TYPES:
            value = getattr(struct, name)
            if getattr(prop, "is_array", False) or (prop.type != "STRING" and hasattr(value, "__len__")
                                                    and not isinstance(value, (str, set))):
                value = tuple(value)
            elif isinstance(value, set):
                value = frozenset(value)
            values[name] = value
        elif prop.type == "POINTER" and getattr(prop.fixed_type, "bl_rna", None) is not None:
            target = getattr(struct, name)
            if target is None or _is_id(target):
                values[name] = target
    return values


def _is_id(value) -> bool:
    import bpy

    return isinstance(value, bpy.types.ID)


def restore_values(struct, values: dict) -> None:
    """Set every recorded property back, in two passes (some settings depend on others)."""
    for _ in range(2):
        for name, value in values.items():
            try:
                if plain(getattr(struct, name)) != value:
                    setattr(struct, name, set(value) if isinstance(value, frozenset) else value)
            except (AttributeError, TypeError, ValueError, RuntimeError):
                # A property that is only settable in some states; the second pass retries.
                continue
    if values.get("name") == "" and struct.bl_rna.identifier in _COLORSPACE_STRUCTS \
            and struct.name != "":
        _clear_colorspace_name(struct)


#: Structs that are Blender's ``ColorManagedColorspaceSettings``: one ``char name[64]``.
_COLORSPACE_STRUCTS = ("ColorManagedInputColorspaceSettings",)


def _clear_colorspace_name(struct) -> None:
    """Give a colour space its empty name back. Files saved before Blender 5 (and new scenes)
    hold "" in the image format's linear colour space, which the interface cannot set:
    choosing a file format fills it in (with 'sRGB' for PNG) and every render to a file
    chooses one. The struct is a single ``char name[64]``, so a zero first byte is exactly
    the empty name; read back through RNA to make sure."""
    import ctypes

    ctypes.memset(struct.as_pointer(), 0, 1)
    if struct.name != "":
        raise RuntimeError(f"could not restore the empty colour space of {struct!r}")


def _structs(scene) -> dict:
    """Name -> RNA struct for everything a render may touch."""
    image = scene.render.image_settings
    structs = {
        "scene": scene,
        "render": scene.render,
        "image_settings": image,
        # Setting the file format (every render to a file does) sets these too.
        "image_linear_colorspace": image.linear_colorspace_settings,
        "image_view_settings": image.view_settings,
        "image_display_settings": image.display_settings,
        "view_settings": scene.view_settings,
        "display_settings": scene.display_settings,
    }
    if hasattr(scene, "cycles"):
        structs["cycles"] = scene.cycles
    for layer in scene.view_layers:
        structs[f"view_layer:{layer.name}"] = layer
        if hasattr(layer, "cycles"):
            structs[f"view_layer_cycles:{layer.name}"] = layer.cycles
    if scene.world is not None and hasattr(scene.world, "cycles_visibility"):
        structs["world_visibility"] = scene.world.cycles_visibility
    if scene.world is not None and hasattr(scene.world, "cycles"):
        structs["world_cycles"] = scene.world.cycles           # the world volume's step size
    # The materials' own Cycles settings (a volume's step rate: --estimator auto may set it).
    materials = {slot.material for ob in scene.objects for slot in ob.material_slots
                 if slot.material is not None}
    for material in sorted(materials, key=lambda m: m.name):
        if hasattr(material, "cycles"):
            structs[f"material_cycles:{material.name}"] = material.cycles
    return structs


def settings_dump(scene) -> dict:
    """Every recorded setting of the scene, render, Cycles and view layers, and the Cycles
    settings of every material and world of the file (a run may reach them through
    instances, Geometry Nodes or libraries), for comparing."""
    import bpy

    dump = {name: rna_values(struct) for name, struct in _structs(scene).items()}
    dump["material_slots"] = _material_slots(scene)
    dump["hide_render"] = {ob.name: ob.hide_render for ob in scene.objects}
    dump["datablocks_cycles"] = {f"{type(item).__name__}:{item.name_full}": rna_values(item.cycles)
                                 for collection in (bpy.data.materials, bpy.data.worlds)
                                 for item in collection if hasattr(item, "cycles")}
    return dump


def _material_slots(scene) -> dict:
    return {ob.name: tuple((slot.link, slot.material) for slot in ob.material_slots)
            for ob in scene.objects}


class SceneState:
    """Handle given to the body of ``preserved_scene``: swap materials, keep datablocks, and
    ``changes``, the block's change record (``scene_changes``)."""

    def __init__(self, scene):
        self.scene = scene
        self._kept: set = set()
        self.changes = ChangeRecord()

    def swap_material(self, ob, slot_index: int, material, link: str | None = None) -> None:
        """Put ``material`` into a slot for the duration of the block (the original returns).

        ``link="OBJECT"`` makes the slot override whatever material the evaluated geometry
        carries (a geometry-nodes Set Material, say), which a data slot would not."""
        slot = ob.material_slots[slot_index]
        if link is not None and slot.link != link:
            slot.link = link
        slot.material = material

    def keep(self, datablock) -> None:
        """Do not remove this datablock at the end (e.g. an image shown to the artist)."""
        self._kept.add(datablock.as_pointer())


#: Per scene (its pointer), the most samples per pixel a render of ours asked of the Cycles
#: session persistent data keeps for it: with blue noise a later render of fewer samples
#: draws them from that longer sequence (``core.sampling.sample_pattern.session_sequence``).
#: Absent: not known (a session kept from before, whose renders may have asked for any
#: count). The outermost ``preserved_scene`` lets a session we rendered in go.
_session_counts: dict[int, int] = {}


def session_largest_count(scene) -> int | None:
    """The most samples per pixel asked of the scene's kept Cycles session, None if not known."""
    return _session_counts.get(scene.as_pointer())


def note_session_count(scene, samples: int) -> None:
    """A render of ``samples`` per pixel in the scene's kept session."""
    key = scene.as_pointer()
    _session_counts[key] = max(_session_counts.get(key, 0), int(samples))


def let_session_go(scene) -> None:
    """Turn persistent data off: Blender frees the scene's kept Cycles session (with it what
    it synced and the counts it rendered), and its next render creates a fresh one."""
    scene.render.use_persistent_data = False
    _session_counts[scene.as_pointer()] = 0


def forget_session_counts() -> None:
    """A new run starts: the artist may have rendered since, any count."""
    _session_counts.clear()


def preserved_scene_open(scene) -> bool:
    """Whether a ``preserved_scene`` block is open on ``scene``."""
    return scene.as_pointer() in _open_blocks


def scene_changes(scene) -> ChangeRecord:
    """The change record of the innermost ``preserved_scene`` block open on ``scene``: what
    is changed through it is put back when that block ends."""
    records = _open_records.get(scene.as_pointer())
    if not records:
        raise RuntimeError(f"no preserved_scene block is open on scene '{scene.name}': "
                           "its changes would not be put back")
    return records[-1]


@contextmanager
def preserved_scene(scene):
    """Record the scene's settings, run the block, put everything back.

    Restores: scene, render, image, colour-management, Cycles and view-layer settings
    (frame, camera, world, engine, samples, border, output path, persistent data, passes,
    volume flags, material override), material slot assignments and object render
    visibility, every setting changed through the block's change record (``scene_changes``),
    and the animated values of the scene's frame when the block changed the frame; removes
    datablocks the block created (unless kept). The outermost block also puts back the
    Blender preferences a debug sample pattern turns on (``DEBUG_PATTERN_PREFERENCES``).
    """
    import bpy

    structs = _structs(scene)
    saved = {name: rna_values(struct) for name, struct in structs.items()}
    slots = {ob: [(slot.link, slot.material) for slot in ob.material_slots] for ob in scene.objects}
    hidden = {ob: ob.hide_render for ob in scene.objects}
    before = {name: set(item.as_pointer() for item in getattr(bpy.data, name))
              for name in _DATA_COLLECTIONS}
    state = SceneState(scene)
    frame = (scene.frame_current, scene.frame_subframe)
    key = scene.as_pointer()
    preferences = _preference_values() if key not in _open_blocks else None
    _open_blocks[key] = _open_blocks.get(key, 0) + 1
    _open_records.setdefault(key, []).append(state.changes)
    try:
        yield state
    finally:
        moved = (scene.frame_current, scene.frame_subframe) != frame
        _open_blocks[key] -= 1
        _open_records[key].pop()
        outermost = not _open_blocks[key]
        if outermost:
            del _open_blocks[key], _open_records[key]
        # What the run changed through its records, for the outermost block to tag.
        changed = _changed_datablocks.setdefault(key, {})
        changed.update((item.as_pointer(), item) for item in state.changes.datablocks())
        touched = _volume_changes(structs, saved) if outermost else set()
        # Settings first: they matter most and cannot fail as a whole.
        failure = None
        try:
            state.changes.restore()
        except (AttributeError, TypeError, ValueError, RuntimeError) as error:
            failure = error                 # the rest still goes back; raised at the end
        for name, struct in structs.items():
            restore_values(struct, saved[name])
        if outermost:
            changed = _changed_datablocks.pop(key)
            for item in changed.values():
                try:
                    item.update_tag()       # their own settings changed (a material's step)
                except ReferenceError:
                    pass
            if changed:
                scene.update_tag()
        if touched:
            # Cycles' volume settings (and its sample pattern) are add-on properties, which do
            # not tag the scene: with the artist's persistent data on, their next render would
            # keep the block's. Only
            # the outermost block tags: an inner one (a frame of a range) would make the next
            # frame sync the whole scene again (Blender 5's octree for null scattering). A
            # material's or the world's own step needs its own tag.
            scene.update_tag()
            for name in touched - {"cycles"}:
                structs[name].id_data.update_tag()
        if outermost and _session_counts.get(key) and scene.render.use_persistent_data:
            # The artist keeps a session (persistent data): let go of the one the block
            # rendered in, whose longest sample count their next render would otherwise
            # draw its blue noise from (``core.sampling.sample_pattern.session_sequence``).
            # Their next render syncs the scene afresh.
            let_session_go(scene)
            scene.render.use_persistent_data = True
        if outermost:
            _session_counts.pop(key, None)      # the artist's renders are not ours to count
        if preferences is not None:
            # After the settings: a debug sample pattern reads back only while they are on.
            _restore_preferences(preferences)
        if moved:
            # Setting frame_current back does not re-evaluate the animation: the animated
            # values (fog density, lamp energy...) would keep the later frame's until the
            # next update. frame_set evaluates them at the scene's own frame again.
            scene.frame_set(frame[0], subframe=frame[1])
        for ob, entries in slots.items():
            _restore_slots(ob, entries)
        for ob, value in hidden.items():
            if ob.hide_render != value:
                ob.hide_render = value
        for name in _DATA_COLLECTIONS:
            collection = getattr(bpy.data, name)
            for item in list(collection):
                pointer = item.as_pointer()
                if pointer not in before[name] and pointer not in state._kept \
                        and not _render_output(item):
                    collection.remove(item)
        if failure is not None:
            raise failure


#: preserved_scene blocks open per scene (its pointer): they nest (a range around its frames).
_open_blocks: dict[int, int] = {}
#: Their change records, innermost last (``scene_changes``).
_open_records: dict[int, list[ChangeRecord]] = {}
#: Per scene, the datablocks its open blocks' records changed: the outermost tags them.
_changed_datablocks: dict[int, dict] = {}


def _volume_changes(structs: dict, saved: dict) -> set[str]:
    """The ``_structs`` names whose volume settings (``volume_*`` of Cycles, the world and
    the materials, and Cycles' sample pattern, which auto may set too) differ from the
    ``saved`` values."""
    return {name for name, struct in structs.items()
            if (name in ("cycles", "world_cycles") or name.startswith("material_cycles:"))
            and any(value != saved[name].get(prop) for prop, value in rna_values(struct).items()
                    if prop.startswith("volume_") or prop == "sampling_pattern")}


#: Blender preferences a block may turn on: (path from ``bpy.context.preferences``, name).
#: Cycles honours a debug sample pattern only with both (``addon.cycles.sample_pattern``).
DEBUG_PATTERN_PREFERENCES = (("view", "show_developer_ui"), ("experimental", "use_cycles_debug"))


def _preference_values() -> dict:
    """The preferences a block may touch, and whether they were unsaved changes already."""
    import bpy

    preferences = bpy.context.preferences
    values = {(path, name): getattr(getattr(preferences, path), name) for path, name in DEBUG_PATTERN_PREFERENCES}
    return values | {("", "is_dirty"): preferences.is_dirty}


def _restore_preferences(values: dict) -> None:
    """Put back what ``_preference_values`` recorded, the unsaved-changes flag last (Blender
    would otherwise save the preferences on quit, if the artist auto-saves them)."""
    import bpy

    preferences = bpy.context.preferences
    for (path, name), value in values.items():
        struct = getattr(preferences, path) if path else preferences
        if getattr(struct, name) != value:
            setattr(struct, name, value)


def _render_output(item) -> bool:
    """Blender's own "Render Result" / "Viewer Node" images, which every render makes. They
    stay: removing one makes Cycles sync the whole scene again at its next render, even with
    persistent data (3.4 s of heterogeneous fog's octree on balls_b at 64x48), which would
    cost every frame of an animation its sync."""
    return getattr(item, "type", None) in ("RENDER_RESULT", "COMPOSITING")


def _restore_slots(ob, entries) -> None:
    # Blocks swap materials in existing slots (SceneState.swap_material); they never add slots.
    for slot, (link, material) in zip(ob.material_slots, entries):
        if slot.link != link:
            slot.link = link
        if slot.material != material:
            slot.material = material
