"""Set the sample pattern auto chose (``core.sampling.sample_pattern``), debug patterns too.

Cycles renders a pattern outside its plain list (Blue-Noise (round), auto's) only where
Blender's developer interface and Cycles' debug options are both on, and it reads them once,
when it creates its render session; a session kept by persistent data and created without
them renders the pure blue noise in the pattern's place, silently. So the options are turned
on before the run's first render, and where they were off, a session the artist's persistent
data kept is let go (Blender frees it when persistent data is turned off); ``preserved_scene``
puts the preferences back when the outermost block ends. The preferences are never saved.
"""
from __future__ import annotations

from ...core.sampling.sample_pattern import needs_debug_options
from ..scene.state import DEBUG_PATTERN_PREFERENCES, let_session_go, preserved_scene_open


def apply_sample_pattern(scene, pattern: str, changes=None) -> None:
    """Render ``scene`` with Cycles' sample ``pattern`` (inside ``preserved_scene``, or
    through the change record ``changes``, ``addon.scene.changes``: outside every
    ``preserved_scene`` block, the debug preferences and the persistent data go through it
    too; inside one, the outermost block puts them back, once a run)."""
    if needs_debug_options(pattern):
        enable_debug_patterns(scene, None if changes is None or preserved_scene_open(scene) else changes)
    if changes is not None:
        changes.set(scene.cycles, "sampling_pattern", pattern)
    else:
        scene.cycles.sampling_pattern = pattern


def debug_patterns_enabled() -> bool:
    """Whether a Cycles session created now honours a debug pattern."""
    import bpy

    preferences = bpy.context.preferences
    return all(getattr(getattr(preferences, path), name) for path, name in DEBUG_PATTERN_PREFERENCES)


def enable_debug_patterns(scene, changes=None) -> None:
    """Turn the debug preferences on (through ``changes`` where given: the unsaved-changes
    flag noted first, so that it is put back last); a session persistent data kept without
    them is let go."""
    import bpy

    if debug_patterns_enabled():
        return
    preferences = bpy.context.preferences
    if changes is not None:
        changes.set(preferences, "is_dirty", preferences.is_dirty)
    for path, name in DEBUG_PATTERN_PREFERENCES:
        if changes is not None:
            changes.set(getattr(preferences, path), name, True)
        else:
            setattr(getattr(preferences, path), name, True)
    if scene.render.use_persistent_data:
        # A kept session read the options off; letting it go (the renderer turns persistent
        # data on again), the next render creates one that reads them on.
        if changes is not None:
            changes.set(scene.render, "use_persistent_data", True)      # noted, put back
        let_session_go(scene)
