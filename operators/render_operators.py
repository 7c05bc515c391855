"""``bpy.ops.xsl.render_budget``, ``render_selective`` and ``render_gold``: the panel's renders
(within its time budget, the paper's selective render, the gold standard), with the settings
of ``scene.xsl_render``. The result is shown as images ("XSL Render" and "XSL Samples", or "XSL
Gold" and "XSL Gold Samples") and, with ``filepath`` or ``animation``, written as EXR files as
``xsl-render render`` writes them.
"""
from __future__ import annotations

import bpy

from ..addon.panel.properties import path_options
from .job_operator import JobOperator
from .jobs import gold_job, selective_job

_ANIMATION = bpy.props.BoolProperty(
    name="Animation", default=False,
    description="Render the scene's frame range, each frame with its own maps, as numbered EXRs")
_FILEPATH = bpy.props.StringProperty(
    name="Output", subtype="FILE_PATH", default="", options=path_options(),
    description="EXR file to write (optional for one frame; for animations the pattern, e.g. "
                "//render/frame_####.exr; empty: the scene's output path)")


class XSL_OT_render_budget(JobOperator, bpy.types.Operator):
    """Render within the time budget: as many samples as its seconds afford, with the panel's
    Volumes estimator; result in the "XSL Render" and "XSL Samples" images"""

    bl_idname = "xsl.render_budget"
    bl_label = "Render Within Budget"
    bl_options = {"REGISTER"}

    animation: _ANIMATION
    filepath: _FILEPATH

    def make_job(self, context, modal: bool):
        return selective_job(context.scene, self.animation, self.filepath, budget=True)


class XSL_OT_render_selective(JobOperator, bpy.types.Operator):
    """Render with samples where a viewer will notice them (the paper): the director map (XS
    or XSL) scales Max Samples per pixel; result in the "XSL Render" and "XSL Samples" images"""

    bl_idname = "xsl.render_selective"
    bl_label = "Selective Render"
    bl_options = {"REGISTER"}

    animation: _ANIMATION
    filepath: _FILEPATH

    def make_job(self, context, modal: bool):
        return selective_job(context.scene, self.animation, self.filepath)


class XSL_OT_render_gold(JobOperator, bpy.types.Operator):
    """Render the gold standard: Max Samples in every pixel (the reference for Compare);
    result in the "XSL Gold" image"""

    bl_idname = "xsl.render_gold"
    bl_label = "Gold Render"
    bl_options = {"REGISTER"}

    animation: _ANIMATION
    filepath: _FILEPATH

    def make_job(self, context, modal: bool):
        # In the panel the frame renders in bands (bit-identical) so that ESC can stop it.
        return gold_job(context.scene, self.animation, self.filepath, banded=modal)
