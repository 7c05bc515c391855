"""A farm task of a plain Blender job (``core.farm.blender_job``), inside the worker's Blender:
the chunk's frames rendered as Blender renders the file, Auto Volumes on (or off), into
OutputDir/frame_NNNN. Each evenly spaced run of the chunk is one animation render, so Cycles
may keep its session from frame to frame; the scene's range is set for it and put back, and
Auto Volumes takes its shots from the range the file was loaded with."""
from __future__ import annotations

import argparse
import os
import sys

from ...core.errors import InputError
from ...core.frames import frame_runs, parse_frame_list
from .. import auto_volumes
from ..cycles.device import use_device
from ..scene.state import preserved_scene


def _arguments(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="xsl_render_chunk.py")
    parser.add_argument("--scene-name", required=True)
    parser.add_argument("--frames", required=True)
    parser.add_argument("--output", required=True)
    parser.add_argument("--device", choices=("CPU", "GPU"), default=None)
    parser.add_argument("--auto-volumes", choices=("true", "false"), default="true")
    return parser.parse_args(argv)


def render_chunk(argv) -> int:
    """Render the task's frames; 0 when every frame is written, 2 for bad input, 1 when Blender
    could not render or write one (its message on stderr)."""
    import bpy

    try:
        args = _arguments(argv)
        scene = bpy.data.scenes.get(args.scene_name)
        if scene is None:
            raise InputError(f"the file has no scene named '{args.scene_name}' "
                             f"(it has: {', '.join(s.name for s in bpy.data.scenes)})")
        frames = parse_frame_list(args.frames)
    except InputError as error:
        print(f"xsl-render: error: {error}", file=sys.stderr)
        return 2
    try:
        with preserved_scene(scene), auto_volumes.forced(scene, args.auto_volumes == "true"):
            scene.render.filepath = os.path.join(args.output, "frame_####")
            if args.device is not None:
                use_device(scene, args.device)
            for run in frame_runs(frames):
                scene.frame_start, scene.frame_end, scene.frame_step = run.start, run[-1], run.step
                print(f"openjd_status: frames {run.start}-{run[-1]}", flush=True)
                bpy.ops.render.render(animation=True, scene=scene.name)
    except InputError as error:
        print(f"xsl-render: error: {error}", file=sys.stderr)
        return 2
    except RuntimeError as error:
        print(f"xsl-render: error: {str(error).strip().splitlines()[0]}", file=sys.stderr)
        return 1
    return 0
