"""Extension preferences: the defaults of every panel setting.

``bl_idname`` is the extension's own package (``bl_ext.<repository>.xsl_render`` when
installed, ``xsl_render`` when imported from a checkout), as Blender requires.
"""
from __future__ import annotations

import bpy

from ...core.panel.settings import SETTING_NAMES, builtin_defaults
from .properties import settings_annotations

ROOT_PACKAGE = __package__.rsplit(".", 2)[0]           # <root>.addon.panel -> <root>


def _draw(self, context):
    layout = self.layout
    layout.label(text="Defaults of the XSL Render panel for scenes that have not changed them "
                      "(applied at start-up; the panel's preset menu can copy them now).")
    layout.use_property_split = True
    grid = layout.grid_flow(columns=2, even_columns=True)
    for name in SETTING_NAMES:
        grid.prop(self, name)


XSL_AP_preferences = type("XSL_AP_preferences", (bpy.types.AddonPreferences,), {
    "bl_idname": ROOT_PACKAGE,
    "__annotations__": settings_annotations(),
    "__doc__": "Defaults of the XSL Render panel",
    "draw": _draw,
})


def preferences():
    """The preferences struct, or None when the package is not an enabled add-on (a
    checkout imported by scripts or tests)."""
    addon = bpy.context.preferences.addons.get(ROOT_PACKAGE)
    return None if addon is None else addon.preferences


def default_values() -> dict:
    """Every setting's default: the preferences' value, else the built-in one."""
    values = builtin_defaults()
    prefs = preferences()
    if prefs is not None:
        values.update({name: getattr(prefs, name) for name in values})
    return values
