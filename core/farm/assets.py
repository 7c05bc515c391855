"""The files a scene reads, as a job bundle's ``asset_references.yaml``.

A farm copies a job's inputs to its workers; a fog scene rendered from its .blend alone loses
its OpenVDB caches, textures and libraries. Blender lists them (``bpy.utils.blend_paths``)
with their numbered parts as patterns; here they become files: a UDIM image one per tile, a
sequence every file of its folder that differs only in the last run of digits (as Blender
reads a sequence). Paths absolute inside the .blend are reported: a worker finds such a file
only where the same path exists."""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

#: Blender's tile tokens: <UDIM> is 1001, 1002, ...; <UVTILE> is u1_v1, u2_v1, ...
UDIM_TOKEN, UVTILE_TOKEN = "<UDIM>", "<UVTILE>"
FILE_NAME = "asset_references.yaml"


@dataclass(frozen=True)
class ScenePath:
    """One path the scene reads, absolute, with how its numbered parts expand."""

    path: str
    tiles: tuple[int, ...] = ()         # UDIM numbers of a tiled image
    sequence: bool = False              # one file per frame (VDB cache, image sequence)


@dataclass
class SceneFiles:
    """The scene's files found on disk, those it names but that do not exist, and the paths
    written absolute inside the .blend (a warning each)."""

    found: list[Path] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    absolute_in_blend: list[str] = field(default_factory=list)


def tile_paths(path: str, tiles: tuple[int, ...]) -> list[str]:
    """``path`` with its tile token replaced by each UDIM number of ``tiles``."""
    paths = []
    for tile in tiles:
        u, v = (tile - 1001) % 10 + 1, (tile - 1001) // 10 + 1
        paths.append(path.replace(UDIM_TOKEN, str(tile)).replace(UVTILE_TOKEN, f"u{u}_v{v}"))
    return paths


def sequence_paths(path: str) -> list[str]:
    """Every file of ``path``'s folder that belongs to its numbered sequence (itself too
    when it exists); just ``path`` when its name has no digits."""
    folder, name = os.path.split(path)
    stem, extension = _split_extension(name)
    runs = list(re.finditer(r"\d+", stem))
    if not runs:
        return [path]
    last = runs[-1]
    pattern = re.compile(re.escape(stem[:last.start()]) + r"\d+" + re.escape(stem[last.end():])
                         + re.escape(extension) + r"\Z")
    try:
        names = sorted(entry for entry in os.listdir(folder or ".") if pattern.match(entry))
    except OSError:
        return [path]
    return [os.path.join(folder, entry) for entry in names] or [path]


def _split_extension(name: str) -> tuple[str, str]:
    stem, extension = os.path.splitext(name)
    return (stem, extension) if stem else (name, "")


def scene_files(paths: list[ScenePath], raw_paths: list[str]) -> SceneFiles:
    """The files ``paths`` name (tiles and sequences expanded), split into found and missing;
    ``raw_paths``: the same paths as written in the .blend (``//`` is relative to it)."""
    result = SceneFiles()
    seen: set[str] = set()
    for item in paths:
        if item.tiles and (UDIM_TOKEN in item.path or UVTILE_TOKEN in item.path):
            candidates = tile_paths(item.path, item.tiles)
        elif item.sequence:
            candidates = sequence_paths(item.path)
        else:
            candidates = [item.path]
        for candidate in candidates:
            candidate = os.path.normpath(candidate)
            if candidate in seen:
                continue
            seen.add(candidate)
            if os.path.isfile(candidate):
                result.found.append(Path(candidate))
            else:
                result.missing.append(candidate)
    result.found.sort()
    result.missing.sort()
    result.absolute_in_blend = sorted({raw for raw in raw_paths if raw and not raw.startswith("//")})
    return result


def asset_references(scene: Path, files: SceneFiles, output: Path) -> dict:
    """``asset_references.yaml`` as plain data: the .blend and its files as inputs, the job's
    output folder as output (the layout Deadline Cloud's job bundles use)."""
    inputs = sorted({str(Path(scene).absolute()), *(str(path) for path in files.found)})
    return {"assetReferences": {
        "inputs": {"filenames": inputs, "directories": []},
        "outputs": {"directories": [str(Path(output).absolute())]},
        "referencedPaths": [],
    }}
