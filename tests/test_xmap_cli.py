"""``xsl-render xmap`` and the ray cache: files, instant recomputation, bad input."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from support.xmap_scenes import add, base_scene, ground_and_props, volume_material, world_fog

pytestmark = pytest.mark.blender


def _save(bpy, path):
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    return path


@pytest.fixture
def fog_blend(blender, tmp_path):
    scene = base_scene(blender)
    ground_and_props(blender)
    world_fog(scene, density=0.05)
    material, _ = volume_material(blender, "fog box", "ShaderNodeVolumeScatter", density=0.3)
    add(blender, "primitive_cube_add", material, size=3, location=(0.5, 8, 1))
    return _save(blender, tmp_path / "fog.blend")


def test_xmap_command_writes_the_maps(cli, fog_blend, tmp_path):
    from xsl_render.core.imageio import read_image
    from xsl_render.core.maps.camera_rays import depth_from_exr

    out = tmp_path / "maps"
    result = cli("xmap", fog_blend, "--out", out, "--resolution", "48x27")
    assert result.returncode == 0, result.stderr
    z, x = read_image(out / "z.exr")[:, :, 0], read_image(out / "x.exr")[:, :, 0]
    assert z.shape == x.shape == (27, 48)
    info = json.loads((out / "xmap.json").read_text())
    assert info["cache"]["hit"] is False and info["minbound"]["enabled"]
    sky = ~np.isfinite(depth_from_exr(z))
    assert sky.any() and (~sky).any() and z.max() == np.float32(1e10)
    assert np.all((x >= 0) & (x <= 1)) and np.all(x[sky] == x[~sky].min())
    again = cli("xmap", fog_blend, "--out", out, "--resolution", "48x27", "--no-minbound")
    assert again.returncode == 0, again.stderr
    info = json.loads((out / "xmap.json").read_text())
    assert info["cache"]["hit"] is True and not info["minbound"]["enabled"]
    assert read_image(out / "x.exr")[:, :, 0][sky].max() < x[~sky].min()


@pytest.mark.timing
def test_changed_media_reuse_the_cached_rays(blender, tmp_path):
    """Density, colour and an animated frame change X but not the rays: no ray is cast,
    and the result is what a fresh computation gives."""
    from xsl_render.addon.maps.xmap import compute_x_map

    scene = base_scene(blender)
    ground_and_props(blender)
    fog = world_fog(scene, density=0.05)
    material, box = volume_material(blender, "box", "ShaderNodeVolumeScatter", density=0.3)
    cube = add(blender, "primitive_cube_add", material, size=3, location=(0.5, 8, 1))
    fog.inputs["Density"].keyframe_insert("default_value", frame=1)
    fog.inputs["Density"].default_value = 0.15
    fog.inputs["Density"].keyframe_insert("default_value", frame=10)
    scene.frame_set(1)
    first, _, info = compute_x_map(scene, cache_dir=tmp_path)
    assert not info["cache"]["hit"]
    box.inputs["Color"].default_value = (1.0, 0.3, 0.1, 1.0)
    scene.frame_set(10)
    cached, z, info = compute_x_map(scene, cache_dir=tmp_path)
    fresh, fresh_z, _ = compute_x_map(scene)
    assert info["cache"]["hit"] and info["seconds"]["rays"] < 0.1
    assert np.array_equal(cached, fresh) and np.array_equal(z, fresh_z)
    assert np.abs(cached - first).max() > 0.05
    cube.location.z += 0.5                      # geometry moved: the rays must be cast again
    _, _, info = compute_x_map(scene, cache_dir=tmp_path)
    assert not info["cache"]["hit"]


def test_no_media_gives_ones_and_one_warning_line(blender, cli, tmp_path):
    base_scene(blender)
    ground_and_props(blender)
    path = _save(blender, tmp_path / "clear.blend")
    result = cli("xmap", path, "--out", tmp_path / "out", "--resolution", "32x18")
    assert result.returncode == 0, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("xsl-render: warning:") and "no participating media" in lines[0]
    from xsl_render.core.imageio import read_image

    assert np.all(read_image(tmp_path / "out" / "x.exr") == 1.0)


def _broken(kind):
    def make(bpy, scene):
        if kind == "negative density":
            world_fog(scene, density=-0.2)
        elif kind == "nan density":
            material, _ = volume_material(bpy, "nan", density=float("nan"))
            add(bpy, "primitive_cube_add", material, size=2, location=(0, 6, 1))
        elif kind == "zero-area border":
            world_fog(scene)
            scene.render.use_border = True
            scene.render.border_min_x = scene.render.border_max_x = 0.5
        elif kind == "clip start beyond clip end":
            world_fog(scene)
            scene.camera.data.clip_start, scene.camera.data.clip_end = 50.0, 10.0
    return make


@pytest.mark.parametrize("kind, message", [
    ("negative density", "density -0.2"),
    ("nan density", "density nan"),
    ("zero-area border", "zero area"),
    ("clip start beyond clip end", "clip start 50 >= clip end 10"),
])
def test_bad_input_exits_2_with_one_line(blender, cli, tmp_path, kind, message):
    scene = base_scene(blender)
    ground_and_props(blender)
    _broken(kind)(blender, scene)
    path = _save(blender, tmp_path / "bad.blend")
    out = tmp_path / "out"
    result = cli("xmap", path, "--out", out)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr
    assert not (out / "x.exr").exists() and not (out / "z.exr").exists()


def test_bad_resolution_is_refused(cli, tmp_path):
    (tmp_path / "unopened.blend").write_bytes(b"BLENDER-v500")    # refused before Blender opens it
    result = cli("xmap", tmp_path / "unopened.blend", "--out", tmp_path, "--resolution", "wide")
    assert result.returncode == 2 and "--resolution" in result.stderr


def test_scene_is_unchanged_after_compute(blender):
    from xsl_render.addon.maps.xmap import compute_x_map
    from xsl_render.addon.scene.state import settings_dump

    scene = base_scene(blender)
    ground_and_props(blender)
    world_fog(scene)
    before = settings_dump(scene)
    compute_x_map(scene)
    assert settings_dump(scene) == before
    assert math.isclose(scene.camera.data.lens, 24.0)


@pytest.mark.parametrize("options, message", [
    (("--tolerance", "2"), "--tolerance"),
    (("--tolerance", "0"), "--tolerance"),
    (("--samples", "16", "--tolerance", "0.01"), "exclude each other"),
])
def test_bad_integration_options_are_refused(cli, tmp_path, options, message):
    (tmp_path / "unopened.blend").write_bytes(b"BLENDER-v500")    # refused before Blender opens it
    result = cli("xmap", tmp_path / "unopened.blend", "--out", tmp_path, *options)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and message in lines[0]
