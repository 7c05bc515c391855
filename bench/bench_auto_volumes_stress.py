"""Stress: 200 consecutive F12 renders in one process, toggling Auto Volumes and changing the
frame, the frame range and persistent data; no crash, and every setting as it was after each.
(The suite renders 200 of a tiny fog scene: ``tests/test_auto_volumes.py``.)

    .venv/bin/python bench/bench_auto_volumes_stress.py [--renders 200] [--scene balls_b]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--renders", type=int, default=200)
    parser.add_argument("--scene", default="balls_b", help="example scene, rendered at 10 %% size, 1 spp")
    args = parser.parse_args(argv)

    import bpy

    import xsl_render
    from xsl_render.addon.scene.state import DEBUG_PATTERN_PREFERENCES, settings_dump

    def everything(scene) -> dict:
        preferences = bpy.context.preferences
        return settings_dump(scene) | {"preferences": [getattr(getattr(preferences, path), name)
                                                       for path, name in DEBUG_PATTERN_PREFERENCES]}

    xsl_render.register()
    bpy.ops.wm.open_mainfile(filepath=str(ROOT / "example_blends" / f"{args.scene}.blend"), load_ui=False)
    scene = bpy.context.scene
    scene.render.resolution_percentage, scene.cycles.samples = 10, 1
    scene.render.image_settings.file_format = "OPEN_EXR"
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        scene.render.filepath = str(Path(tmp) / "f12")
        before = everything(scene)
        for index in range(args.renders):
            scene.xsl_render.auto_volumes = index % 3 != 0
            scene.frame_current = 1 + index % 7
            scene.frame_end = 6 + index % 4
            scene.render.use_persistent_data = index % 5 == 0
            bpy.ops.render.render(write_still=True, scene=scene.name)
            scene.xsl_render.auto_volumes = False
            scene.frame_current, scene.frame_end = before["scene"]["frame_current"], before["scene"]["frame_end"]
            scene.render.use_persistent_data = before["render"]["use_persistent_data"]
            if everything(scene) != before:
                print(f"render {index + 1}: a setting was left changed", file=sys.stderr)
                return 1
    print(f"bench_auto_volumes_stress: {args.renders} F12 renders of {args.scene}, no setting left "
          f"changed, {(time.perf_counter() - started) / args.renders:.2f} s a render")
    return 0


if __name__ == "__main__":
    sys.exit(main())
