"""The bundled example scenes (the paper's four: balls A, balls B, a statue for Lucy, road; and
one animation, street) and how a command names scenes: an example's name, or the path of any
.blend file.

``EXAMPLE_SCENES`` are the paper's four: what ``experiment`` runs by default, one frame each.
``ANIMATED_EXAMPLES`` (street, 24 frames) is named like them but never part of a default:
a fifth scene would add its 1024-spp reference and every run to the default experiment,
which renders one frame of a scene and so would not use the animation anyway.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

from ..checks import name_list
from ..errors import Field, InputError

EXAMPLE_SCENES = ("balls_a", "balls_b", "statue", "road")
ANIMATED_EXAMPLES = ("street",)
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]*\Z")


def example_folders() -> list[Path]:
    """Where example_blends/ may be: next to the package (a source checkout, where the package
    is the repository itself) and under the current folder."""
    package = Path(__file__).resolve().parents[2]           # core/validation/ -> the package
    return list(dict.fromkeys([package / "example_blends", Path.cwd() / "example_blends"]))


def example_scene_path(name: str) -> Path:
    """The .blend of a bundled example; InputError (one line) when it is not there."""
    for folder in example_folders():
        path = folder / f"{name}.blend"
        if path.is_file():
            return path
    raise InputError(f"example scene '{name}' not found: no {name}.blend in "
                     f"{' or '.join(str(f) for f in example_folders())} (example_blends/README.md "
                     "says how to build it)")


def resolve_scenes(text: str | None) -> list[tuple[str, Path]]:
    """'balls_a,road' or 'scene.blend,...' -> [(name, path)]; None means the paper's four
    examples (``EXAMPLE_SCENES``); the animated ones are taken by name.

    A name is reported as is; a path under its file stem. Names must be unique, because each
    scene gets a folder of that name.
    """
    items = list(EXAMPLE_SCENES) if text is None else name_list(text, Field("scenes"))
    scenes: list[tuple[str, Path]] = []
    for item in items:
        if item.lower().endswith(".blend") or os.sep in item or "/" in item:
            path = Path(item)
            if not path.is_file():
                raise InputError(f"no such scene file: {item}")
            name = path.stem
        elif item in EXAMPLE_SCENES + ANIMATED_EXAMPLES:
            name, path = item, example_scene_path(item)
        else:
            raise InputError(f"unknown scene '{item}' (examples: "
                             f"{', '.join(EXAMPLE_SCENES + ANIMATED_EXAMPLES)}; "
                             "or give the path of a .blend file)")
        if not _NAME.match(name):
            raise InputError(f"scene name '{name}' must be letters, digits, '_' or '-' (it names a folder)")
        if name in (n for n, _ in scenes):
            raise InputError(f"scene '{name}' is given twice")
        scenes.append((name, path))
    return scenes
