"""The Blender side that is not an operator: ``scene`` (the scene as plain data, and left as
found), ``cycles`` (driving Cycles: renders, tile windows, denoising, the selective render),
``maps`` (the director maps of a frame) and ``panel`` (properties, preferences, ui). The
modules at this level run whole jobs on top of them: an animation, the validation, a farm
job's tasks.

``register()`` imports the bpy modules only when Blender registers the add-on, so the
command line can import ``addon`` helpers without the panel's classes.
"""

_registered: list = []


def register():
    import bpy

    from . import auto_volumes
    from .panel import auto_volumes_ui, preferences, properties, ui

    # Preferences first: the scene settings take their defaults from them.
    bpy.utils.register_class(preferences.XSL_AP_preferences)
    settings = properties.make_settings_class(preferences.default_values())
    for cls in (properties.XSL_PG_status, settings, *ui.CLASSES):
        bpy.utils.register_class(cls)
    bpy.types.Scene.xsl_render = bpy.props.PointerProperty(
        type=settings, name="XSL Render", description="Perceptual selective rendering settings")
    bpy.types.WindowManager.xsl_render_status = bpy.props.PointerProperty(type=properties.XSL_PG_status)
    _registered[:] = [preferences.XSL_AP_preferences, properties.XSL_PG_status, settings, *ui.CLASSES]
    auto_volumes.register()
    auto_volumes_ui.register()


def unregister():
    import bpy

    from . import auto_volumes
    from .panel import auto_volumes_ui

    auto_volumes_ui.unregister()
    auto_volumes.unregister()
    del bpy.types.WindowManager.xsl_render_status
    del bpy.types.Scene.xsl_render
    for cls in reversed(_registered):
        bpy.utils.unregister_class(cls)
    _registered.clear()
