"""Benchmark: the X map and Z buffer, and X recomputed from the cached rays.

Per scene (a road-like stand-in built in memory, about 40k triangles, or .blend files; the
example scenes with ``--examples``), the median of ``--runs`` runs of ``compute_x_map`` with no
cache (scene scan, BVH build, ray casts, media), of X recomputed from the cached rays after a
density changed (with and without reading the cache file), and of a cache hit.
``--noise-fog`` and ``--smoke`` make the stand-in's fog heterogeneous or add OpenVDB smoke.

    .venv/bin/python bench/bench_xmap.py [SCENE.blend ...] [--examples] [--runs 5] [--resolution WxH]"""
from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The example scenes ``--examples`` measures (example_blends/<name>.blend).
EXAMPLES = ("road", "balls_b", "statue")


def build_road_scene(bpy) -> None:
    """A night road in fog: what the paper's road scene holds, in simple shapes."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = 512, 288
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (1.5, -8.0, 1.6)
    camera.rotation_euler = (math.radians(86), 0.0, math.radians(-4))
    camera.data.lens = 30
    camera.data.clip_end = 500

    def add(op, **kw):
        op(**kw)
        return bpy.context.active_object

    road = add(bpy.ops.mesh.primitive_grid_add, x_subdivisions=8, y_subdivisions=200,
               size=1.0, location=(0, 90, 0))
    road.scale = (8, 200, 1)
    add(bpy.ops.mesh.primitive_plane_add, size=600, location=(0, 100, -0.05))
    for i in range(24):
        for side in (-1, 1):
            y = i * 9.0
            pole = add(bpy.ops.mesh.primitive_cylinder_add, vertices=24, radius=0.08, depth=6,
                       location=(side * 5.0, y, 3.0))
            add(bpy.ops.mesh.primitive_uv_sphere_add, segments=24, radius=0.35,
                ring_count=12, location=(side * 4.4, y, 6.0))
            pole.name = f"pole {i} {side}"
    for i in range(10):
        add(bpy.ops.mesh.primitive_cube_add, size=1, location=(6.0, 12 + i * 18, 2.5)).scale = (0.05, 1.2, 0.8)
        add(bpy.ops.mesh.primitive_cylinder_add, vertices=16, radius=0.05, depth=2,
            location=(6.0, 12 + i * 18, 1.0))
    for i in range(12):
        car = add(bpy.ops.mesh.primitive_cube_add, size=1, location=((-1.8 if i % 2 else 1.8), 6 + i * 11, 0.7))
        car.scale = (1.8, 4.2, 1.2)
        modifier = car.modifiers.new("bevel", "SUBSURF")
        modifier.levels = modifier.render_levels = 3
    world = bpy.data.worlds.new("Fog")
    scene.world = world
    tree = world.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputWorld")
    fog = tree.nodes.new("ShaderNodeVolumePrincipled")
    fog.inputs["Density"].default_value = 0.02
    tree.links.new(fog.outputs[0], output.inputs["Volume"])


def make_fog_noisy(bpy, scene) -> None:
    """Density 0.04 * noise(world position / 8): fog banks drifting across the road."""
    tree = scene.world.node_tree
    fog = next(n for n in tree.nodes if n.type == "PRINCIPLED_VOLUME")
    coords, noise, scale = (tree.nodes.new(t) for t in ("ShaderNodeTexCoord", "ShaderNodeTexNoise",
                                                        "ShaderNodeMath"))
    noise.inputs["Scale"].default_value = 0.125
    noise.inputs["Detail"].default_value = 3.0
    scale.operation = "MULTIPLY"
    scale.inputs[1].default_value = 0.04
    tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    tree.links.new(noise.outputs["Fac"], scale.inputs[0])
    tree.links.new(scale.outputs[0], fog.inputs["Density"])


def add_smoke(bpy, scene) -> None:
    """A 6 x 6 x 4 smoke volume (a 48^3 'density' grid made by geometry nodes) on the road."""
    volume = bpy.data.volumes.new("smoke")
    ob = bpy.data.objects.new("smoke", volume)
    scene.collection.objects.link(ob)
    ob.location = (0.0, 25.0, 2.0)
    tree = bpy.data.node_groups.new("smoke grid", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    cube, noise = tree.nodes.new("GeometryNodeVolumeCube"), tree.nodes.new("ShaderNodeTexNoise")
    tree.links.new(tree.nodes.new("GeometryNodeInputPosition").outputs[0], noise.inputs["Vector"])
    tree.links.new(noise.outputs["Fac"], cube.inputs["Density"])
    cube.inputs["Min"].default_value, cube.inputs["Max"].default_value = (-3, -3, -2), (3, 3, 2)
    for axis in "XYZ":
        cube.inputs[f"Resolution {axis}"].default_value = 48
    tree.links.new(cube.outputs[0], tree.nodes.new("NodeGroupOutput").inputs[0])
    ob.modifiers.new("grid", "NODES").node_group = tree
    material = bpy.data.materials.new("smoke")
    material.node_tree.nodes.clear()
    principled = material.node_tree.nodes.new("ShaderNodeVolumePrincipled")
    output = material.node_tree.nodes.new("ShaderNodeOutputMaterial")
    material.node_tree.links.new(principled.outputs[0], output.inputs["Volume"])
    volume.materials.append(None)
    ob.material_slots[0].link = "OBJECT"
    ob.material_slots[0].material = material


def median_time(function, runs: int) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def measure(bpy, scene, label: str, runs: int) -> dict:
    """Print and return the medians of one scene: X + Z with rays cast, X from the cached
    rays (in memory and from disk) after the media changed, compute_x_map with a cache hit."""
    import numpy as np

    from xsl_render.addon.maps.xmap import compute_x_map
    from xsl_render.addon.scene.geometry import scan_scene
    from xsl_render.core.maps.camera_rays import load_rays
    from xsl_render.core.maps.xmap import x_map_from_cached_rays

    depsgraph = bpy.context.evaluated_depsgraph_get()
    geometry, media = scan_scene(scene, depsgraph)
    kinds = [f"{m.name} ({'homogeneous' if m.constant_extinction() is not None else 'heterogeneous'}, "
             f"{'numpy' if m.evaluable else 'Cycles'})" for m in media]
    width, height = scene.render.resolution_x, scene.render.resolution_y
    scale = scene.render.resolution_percentage / 100.0
    print(f"scene: {label}, {round(width * scale)}x{round(height * scale)}, "
          f"{len(geometry.surfaces.triangles)} surface triangles, media: {', '.join(kinds) or 'none'}")

    compute_x_map(scene, depsgraph=depsgraph)            # warm-up (imports, first BVH)
    full = median_time(lambda: compute_x_map(scene, depsgraph=depsgraph), runs)
    _, _, info = compute_x_map(scene, depsgraph=depsgraph)
    parts = ", ".join(f"{k} {v:.3f}" for k, v in info["seconds"].items())
    print(f"  X + Z, rays cast:          median {full:.3f} s of {runs}  ({parts})")
    for entry in info["integration"]:
        print(f"    {entry['medium']}: {entry['method']}")

    with tempfile.TemporaryDirectory() as folder:
        compute_x_map(scene, cache_dir=folder, depsgraph=depsgraph)
        cache = Path(folder) / "zcache.npz"
        rays = load_rays(cache)
        densities = iter(np.linspace(0.01, 0.05, 10 * runs))

        def recompute(from_disk: bool):
            for medium in media:              # a different density where it is a constant
                for node in medium.graph.nodes.values():
                    if "Density" in node.inputs and isinstance(node.inputs["Density"], float):
                        node.inputs["Density"] = float(next(densities))
            cached = load_rays(cache) if from_disk else rays
            x_map_from_cached_rays(cached, media)

        in_memory = median_time(lambda: recompute(False), runs)
        from_disk = median_time(lambda: recompute(True), runs)
        cached_api = median_time(lambda: compute_x_map(scene, cache_dir=folder, depsgraph=depsgraph), runs)
    print(f"  X from cached rays:        median {in_memory:.4f} s (rays in memory), "
          f"{from_disk:.4f} s (rays read from zcache.npz)")
    print(f"  compute_x_map, cache hit:  median {cached_api:.3f} s (scene scan + cache check + X)")
    fallback = info.get("cycles_fallback")
    if fallback:
        print(f"  Cycles fallback for {', '.join(fallback['media'])}: "
              f"{fallback['seconds']:.2f} s of the total")
    return {"label": label, "full": full, "in_memory": in_memory, "from_disk": from_disk,
            "cached_api": cached_api, "fallback": bool(fallback)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", help=".blend files (default: the built-in stand-in)")
    parser.add_argument("--examples", action="store_true",
                        help="the example scenes road, balls_b (noise fog) and statue (OpenVDB smoke)")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--resolution", default=None,
                        help="WxH (default: 512x288 for the stand-in, a file's own size)")
    parser.add_argument("--noise-fog", action="store_true", help="noise-driven fog density")
    parser.add_argument("--smoke", action="store_true", help="add an OpenVDB smoke volume")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT.parent))
    import bpy

    from xsl_render.addon.scene.blend_session import open_blend

    files = list(args.scenes)
    if args.examples:
        files += [str(ROOT / "example_blends" / f"{name}.blend") for name in EXAMPLES]
    results = []
    for path in files or [None]:
        if path is not None:
            scene = open_blend(path)
            label = Path(path).stem
        else:
            build_road_scene(bpy)
            scene = bpy.context.scene
            if args.noise_fog:
                make_fog_noisy(bpy, scene)
            if args.smoke:
                add_smoke(bpy, scene)
            label = "built-in road stand-in"
        resolution = args.resolution or (None if path is not None else "512x288")
        if resolution is not None:
            width, height = (int(v) for v in resolution.lower().split("x"))
            scene.render.resolution_x, scene.render.resolution_y = width, height
            scene.render.resolution_percentage = 100
        results.append(measure(bpy, scene, label, args.runs))
    if len(results) > 1:
        print(f"\n{'scene':<24} {'X + Z (s)':>10} {'X from cache (s)':>17} {'cache hit (s)':>14}")
        for r in results:
            print(f"{r['label']:<24} {r['full']:>10.3f} {r['from_disk']:>17.4f} {r['cached_api']:>14.3f}"
                  + ("  (Cycles fallback)" if r["fallback"] else ""))
    if files or args.noise_fog or args.smoke:
        return 0
    ok = results[0]["full"] <= 1.0 and results[0]["from_disk"] <= 0.1
    print("targets (<= 1.0 s, <= 0.1 s):", "met" if ok else "NOT met")
    return 0


if __name__ == "__main__":
    sys.exit(main())
