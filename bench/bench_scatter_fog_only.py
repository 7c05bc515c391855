"""Benchmark: the fog's light alone, per volume sampling method, against auto's prediction.

Cycles' noise (``tests/support/scatter_oracle.py``: pixel variance over 6 seeds of 4 spp,
ray marching) with every switchable medium at distance and at equiangular, each over the
noise at "both" (multiple importance), in a frame where only the fog's single scattering
shows: surfaces held out, the sky black, no bounces. Beside it auto's prediction
(``core.media.scatter_sampling``), which models exactly that light. A full frame
(``bench_scatter_random.py``) mixes in the surfaces behind the fog; this bench tells the
model's two terms apart (docs/performance.md, "Where the scattering is placed").

    .venv/bin/python bench/bench_scatter_fog_only.py --scenes balls_a,balls_b --seeds 20,88
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))          # the generator and the oracle live with the tests

from bench_xmap_oracle import seed_list  # noqa: E402

#: The example scenes are rendered this small: the oracle takes 18 renders each.
EXAMPLE_SIZE = (96, 54)
METHODS = ("DISTANCE", "EQUIANGULAR")


def hold_out_surfaces(bpy, scene) -> None:
    """Every surface held out (it still hides what is behind it) and the sky black, so the
    frame shows the fog's light alone."""
    for material in bpy.data.materials:
        tree = material.node_tree if material.use_nodes else None
        output = next((n for n in tree.nodes if n.type == "OUTPUT_MATERIAL"), None) if tree else None
        if output is None or output.inputs["Volume"].is_linked:
            continue
        tree.links.new(tree.nodes.new("ShaderNodeHoldout").outputs[0], output.inputs["Surface"])
    world = scene.world
    if world is not None and world.use_nodes:
        for node in world.node_tree.nodes:
            if node.type == "BACKGROUND":
                for link in list(node.inputs["Color"].links):
                    world.node_tree.links.remove(link)
                node.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    scene.cycles.max_bounces = 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="balls_a,balls_b", help="example scenes (default balls_a,balls_b)")
    parser.add_argument("--seeds", default="20,88", help="random scenes, e.g. 20,88 or 0-9 (default 20,88)")
    args = parser.parse_args(argv)
    try:
        seeds = seed_list(args.seeds) if args.seeds else []
    except ValueError:
        print(f"bench_scatter_fog_only: --seeds '{args.seeds}' is not a list of seeds", file=sys.stderr)
        return 2
    scenes = [name for name in args.scenes.split(",") if name]
    missing = [name for name in scenes if not (ROOT / "example_blends" / f"{name}.blend").is_file()]
    if missing:
        print(f"bench_scatter_fog_only: no example scene '{missing[0]}'", file=sys.stderr)
        return 2

    import bpy
    from support.random_lights import add_random_lights
    from support.random_scenes import build_random_scene
    from support.scatter_oracle import auto_scatter, cycles_noise
    from xsl_render.core.media.scatter_sampling import BOTH

    print("scene: Cycles distance / equiangular over both (fog light alone) | the model's")
    for name in scenes + seeds:
        if isinstance(name, int):
            built = build_random_scene(bpy, name, 48, 27)
            add_random_lights(bpy, built.scene, name)
            scene, label = built.scene, f"seed {name}"
        else:
            bpy.ops.wm.open_mainfile(filepath=str(ROOT / "example_blends" / f"{name}.blend"), load_ui=False)
            scene, label = bpy.context.scene, name
            scene.render.resolution_x, scene.render.resolution_y = EXAMPLE_SIZE
            scene.render.resolution_percentage = 100
        choice, own = auto_scatter(scene)
        predicted, keys = choice.scatter_noise or {}, list(own)
        if not keys:
            print(f"{label}: no medium could switch", flush=True)
            continue
        hold_out_surfaces(bpy, scene)
        both = max(cycles_noise(bpy, scene, dict.fromkeys(keys, BOTH)), 1e-12)
        cycles = " / ".join(f"{cycles_noise(bpy, scene, dict.fromkeys(keys, m)) / both:.2f}" for m in METHODS)
        model = "; ".join(f"{key} " + " / ".join(
            f"{noise[m] / noise[BOTH]:.2f}" if noise[BOTH] > 0 else "-" for m in METHODS)
            for key, noise in sorted(predicted.items()) if key in keys)
        print(f"{label}: Cycles {cycles} | model {model}", flush=True)
        bpy.ops.wm.read_factory_settings(use_empty=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
