"""What a render of the open file is made from, as a rerun compares it: the .blend's content
hash and the identity (path, size, modification time) of every file it reads
(``external_files``: linked libraries, textures, OpenVDB caches, image sequences), so that
work made from other inputs is redone, never kept.
"""
from __future__ import annotations

from pathlib import Path

from ...core.files import file_identity, file_sha256
from .external_files import external_files


def blend_inputs(blend: str | Path) -> tuple[dict, list[str]]:
    """({"blend_sha256": the hash of ``blend``, the file open now, "files": the identities
    of the files it reads}, the paths of those it reads that do not exist)."""
    files = external_files()
    return ({"blend_sha256": file_sha256(blend), "files": [file_identity(path) for path in files.found]},
            files.missing)


def scene_inputs(scene, blend: str | Path | None) -> dict | None:
    """The inputs of renders of ``scene`` opened from the file ``blend``, missing files among
    them; None for ``blend`` None (the batch entry): the file Blender has open may hold
    changes no file on disk has (Blender counts even a file just opened as changed, so that
    cannot be told)."""
    if blend is None:
        return None
    inputs, missing = blend_inputs(blend)
    return inputs | {"scene": scene.name, "missing": missing}
