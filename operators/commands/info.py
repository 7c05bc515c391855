"""``xsl-render info SCENE.blend [--json]``: what the scene holds for selective rendering."""
from __future__ import annotations

import json

NAME = "info"
HELP = "describe the camera, render settings, participating media, visible lights and frames"


def add_arguments(parser) -> None:
    from .common import add_scene_positional

    add_scene_positional(parser, "the .blend file to inspect")
    parser.add_argument("--scene-name", help="which scene of the file (default: the active one)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")


def run(args) -> int:
    from ...addon.scene.blend_session import open_blend
    from ...addon.scene.probe import describe_scene

    import bpy

    scene = open_blend(args.scene, args.scene_name)
    info = describe_scene(scene, bpy.context.evaluated_depsgraph_get())
    info["file"] = str(args.scene or bpy.data.filepath or "(unsaved)")
    info["estimator"] = _estimator(scene, info)
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        print(format_text(info))
    return 0


def _estimator(scene, info: dict) -> dict:
    """How the scene estimates its volumes, and what ``--estimator auto`` would choose at its
    own samples per pixel (with the predicted visible bias of each step rate it tried)."""
    from ...addon.maps.estimator_choice import choose_estimator
    from ...core.sampling.render_options import RenderOptions

    cycles = getattr(scene, "cycles", None)
    spp = info["render"]["samples"] or 1
    own = {"biased": bool(getattr(cycles, "volume_biased", False)),
           "step_rate": float(getattr(cycles, "volume_step_rate", 1.0))}
    chosen = choose_estimator(scene, RenderOptions(max_spp=spp, estimator="auto"), spp)
    return {"scene": own, "auto": chosen.to_dict() | {"spp": spp, "described": chosen.describe()}}


def _fmt(values) -> str:
    return "(" + ", ".join(f"{v:.3g}" for v in values) + ")"


def format_text(info: dict) -> str:
    cam, render = info["camera"], info["render"]
    lines = [f"{info['file']}  scene '{info['scene']}'"]
    optics = (f"lens {cam['lens_mm']:g} mm" if cam["type"] == "PERSP"
              else f"ortho scale {cam['ortho_scale']:g}")
    lines.append(f"camera  {cam['name']}: {cam['type'].lower()}, {optics}, "
                 f"clip {cam['clip_start']:g}..{cam['clip_end']:g}, at {_fmt(cam['location'])}")
    width, height = render["resolution"]
    lines.append(f"render  {render['engine']} {width}x{height}"
                 + (f", {render['samples']} samples" if render["samples"] is not None else ""))
    if not info["media"]:
        lines.append("media   none (the X map will be 1 everywhere)")
    for medium in info["media"]:
        closures = ", ".join(
            f"{c['node_type'].lower()} density "
            + (f"{c['density']:g}" if c["density"] is not None else f"driven by {c['density_driver']}")
            for c in medium["closures"])
        ext = (f", extinction {_fmt(medium['extinction'])}/unit" if medium["extinction"] else "")
        where = "" if medium["bbox_min"] is None else f", bounds {_fmt(medium['bbox_min'])}..{_fmt(medium['bbox_max'])}"
        lines.append(f"medium  {medium['name']} ({medium['kind']}): {closures}{ext}{where}")
    estimator = info.get("estimator")
    if estimator:
        own, auto = estimator["scene"], estimator["auto"]
        scene_way = (f"ray marching at step rate {own['step_rate']:g}" if own["biased"]
                     else "null scattering (unbiased)")
        tried = ", ".join(f"{rate}: {value:.2%}" for rate, value in (auto.get("tried") or {}).items())
        lines.append(f"volumes {scene_way}; --estimator auto at {auto['spp']} spp: {auto['described']} "
                     f"({auto['reason']}{'; predicted bias by step rate ' + tried if tried else ''})")
    if not info["lights"]:
        lines.append("lights  none in frame")
    for light in info["lights"]:
        lines.append(f"light   {light['name']} ({light['kind'].lower()}): energy {light['energy']:g}, "
                     f"colour {_fmt(light['color'])}, size {light['size']:.3g}, at {_fmt(light['location'])}")
    if info["lights_out_of_frame"]:
        lines.append(f"        not in frame: {', '.join(info['lights_out_of_frame'])}")
    frames = info["frames"]
    lines.append(f"frames  {frames['start']}..{frames['end']} step {frames['step']} at {frames['fps']:g} fps")
    return "\n".join(lines)
