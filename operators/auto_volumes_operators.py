"""``bpy.ops.xsl.preview_auto_volumes`` and ``bpy.ops.xsl.apply_auto_volumes``: what Auto
Volumes would render the current frame with, and that choice written into the file."""
from __future__ import annotations

import bpy


def _shot_choice(scene):
    from ..addon.auto_volumes import shot_range
    from ..addon.maps.shot_choice import choose_for_shot
    from ..core.sampling.shot_plan import shot_of

    return choose_for_shot(scene, shot_of(scene.frame_current, *shot_range(scene)))


def _poll(cls, context) -> bool:
    from ..addon.cycles.volume_record import unsupported

    if context.scene is None:
        cls.poll_message_set("There is no scene")
        return False
    reason = unsupported()
    if reason:
        cls.poll_message_set(reason)
        return False
    return True


class XSL_OT_preview_auto_volumes(bpy.types.Operator):
    """Show what Auto Volumes renders this frame with: each volume's estimator and step, volume sampling, light tree, sample pattern and the predicted error"""

    bl_idname = "xsl.preview_auto_volumes"
    bl_label = "Preview"

    @classmethod
    def poll(cls, context):
        return _poll(cls, context)

    def execute(self, context):
        from ..addon.panel.auto_volumes_ui import previews
        from ..core.errors import InputError
        from ..core.panel.auto_volumes import preview_lines

        scene = context.scene
        try:
            plan = _shot_choice(scene)
        except InputError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        previews[(scene.as_pointer(), scene.frame_current)] = preview_lines(
            plan.choice, plan.shot, plan.frame, plan.frames)
        self.report({"INFO"}, f"Auto Volumes: {plan.describe()}")
        return {"FINISHED"}


class XSL_OT_apply_auto_volumes(bpy.types.Operator):
    """Write Auto Volumes' choice for this frame's shot into the scene's own volume settings (for renders without this extension); Auto Volumes is turned off, as the file now carries its choice"""

    bl_idname = "xsl.apply_auto_volumes"
    bl_label = "Apply to Scene"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _poll(cls, context)

    def execute(self, context):
        from dataclasses import replace

        from ..addon.cycles.selective_render import apply_estimator
        from ..addon.maps.shot_choice import applied
        from ..core.errors import InputError
        from ..core.sampling.sample_pattern import needs_debug_options

        scene = context.scene
        try:
            plan = _shot_choice(scene)
        except InputError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        choice, kept = plan.choice, ""
        if choice.sample_pattern is not None and needs_debug_options(choice.sample_pattern):
            # Cycles renders it only with Blender's debug options on, which a file cannot carry.
            choice, kept = replace(choice, sample_pattern=None), "; the sample pattern stays the file's"
        apply_estimator(scene, choice)
        for datablock in (scene, scene.world, *bpy.data.materials):
            if datablock is not None:
                datablock.update_tag()          # add-on properties do not tag: the viewport
        scene.xsl_render.auto_volumes = False
        self.report({"INFO"}, f"Applied: {applied(choice)}{kept}; Auto Volumes is off")
        return {"FINISHED"}
