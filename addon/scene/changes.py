"""A record of the settings a run changed, put back when it ends: restore by what was
changed, not by where it was looked for.

``ChangeRecord.set(struct, name, value)`` notes a property's value the first time it is
changed, then writes it; ``restore()`` puts every noted value back, newest first, and
returns the datablocks it wrote, for the caller to tag. The record holds the structs
themselves, so a datablock is known by identity wherever it was found (through a
collection instance, Geometry Nodes, a library: a linked ``Fog`` and a local ``Fog`` are
two). Data linked from a library (not a local override of it) is never written:
``writable`` tells beforehand, ``set`` refuses it. Use it as a context manager, or call
``set`` and ``restore`` yourself where the two happen in different calls (render handlers).
"""
from __future__ import annotations


class LinkedDataError(ValueError):
    """A write to a datablock linked from a library, which the run must never change."""


def writable(struct) -> bool:
    """Whether a run may change ``struct``: it belongs to no datablock (preferences), or to a
    local one (a library override is local); not to one linked from a library."""
    owner = getattr(struct, "id_data", None)
    return owner is None or getattr(owner, "library", None) is None


def plain(value):
    """An RNA value as a comparable Python value (arrays as tuples, enum sets frozen)."""
    import bpy

    if isinstance(value, set):
        return frozenset(value)
    if hasattr(value, "__len__") and not isinstance(value, (str, bpy.types.ID)):
        return tuple(value)
    return value


class ChangeRecord:
    """Settings changed through ``set``, each with the value it had before the first change."""

    def __init__(self):
        # (datablock or struct pointer, path, property) -> (datablock, path, struct, old value)
        self._saved: dict[tuple, tuple] = {}
        self._written: set[tuple] = set()           # the keys of those that were changed

    def set(self, struct, name: str, value) -> bool:
        """Write ``struct.name = value``, noting the old value first; True if it changed."""
        if not writable(struct):
            owner = struct.id_data
            raise LinkedDataError(f"{type(owner).__name__} '{owner.name_full}' is linked from "
                                  f"{owner.library.filepath}; it is never written")
        current = plain(getattr(struct, name))
        owner, path = _address(struct)
        key = (owner.as_pointer() if owner is not None else struct.as_pointer(), path, name)
        if key not in self._saved:
            # A struct inside a datablock is found again from the datablock when restoring:
            # Python's handle on a removed datablock says so, one on a struct inside it does not.
            self._saved[key] = (owner, path, None if owner is not None else struct, current)
        if current == plain(value):
            return False
        setattr(struct, name, set(value) if isinstance(value, frozenset) else value)
        self._written.add(key)
        return True

    def datablocks(self, kind: type | None = None) -> list:
        """The datablocks whose settings ``set`` changed (of type ``kind``), until ``restore``."""
        found = {}
        for key in self._written:
            owner = self._saved[key][0]
            if _alive(owner) and (kind is None or isinstance(owner, kind)):
                found[owner.as_pointer()] = owner
        return list(found.values())

    def restore(self) -> list:
        """Put every noted value back (newest first) and forget them; the datablocks written.
        A datablock removed meanwhile is skipped; a value that cannot be set back does not
        stop the others, and is raised once they are back."""
        entries, self._saved, self._written = list(self._saved.items()), {}, set()
        written, failure = {}, None
        for (_, _, name), (owner, path, struct, value) in reversed(entries):
            if owner is not None:
                if not _alive(owner):
                    continue                # its datablock was removed: nothing to restore
                struct = owner.path_resolve(path) if path else owner
            try:
                if plain(getattr(struct, name)) == value:
                    continue
                setattr(struct, name, set(value) if isinstance(value, frozenset) else value)
            except (AttributeError, TypeError, ValueError, RuntimeError) as error:
                failure = failure or error
                continue
            if owner is not None:
                written[owner.as_pointer()] = owner
        if failure is not None:
            raise failure
        return list(written.values())

    def __enter__(self) -> "ChangeRecord":
        return self

    def __exit__(self, *exc) -> None:
        self.restore()


def _address(struct) -> tuple:
    """(the datablock holding ``struct``, its path there), or (None, "") for a struct outside
    every datablock (the preferences)."""
    owner = getattr(struct, "id_data", None)
    if owner is None:
        return None, ""
    if owner == struct:
        return owner, ""
    return owner, struct.path_from_id()


def _alive(owner) -> bool:
    """Whether ``owner`` is a datablock that still exists."""
    if owner is None:
        return False
    try:
        owner.as_pointer()
    except ReferenceError:
        return False
    return True
