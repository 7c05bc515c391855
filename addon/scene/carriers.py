"""What carries a medium's own volume settings in Blender, found by identity: a material's
or the world's Cycles settings, keyed "material:<full name>" or "world:<full name>".

The key holds Blender's full name (``ID.name_full``: "Fog [lib.blend]" for a ``Fog`` linked
from lib.blend, plain "Fog" for a local one), so a linked material and a local one of the
same name have two keys, and ``carrier`` finds the datablock a key was made from, never
another of the same name (``bpy.data.materials["Fog"]`` is the local one). A carrier a run
must not change (linked from a library and not a local override, or a name two datablocks
share) has a ``kept_reason``: auto keeps that medium's own settings.
"""
from __future__ import annotations

from .changes import writable

_COLLECTIONS = {"material": "materials", "world": "worlds"}


def carrier_key(datablock) -> str:
    """The key of a material or world (see the module notes)."""
    import bpy

    kind = "world" if isinstance(datablock, bpy.types.World) else "material"
    return f"{kind}:{datablock.name_full}"


def _candidates(key: str) -> list:
    import bpy

    kind, name = key.split(":", 1)
    return [item for item in getattr(bpy.data, _COLLECTIONS[kind]) if item.name_full == name]


def carrier(key: str):
    """The one material or world with ``key``; KeyError when none or several have it."""
    found = _candidates(key)
    if len(found) != 1:
        raise KeyError(f"{len(found)} datablocks have the key {key!r}")
    return found[0]


def kept_reason(key: str) -> str | None:
    """Why a run may not change the settings of the carrier ``key``, as the run says it
    (None: it may)."""
    found = _candidates(key)
    kind, name = key.split(":", 1)
    if len(found) != 1:
        why = f"{kind} '{name}' is not one datablock ({len(found)} have that name)"
    elif not writable(found[0]):
        why = f"{kind} '{found[0].name}' is linked from {found[0].library.filepath}"
    else:
        return None
    return f"{why}: its media keep their own volume settings"
