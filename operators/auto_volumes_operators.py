"""``bpy.ops.xsl.preview_auto_volumes`` and ``bpy.ops.xsl.apply_auto_volumes``: what Auto
Volumes would render the current frame with, and that choice written into the file
(``addon.auto_volumes``)."""
from __future__ import annotations

import bpy


class _AutoVolumesOperator:
    @classmethod
    def poll(cls, context):
        from ..addon.cycles.volume_settings import unsupported

        if context.scene is None:
            cls.poll_message_set("There is no scene")
            return False
        reason = unsupported()
        if reason:
            cls.poll_message_set(reason)
            return False
        return True

    def run(self, context, action):
        """``action(scene)``, a bad scene reported as an error (None then)."""
        from ..core.errors import InputError

        try:
            return action(context.scene)
        except InputError as error:
            self.report({"ERROR"}, str(error))
            return None


class XSL_OT_preview_auto_volumes(_AutoVolumesOperator, bpy.types.Operator):
    """Show what Auto Volumes renders this frame with: each volume's estimator and step, volume sampling, light tree, sample pattern and the predicted error"""

    bl_idname = "xsl.preview_auto_volumes"
    bl_label = "Preview"

    def execute(self, context):
        from ..addon.auto_volumes import current_choice
        from ..addon.panel.auto_volumes_ui import previews
        from ..core.panel.auto_volumes import preview_lines

        plan = self.run(context, current_choice)
        if plan is None:
            return {"CANCELLED"}
        scene = context.scene
        previews[(scene.as_pointer(), scene.frame_current)] = preview_lines(
            plan.choice, plan.shot, plan.frame, plan.frames)
        self.report({"INFO"}, f"Auto Volumes: {plan.describe()}")
        return {"FINISHED"}


class XSL_OT_apply_auto_volumes(_AutoVolumesOperator, bpy.types.Operator):
    """Write Auto Volumes' choice for this frame's shot into the scene's own volume settings (for renders without this extension); Auto Volumes is turned off, as the file now carries its choice"""

    bl_idname = "xsl.apply_auto_volumes"
    bl_label = "Apply to Scene"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        from ..addon.auto_volumes import apply_to_scene
        from ..addon.maps.shot_choice import applied

        done = self.run(context, apply_to_scene)
        if done is None:
            return {"CANCELLED"}
        plan, left_out = done
        self.report({"INFO"}, f"Applied: {applied(plan.choice)}{'; ' + left_out if left_out else ''}; "
                              "Auto Volumes is off")
        return {"FINISHED"}
