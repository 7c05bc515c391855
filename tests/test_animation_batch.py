"""Animation and batch use: ``xsl-render render --frames`` through the batch entry (what
``blender -b scene.blend --python-expr "...x.batch()" -- render ...`` runs), the render
operator's animation toggle, and the batch entry against the ``xsl-render`` command.

The scene: fog whose density is keyframed (0.02 at frame 1, 0.3 at frame 3) in front of
static geometry and a static camera, so frames 2 and 3 must reuse frame 1's camera rays."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from conftest import EXAMPLES
from support.fog_scene import build_fog_scene

from xsl_render.core.imageio import read_image

pytestmark = [pytest.mark.blender, pytest.mark.render]

W, H = 32, 18


@pytest.fixture(scope="module")
def addon():
    import xsl_render

    xsl_render.register()
    yield xsl_render
    xsl_render.unregister()


def density(scene):
    return next(node for node in scene.world.node_tree.nodes
                if node.type == "PRINCIPLED_VOLUME").inputs["Density"]


@pytest.fixture
def foggy_animation(blender, addon):
    scene = build_fog_scene(blender, W, H)
    for frame, value in ((1, 0.02), (3, 0.3)):
        density(scene).default_value = value
        density(scene).keyframe_insert("default_value", frame=frame)
    scene.frame_start, scene.frame_end = 1, 3
    scene.frame_set(2)
    settings = scene.xsl_render
    settings.max_spp, settings.tile_size = 4, 16
    return scene


def test_frames_reuse_the_camera_rays_and_are_numbered(blender, addon, foggy_animation, tmp_path):
    from xsl_render.addon.scene.state import settings_dump

    before, fog_before = settings_dump(foggy_animation), density(foggy_animation).default_value
    out, maps = tmp_path / "out", tmp_path / "maps"
    assert addon.batch(["render", "--mode", "xsl", "--max-spp", "4", "--tile-size", "16", "--frames", "1-3",
                        "--out", str(out / "frame_####.exr"), "--stats", str(out / "stats.json"),
                        "--save-maps", str(maps), "--quiet"]) == 0
    assert settings_dump(foggy_animation) == before and foggy_animation.frame_current == 2
    assert density(foggy_animation).default_value == fog_before          # frame 2's fog again
    assert sorted(p.name for p in out.glob("*.exr")) == [
        f"frame_000{i}{suffix}.exr" for i in (1, 2, 3) for suffix in ("", "_spp")]
    stats = json.loads((out / "stats.json").read_text())
    assert [frame["frame"] for frame in stats["frames"]] == [1, 2, 3]
    assert [frame["maps"]["ray_cache_hit"] for frame in stats["frames"]] == [False, True, True]
    assert stats["ray_cache_hits"] == 2 and (maps / "zcache.npz").exists()
    # Each frame saw its own fog: denser fog lets less light through.
    x_means = [float(read_image(maps / f"000{i}" / "x.exr").mean()) for i in (1, 2, 3)]
    assert x_means[0] > x_means[1] > x_means[2]
    for frame in stats["frames"]:
        assert read_image(frame["out"]).shape == (H, W, 4)
        assert frame["maps"]["frame"] == frame["frame"]


def test_the_render_operator_renders_the_frame_range(blender, foggy_animation, tmp_path):
    from xsl_render.addon.panel.image_display import read_pixels
    from xsl_render.addon.scene.state import settings_dump
    from xsl_render.operators.jobs import ray_cache_dir

    shutil.rmtree(ray_cache_dir(foggy_animation), ignore_errors=True)
    foggy_animation.render.filepath = str(tmp_path / "anim" / "shot_##")
    before = settings_dump(foggy_animation)
    assert blender.ops.xsl.render_selective(animation=True) == {"FINISHED"}
    assert settings_dump(foggy_animation) == before
    assert sorted(p.name for p in (tmp_path / "anim").glob("shot_0?.exr")) == ["shot_01.exr", "shot_02.exr",
                                                                              "shot_03.exr"]
    report = blender.context.window_manager.xsl_render_status.last_report
    assert "3 frame(s) 1..3" in report and "camera rays cast 1x, reused 2x" in report
    last = read_image(tmp_path / "anim" / "shot_03.exr")
    np.testing.assert_array_equal(read_pixels(blender.data.images["XSL Render"]), last)

    assert blender.ops.xsl.render_gold(animation=True, filepath=str(tmp_path / "gold" / "g_###.exr")) == {"FINISHED"}
    assert sorted(p.name for p in (tmp_path / "gold").glob("g_*.exr")) == [
        f"g_00{i}{suffix}.exr" for i in (1, 2, 3) for suffix in ("", "_spp")]
    assert settings_dump(foggy_animation) == before


def test_batch_entry_renders_like_the_command(blender, addon, cli, foggy_animation, tmp_path):
    path = tmp_path / "fog.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    args = ["--mode", "xsl", "--max-spp", "4", "--tile-size", "16", "--frame", "3", "--quiet"]
    result = cli("render", path, *args, "--out", tmp_path / "cli_#.exr")
    assert result.returncode == 0, result.stderr
    assert addon.batch(["render", *args, "--out", str(tmp_path / "batch_#.exr")]) == 0
    assert blender.context.scene.frame_current == 2                  # the open scene keeps its frame
    np.testing.assert_array_equal(read_image(tmp_path / "batch_3.exr"), read_image(tmp_path / "cli_3.exr"))


@pytest.mark.parametrize("args, message", [
    (["render", "fog.blend", "--mode", "gold", "--max-spp", "4", "--out", "x.exr"],
     "inside Blender the open file is used; leave out 'fog.blend'"),
    (["render", "--mode", "gold", "--max-spp", "4", "--out", "x.exr", "--frame", "1", "--frames", "1-2"],
     "--frame and --frames cannot be combined"),
    (["render", "--mode", "xsl", "--max-spp", "4", "--out", "x.exr", "--frames", "3-1"],
     "the end frame 1 is before the start frame 3"),
    (["render", "--mode", "xsl", "--max-spp", "4", "--out", "x.exr", "--frames", "1-2", "--maps", str(EXAMPLES)],
     "--frames computes every frame's own maps"),
    ([], "the following arguments are required: COMMAND"),
])
def test_batch_bad_input_exits_2_with_one_line(addon, foggy_animation, capfd, tmp_path, monkeypatch,
                                               args, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as done:
        addon.batch(args)
    assert done.value.code == 2
    lines = capfd.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]
    assert not list(tmp_path.iterdir())


def test_batch_arguments_follow_the_separator(addon, foggy_animation, capfd, monkeypatch):
    from xsl_render.operators.batch import arguments_after_separator

    assert arguments_after_separator(["blender", "-b", "f.blend", "--python-expr", "x", "--", "info"]) == ["info"]
    assert arguments_after_separator(["blender", "-b"]) == []
    monkeypatch.setattr("sys.argv", ["blender", "-b", "--", "info", "--json"])
    assert addon.batch() == 0
    info = json.loads(capfd.readouterr().out)
    assert info["scene"] == "Scene" and info["frames"]["end"] == 3


@pytest.mark.parametrize("mode, budget", [("uniform", ["--spp", "2", "--estimator", "scene"]),
                                          ("xsl", ["--estimator", "scene"]),
                                          ("uniform", ["--spp", "2", "--estimator", "unbiased"]),
                                          ("guided", ["--time-budget", "1.5", "--estimator", "unbiased"])])
def test_frames_after_the_first_cost_no_scene_sync(blender, addon, mode, budget, tmp_path):
    """One Cycles session for the frame range: balls_b's noise fog makes Cycles build its
    volume octree at every full sync (seconds); with a moving camera, frames 2 and 3 sync
    only the camera. Cycles' own synchronization time (EXR header) says so. With
    ``--estimator unbiased`` the scene is set to ray march: each frame's settings are put back
    after it, which must not make the next frame sync the octree again."""
    blender.ops.wm.open_mainfile(filepath=str(EXAMPLES / "balls_b.blend"))
    scene = blender.context.scene
    own_estimator = "unbiased" in budget
    scene.cycles.volume_biased = own_estimator
    camera = scene.camera
    for frame in (1, 3):
        camera.location.x += 0.1 * frame
        camera.keyframe_insert("location", frame=frame)
    out = tmp_path / "out"
    assert addon.batch(["render", "--mode", mode, "--max-spp", "4", "--resolution", "32x24",
                        "--tile-size", "16", *budget, "--frames", "1-3", "--quiet",
                        "--out", str(out / "f_####.exr"), "--stats", str(out / "stats.json")]) == 0
    frames = json.loads((out / "stats.json").read_text())["frames"]
    synced = [frame["cycles_sync_s"] for frame in frames]
    assert synced[0] > 0.3 and synced[1] + synced[2] < 0.1 * synced[0], synced
    images = [read_image(frame["out"]) for frame in frames]
    assert not np.array_equal(images[0], images[2])                  # the camera moved
    assert scene.render.use_persistent_data is False                 # the file's own setting
    assert scene.cycles.volume_biased is own_estimator
    if mode == "guided":
        # The frames after the first know what a sample costs: no pilot, one render each, at
        # the count of the frame before.
        assert frames[0]["pilot_spp"] >= 1 and frames[0]["renders"] >= 2
        assert [(frame["pilot_spp"], frame["renders"]) for frame in frames[1:]] == [(0, 1), (0, 1)]
        assert frames[1]["mean_spp"] == frames[2]["mean_spp"] == frames[1]["sequence_budget"]["spp"]


def test_the_first_frame_of_a_guided_range_renders_whole(cli, tmp_path):
    """The first frame of a guided range renders the whole frame in one render (no columns),
    at the count the frames after it hold, priced by a full-resolution pilot.

    At 256x144 with auto's blue noise and null scattering (street, guided at uniform 32 spp's
    time), a later frame rendered after the first one's columns had other pixels than a
    fresh render of it at its count, and every later frame scored mean FLIP 0.0706-0.0723
    against a fresh render's 0.068; with the whole first frame, frame 2 was bit-identical to
    the fresh render. At this test's size the columns did not show it (nor at 128x72), and
    one of six such comparisons here differed even with the whole first frame (under the
    parallel suite; not reproduced alone), so the pixels are not compared."""
    street = str(EXAMPLES / "street.blend")
    out = tmp_path / "guided"
    done = cli("render", street, "--mode", "guided", "--time-budget", "1", "--frames", "1-3", "--max-spp", "64",
               "--resolution", "64x36", "--estimator", "auto", "--quiet",
               "--out", out / "f_####.exr", "--stats", out / "stats.json")
    assert done.returncode == 0, done.stderr
    frames = json.loads((out / "stats.json").read_text())["frames"]
    assert frames[0]["final_pass"]["renders"] == 1
    assert frames[0]["final_pass"]["rects"][0] | {"spp": 0} == {"row0": 0, "row1": 36, "col0": 0, "col1": 64, "spp": 0}
    assert [frame["renders"] for frame in frames[1:]] == [1, 1]
    # Its count is the range's: priced at full resolution (a quarter-resolution pilot put a
    # sample of street at 1.4-1.8x its cost), of 1 and 4 samples.
    assert frames[0]["pilot_resolution_divisor"] == 1 and frames[0]["pilot_spp"] >= 4
    assert frames[0]["pilot_seconds"] > 0
    # Auto's denoise: street's guides at this size are noise (0.07-0.15 against 0.001); each
    # frame records what it decided, and a later frame sets aside what the frames before
    # measured the same denoise to cost (not a guess from the pixel count).
    assert all(frame["denoise_guides"]["noisy"] for frame in frames)
    carried = 0
    for before, after in zip(frames, frames[1:]):
        key = "denoise_prefiltered_s" if after["denoise_guides"]["prefiltered"] else "denoise_plain_s"
        if before["sequence_budget"][key] is not None:
            assert after["denoise_reserved_s"] == pytest.approx(before["sequence_budget"][key])
            carried += 1
    assert carried and frames[-1]["sequence_budget"]["guides_noisy"] is True
