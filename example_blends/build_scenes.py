"""Build the example scenes and save them as .blend files next to this script.

    python build_scenes.py                  # all five scenes
    python build_scenes.py road statue      # only these
    python build_scenes.py --out DIR road   # write DIR/road.blend instead

Run it with the project's Python (``.venv/bin/python``), which has the bpy module. Each
scene script has a ``build()`` that starts an empty session and builds the scene; nothing
is random, so the same script always gives the same scene.
"""
from __future__ import annotations

import argparse
import importlib
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCENES = ("balls_a", "balls_b", "statue", "road", "street")


def build_scene(name: str, out_dir: Path = HERE) -> Path:
    """Build one scene by name and save it as ``out_dir/<name>.blend``."""
    if name not in SCENES:
        raise ValueError(f"unknown scene '{name}' (known: {', '.join(SCENES)})")
    if str(HERE) not in sys.path:
        sys.path.insert(0, str(HERE))
    import _scene_kit as kit
    module = importlib.import_module(name)
    module.build()
    return kit.save(Path(out_dir) / f"{name}.blend")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", metavar="SCENE",
                        help=f"which scenes to build (default: all of {', '.join(SCENES)})")
    parser.add_argument("--out", type=Path, default=HERE, help="folder for the .blend files")
    args = parser.parse_args(argv)
    unknown = [n for n in args.scenes if n not in SCENES]
    if unknown:
        parser.error(f"unknown scene(s): {', '.join(unknown)} (known: {', '.join(SCENES)})")
    for name in args.scenes or SCENES:
        start = time.perf_counter()
        path = build_scene(name, args.out)
        print(f"{name}: {path} ({path.stat().st_size / 1024:.0f} KiB, "
              f"{time.perf_counter() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
