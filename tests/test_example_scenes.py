"""The example scenes: the build is deterministic, the committed .blend files are what the
scripts build, each renders in Cycles, and scene probing finds what each scene is for (the
street's: only its camera moves)."""
from __future__ import annotations

import importlib.util
import json
import math

from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "example_blends"

SCENES = ("balls_a", "balls_b", "statue", "road", "street")
#: Each scene's render size: the paper's four at 512 px on the largest side, the animated
#: street smaller (24 frames).
SIZES = {"balls_a": (512, 384), "balls_b": (512, 384), "statue": (384, 512), "road": (512, 288),
         "street": (256, 144)}

pytestmark = pytest.mark.blender


def _build_scenes_module():
    spec = importlib.util.spec_from_file_location("build_scenes", EXAMPLES / "build_scenes.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---------------------------------------------------------------------------------------
# A content summary of a .blend: what the scene holds, not how the file stores it.

#: RNA properties that change with the session or the file, not with the scene.
_VOLATILE = {"rna_type", "name_full", "session_uid", "is_evaluated", "original", "users",
             "use_fake_user", "use_extra_user", "is_embedded_data", "is_library_indirect",
             "is_missing", "is_runtime_data", "tag", "is_editmode", "id_type", "preview",
             "library_weak_reference", "asset_data", "override_library", "library",
             "select", "is_active_output", "dimensions", "width_hidden", "show_expanded"}


def _plain(value):
    if isinstance(value, float):
        return round(value, 5) + 0.0           # + 0.0 folds -0.0 into 0.0
    if isinstance(value, (bool, int, str)) or value is None:
        return value
    if isinstance(value, set):
        return sorted(value)
    try:
        return [_plain(v) for v in value]
    except TypeError:
        return getattr(value, "name", repr(type(value)))


def rna_values(struct) -> dict:
    """Every plain (non-pointer, non-collection) RNA property of ``struct``."""
    out = {}
    for prop in struct.bl_rna.properties:
        key = prop.identifier
        if prop.type in ("POINTER", "COLLECTION") or key in _VOLATILE:
            continue
        out[key] = _plain(getattr(struct, key))
    return out


def node_tree_summary(tree) -> dict | None:
    if tree is None:
        return None
    nodes = {}
    for node in tree.nodes:
        sockets = {f"{s.identifier}": _plain(s.default_value)
                   for s in node.inputs if hasattr(s, "default_value")}
        nodes[node.name] = {"type": node.bl_idname, "props": rna_values(node), "inputs": sockets,
                            "material": getattr(getattr(node.inputs.get("Material"), "default_value", None),
                                                "name", None) if "Material" in node.inputs else None}
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links)
    interface = [(item.item_type, getattr(item, "in_out", None), item.name)
                 for item in tree.interface.items_tree] if hasattr(tree, "interface") else []
    return {"nodes": nodes, "links": links, "interface": interface}


def animation_summary(idtype) -> dict | None:
    """The keyframes of a datablock's action (its slot's channels), or None without one."""
    data = getattr(idtype, "animation_data", None)
    if data is None or data.action is None:
        return None
    from bpy_extras.anim_utils import action_get_channelbag_for_slot

    channels = action_get_channelbag_for_slot(data.action, data.action_slot)
    curves = [] if channels is None else channels.fcurves
    return {"action": data.action.name, "curves": sorted(
        (c.data_path, c.array_index, c.extrapolation,
         _plain([(tuple(k.co), k.interpolation, tuple(k.handle_left), tuple(k.handle_right))
                 for k in c.keyframe_points]))
        for c in curves)}


def mesh_fingerprint(mesh) -> dict:
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    return {"vertices": len(mesh.vertices), "faces": len(mesh.polygons),
            "sum": _plain(co.sum(axis=0).tolist()), "abs_sum": _plain(np.abs(co).sum(axis=0).tolist()),
            "materials": [m.name if m else None for m in mesh.materials]}


