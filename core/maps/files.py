"""A set of director maps in memory and on disk (``xsl-render maps`` output).

On disk: ``z.exr`` (distance along each camera ray; sky = 1e10 as in Cycles' Depth pass),
``x.exr``, ``snapshot.exr`` (RGBA, scene-linear), ``s.exr``, ``l.exr``, ``xs.exr``,
``xsl.exr`` (one channel, [0, 1]), ``maps.json`` (every parameter used and the seconds
each map took) and ``preview/<name>.png`` for people to look at.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import output_set, write_json
from ..imageio import read_image, write_exr, write_png
from .camera_rays import SKY_DEPTH, depth_from_exr, depth_to_exr

MAP_NAMES = ("x", "s", "l", "xs", "xsl")


@dataclass
class MapSet:
    """Every map of one frame at one resolution (row 0 at the top)."""

    z: np.ndarray            # (H, W) distance, inf for sky
    x: np.ndarray            # (H, W) in [0, 1]
    snapshot: np.ndarray     # (H, W, 4) scene-linear
    s: np.ndarray
    l: np.ndarray
    xs: np.ndarray
    xsl: np.ndarray
    info: dict = field(default_factory=dict)

    def director(self, name: str) -> np.ndarray:
        if name not in MAP_NAMES:
            raise InputError(f"no director map named '{name}' (choose from {', '.join(MAP_NAMES)})")
        return getattr(self, name)


def map_set_paths(folder: str | Path) -> dict[str, Path]:
    """The files :func:`write_map_set` writes into ``folder``, by name ("x.exr",
    "preview/x.png", "maps.json"): what a command's check compares with its inputs."""
    folder = Path(folder)
    names = ["z.exr", "snapshot.exr"] + [f"{name}.exr" for name in MAP_NAMES]
    names += [f"preview/{name}.png" for name in MAP_NAMES + ("snapshot", "z")] + ["maps.json"]
    return {name: folder / name for name in names}


def write_map_set(folder: str | Path, maps: MapSet) -> list[Path]:
    """Write every map, maps.json and the PNG previews (:func:`map_set_paths`), all together
    or none (``core.files.output_set``); returns the paths written. The names are the same
    every time, so a new set replaces an earlier one in the folder whole."""
    paths = map_set_paths(folder)
    with output_set():
        written = [
            write_exr(paths["z.exr"], depth_to_exr(maps.z), ["Z"],
                      attributes={"xsl:z": "distance along the camera ray", "xsl:sky": SKY_DEPTH}),
            write_exr(paths["snapshot.exr"], maps.snapshot),
        ]
        for name in MAP_NAMES:
            written.append(write_exr(paths[f"{name}.exr"], maps.director(name), ["Y"]))
            written.append(write_png(paths[f"preview/{name}.png"], maps.director(name)))
        written.append(write_png(paths["preview/snapshot.png"], _display(maps.snapshot)))
        written.append(write_png(paths["preview/z.png"], _depth_preview(maps.z)))
        written.append(write_json(paths["maps.json"], maps.info))
    return written


def _depth_preview(z: np.ndarray) -> np.ndarray:
    """Near white, far black, sky (and a frame of only sky) black."""
    finite = np.isfinite(z)
    if not finite.any():
        return np.zeros(z.shape, np.float32)
    near, far = float(z[finite].min()), float(z[finite].max())
    return np.where(finite, 1.0 - (z - near) / max(far - near, 1e-9), 0.0)


def _display(snapshot: np.ndarray) -> np.ndarray:
    from ..tonemap import tonemap

    rgb = np.maximum(snapshot[..., :3], 0.0)
    return tonemap(rgb) if rgb.any() else rgb


def read_map_set(folder: str | Path) -> MapSet:
    """Read a folder written by :func:`write_map_set` (for ``render --maps DIR``)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"no such maps folder: {folder}")
    import json

    def one(name: str) -> np.ndarray:
        path = folder / f"{name}.exr"
        if not path.exists():
            raise InputError(f"the maps folder {folder} has no {name}.exr (run xsl-render maps)")
        return read_image(path)[..., 0]

    info_path = folder / "maps.json"
    info = json.loads(info_path.read_text()) if info_path.exists() else {}
    snapshot_path = folder / "snapshot.exr"
    maps = MapSet(z=depth_from_exr(one("z")), x=one("x"),
                  snapshot=read_image(snapshot_path) if snapshot_path.exists() else np.zeros((1, 1, 4)),
                  s=one("s"), l=one("l"), xs=one("xs"), xsl=one("xsl"), info=info)
    shapes = {m.shape for m in (maps.x, maps.s, maps.l, maps.xs, maps.xsl)}
    if len(shapes) != 1:
        raise InputError(f"the maps in {folder} have different sizes: {sorted(shapes)}")
    return maps
