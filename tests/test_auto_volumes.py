"""Auto Volumes in Blender's own render (bpy headless): F12 and Ctrl+F12 render auto's choice,
the same pixels as ``--estimator auto``; off, plain Blender's; every setting back after a
render, a cancel and an error inside the choice; the saved file, the viewport, the
compositor's File Output and the frame's header as they should be; a frame's choice and
pixels the same however a range is split."""
from __future__ import annotations

import numpy as np
import pytest
from support.fog_scene import build_fog_scene
from test_ray_marching import _two_media_scene

from xsl_render.core.imageio import image_attributes, read_image

pytestmark = [pytest.mark.blender, pytest.mark.render]

W, H = 32, 18
SPP = 4


@pytest.fixture(scope="module")
def addon():
    import xsl_render

    xsl_render.register()
    yield xsl_render
    xsl_render.unregister()


def media_scene(blender, tmp_path, frames=(1, 4), camera_moves=True):
    """The two-media scene (a noise fog box over an OpenVDB smoke) at W x H, SPP samples, no
    denoiser, ray marching at step rate 1 (the artist's: no octree to wait for), EXR frames
    into tmp_path; the camera drifts over ``frames``; the range as the file has it."""
    from xsl_render.addon.maps import shot_choice

    scene = _two_media_scene(blender)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.cycles.samples, scene.cycles.use_denoising, scene.cycles.seed = SPP, False, 0
    scene.cycles.volume_biased = True
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.filepath = str(tmp_path / "frame_")
    scene.frame_start, scene.frame_end = frames
    if camera_moves:
        camera = scene.camera
        camera.keyframe_insert("location", frame=frames[0])
        camera.location.x += 0.05 * (frames[1] - frames[0])
        camera.keyframe_insert("location", frame=frames[1])
    scene.frame_set(frames[0])
    shot_choice.remember_ranges()
    return scene


def everything(blender, scene) -> dict:
    """Every setting a render could leave changed: the scene's (render, Cycles, view layers,
    world, materials, slots, visibility) and Blender's debug preferences."""
    from xsl_render.addon.scene.state import DEBUG_PATTERN_PREFERENCES, settings_dump

    preferences = blender.context.preferences
    return settings_dump(scene) | {"preferences": [getattr(getattr(preferences, path), name)
                                                   for path, name in DEBUG_PATTERN_PREFERENCES]}


def f12(blender, scene, path) -> np.ndarray:
    """F12 into ``path``.exr (the scene's output path as it was afterwards)."""
    own, scene.render.filepath = scene.render.filepath, str(path)
    try:
        blender.ops.render.render(write_still=True, scene=scene.name)
    finally:
        scene.render.filepath = own
    return read_image(f"{path}.exr")


def test_f12_renders_the_command_lines_auto_choice_and_gives_every_setting_back(
        blender, addon, tmp_path, capsys):
    from dataclasses import replace

    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.maps.shot_choice import choose_for_shot
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = media_scene(blender, tmp_path)
    scene.frame_set(2)
    scene.xsl_render.auto_volumes = True
    before = everything(blender, scene)
    image = f12(blender, scene, tmp_path / "f12")
    assert everything(blender, scene) == before
    line = [line for line in capsys.readouterr().out.splitlines() if line.startswith("Auto Volumes:")]
    assert len(line) == 1 and "frame 2" in line[0] and "ray marching" in line[0]
    note = image_attributes(tmp_path / "f12.exr")["Note"]
    assert note.startswith("Auto Volumes: ray marching")
    # The viewport's depsgraph never saw auto's settings.
    evaluated = blender.context.evaluated_depsgraph_get().scene_eval.cycles
    assert (evaluated.volume_biased, evaluated.volume_step_rate) == (True, 1.0)

    scene.xsl_render.auto_volumes = False
    options = RenderOptions(max_spp=SPP, estimator="auto", denoise=False)
    options = replace(options, estimator_choice=choose_for_shot(scene, (1, 4), options, SPP).choice)
    assert options.estimator_choice.biased
    np.testing.assert_array_equal(image, sr.render_gold(scene, options).image)
    assert everything(blender, scene) == before


