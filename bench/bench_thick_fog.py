"""Benchmark: the selective render on the example scenes with their media made denser.

A what-if, not a change of the example scenes: the thin media of the examples cap the ideal
speedup (``bench_bounds.py``). This writes copies whose every medium has ``--density-scale``
times its density (never the originals), runs ``xsl-render experiment`` on them (gold, XS,
XSL, the equal-time baselines) and prints each copy's mean transmittance, ideal and achieved
speedups and the quality of XS and XSL.

    .venv/bin/python bench/bench_thick_fog.py [--density-scale 4] [--max-spp 64] [SCENE ...]"""
from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "example_blends"
SCENES = ("balls_a", "balls_b", "statue", "road")
#: Volume shader nodes and the input that sets how dense they are.
DENSITY_INPUTS = {"PRINCIPLED_VOLUME": "Density", "VOLUME_SCATTER": "Density",
                  "VOLUME_ABSORPTION": "Density", "VOLUME_COEFFICIENTS": None}


def scale_density(tree, factor: float) -> int:
    """Multiply the density of every volume shader in a node tree by ``factor``; returns
    how many were scaled. A linked density gets a Math (multiply) node in its link."""
    scaled = 0
    for node in list(tree.nodes):
        name = DENSITY_INPUTS.get(node.type, "")
        if name is None:
            raise SystemExit(f"{tree.name}: {node.type} has no single density input to scale")
        socket = node.inputs.get(name) if name else None
        if socket is None:
            continue
        if socket.is_linked:
            link = socket.links[0]
            math = tree.nodes.new("ShaderNodeMath")
            math.operation = "MULTIPLY"
            math.inputs[1].default_value = factor
            tree.links.new(link.from_socket, math.inputs[0])
            tree.links.new(math.outputs[0], socket)
        else:
            socket.default_value *= factor
        scaled += 1
    return scaled


def write_denser_copy(bpy, name: str, factor: float, folder: Path) -> Path:
    """``folder/<name>_x<factor>.blend``: the example with every medium ``factor`` times denser."""
    bpy.ops.wm.open_mainfile(filepath=str(EXAMPLES / f"{name}.blend"), load_ui=False)
    trees = [bpy.context.scene.world.node_tree] if bpy.context.scene.world else []
    trees += [m.node_tree for m in bpy.data.materials if m.use_nodes and m.node_tree]
    if not sum(scale_density(tree, factor) for tree in trees if tree is not None):
        raise SystemExit(f"{name}: no participating medium found to scale")
    out = folder / f"{name}_x{factor:g}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(out), copy=True)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=list(SCENES), metavar="SCENE")
    parser.add_argument("--density-scale", type=float, default=4.0)
    parser.add_argument("--max-spp", type=int, default=64)
    parser.add_argument("--out", help="experiment folder (default: a temporary one)")
    args = parser.parse_args(argv)

    import bpy

    from xsl_render.core.imageio import read_image
    from xsl_render.operators.cli import main as cli

    folder = Path(args.out or tempfile.mkdtemp(prefix="xsl-thick-fog-"))
    folder.mkdir(parents=True, exist_ok=True)
    copies = [write_denser_copy(bpy, name, args.density_scale, folder) for name in args.scenes]
    code = cli(["experiment", "--scenes", ",".join(map(str, copies)), "--out", str(folder / "experiment"),
                "--max-spp", str(args.max_spp), "--variants", "xs,xsl,uniform_equal_time", "--quiet"])
    if code:
        return code
    experiment = folder / "experiment"
    results = json.loads((experiment / "results.json").read_text())
    print(f"\nmedia x{args.density_scale:g}, {args.max_spp} spp; speedup = gold wall / run wall, maps included")
    print(f"{'scene':14} {'mean X':>7} {'run':>18} {'speedup':>8} {'ideal':>7} {'FLIP':>6} {'MSE %':>7}")
    for name, scene in results["scenes"].items():
        mean_x = float(read_image(experiment / scene["maps"]["minbound"]["folder"] / "x.exr")[..., 0].mean())
        for run, entry in scene["runs"].items():
            if run == "gold":
                continue
            metrics = entry["metrics"]
            ideal = entry.get("sample_ratio_over_gold") or float("nan")
            print(f"{name:14} {mean_x:7.3f} {run:>18} {entry['speedup_over_gold']:7.2f}x {ideal:6.2f}x "
                  f"{metrics['flip']['mean_flip']:6.3f} {metrics['mse']['average_error_percent']:7.3f}")
    print(f"(report: {experiment / 'report.html'})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
