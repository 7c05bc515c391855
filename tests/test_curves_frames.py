"""``xsl-render curves --frames``: every run renders all the frames in one Cycles session,
each frame against its own reference; curves.json holds the per-frame figures, their means
and the sequence's flicker for every run, a second call reuses the finished runs (and renders
again only a run cut short), and --frames refuses what does not go with it in one line.

The scene: the fog scene with its density keyframed (0.02 at frame 1, 0.3 at frame 2) in
front of a still camera, at 32x18 with a ceiling of 2 spp (every curve, a few seconds)."""
from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import EXAMPLES, xsl_render_cli
from test_cli_info import one_line_error

from xsl_render.core.imageio import read_image

W, H = 32, 18
TINY = ("--resolution", f"{W}x{H}", "--max-spp", "2", "--reference-spp", "16", "--no-vdp", "--quiet")
FIGURES = ("flip", "flip_tile95", "flip_share", "mse")


@pytest.fixture(scope="module")
def animated_blend(tmp_path_factory):
    import bpy
    from support.fog_scene import build_fog_scene

    scene = build_fog_scene(bpy, W, H)
    density = next(node for node in scene.world.node_tree.nodes
                   if node.type == "PRINCIPLED_VOLUME").inputs["Density"]
    for frame, value in ((1, 0.02), (2, 0.3)):
        density.default_value = value
        density.keyframe_insert("default_value", frame=frame)
    scene.frame_start, scene.frame_end = 1, 2
    scene.frame_set(1)
    path = tmp_path_factory.mktemp("scene") / "fog_anim.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


@pytest.fixture(scope="module")
def curves(animated_blend, tmp_path_factory):
    out = tmp_path_factory.mktemp("curves") / "out"
    result = xsl_render_cli("curves", animated_blend, "--out", out, "--frames", "1-2", *TINY)
    assert result.returncode == 0, result.stderr
    return out, result


def read(out) -> dict:
    return json.loads((out / "curves.json").read_text())


@pytest.mark.blender
@pytest.mark.render
def test_every_run_has_its_frames_their_means_and_the_flicker(curves):
    out, result = curves
    data = read(out)
    assert data["scene"]["frames"] == [1, 2] and data["scene"]["frame_range"] == "1-2"
    assert data["scene"]["fps"] == 24.0 and data["scene"]["size"] == [W, H]
    assert data["metrics"] == ["flip", "flip_tile95", "flip_share", "mse", "flicker", "jod"]
    assert [ref["inputs"]["frame"] for ref in data["reference"]["frames"]] == [1, 2]
    assert len({ref["key"] for ref in data["reference"]["frames"]}) == 2
    assert data["reference"]["inputs"] == {"spp": 16, "seed": 7}
    assert set(data["curves"]) == {"uniform", "adaptive", "guiding", "xs", "xsl", "guided", "guided_xsl"}
    assert data["rendered"] == len(data["runs"]) == 2 + 3 + 2 + 3 + 3 + 2 + 2
    for name, run in data["runs"].items():
        (repeat,) = run["repeats"]
        frames = repeat["frames"]
        assert [f["frame"] for f in frames] == [1, 2], name
        assert repeat["file"] == f"runs/{name}_seed0"
        for frame in frames:
            assert frame["file"] == f"runs/{name}_seed0/frame_000{frame['frame']}.exr"
            assert read_image(out / frame["file"]).shape == (H, W, 4)
            assert all(frame[figure] > 0 for figure in FIGURES)
        for figure in FIGURES:                  # the run's error: the mean over its frames
            assert repeat[figure] == pytest.approx(np.mean([f[figure] for f in frames]))
            assert run[figure] == repeat[figure]
        # One transition between two frames: the sequence's flicker is frame 2's.
        assert frames[0]["flicker"] is None and frames[1]["flicker"] > 0
        assert run["flicker"] == repeat["flicker"] == pytest.approx(frames[1]["flicker"])
        assert run["jod"] is None
        # The run's time is the whole run: every frame's render and more (one session).
        assert run["seconds"] >= sum(f["seconds"] for f in frames) > 0
        assert set(run["speedups"]) == {"uniform", "adaptive"} - ({run["curve"]} & {"uniform", "adaptive"})
        for speedups in run["speedups"].values():
            assert set(speedups) == set(data["metrics"])
    # The fog thickens from frame 1 to frame 2: each frame is its own.
    uniform = data["runs"]["uniform_2spp"]["repeats"][0]["frames"]
    assert not np.allclose(*(read_image(out / f["file"]) for f in uniform))
    # xs and xsl cast the camera rays once; guided shares its uniform run's time between frames.
    hits = [f["stats"]["maps"]["ray_cache_hit"] for f in data["runs"]["xsl_2"]["repeats"][0]["frames"]]
    assert hits == [False, True]
    guided = data["runs"]["guided_at_uniform_2spp"]
    assert guided["budget_s"] == pytest.approx(data["runs"]["uniform_2spp"]["seconds"])
    for frame in guided["repeats"][0]["frames"]:
        assert frame["stats"]["sequence_budget"]["per_frame"] == pytest.approx(guided["budget_s"] / 2)
    lines = result.stdout.splitlines()
    assert lines[0].startswith(f"fog_anim.blend (scene 'Scene', frames 1-2, mean over 2 frames) at {W}x{H}")
    assert "flicker" in lines[2] and "FLICKER" in lines[2]
    html = (out / "report.html").read_text()
    assert "mean over 2 frames" in html and "<th rowspan=2>flicker</th>" in html


