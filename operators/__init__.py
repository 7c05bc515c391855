"""Blender operators (``bpy.ops.xsl.*``) and the ``xsl-render`` command line."""


def _operator_classes():
    from .scene_info import XSL_OT_scene_info

    return [XSL_OT_scene_info]


def register():
    import bpy

    for cls in _operator_classes():
        bpy.utils.register_class(cls)


def unregister():
    import bpy

    for cls in reversed(_operator_classes()):
        bpy.utils.unregister_class(cls)
