"""Issue 46, point 3: light too strong for 32-bit floats.

The road with a small emissive plane of strength 1e38 in front of the camera: the fog
scatters its light over the whole frame (about 1e34 a pixel) and Cycles' sums overflow to
infinity in 3 pixels. OIDN turned that frame black (its auto-exposure overflows), on the
direct and the compositor path, and ``--no-denoise`` ended with an internal error.
"""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from conftest import EXAMPLES

from xsl_render.core.errors import InputError
from xsl_render.core.imageio import read_image
from xsl_render.core.sampling.finite_pixels import zero_non_finite

W, H = 96, 54


def test_non_finite_values_are_set_to_0_and_counted_per_pixel():
    image = np.ones((4, 5, 4), np.float32)
    assert zero_non_finite(image) == (image, 0) and zero_non_finite(image)[0] is image
    image[1, 2, 0], image[1, 2, 2], image[3, 4, 3] = np.inf, np.nan, -np.inf
    out, pixels = zero_non_finite(image)
    assert pixels == 2 and np.isfinite(out).all() and out.dtype == np.float32
    assert (out[1, 2, [0, 2]] == 0).all() and out[1, 2, 1] == 1 and out[3, 4, 3] == 0
    with pytest.raises(InputError, match="every pixel Cycles rendered is infinite or NaN"):
        zero_non_finite(np.full((2, 2, 4), np.inf, np.float32))


def hot_road(bpy, folder, strength: float = 1e38):
    """road.blend with a 0.3 m emissive plane of ``strength`` 2 m in front of the camera, saved."""
    import mathutils

    copy = folder / "road.blend"
    shutil.copy(EXAMPLES / "road.blend", copy)
    bpy.ops.wm.open_mainfile(filepath=str(copy))
    scene = bpy.context.scene
    camera = scene.camera
    bpy.ops.mesh.primitive_plane_add(size=0.3)
    plane = bpy.context.active_object
    plane.location = camera.matrix_world @ mathutils.Vector((0.2, 0.1, -2.0))
    plane.rotation_euler = camera.rotation_euler
    material = bpy.data.materials.new("Hot")
    nodes = material.node_tree.nodes
    nodes.clear()
    emission, output = nodes.new("ShaderNodeEmission"), nodes.new("ShaderNodeOutputMaterial")
    emission.inputs["Strength"].default_value = strength
    material.node_tree.links.new(emission.outputs[0], output.inputs["Surface"])
    plane.data.materials.append(material)
    path = folder / "hot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return scene, path


def _an_image(image) -> bool:
    """Finite, and more than a few pixels lit: not the black frame OIDN made of it."""
    return bool(np.isfinite(image).all() and (image[..., :3].max(axis=-1) > 0).mean() > 0.9)


@pytest.mark.blender
@pytest.mark.render
def test_an_infinite_emitter_frame_denoises_to_an_image_on_both_oidn_paths(blender, tmp_path, monkeypatch):
    from xsl_render.addon.cycles import denoise as module
    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.core.sampling.render_options import RenderOptions

    scene, _ = hot_road(blender, tmp_path)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    direct = sr.render_gold(scene, RenderOptions(max_spp=16))
    assert direct.stats.non_finite_pixels == 3 and _an_image(direct.image)
    assert any("3 pixel(s) Cycles rendered were infinite or NaN" in w for w in direct.stats.warnings)
    monkeypatch.setattr(module, "load_oidn", lambda: None)          # the compositor's Denoise node
    through = sr.render_gold(scene, RenderOptions(max_spp=16))
    assert through.stats.non_finite_pixels == 3 and _an_image(through.image)
    # The two paths denoise alike (bit for bit on ordinary frames, tests/test_denoise.py).
    np.testing.assert_allclose(through.image, direct.image, rtol=1e-3)


@pytest.mark.blender
@pytest.mark.render
def test_the_command_line_renders_it_with_and_without_denoising(blender, cli, tmp_path):
    """Gold with and without denoising, and xsl, whose maps' snapshot sees the emitter too
    (its light map had ended in "cannot convert float NaN to integer")."""
    _, path = hot_road(blender, tmp_path)
    for mode, flag in (("gold", []), ("gold", ["--no-denoise"]), ("xsl", [])):
        out = tmp_path / f"{mode}{len(flag)}.exr"
        done = cli("render", path, "--mode", mode, "--max-spp", "16", "--resolution", f"{W}x{H}", "--quiet",
                   "--estimator", "scene", "--out", out, "--stats", out.with_suffix(".json"), *flag)
        assert done.returncode == 0, done.stderr
        assert "were infinite or NaN" in done.stderr and _an_image(read_image(out))
        assert json.loads(out.with_suffix(".json").read_text())["non_finite_pixels"] == 3


@pytest.mark.blender
@pytest.mark.render
def test_a_frame_with_no_finite_pixel_is_bad_input(blender, cli, tmp_path):
    """Nothing but a sky of strength 1e38: each sample is finite, every pixel's sum is not."""
    from support.fog_scene import build_fog_scene

    scene = build_fog_scene(blender, 32, 18)
    scene.world = blender.data.worlds.new("Blinding")
    nodes = scene.world.node_tree.nodes
    background = next(node for node in nodes if node.type == "BACKGROUND")
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = 1e38
    for ob in list(blender.data.objects):
        if ob.type != "CAMERA":
            blender.data.objects.remove(ob)
    path = tmp_path / "sky.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    done = cli("render", path, "--mode", "gold", "--max-spp", "16", "--quiet", "--out", tmp_path / "s.exr")
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "every pixel Cycles rendered is infinite or NaN" in done.stderr
    assert not list(tmp_path.glob("s.*")) and not list(tmp_path.glob("s_*"))