@pytest.mark.blender
@pytest.mark.render
def test_a_second_call_reuses_the_runs_and_renders_a_run_cut_short_again(curves, animated_blend):
    out, _ = curves
    before = read(out)
    (out / "runs" / "xs_1_seed0" / "frame_0002.exr").unlink()         # as if killed on frame 2
    result = xsl_render_cli("curves", animated_blend, "--out", out, "--frames", "1-2", *TINY)
    assert result.returncode == 0, result.stderr
    data = read(out)
    assert (data["rendered"], data["reused"]) == (1, len(data["runs"]) - 1)
    for name, run in data["runs"].items():
        assert run["repeats"][0]["reused"] is (name != "xs_1")
        if name != "xs_1":
            assert run["seconds"] == before["runs"][name]["seconds"]
            assert run["flip"] == before["runs"][name]["flip"]
    assert (out / "runs" / "xs_1_seed0" / "frame_0002.exr").is_file()


@pytest.mark.parametrize("extra, message", [
    (("--frames", "1-2", "--frame", "1"), "--frame and --frames cannot be combined"),
    (("--frames", "1-2", "--reference", EXAMPLES / "road.blend"),
     "--reference is one frame's reference and cannot be combined with --frames"),
    (("--frames", "3-1"), "--frames 3-1: the end frame 1 is before the start frame 3"),
    (("--frames", "1-3,2"), "--frames 1-3,2: 1-3 and 2 overlap"),
    (("--frames", "one"), "--frames must look like START-END"),
])
@pytest.mark.blender          # the command line, as a user runs it
def test_bad_frames_exit_2_with_one_line(extra, message, tmp_path):
    result = xsl_render_cli("curves", EXAMPLES / "road.blend", "--out", tmp_path / "o", *extra)
    assert message in one_line_error(result)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("text, expected", [("1-24", "1-24"), ("1-3,8", "1-3,8"), ("1-24:2", "1-23:2"),
                                            ("7", "7"), ("1,3", "1,3"), ("1-9:2,20", "1-9:2,20")])
def test_frames_text(text, expected):
    from xsl_render.addon.validation.curves_runner import frames_text
    from xsl_render.core.frames import parse_frame_list

    assert frames_text(list(parse_frame_list(text))) == expected