def scene_summary(bpy) -> dict:
    """A comparable digest of the open session: objects, data, materials, world, settings,
    and what the depsgraph makes of the objects (evaluated vertex counts, volume grids)."""
    scene = bpy.context.scene
    depsgraph = bpy.context.evaluated_depsgraph_get()
    objects = {}
    for ob in bpy.data.objects:
        entry = {"type": ob.type, "parent": ob.parent.name if ob.parent else None,
                 "matrix": _plain([list(row) for row in ob.matrix_world]),
                 "props": rna_values(ob), "data": ob.data.name if ob.data else None,
                 "modifiers": [{"type": m.type, "props": rna_values(m),
                                "node_group": getattr(getattr(m, "node_group", None), "name", None)}
                               for m in ob.modifiers],
                 "slots": [s.material.name if s.material else None for s in ob.material_slots],
                 "in_scene": ob.name in scene.objects, "animation": animation_summary(ob)}
        if ob.type == "MESH":
            entry["mesh"] = mesh_fingerprint(ob.data)
            entry["evaluated_faces"] = len(ob.evaluated_get(depsgraph).data.polygons)
        elif ob.type in ("LIGHT", "CAMERA"):
            entry["data_props"] = rna_values(ob.data)
        elif ob.type == "VOLUME":
            evaluated = ob.evaluated_get(depsgraph).data
            evaluated.grids.load()
            entry["data_props"] = rna_values(ob.data.render)
            entry["materials"] = [m.name for m in ob.data.materials]
            entry["grids"] = [(g.name, g.data_type) for g in evaluated.grids]
            entry["evaluated_materials"] = [m.name if m else None for m in evaluated.materials]
        objects[ob.name] = entry
    materials = {m.name: {"cycles": rna_values(m.cycles), "tree": node_tree_summary(m.node_tree),
                          "animation": animation_summary(m)}
                 for m in bpy.data.materials}
    groups = {g.name: node_tree_summary(g) for g in bpy.data.node_groups}
    world = scene.world
    return {
        "scene": scene.name, "camera": scene.camera.name if scene.camera else None,
        "frames": (scene.frame_start, scene.frame_end, scene.frame_current),
        "render": rna_values(scene.render), "cycles": rna_values(scene.cycles),
        "view": rna_values(scene.view_settings),
        "display": scene.display_settings.display_device,
        "world": None if world is None else {"name": world.name, "color": _plain(world.color),
                                             "tree": node_tree_summary(world.node_tree)},
        "objects": objects, "materials": materials, "node_groups": groups,
        "counts": {kind: len(getattr(bpy.data, kind)) for kind in
                   ("objects", "meshes", "lights", "cameras", "volumes", "materials",
                    "node_groups", "worlds", "images", "textures", "scenes", "actions")},
    }


def summary_of_file(bpy, path) -> dict:
    bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
    return scene_summary(bpy)