def test_off_renders_plain_blenders_pixels(blender, addon, tmp_path):
    scene = media_scene(blender, tmp_path)
    assert scene.xsl_render.auto_volumes is False
    before = everything(blender, scene)
    off = f12(blender, scene, tmp_path / "off")
    assert everything(blender, scene) == before
    assert "Note" not in image_attributes(tmp_path / "off.exr")
    addon.unregister()                       # Blender without the extension
    try:
        np.testing.assert_array_equal(f12(blender, scene, tmp_path / "plain"), off)
    finally:
        addon.register()


def test_an_animation_renders_each_frame_as_the_command_line_does(blender, addon, tmp_path):
    from dataclasses import replace

    from xsl_render.addon.cycles import selective_render as sr
    from xsl_render.addon.maps.shot_choice import choose_for_shot
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = media_scene(blender, tmp_path)
    options = RenderOptions(max_spp=SPP, estimator="auto", denoise=False)
    shot = choose_for_shot(scene, (1, 4), options, SPP)
    own = {frame: shot.choice for frame in range(1, 5)}      # the command line's: one per shot
    scene.xsl_render.auto_volumes = True
    before = everything(blender, scene)
    blender.ops.render.render(animation=True, scene=scene.name)
    assert everything(blender, scene) == before
    scene.xsl_render.auto_volumes = False
    for frame in range(1, 5):
        scene.frame_set(frame)
        cli = sr.render_gold(scene, replace(options, estimator_choice=own[frame])).image
        np.testing.assert_array_equal(read_image(tmp_path / f"frame_{frame:04d}.exr"), cli, err_msg=f"{frame}")
    scene.frame_set(1)
    assert everything(blender, scene) == before


def test_a_cancelled_animation_gives_every_setting_back(blender, addon, tmp_path):
    """Blender cancels an animation whose frame cannot be written (as Esc does)."""
    scene = media_scene(blender, tmp_path)
    (tmp_path / "frame_0002.exr").mkdir()                  # frame 2's file cannot be written
    scene.xsl_render.auto_volumes = True
    before = everything(blender, scene)
    with pytest.raises(RuntimeError, match="Is a directory"):
        blender.ops.render.render(animation=True, scene=scene.name)
    assert (tmp_path / "frame_0001.exr").is_file() and not (tmp_path / "frame_0003.exr").exists()
    assert everything(blender, scene) == before


def test_an_error_inside_the_choice_leaves_the_artists_render_with_a_warning(
        blender, addon, tmp_path, monkeypatch, capsys):
    from xsl_render.addon.maps import shot_choice

    scene = media_scene(blender, tmp_path)
    plain = f12(blender, scene, tmp_path / "plain")
    scene.xsl_render.auto_volumes = True
    before = everything(blender, scene)

    def failing(*args, **kwargs):
        raise RuntimeError("the prediction broke")

    monkeypatch.setattr(shot_choice, "choose_estimator", failing)
    np.testing.assert_array_equal(f12(blender, scene, tmp_path / "failed"), plain)
    assert "the prediction broke" in capsys.readouterr().err
    assert everything(blender, scene) == before
    blender.ops.render.render(animation=True, scene=scene.name)              # every frame, too
    assert everything(blender, scene) == before
    assert capsys.readouterr().err.count("the prediction broke") == 4


