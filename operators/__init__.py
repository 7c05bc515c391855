"""Blender operators (``bpy.ops.xsl.*``) and the ``xsl-render`` command line.

Nothing here imports bpy at import time: the command line stays bpy-free where it can;
``register()`` imports the operator modules.
"""


def _operator_classes():
    from .auto_volumes_operators import XSL_OT_apply_auto_volumes, XSL_OT_preview_auto_volumes
    from .compare_operator import XSL_OT_compare
    from .maps_operator import XSL_OT_compute_maps
    from .render_operators import XSL_OT_render_budget, XSL_OT_render_gold, XSL_OT_render_selective
    from .scene_info import XSL_OT_scene_info
    from .settings_operators import XSL_OT_apply_preset, XSL_OT_reset_settings

    return [XSL_OT_scene_info, XSL_OT_compute_maps, XSL_OT_render_budget, XSL_OT_render_selective,
            XSL_OT_render_gold,
            XSL_OT_compare, XSL_OT_apply_preset, XSL_OT_reset_settings, XSL_OT_preview_auto_volumes,
            XSL_OT_apply_auto_volumes]


def register():
    import bpy

    for cls in _operator_classes():
        bpy.utils.register_class(cls)


def unregister():
    import bpy

    for cls in reversed(_operator_classes()):
        bpy.utils.unregister_class(cls)
