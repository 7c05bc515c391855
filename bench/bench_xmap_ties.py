"""Benchmark: every map of a fog box resting on the ground, where half the frame is ties.

The scene of ``tests/test_xmap_coincident.py``: every ground pixel is a tie
(``CameraRays.ties``). The median of ``--runs`` runs of ``compute_maps`` (no ray cache), each
map's seconds and the X map's parts, twice: every tie measured by a Cycles render
(``addon.maps.ties.WORK_OUT`` off), and the ties worked out (``core.maps.embree_ties``) with
small probe renders; ``cpu`` is the process's CPU time.

    .venv/bin/python bench/bench_xmap_ties.py [--runs 3] [--resolution 384x216] [--after-only]"""
from __future__ import annotations

import argparse
import math
import statistics
import sys
import time


def build_scene(bpy, width: int, height: int):
    """The camera inside a fog box (Principled Volume, density 0.15) resting on the ground."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (0.0, -2.0, 1.5)
    camera.rotation_euler = tuple(math.radians(a) for a in (60.0, 0.0, 10.0))
    camera.data.lens = 24.0
    scene.world = bpy.data.worlds.new("World")
    fog = bpy.data.materials.new("fog")
    tree = fog.node_tree
    tree.nodes.clear()
    node = tree.nodes.new("ShaderNodeVolumePrincipled")
    node.inputs["Density"].default_value = 0.15
    node.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    tree.links.new(node.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Volume"])
    bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 4, 3))
    box = bpy.context.active_object
    box.scale = (8, 8, 3)
    box.data.materials.append(fog)
    bpy.ops.mesh.primitive_plane_add(size=40, location=(0, 4, 0))
    return scene


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--resolution", default="384x216", help="WxH")
    parser.add_argument("--after-only", action="store_true", help="skip the slow 'before'")
    args = parser.parse_args(argv)
    width, height = (int(v) for v in args.resolution.lower().split("x"))

    import warnings

    import bpy

    from xsl_render.addon.maps import ties
    from xsl_render.addon.maps.director_maps import compute_maps
    from xsl_render.core.maps.options import MapOptions

    warnings.simplefilter("ignore")
    scene = build_scene(bpy, width, height)
    print(f"fog box resting on the ground, {width}x{height}, median of {args.runs}:")
    for label, work_out in (("before", False), ("after", True)):
        if args.after_only and not work_out:
            continue
        ties.WORK_OUT = work_out
        per_map: dict[str, list[float]] = {}
        parts: dict[str, list[float]] = {}
        walls, cpus = [], []
        for _ in range(args.runs):
            started, cpu = time.perf_counter(), time.process_time()
            # A fresh depsgraph each run: one kept across runs no longer shows the box's
            # volume once a render has swapped the materials and put them back.
            maps = compute_maps(scene, MapOptions())
            walls.append(time.perf_counter() - started)
            cpus.append(time.process_time() - cpu)
            for name, seconds in maps.info["seconds"].items():
                per_map.setdefault(name, []).append(seconds)
            for name, seconds in maps.info["x"]["seconds"].items():
                parts.setdefault(name, []).append(seconds)
        tie_info = maps.info["x"]["ties"] or {}
        how = (f"{tie_info.get('worked_out', 0)} of {tie_info.get('pixels', 0)} tie pixels "
               f"worked out, {len(tie_info.get('probes', []))} probes, measured: "
               f"{(tie_info.get('measured') or {}).get('samples', 'none')} spp")
        print(f"  {label} ({how}):")
        print("    " + ", ".join(f"{name} {statistics.median(v):.3f} s" for name, v in per_map.items())
              + f"; wall {statistics.median(walls):.3f} s, cpu {statistics.median(cpus):.3f} s")
        print("    x map: " + ", ".join(f"{name} {statistics.median(v):.3f} s"
                                       for name, v in parts.items()))
        sys.stdout.flush()
    ties.WORK_OUT = True
    return 0


if __name__ == "__main__":
    sys.exit(main())
