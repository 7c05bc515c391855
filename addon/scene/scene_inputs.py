"""What a render of the open scene is made from, as a rerun compares it: the .blend's content
hash, the scene's name, and the identity (path, size, modification time) of every file the
scene reads (``external_files``: linked libraries, textures, OpenVDB caches, image sequences,
missing ones too), so that work made from other inputs is redone, never kept.
"""
from __future__ import annotations

from pathlib import Path

from ...core.files import file_identity, file_sha256
from .external_files import external_files


def scene_inputs(scene, blend: str | Path | None) -> dict | None:
    """The inputs of renders of ``scene`` opened from the file ``blend``; None where that
    cannot be told: no file, or (``blend`` None, the batch entry) the open file has changes
    not saved, which nothing on disk holds."""
    import bpy

    if blend is None:
        if not bpy.data.filepath or bpy.data.is_dirty:
            return None
        blend = bpy.data.filepath
    files = external_files()
    return {"blend_sha256": file_sha256(blend), "scene": scene.name,
            "files": [file_identity(path) for path in files.found + [Path(p) for p in files.missing]]}
