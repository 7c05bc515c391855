"""Auto Volumes in the interface: its switch (in Cycles' own Volumes panel and at the top of
the XSL panel), the preview of its choice for the current frame, Apply to Scene.

Cycles' Volumes panel has no header function and a panel's header functions are fixed when
it registers (re-registering moves it to the end of Render Properties), so the switch is the
first row of the panel, added with ``Panel.prepend``.
"""
from __future__ import annotations

#: The preview the panel shows: (scene pointer, frame) -> its lines, made by the Preview
#: operator (a prediction takes too long for a redraw).
previews: dict[tuple[int, int], list[str]] = {}


def draw_switch(layout, scene) -> None:
    """The Auto Volumes switch, greyed out with the reason where Blender lacks its settings,
    and Lock Interface beside it where a render from the interface needs it."""
    from ..cycles.volume_settings import unsupported

    reason = unsupported()
    row = layout.row()
    row.enabled = not reason
    row.prop(scene.xsl_render, "auto_volumes")
    if reason:
        layout.label(text=reason, icon="ERROR")
    elif scene.xsl_render.auto_volumes and not scene.render.use_lock_interface:
        row = layout.row()
        row.prop(scene.render, "use_lock_interface", text="Lock Interface (needed for F12 here)")


def draw_preview(layout, scene) -> None:
    """Preview and Apply to Scene, and the preview's lines for the current frame."""
    row = layout.row(align=True)
    row.operator("xsl.preview_auto_volumes", icon="VIEWZOOM")
    row.operator("xsl.apply_auto_volumes", icon="CHECKMARK")
    lines = previews.get((scene.as_pointer(), scene.frame_current))
    if lines:
        box = layout.box()
        for line in lines:
            box.label(text=line)


def draw_in_cycles_volumes(self, context) -> None:
    """The first row of Cycles' Volumes panel (Render Properties › Volumes)."""
    scene = getattr(context, "scene", None)
    if scene is not None and hasattr(scene, "xsl_render"):
        draw_switch(self.layout, scene)


def _cycles_volumes_panel():
    import bpy

    return getattr(bpy.types, "CYCLES_RENDER_PT_volumes", None)


def register() -> None:
    panel = _cycles_volumes_panel()
    if panel is not None:
        panel.prepend(draw_in_cycles_volumes)


def unregister() -> None:
    panel = _cycles_volumes_panel()
    if panel is not None:
        panel.remove(draw_in_cycles_volumes)
