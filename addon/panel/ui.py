"""The artist panel: Properties > Render > XSL Render (Cycles only).

What pays comes first: Auto Volumes with its preview, then a render within a time budget
(``bpy.ops.xsl.render_budget``). The paper's system, its maps and selective render, is one
sub-panel closed by default; the gold standard and Compare are another ("Validate"). Buttons
run modal operators (ESC cancels; ``operators/job_operator.py``); the presets menu sits on the
paper's sub-panel.
"""
from __future__ import annotations

import textwrap

import bpy

from ...core.panel.settings import PRESETS
from .auto_volumes_ui import draw_preview, draw_switch

PAPER_LABEL = "Perceptual Selective Rendering (Sundstedt 2007)"


class XSL_MT_presets(bpy.types.Menu):
    """Map options for a kind of medium (the paper's section 4.4)"""

    bl_idname = "XSL_MT_presets"
    bl_label = "XSL Presets"

    def draw(self, context):
        layout = self.layout
        for key, preset in PRESETS.items():
            layout.operator("xsl.apply_preset", text=preset.label).preset = key
        layout.separator()
        layout.operator("xsl.reset_settings", icon="PREFERENCES")


class _XSLPanel:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {"CYCLES"}

    @classmethod
    def poll(cls, context):
        scene = context.scene
        return scene is not None and scene.render.engine in cls.COMPAT_ENGINES


def _split(layout):
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


def _render_button(layout, settings, idname: str, text: str) -> None:
    """A render operator's button: the frame, or the frame range with Animation on."""
    animation = settings.use_animation
    op = layout.operator(idname, text=text + (" (Frames)" if animation else ""),
                         icon="RENDER_ANIMATION" if animation else "RENDER_STILL")
    op.animation = animation
    op.filepath = settings.filepath if animation else ""


class RENDER_PT_xsl_render(_XSLPanel, bpy.types.Panel):
    bl_label = "XSL Render"

    def draw(self, context):
        layout = _split(self.layout)
        scene = context.scene
        draw_switch(layout, scene)
        draw_preview(layout, scene)
        layout.separator()
        settings = scene.xsl_render
        layout.prop(settings, "time_budget")
        layout.prop(settings, "volume_estimator")
        _render_button(layout, settings, "xsl.render_budget", "Render Within Budget")
        status = getattr(context.window_manager, "xsl_render_status", None)
        if status is None:
            return
        if status.running:
            layout.progress(factor=status.fraction, type="BAR", text=f"{status.label}: {status.message}")
            layout.label(text="ESC cancels; the scene's settings come back", icon="INFO")
        elif status.last_report:
            box = layout.box()
            for line in textwrap.wrap(status.last_report, 56):
                box.label(text=line)


class RENDER_PT_xsl_render_paper(_XSLPanel, bpy.types.Panel):
    bl_label = PAPER_LABEL
    bl_parent_id = "RENDER_PT_xsl_render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header_preset(self, context):
        self.layout.menu(XSL_MT_presets.bl_idname, text="", icon="PRESET")

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.xsl_render
        layout.prop(settings, "director", expand=True)
        column = layout.column(align=True)
        column.prop(settings, "max_spp")
        column.prop(settings, "min_spp")
        layout.prop(settings, "tile_size")
        layout.prop(settings, "denoise")
        layout.prop(settings, "importance")
        column = layout.column(align=True)
        column.operator("xsl.compute_maps", icon="IMAGE_DATA")
        _render_button(column, settings, "xsl.render_selective", "Selective Render")


class RENDER_PT_xsl_render_maps(_XSLPanel, bpy.types.Panel):
    bl_label = "Director Maps"
    bl_parent_id = "RENDER_PT_xsl_render_paper"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.xsl_render
        column = layout.column(heading="XS")
        column.prop(settings, "wx")
        column.prop(settings, "ws")
        column.prop(settings, "xs_op")
        column = layout.column(heading="XSL")
        column.active = settings.director == "XSL" or settings.importance == "XSL"
        column.prop(settings, "wxs")
        column.prop(settings, "wl")
        column.prop(settings, "xsl_op")
        layout.prop(settings, "minbound")


class RENDER_PT_xsl_render_light(_XSLPanel, bpy.types.Panel):
    bl_label = "Light Map"
    bl_parent_id = "RENDER_PT_xsl_render_maps"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.xsl_render
        layout.active = settings.director == "XSL" or settings.importance == "XSL"
        layout.prop(settings, "light_auto")
        column = layout.column()
        column.active = not settings.light_auto
        column.prop(settings, "light_n")
        column.prop(settings, "light_sigma_base")


class RENDER_PT_xsl_render_validate(_XSLPanel, bpy.types.Panel):
    bl_label = "Validate"
    bl_parent_id = "RENDER_PT_xsl_render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.label(text="The gold standard: Max Samples in every pixel")
        column = layout.column(align=True)
        _render_button(column, context.scene.xsl_render, "xsl.render_gold", "Gold Render")
        column.operator("xsl.compare", icon="IMAGE_REFERENCE")


class RENDER_PT_xsl_render_animation(_XSLPanel, bpy.types.Panel):
    bl_label = "Animation"
    bl_parent_id = "RENDER_PT_xsl_render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.scene.xsl_render, "use_animation", text="")

    def draw(self, context):
        layout = _split(self.layout)
        scene = context.scene
        settings = scene.xsl_render
        layout.active = settings.use_animation
        layout.prop(settings, "filepath")
        layout.label(text=f"Frames {scene.frame_start}-{scene.frame_end}, step {scene.frame_step} "
                          "(Output properties)", icon="TIME")


CLASSES = (XSL_MT_presets, RENDER_PT_xsl_render, RENDER_PT_xsl_render_paper, RENDER_PT_xsl_render_maps,
           RENDER_PT_xsl_render_light, RENDER_PT_xsl_render_validate, RENDER_PT_xsl_render_animation)
