"""Benchmark: Ctrl+F12 on the moving street with and without Auto Volumes: each frame's time,
and how many times Cycles built the fog's octree (a count, not seconds).

One Ctrl+F12 (``bpy.ops.render.render(animation=True)``) of frames 1 .. ``--frames`` per arm
and repeat, the arms alternating: the file as saved (null scattering, persistent data off:
every frame syncs the fog again), and with Auto Volumes (its choice for the shot, and Cycles'
session kept between frames where the media stand still and memory allows:
``addon.auto_volumes``). A frame's time runs from the end of the frame before (the job's
start for the first) to the end of its own, so the prediction and the sync count in it.

    .venv/bin/python bench/bench_auto_volumes_animation.py --frames 8 --repeats 3
    .venv/bin/python bench/bench_auto_volumes_animation.py --tiny       # end to end, quickly
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def ctrl_f12(bpy, scene, folder: Path, auto: bool) -> tuple[list[float], list[int], bool]:
    """One animation render: (seconds per frame, octree builds per frame, persistent data on)."""
    marks, builds, kept = [], [], []

    def init(*_):
        marks.append(time.perf_counter())
        builds.append(0)

    def pre(*_):
        kept.append(scene.render.use_persistent_data)

    def written(*_):
        marks.append(time.perf_counter())
        builds.append(0)

    def status(text):
        if "Building octree" in str(text):
            builds[-1] += 1

    handlers = (("render_init", init), ("render_pre", pre), ("render_write", written), ("render_stats", status))
    for name, function in handlers:
        getattr(bpy.app.handlers, name).append(function)
    scene.xsl_render.auto_volumes = auto
    scene.render.filepath = str(folder / "frame_####")
    try:
        bpy.ops.render.render(animation=True, scene=scene.name)
    finally:
        scene.xsl_render.auto_volumes = False
        for name, function in handlers:
            getattr(bpy.app.handlers, name).remove(function)
    return [b - a for a, b in zip(marks, marks[1:])], builds[:-1], any(kept)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--percentage", type=int, default=100, help="of the street's 256x144")
    parser.add_argument("--tiny", action="store_true", help="3 frames at 10 %%, once: a check")
    parser.add_argument("--out", type=Path, default=Path("bench-auto-volumes"))
    args = parser.parse_args(argv)
    frames, repeats, percentage = (3, 1, 10) if args.tiny else (args.frames, args.repeats, args.percentage)

    import bpy

    import xsl_render

    xsl_render.register()
    bpy.ops.wm.open_mainfile(filepath=str(ROOT / "example_blends" / "street.blend"), load_ui=False)
    scene = bpy.context.scene
    scene.frame_end = scene.frame_start + frames - 1
    scene.render.resolution_percentage = percentage
    scene.render.image_settings.file_format = "OPEN_EXR"
    runs = {"file": [], "auto": []}
    with tempfile.TemporaryDirectory() as tmp:
        for repeat in range(repeats):
            for arm in (("file", "auto") if repeat % 2 == 0 else ("auto", "file")):
                runs[arm].append(ctrl_f12(bpy, scene, Path(tmp), arm == "auto"))
    lines = [f"bench_auto_volumes_animation: street frames 1-{frames} at {percentage} %, median of "
             f"{repeats}", f"{'frame':>5s} {'file s':>8s} {'auto s':>8s} {'octrees file':>13s} {'auto':>5s}"]
    for index in range(frames):
        file_s = statistics.median(run[0][index] for run in runs["file"])
        auto_s = statistics.median(run[0][index] for run in runs["auto"])
        lines.append(f"{scene.frame_start + index:5d} {file_s:8.2f} {auto_s:8.2f} "
                     f"{runs['file'][0][1][index]:13d} {runs['auto'][0][1][index]:5d}")
    totals = {arm: statistics.median(sum(run[0]) for run in runs[arm]) for arm in runs}
    lines.append(f"total {totals['file']:8.2f} {totals['auto']:8.2f}  ({totals['file'] / totals['auto']:.2f}x); "
                 f"Cycles' session kept between frames: file {runs['file'][0][2]}, auto {runs['auto'][0][2]}")
    print("\n".join(lines))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_auto_volumes_animation.txt").write_text("\n".join(lines) + "\n")
    if not args.tiny:
        sys.path.insert(0, str(ROOT / "bench"))
        from performance_doc import write_bench_output

        write_bench_output("auto_volumes_animation", "Ctrl+F12 on the moving street (bench_auto_volumes_animation.py)",
                           "bench_auto_volumes_animation.py", argv, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
