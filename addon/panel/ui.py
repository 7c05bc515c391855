"""The artist panel: Properties > Render > XSL Selective Rendering (Cycles only).

Buttons run ``bpy.ops.xsl.compute_maps / render_selective / render_gold / compare`` (modal,
ESC cancels; see ``operators/job_operator.py``); the sampler is the paper's director map or
the guided render within a time budget ("Guided Render"); the sub-panels hold the paper's
map options and the sampling of ``scene.xsl_render``; the header's menu applies the fog
presets.
"""
from __future__ import annotations

import textwrap

import bpy

from ...core.panel.settings import PRESETS, uses_budget
from .auto_volumes_ui import draw_preview, draw_switch


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


def _map_in_use(settings) -> str:
    """The director map the next render uses: the sampler's, or the guided importance."""
    return settings.importance if uses_budget(settings) else settings.director


class _XSLPanel:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {"CYCLES"}

    @classmethod
    def poll(cls, context):
        scene = context.scene
        return scene is not None and scene.render.engine in cls.COMPAT_ENGINES


class RENDER_PT_xsl_render(_XSLPanel, bpy.types.Panel):
    bl_label = "XSL Selective Rendering"

    def draw_header_preset(self, context):
        self.layout.menu(XSL_MT_presets.bl_idname, text="", icon="PRESET")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        draw_switch(layout, context.scene)
        draw_preview(layout, context.scene)
        layout.separator()
        settings = context.scene.xsl_render
        layout.prop(settings, "sampler", expand=True)
        budget = uses_budget(settings)
        if budget:
            layout.prop(settings, "time_budget")
            layout.prop(settings, "importance")
        else:
            layout.prop(settings, "director", expand=True)

        column = layout.column(align=True)
        column.operator("xsl.compute_maps", icon="IMAGE_DATA")
        row = column.row(align=True)
        animation = settings.use_animation
        selective = "Guided Render" if budget else "Selective Render"
        for idname, text in (("xsl.render_selective", selective), ("xsl.render_gold", "Gold Render")):
            op = row.operator(idname, text=text + (" (Frames)" if animation else ""),
                              icon="RENDER_ANIMATION" if animation else "RENDER_STILL")
            op.animation = animation
            op.filepath = settings.filepath if animation else ""
        column.operator("xsl.compare", icon="IMAGE_REFERENCE")

        status = getattr(context.window_manager, "xsl_render_status", None)
        if status is None:
            return
        if status.running:
            layout.progress(factor=status.fraction, type="BAR",
                            text=f"{status.label}: {status.message}")
            layout.label(text="ESC cancels; the scene's settings come back", icon="INFO")
        elif status.last_report:
            box = layout.box()
            for line in textwrap.wrap(status.last_report, 56):
                box.label(text=line)


class RENDER_PT_xsl_render_maps(_XSLPanel, bpy.types.Panel):
    bl_label = "Director Maps"
    bl_parent_id = "RENDER_PT_xsl_render"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        settings = context.scene.xsl_render
        column = layout.column(heading="XS")
        column.prop(settings, "wx")
        column.prop(settings, "ws")
        column.prop(settings, "xs_op")
        column = layout.column(heading="XSL")
        column.active = _map_in_use(settings) == "XSL"
        column.prop(settings, "wxs")
        column.prop(settings, "wl")
        column.prop(settings, "xsl_op")
        layout.prop(settings, "minbound")


class RENDER_PT_xsl_render_light(_XSLPanel, bpy.types.Panel):
    bl_label = "Light Map"
    bl_parent_id = "RENDER_PT_xsl_render_maps"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        settings = context.scene.xsl_render
        layout.active = _map_in_use(settings) == "XSL"
        layout.prop(settings, "light_auto")
        column = layout.column()
        column.active = not settings.light_auto
        column.prop(settings, "light_n")
        column.prop(settings, "light_sigma_base")


class RENDER_PT_xsl_render_sampling(_XSLPanel, bpy.types.Panel):
    bl_label = "Sampling"
    bl_parent_id = "RENDER_PT_xsl_render"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        settings = context.scene.xsl_render
        column = layout.column(align=True)
        # With the time budget, Max Samples is the guided render's per-pixel ceiling.
        column.prop(settings, "max_spp", **({"text": "Max Samples (ceiling)"} if uses_budget(settings) else {}))
        row = column.row(align=True)
        row.active = not uses_budget(settings)
        row.prop(settings, "min_spp")
        layout.prop(settings, "tile_size")
        layout.prop(settings, "volume_estimator")
        layout.prop(settings, "denoise")


class RENDER_PT_xsl_render_animation(_XSLPanel, bpy.types.Panel):
    bl_label = "Animation"
    bl_parent_id = "RENDER_PT_xsl_render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.scene.xsl_render, "use_animation", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        scene = context.scene
        settings = scene.xsl_render
        layout.active = settings.use_animation
        layout.prop(settings, "filepath")
        layout.label(text=f"Frames {scene.frame_start}-{scene.frame_end}, step {scene.frame_step} "
                          "(Output properties)", icon="TIME")


CLASSES = (XSL_MT_presets, RENDER_PT_xsl_render, RENDER_PT_xsl_render_maps,
           RENDER_PT_xsl_render_light, RENDER_PT_xsl_render_sampling, RENDER_PT_xsl_render_animation)