def test_the_saved_file_has_the_artists_settings_even_when_saved_during_the_render(blender, addon, tmp_path):
    scene = media_scene(blender, tmp_path)
    scene.xsl_render.auto_volumes = True
    artists = (scene.cycles.sampling_pattern, scene.cycles.use_light_tree)
    saved = tmp_path / "during.blend"
    seen = []

    def save_while_rendering(text):
        if "Time" in str(text) and not seen:
            seen.append(scene.cycles.volume_step_rate)       # auto's settings are on now
            blender.ops.wm.save_as_mainfile(filepath=str(saved), copy=True)

    blender.app.handlers.render_stats.append(save_while_rendering)
    try:
        f12(blender, scene, tmp_path / "f12")
    finally:
        blender.app.handlers.render_stats.remove(save_while_rendering)
    assert seen and seen[0] != 1.0
    blender.ops.wm.save_as_mainfile(filepath=str(tmp_path / "after.blend"), copy=True)
    for path in (saved, tmp_path / "after.blend"):
        blender.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
        reopened = blender.context.scene
        assert (reopened.cycles.volume_biased, reopened.cycles.volume_step_rate) == (True, 1.0)
        assert (reopened.cycles.sampling_pattern, reopened.cycles.use_light_tree) == artists
        assert {m.name: m.cycles.volume_step_rate for m in blender.data.materials
                if m.name in ("noise fog", "smoke")} == {"noise fog": 1.0, "smoke": 1.0}
        assert not reopened.render.use_stamp_note and reopened.xsl_render.auto_volumes


def test_the_compositors_file_output_node_writes_its_passes(blender, addon, tmp_path):
    scene = media_scene(blender, tmp_path, camera_moves=False)
    scene.view_layers[0].use_pass_z = True
    tree = blender.data.node_groups.new("Compositing", "CompositorNodeTree")
    scene.compositing_node_group = tree
    layers = tree.nodes.new("CompositorNodeRLayers")
    output = tree.nodes.new("CompositorNodeOutputFile")
    output.directory = str(tmp_path / "passes")
    output.file_name = "pass_"
    output.format.media_type = "IMAGE"                  # a file per pass
    output.format.file_format = "OPEN_EXR"
    output.file_output_items.clear()
    for name in ("Image", "Depth"):
        output.file_output_items.new("FLOAT" if name == "Depth" else "RGBA", name)
        tree.links.new(layers.outputs[name], output.inputs[name])
    scene.render.use_compositing = True
    scene.xsl_render.auto_volumes = True
    before = everything(blender, scene)
    f12(blender, scene, tmp_path / "f12")
    written = sorted(p.name for p in (tmp_path / "passes").iterdir())
    assert len(written) == 2 and all(read_image(tmp_path / "passes" / name).size for name in written), written
    assert everything(blender, scene) == before


def test_a_frame_renders_the_same_alone_in_a_chunk_and_in_the_range(blender, addon, tmp_path):
    """Frames 1-8 as one range, as two chunks of 4 (``blender -b -s 5 -e 8 -a`` sets the
    range before the render) and one by one (F12 of each): the same choice, the same pixels."""
    scene = media_scene(blender, tmp_path, frames=(1, 8))
    scene.xsl_render.auto_volumes = True
    blend = tmp_path / "shot.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(blend))
    runs = {"range": [(1, 8)], "chunks": [(1, 4), (5, 8)], "frames": [(n, n) for n in range(1, 9)]}
    for name, parts in runs.items():
        for first, last in parts:
            blender.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
            scene = blender.context.scene
            scene.render.filepath = str(tmp_path / name / "frame_####")
            if first == last:                          # F12 of the frame (a still has no #)
                scene.frame_set(first)
                scene.render.filepath = str(tmp_path / name / f"frame_{first:04d}")
                blender.ops.render.render(write_still=True, scene=scene.name)
            else:
                scene.frame_start, scene.frame_end = first, last
                blender.ops.render.render(animation=True, scene=scene.name)
    for frame in range(1, 9):
        files = [tmp_path / name / f"frame_{frame:04d}.exr" for name in runs]
        notes = {image_attributes(path)["Note"] for path in files}
        assert len(notes) == 1, notes
        images = [read_image(path) for path in files]
        for image in images[1:]:
            np.testing.assert_array_equal(image, images[0], err_msg=f"frame {frame}")


