"""``bpy.ops.xsl.compute_maps``: every director map of the frame as an image."""
from __future__ import annotations

import bpy

from .job_operator import JobOperator
from .jobs import maps_job


class XSL_OT_compute_maps(JobOperator, bpy.types.Operator):
    """Compute the Z, X, snapshot, S, L, XS and XSL maps of the current frame and show them as
    images ("XSL X map", ...). Camera rays are kept for the session: after a change to the
    fog only, the X map is recomputed instantly"""

    bl_idname = "xsl.compute_maps"
    bl_label = "Compute Maps"
    bl_options = {"REGISTER"}

    def make_job(self, context, modal: bool):
        return maps_job(context.scene)
