"""How the panel names a setting in an error message: by its property's label ("Min Samples").

Core raises ``SettingError`` naming settings by their fields (``min_spp``, ``core.errors``);
the panel's property of the same name (``scene.xsl_render``, ``properties.py``) lends the
field its label, read from the property group's RNA so that it is the label the artist sees.
:data:`FIELD_PROPERTIES` names the fields whose property is called otherwise (from
``core.option_table``); a field the panel has no property for (the command line's
``tile_quantile``) keeps its name.
"""
from __future__ import annotations

import bpy

from ...core.errors import InputError, SettingError
from ...core.option_table import OPTIONS

#: Fields whose panel property has another name (the option table's ``prop``): field -> property.
FIELD_PROPERTIES = {name: option.prop for name, option in OPTIONS.items() if option.prop}
#: How a label and its value stand together in a message: "Min Samples (8)".
LABEL_AND_VALUE = "{name} ({value})"


def panel_labels() -> dict[str, str]:
    """Field -> the label of the panel's property that sets it."""
    group = bpy.types.Scene.bl_rna.properties["xsl_render"].fixed_type
    labels = {prop.identifier: prop.name for prop in group.properties
              if prop.identifier != "rna_type"}
    for field, prop in FIELD_PROPERTIES.items():
        labels[field] = labels[prop]
    return labels


def in_panel_words(error: InputError) -> str:
    """``error``'s one line as the panel says it: each setting named by its label, its value
    in brackets after it ("Min Samples (8) is larger than Max Samples (4)")."""
    if isinstance(error, SettingError):
        return error.worded(panel_labels(), pair=LABEL_AND_VALUE)
    return str(error)
