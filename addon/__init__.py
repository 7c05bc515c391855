"""The Blender side that is not an operator: scene probing, the Cycles driver, state."""

_CLASSES: list = []


def register():
    import bpy

    for cls in _CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    import bpy

    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
