"""The files the open .blend reads: images, OpenVDB caches, linked libraries, caches of
simulations, fonts, sounds — as Blender itself lists them (``bpy.utils.blend_paths``),
inside linked libraries too, packed files left out (they travel inside the .blend).

Tiled images and sequences are marked (``core.farm.assets.ScenePath``) so that
``core.farm.assets.scene_files`` expands them into the files on disk; nothing is read here
but Blender's data, and nothing is written.
"""
from __future__ import annotations

import os

from ...core.farm.assets import SceneFiles, ScenePath, scene_files


def _absolute(bpy, datablock) -> str:
    """A datablock's file path made absolute against the .blend that holds it (a linked
    library's paths are relative to that library)."""
    return bpy.path.abspath(datablock.filepath, library=datablock.library)


def _names_a_folder(path: str) -> bool:
    return path.endswith(("/", "\\"))


def scene_paths(bpy) -> tuple[list[ScenePath], list[str]]:
    """(every path the open file reads, absolute and marked; the same paths as written).

    An image's or volume's path that names a folder is no file it reads: a volume whose
    grids Geometry Nodes make keeps such a path (statue's ``//../../../../``, which is "/"
    from where the file lies)."""
    marked: dict[str, ScenePath] = {}
    folders = [item for item in (*bpy.data.images, *bpy.data.volumes)
               if item.filepath and _names_a_folder(item.filepath)]
    no_file = {os.path.normpath(_absolute(bpy, item)) for item in folders}
    for image in bpy.data.images:
        if image.packed_file is not None or not image.filepath:
            continue
        if image.source == "TILED":
            path = _absolute(bpy, image)
            marked[path] = ScenePath(path, tiles=tuple(tile.number for tile in image.tiles))
        elif image.source == "SEQUENCE":
            path = _absolute(bpy, image)
            marked[path] = ScenePath(path, sequence=True)
    for volume in bpy.data.volumes:
        if volume.packed_file is None and volume.filepath and volume.is_sequence:
            path = _absolute(bpy, volume)
            marked[path] = ScenePath(path, sequence=True)
    paths = [marked.get(path, ScenePath(path)) for path in bpy.utils.blend_paths(absolute=True)
             if os.path.normpath(path) not in no_file]
    listed = {item.path for item in paths}
    paths += [item for path, item in marked.items() if path not in listed]
    raw = [path for path in bpy.utils.blend_paths(absolute=False)
           if path not in {item.filepath for item in folders}]
    return paths, raw


def external_files() -> SceneFiles:
    """The files of the open .blend on disk, those missing, and those written absolute."""
    import bpy

    paths, raw = scene_paths(bpy)
    return scene_files(paths, raw)