def test_a_still_shot_keeps_cycles_session_between_frames_and_gives_persistent_data_back(
        blender, addon, tmp_path):
    """Counting Cycles' octree builds (not seconds): null scattering on the fog box, the
    camera moving, is built once over 3 frames where Auto Volumes keeps the session; the
    file's persistent data is off again afterwards."""
    from xsl_render.addon.maps import shot_choice
    from xsl_render.core.sampling.volume_estimator import EstimatorChoice

    scene = media_scene(blender, tmp_path, frames=(1, 3))
    scene.xsl_render.auto_volumes = True
    builds = []

    def octrees(text):
        if "Building octree" in str(text):
            builds.append(scene.frame_current)

    null = EstimatorChoice("auto", biased=False, reason="test: null scattering")
    original = shot_choice.choose_estimator
    shot_choice.choose_estimator = lambda *args, **kwargs: null
    blender.app.handlers.render_stats.append(octrees)
    try:
        blender.ops.render.render(animation=True, scene=scene.name)
    finally:
        blender.app.handlers.render_stats.remove(octrees)
        shot_choice.choose_estimator = original
    assert sorted(set(builds)) == [1] and scene.render.use_persistent_data is False


def test_many_f12_in_one_process_toggling_the_setting_and_the_frame(blender, addon, tmp_path):
    """200 F12 in a row on a tiny fog scene (bench/bench_auto_volumes_stress.py: on an example scene)."""
    scene = build_fog_scene(blender, 16, 9)
    scene.cycles.samples = 1
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.frame_start, scene.frame_end = 1, 5
    scene.render.filepath = str(tmp_path / "f12")
    before = everything(blender, scene)
    for index in range(200):
        scene.xsl_render.auto_volumes = index % 3 != 0
        scene.frame_current = 1 + index % 5
        blender.ops.render.render(write_still=True, scene=scene.name)
        scene.frame_current = 1
        scene.xsl_render.auto_volumes = False
        assert everything(blender, scene) == before, index


def test_the_switch_is_in_cycles_volumes_panel_and_on_top_of_the_xsl_panel(blender, addon, monkeypatch):
    from types import SimpleNamespace

    from support.ui_stub import draw

    from xsl_render.addon.cycles import volume_settings
    from xsl_render.addon.panel import ui

    scene = build_fog_scene(blender, 16, 9)
    context = SimpleNamespace(scene=scene, window_manager=blender.context.window_manager,
                              workspace=SimpleNamespace(use_filter_by_owner=False))
    cycles_panel = draw(blender, blender.types.CYCLES_RENDER_PT_volumes, context)
    assert cycles_panel[0] == ("prop", scene.xsl_render, "auto_volumes")
    assert ("prop", scene.cycles, "volume_biased", "Biased") in cycles_panel     # Cycles' own rows follow
    ours = draw(blender, ui.RENDER_PT_xsl_render, context)
    assert ours[0] == ("prop", scene.xsl_render, "auto_volumes")
    assert {"xsl.preview_auto_volumes", "xsl.apply_auto_volumes"} <= {e[1] for e in ours if e[0] == "operator"}
    scene.xsl_render.auto_volumes = True                   # F12 in the interface needs the lock
    assert ("prop", scene.render, "use_lock_interface", "Lock Interface (needed for F12 here)") \
        in draw(blender, ui.RENDER_PT_xsl_render, context)
    # A Blender without the volume settings: greyed out, with the reason; renders untouched.
    monkeypatch.setattr(volume_settings, "NEEDED_SETTINGS", (("scene", "volume_future_setting"),))
    reason = "this Blender's Cycles has no scene setting 'volume_future_setting' (it needs Blender 5.0 or newer)"
    assert ("label", reason) in draw(blender, blender.types.CYCLES_RENDER_PT_volumes, context)
    assert not blender.ops.xsl.preview_auto_volumes.poll()


