"""The panel's settings on every scene (``scene.xsl_render``) and the run status on the
window manager (``window_manager.xsl_render_status``, never saved).

The settings are Blender properties built from the options of ``core.option_table`` the
panel shows (``core.panel.settings``), with the extension preferences' values as their
defaults: a setting the artist never changed on a scene follows the preferences (read at
start-up; "Defaults from Preferences" in the preset menu copies the current ones).
"""
from __future__ import annotations

import bpy

from ...core.option_table import Option
from ...core.panel.settings import AUTO_VOLUMES, SETTINGS, panel_value


def path_options() -> set:
    """Options of a file path property that may start with Blender's "//" (relative to the
    .blend): Blender 4.5+ warns without the flag, older versions do not know it."""
    try:
        bpy.props.StringProperty(options={"PATH_SUPPORTS_BLEND_RELATIVE"})
    except TypeError:
        return set()
    return {"PATH_SUPPORTS_BLEND_RELATIVE"}


def blender_property(option: Option, default=None):
    """The bpy property of one option (its label, what it does, its range), with ``default``
    (a preferences' value) instead of the table's."""
    value = panel_value(option, option.panel_value) if default is None else default
    common = {"name": option.label, "description": option.help}
    if option.kind == "choice":
        items = [(identifier.upper(), label, text) for identifier, label, text in option.choices]
        return bpy.props.EnumProperty(items=items, default=value, **common)
    if option.kind == "bool":
        return bpy.props.BoolProperty(default=bool(value), **common)
    low = option.low if option.low is not None else option.above
    limits = {key: bound for key, bound in (("min", low), ("max", option.high),
                                            ("soft_min", option.soft_low), ("soft_max", option.soft_high))
              if bound is not None}
    if option.kind == "int":
        limits = {key: int(min(bound, 2 ** 31 - 1)) for key, bound in limits.items()}
        return bpy.props.IntProperty(default=int(value), **limits, **common)
    if option.above is not None:
        # Blender's minimum is inclusive: the smallest step above an exclusive bound.
        limits["min"] = option.above + 0.001
    return bpy.props.FloatProperty(default=float(value), precision=2, step=5, **limits, **common)


_SCENE_ONLY = {
    AUTO_VOLUMES.name: blender_property(AUTO_VOLUMES),
    "use_animation": bpy.props.BoolProperty(
        name="Animation", default=False,
        description="Render the scene's frame range (start to end, by its step), each frame with "
                    "its own maps; the camera rays are reused while camera and geometry stay still"),
    "filepath": bpy.props.StringProperty(
        name="Output", subtype="FILE_PATH", default="", options=path_options(),
        description="Numbered EXR files for animations (frame_####.exr: the last # run becomes the "
                    "frame number); empty: the scene's output path"),
}


def settings_annotations(defaults: dict | None = None) -> dict:
    defaults = defaults or {}
    return {setting.prop or setting.name: blender_property(setting, defaults.get(setting.prop or setting.name))
            for setting in SETTINGS}


def make_settings_class(defaults: dict | None = None) -> type:
    """The scene's PropertyGroup, with ``defaults`` (from the preferences) as its defaults."""
    return type("XSL_PG_settings", (bpy.types.PropertyGroup,), {
        "__annotations__": {**settings_annotations(defaults), **_SCENE_ONLY},
        "__doc__": "XSL Render settings of a scene: the paper's map options and the sampling",
    })


class XSL_PG_status(bpy.types.PropertyGroup):
    """What the running (or last) XSL Render job shows in the panel."""

    running: bpy.props.BoolProperty(name="Running", default=False)
    label: bpy.props.StringProperty(name="Job", default="")
    fraction: bpy.props.FloatProperty(name="Progress", default=0.0, min=0.0, max=1.0, subtype="FACTOR")
    message: bpy.props.StringProperty(name="Message", default="")
    last_report: bpy.props.StringProperty(name="Last Result", default="")
