"""The stimuli folder of a 2AFC experiment: one (gold standard, selective rendering) PNG pair
per scene, flat: ``<scene>.gold.png`` and ``<scene>.test.png``.

A scene name is letters, digits, ``_`` and ``-``; both images of a pair have the same size and
are shown pixel for pixel. Files that are not PNG (notes, the answers database) are ignored;
a PNG with any other name is refused, so a typo cannot drop a scene silently."""
from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass
from pathlib import Path

import OpenImageIO as oiio

from ..errors import InputError

ROLES = ("gold", "test")
_NAME = re.compile(r"^(?P<scene>[A-Za-z0-9][A-Za-z0-9_-]*)\.(?P<role>gold|test)\.png\Z")


@dataclass(frozen=True)
class StimulusPair:
    """One scene's two images, their shared size and their content hashes."""

    scene: str
    gold: Path
    test: Path
    width: int
    height: int
    gold_sha256: str
    test_sha256: str

    def path(self, role: str) -> Path:
        if role not in ROLES:
            raise KeyError(role)
        return self.gold if role == "gold" else self.test


def png_size(path: Path) -> tuple[int, int]:
    """Width and height of a PNG file; InputError when it is not a readable PNG."""
    image = oiio.ImageInput.open(str(path))
    if image is None:
        reason = oiio.geterror().strip().splitlines()
        raise InputError(f"cannot read stimulus {path}: {reason[0] if reason else 'not an image'}")
    try:
        if image.format_name() != "png":
            raise InputError(f"stimulus {path} is {image.format_name()}, not PNG")
        spec = image.spec()
        return spec.width, spec.height
    finally:
        image.close()


def file_sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def scan_stimuli(folder: str | os.PathLike) -> list[StimulusPair]:
    """Find and check every (gold, test) pair of ``folder``, sorted by scene name.

    Raises InputError for a missing folder, a PNG whose name does not follow the layout, a
    scene with only one of its two images, a pair of different sizes, or no pair at all.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"no such stimuli folder: {folder}")
    found: dict[str, dict[str, Path]] = {}
    for entry in sorted(folder.iterdir()):
        if not entry.name.lower().endswith(".png"):
            continue
        match = _NAME.match(entry.name)
        if match is None or not entry.is_file():
            raise InputError(f"stimulus {entry.name} does not follow the layout "
                             "<scene>.gold.png / <scene>.test.png")
        found.setdefault(match["scene"], {})[match["role"]] = entry
    if not found:
        raise InputError(f"no stimuli in {folder}: expected <scene>.gold.png and <scene>.test.png pairs")
    pairs = []
    for scene, roles in sorted(found.items()):
        missing = [role for role in ROLES if role not in roles]
        if missing:
            raise InputError(f"scene '{scene}' has no {scene}.{missing[0]}.png to pair with "
                             f"{roles[next(iter(roles))].name}")
        gold_size, test_size = png_size(roles["gold"]), png_size(roles["test"])
        if gold_size != test_size:
            raise InputError(f"scene '{scene}': gold is {gold_size[0]}x{gold_size[1]} but test is "
                             f"{test_size[0]}x{test_size[1]}; a pair must have the same size")
        pairs.append(StimulusPair(scene=scene, gold=roles["gold"], test=roles["test"],
                                  width=gold_size[0], height=gold_size[1],
                                  gold_sha256=file_sha256(roles["gold"]),
                                  test_sha256=file_sha256(roles["test"])))
    return pairs