def test_preview_shows_the_frames_choice_and_apply_writes_it_into_the_scene(blender, addon, tmp_path):
    from xsl_render.addon.maps.shot_choice import choose_for_shot
    from xsl_render.addon.panel.auto_volumes_ui import previews

    scene = media_scene(blender, tmp_path)
    scene.frame_set(3)
    before = everything(blender, scene)
    assert blender.ops.xsl.preview_auto_volumes() == {"FINISHED"}
    lines = previews[(scene.as_pointer(), 3)]
    assert lines[0] == "Frames 1-4: decided at frame 1 of 1, 2, 3, 4"
    assert any(line.startswith("Volumes: ray marching at step rate") for line in lines)
    assert any(line.startswith("  smoke: its own step") for line in lines)
    assert any(line.startswith("Predicted error") for line in lines)
    assert everything(blender, scene) == before
    plan = choose_for_shot(scene, (1, 4))
    scene.xsl_render.auto_volumes = True
    # Undoable: an UNDO operator, whose step the interface pushes after it (here by hand).
    assert "UNDO" in blender.types.XSL_OT_apply_auto_volumes.bl_options
    blender.ops.ed.undo_push(message="before Apply to Scene")
    assert blender.ops.xsl.apply_auto_volumes() == {"FINISHED"}
    blender.ops.ed.undo_push(message="Apply to Scene")
    assert blender.context.scene.cycles.volume_step_rate != 1.0
    assert blender.ops.ed.undo() == {"FINISHED"}
    scene = blender.context.scene
    assert (scene.cycles.volume_step_rate, scene.xsl_render.auto_volumes) == (1.0, True)
    assert blender.ops.xsl.apply_auto_volumes() == {"FINISHED"}
    assert scene.xsl_render.auto_volumes is False
    assert scene.cycles.volume_biased and scene.cycles.volume_step_rate == pytest.approx(plan.choice.step_rate)
    assert blender.data.materials["smoke"].cycles.volume_step_rate == pytest.approx(
        plan.choice.medium_settings["material:smoke"])
    # Blue-Noise (round) renders only with Blender's debug options: the file keeps its pattern.
    assert scene.cycles.sampling_pattern == before["cycles"]["sampling_pattern"]


def test_a_render_from_the_interfaces_thread_needs_the_interface_locked(blender, addon):
    import threading

    from xsl_render.addon import auto_volumes

    scene = build_fog_scene(blender, 16, 9)
    scene.xsl_render.auto_volumes = True
    started = []

    def render_job_thread():          # what Blender's render job does before the first frame
        auto_volumes._on_render_init(scene)
        started.append(scene.as_pointer() in auto_volumes._jobs)
        auto_volumes._on_render_end(scene)

    for locked in (False, True):
        scene.render.use_lock_interface = locked
        thread = threading.Thread(target=render_job_thread)
        thread.start()
        thread.join()
    assert started == [False, True]
    assert "Lock Interface" in auto_volumes.last_warning


def test_the_command_line_renders_the_file_as_blender_does_with_auto_volumes(blender, addon, cli, tmp_path):
    import json

    scene = media_scene(blender, tmp_path, camera_moves=False)
    scene.render.image_settings.color_depth = "32"
    blend = tmp_path / "shot.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(blend))
    scene.xsl_render.auto_volumes = True
    f12_image = f12(blender, scene, tmp_path / "f12")
    result = cli("render", blend, "--out", tmp_path / "cli.exr", "--stats", tmp_path / "cli.json")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1].startswith("blender: frame 1, 32x18, 4 spp as the file sets")
    np.testing.assert_array_equal(read_image(tmp_path / "cli.exr"), f12_image)
    stats = json.loads((tmp_path / "cli.json").read_text())
    assert stats["auto_volumes"]["estimator"]["biased"] and stats["samples"] == SPP
    plain = cli("render", blend, "--out", tmp_path / "plain.exr", "--estimator", "scene")
    assert plain.returncode == 0 and "the file's own volume settings" in plain.stdout
    assert "Note" not in image_attributes(tmp_path / "plain.exr")
    refused = cli("render", blend, "--out", tmp_path / "x.exr", "--spp", "4")
    assert refused.returncode == 2 and "--spp needs --mode" in refused.stderr
    assert not (tmp_path / "x.exr").exists()