def first_difference(a, b, path="") -> str | None:
    """Where two summaries differ, as a readable path (for the failure message)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b), key=str):
            if key not in a or key not in b:
                return f"{path}/{key}: only in {'first' if key in a else 'second'}"
            found = first_difference(a[key], b[key], f"{path}/{key}")
            if found:
                return found
        return None
    return None if a == b else f"{path}: {a!r} != {b!r}"


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """Each scene built twice by its script (two separate builds, two files)."""
    import bpy

    build = _build_scenes_module()
    out = {}
    for run in ("first", "second"):
        folder = tmp_path_factory.mktemp(f"scenes_{run}")
        for name in SCENES:
            path = build.build_scene(name, folder)
            out[(name, run)] = summary_of_file(bpy, path)
    return out


# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", SCENES)
def test_build_is_deterministic(built, name):
    first, second = built[(name, "first")], built[(name, "second")]
    assert first == second, first_difference(first, second)


@pytest.mark.parametrize("name", SCENES)
def test_committed_blend_is_what_the_script_builds(built, name):
    import bpy

    committed = summary_of_file(bpy, EXAMPLES / f"{name}.blend")
    fresh = built[(name, "first")]
    assert committed == fresh, (f"example_blends/{name}.blend is stale, rebuild it with "
                                f"build_scenes.py: {first_difference(committed, fresh)}")


@pytest.mark.parametrize("name", SCENES)
def test_committed_blend_is_small_and_set_up_for_the_paper(name):
    path = EXAMPLES / f"{name}.blend"
    assert path.stat().st_size < 1_000_000
    import bpy

    bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
    scene = bpy.context.scene
    r, c = scene.render, scene.cycles
    assert r.engine == "CYCLES" and c.device == "CPU"
    assert (r.resolution_x, r.resolution_y) == SIZES[name] and r.resolution_percentage == 100
    assert scene.camera.data.type == "PERSP"
    assert c.samples == 64 and not c.use_adaptive_sampling and not c.use_denoising
    assert c.volume_bounces in (0, 1) and c.max_bounces <= 8


@pytest.mark.render
@pytest.mark.parametrize("name", SCENES)
def test_renders_in_cycles(name, tmp_path):
    """A tiny render of the committed file: no error, finite, not black."""
    import bpy

    from xsl_render.core.imageio import read_image

    bpy.ops.wm.open_mainfile(filepath=str(EXAMPLES / f"{name}.blend"), load_ui=False)
    scene = bpy.context.scene
    r = scene.render
    scale = 32 / max(r.resolution_x, r.resolution_y)
    r.resolution_x, r.resolution_y = (max(1, round(r.resolution_x * scale)),
                                      max(1, round(r.resolution_y * scale)))
    scene.cycles.samples = 2
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.filepath = str(tmp_path / f"{name}.exr")
    bpy.ops.render.render(write_still=True)
    image = read_image(tmp_path / f"{name}.exr")[..., :3]
    assert image.shape[:2] == (r.resolution_y, r.resolution_x)
    assert np.isfinite(image).all()
    assert image.mean() > 1e-3, f"{name} renders black"
    assert (image.max(axis=2) > 1e-3).mean() > 0.5, f"{name}: most of the frame is black"


# ---------------------------------------------------------------------------------------
# What scene probing finds: the reason each scene exists.


def _describe(name):
    import bpy

    from xsl_render.addon.scene.probe import describe_scene

    bpy.ops.wm.open_mainfile(filepath=str(EXAMPLES / f"{name}.blend"), load_ui=False)
    return describe_scene(bpy.context.scene, bpy.context.evaluated_depsgraph_get())


def test_balls_a_fog_is_homogeneous_with_constant_extinction():
    (fog,) = _describe("balls_a")["media"]
    assert fog["name"] == "Fog" and fog["kind"] == "mesh" and fog["homogeneous"]
    assert all(math.isclose(k, 0.04, rel_tol=1e-6) for k in fog["extinction"])


def test_balls_b_fog_density_is_driven_by_noise():
    (fog,) = _describe("balls_b")["media"]
    assert fog["name"] == "Fog" and fog["kind"] == "mesh" and not fog["homogeneous"]
    (closure,) = fog["closures"]
    assert closure["density"] is None and closure["density_driver"]


def test_statue_smoke_is_a_volume_object_with_a_density_grid():
    (smoke,) = _describe("statue")["media"]
    assert smoke["name"] == "Smoke" and smoke["kind"] == "volume_object"
    assert smoke["material"] == "Smoke" and not smoke["homogeneous"]
    assert "grid:density" in smoke["closures"][0]["density_driver"]


def test_info_lists_the_road_fog_headlights_lamps_and_camera(cli):
    result = cli("info", EXAMPLES / "road.blend", "--json")
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    assert info["camera"]["name"] == "Camera" and info["camera"]["type"] == "PERSP"
    (fog,) = info["media"]
    assert fog["kind"] == "world" and fog["homogeneous"] and fog["extinction"][0] > 0
    lights = {light["name"]: light for light in info["lights"]}
    for side in ("L", "R"):
        assert lights[f"Headlight.{side}"]["kind"] == "SPOT"
        assert lights[f"Headlight.{side}.Lens"]["kind"] == "MESH"
    lamps = sorted(n for n, light in lights.items() if n.startswith("Lamp.") and light["kind"] == "POINT")
    assert lamps == [f"Lamp.{i}" for i in range(1, 7)]
    assert all(f"{lamp}.Bulb" in lights for lamp in lamps)
    assert info["lights_out_of_frame"] == []


def test_info_lists_the_street_fog_lamps_and_frames(cli):
    result = cli("info", EXAMPLES / "street.blend", "--json")
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    (fog,) = info["media"]
    assert fog["name"] == "Fog" and fog["kind"] == "mesh" and not fog["homogeneous"]
    lights = {light["name"]: light for light in info["lights"]}
    lamps = sorted(n for n, light in lights.items() if n.startswith("Lamp.") and light["kind"] == "POINT")
    assert lamps == [f"Lamp.{i}" for i in range(1, 5)]
    assert all(f"{lamp}.Bulb" in lights for lamp in lamps)


def test_street_moves_only_its_camera_through_static_fog():
    """24 frames at 24 fps; the camera dollies about 5 m and pans, staying inside the fog box;
    nothing else is animated (the fog stays still, so persistent data can keep it)."""
    import bpy

    bpy.ops.wm.open_mainfile(filepath=str(EXAMPLES / "street.blend"), load_ui=False)
    scene = bpy.context.scene
    assert (scene.frame_start, scene.frame_end, scene.render.fps, scene.render.fps_base) == (1, 24, 24, 1.0)
    animated = [ob.name for ob in bpy.data.objects if animation_summary(ob)]
    animated += [m.name for m in bpy.data.materials if animation_summary(m)]
    animated += [w.name for w in bpy.data.worlds if animation_summary(w)]
    animated += [d.name for d in (*bpy.data.lights, *bpy.data.cameras, *bpy.data.meshes)
                 if animation_summary(d)]
    assert animated == ["Camera"]
    camera, fog = scene.camera, bpy.data.objects["Fog"]
    corners = [fog.matrix_world @ v.co for v in fog.data.vertices]
    low = [min(c[i] for c in corners) for i in range(3)]
    high = [max(c[i] for c in corners) for i in range(3)]
    assert low[2] < 0.0 < 0.5 < high[2]              # resting on the ground
    poses = []
    for frame in (1, 12, 24):
        scene.frame_set(frame)
        location = camera.matrix_world.translation.copy()
        assert all(lo < x < hi for lo, x, hi in zip(low, location, high)), (frame, location)
        poses.append((location, camera.matrix_world.to_quaternion()))
    scene.frame_set(1)
    dolly = (poses[2][0] - poses[0][0]).length
    pan = math.degrees(poses[0][1].rotation_difference(poses[2][1]).angle)
    assert 4.0 < dolly < 6.0 and 1.0 < pan < 10.0, (dolly, pan)
    assert (poses[1][0] - poses[0][0]).length == pytest.approx(dolly * 11 / 23, rel=1e-3)   # linear
