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
from ..scene.state import DEBUG_PATTERN_PREFERENCES, let_session_go


def apply_sample_pattern(scene, pattern: str, changes=None) -> None:
    """Render ``scene`` with Cycles' sample ``pattern`` (inside ``preserved_scene``; through
    the change record ``changes`` where given, ``addon.scene.changes``)."""
    if needs_debug_options(pattern):
        _enable_debug_patterns(scene)
    if changes is not None:
        changes.set(scene.cycles, "sampling_pattern", pattern)
    else:
        scene.cycles.sampling_pattern = pattern


def debug_patterns_enabled() -> bool:
    """Whether a Cycles session created now honours a debug pattern."""
    import bpy

    preferences = bpy.context.preferences
    return all(getattr(getattr(preferences, path), name) for path, name in DEBUG_PATTERN_PREFERENCES)


def _enable_debug_patterns(scene) -> None:
    import bpy

    if debug_patterns_enabled():
        return
    preferences = bpy.context.preferences
    for path, name in DEBUG_PATTERN_PREFERENCES:
        setattr(getattr(preferences, path), name, True)
    if scene.render.use_persistent_data:
        # A kept session read the options off; letting it go (the renderer turns persistent
        # data on again), the next render creates one that reads them on.
        let_session_go(scene)
