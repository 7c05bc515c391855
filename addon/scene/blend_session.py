"""Opening a user's .blend for the command line, without ever writing it back.

Only the ``xsl-render`` command and tests open files; inside Blender the operators work
on the scene the artist already has open.
"""
from __future__ import annotations

import gzip
import sys
from contextlib import contextmanager, redirect_stdout
from pathlib import Path

from ...core.errors import InputError

_BLEND_MAGIC = b"BLENDER"
_ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
_GZIP_MAGIC = b"\x1f\x8b"


def check_blend_file(path: str | Path) -> Path:
    """Raise InputError unless ``path`` is an existing .blend file (plain, zstd or gzip)."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"no such file: {path}")
    if not path.is_file():
        raise InputError(f"not a file: {path}")
    with open(path, "rb") as f:
        head = f.read(16)
    if head.startswith(_BLEND_MAGIC):
        return path
    if head.startswith(_ZSTD_MAGIC):
        import zstandard  # bundled with Blender and a dependency of the bpy module

        with open(path, "rb") as f:
            try:
                head = zstandard.ZstdDecompressor().stream_reader(f).read(16)
            except zstandard.ZstdError:
                head = b""
    elif head.startswith(_GZIP_MAGIC):
        try:
            head = gzip.open(path).read(16)
        except OSError:
            head = b""
    if not head.startswith(_BLEND_MAGIC):
        raise InputError(f"not a .blend file: {path}")
    return path


def open_blend(path: str | Path | None, scene_name: str | None = None):
    """Load a .blend into the running bpy session and return its scene.

    ``scene_name`` picks a scene; the default is the one the file was saved with.
    ``path`` None: the file Blender already has open (the batch entry inside
    ``blender -b scene.blend``). The file on disk is never written: nothing in xsl_render
    calls save_mainfile.
    """
    import bpy

    if path is None:
        return _open_scene(scene_name)
    path = check_blend_file(path).resolve()
    try:
        with _reports_with_blenders_output():
            bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
    except RuntimeError as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else "unreadable"
        raise InputError(f"cannot open {path}: {first}") from None
    if scene_name is None:
        return bpy.context.scene
    scene = bpy.data.scenes.get(scene_name)
    if scene is None:
        raise InputError(f"{path} has no scene named '{scene_name}' "
                         f"(it has: {', '.join(s.name for s in bpy.data.scenes)})")
    return scene


@contextmanager
def _reports_with_blenders_output():
    """An operator's reports ("Info: Read library: ...") go where Blender's own output goes.

    Blender prints them through Python's ``sys.stdout``, not its C output (file descriptor
    1), which the command line sends to its log (``operators/console.py``) while keeping
    ``sys.stdout`` for its own lines: they would land among those."""
    stream = sys.__stdout__
    if stream is None:
        yield
        return
    sys.stdout.flush()
    with redirect_stdout(stream):
        try:
            yield
        finally:
            stream.flush()


def _open_scene(scene_name: str | None):
    import bpy

    if scene_name is None:
        scene = bpy.context.scene
        if scene is None:
            raise InputError("Blender has no scene open")
        return scene
    scene = bpy.data.scenes.get(scene_name)
    if scene is None:
        raise InputError(f"the open file has no scene named '{scene_name}' "
                         f"(it has: {', '.join(s.name for s in bpy.data.scenes)})")
    return scene
