"""``xsl-render info``: what it reports, and one clear line with exit 2 for bad input."""
from __future__ import annotations

import json
import math

import pytest

pytestmark = pytest.mark.blender


def save_scene(bpy, path, camera_type="PERSP", with_camera=True):
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 64, 36
    bpy.ops.mesh.primitive_plane_add(size=20)
    if with_camera:
        data = bpy.data.cameras.new("Cam")
        data.type = camera_type
        cam = bpy.data.objects.new("Cam", data)
        scene.collection.objects.link(cam)
        scene.camera = cam
        cam.location, cam.rotation_euler = (0, -8, 2), (math.radians(85), 0, 0)
    lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT"))
    lamp.location = (0, 6, 2.5)
    scene.collection.objects.link(lamp)
    hidden = bpy.data.objects.new("Behind", bpy.data.lights.new("Behind", "POINT"))
    hidden.location = (0, -20, 2)
    scene.collection.objects.link(hidden)
    world = bpy.data.worlds.new("Fog")
    scene.world = world
    volume = world.node_tree.nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Density"].default_value = 0.04
    volume.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    world.node_tree.links.new(volume.outputs[0], world.node_tree.nodes["World Output"].inputs["Volume"])
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def test_info_reports_camera_media_and_lights(blender, cli, tmp_path):
    path = save_scene(blender, tmp_path / "fog.blend")
    result = cli("info", path, "--json")
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    assert info["camera"]["name"] == "Cam" and info["camera"]["type"] == "PERSP"
    assert info["render"]["resolution"] == [64, 36]
    (fog,) = info["media"]
    assert fog["kind"] == "world" and fog["homogeneous"]
    # Principled Volume, colour 0.5, black absorption colour: extinction = density.
    assert fog["extinction"] == pytest.approx([0.04] * 3)
    assert [light["name"] for light in info["lights"]] == ["Lamp"]
    assert info["lights_out_of_frame"] == ["Behind"]
    text = cli("info", path)
    assert text.returncode == 0 and "medium  Fog (world)" in text.stdout


def one_line_error(result) -> str:
    assert result.returncode == 2, (result.returncode, result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    return lines[0]


def test_missing_file(cli, tmp_path):
    assert "no such file" in one_line_error(cli("info", tmp_path / "nope.blend"))


def test_not_a_blend_file(cli, tmp_path):
    fake = tmp_path / "fake.blend"
    fake.write_text("hello")
    assert "not a .blend file" in one_line_error(cli("info", fake))


def test_scene_without_camera(blender, cli, tmp_path):
    path = save_scene(blender, tmp_path / "nocam.blend", with_camera=False)
    assert "no active camera" in one_line_error(cli("info", path))


def test_panoramic_camera(blender, cli, tmp_path):
    path = save_scene(blender, tmp_path / "pano.blend", camera_type="PANO")
    assert "panoramic" in one_line_error(cli("info", path))


def test_usage_error_is_one_line(cli):
    assert "required" in one_line_error(cli("info"))
