"""Issue 46, point 4: ``render --frames`` continues, as the README says: a rerun of the same
request keeps every frame an earlier run finished whole and renders only the rest; a frame
made from anything else (other options, another scene file, a file the scene reads that
changed) is rendered again."""
from __future__ import annotations

import json
import os

import pytest
from support.fog_scene import build_fog_scene

pytestmark = [pytest.mark.blender, pytest.mark.render]

RUN = ["--mode", "uniform", "--spp", "2", "--max-spp", "2", "--frames", "1-3", "--quiet"]


@pytest.fixture
def saved_scene(blender, tmp_path):
    scene = build_fog_scene(blender, 24, 16)
    scene.frame_start, scene.frame_end = 1, 3
    path = tmp_path / "fog.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def frame_files(folder, frame):
    return [folder / f"f_{frame:04d}{suffix}" for suffix in (".exr", "_spp.exr", "_spp.png")]


def stamps(folder):
    return {path.name: os.stat(path).st_mtime_ns for path in sorted(folder.glob("f_*"))}


def test_a_rerun_keeps_the_finished_frames_and_renders_the_rest(cli, saved_scene, tmp_path):
    out = tmp_path / "out"
    command = ["render", saved_scene, *RUN, "--out", out / "f_####.exr", "--stats", tmp_path / "s.json"]
    first = cli(*command)
    assert first.returncode == 0, first.stderr
    # As a run cancelled during frame 3 leaves it: frames 1 and 2 whole, nothing of frame 3;
    # and frame 2's preview lost since: not whole.
    for path in frame_files(out, 3):
        path.unlink()
    frame_files(out, 2)[2].unlink()
    before = stamps(out)
    again = cli(*command)
    assert again.returncode == 0, again.stderr
    assert "frame 1: kept" in again.stdout and "frame 2: kept" not in again.stdout
    assert "frame 3: kept" not in again.stdout
    after = stamps(out)
    assert {name: after[name] for name in before if name.startswith("f_0001")} == \
        {name: stamp for name, stamp in before.items() if name.startswith("f_0001")}
    assert all(path.is_file() for frame in (1, 2, 3) for path in frame_files(out, frame))
    assert after["f_0002.exr"] != before["f_0002.exr"]
    stats = json.loads((tmp_path / "s.json").read_text())
    assert [frame["frame"] for frame in stats["frames"]] == [1, 2, 3]
    assert stats["total_samples"] == 3 * 24 * 16 * 2
    # Everything finished: nothing is rendered.
    third = cli(*command)
    assert third.returncode == 0 and third.stdout.count(": kept") == 3
    assert stamps(out) == after


def test_frames_made_from_other_inputs_are_rendered_again(blender, cli, saved_scene, tmp_path):
    out = tmp_path / "out"
    command = ["render", saved_scene, *RUN, "--out", out / "f_####.exr"]
    assert cli(*command).returncode == 0
    other_seed = cli(*command, "--seed", "1")
    assert other_seed.returncode == 0 and ": kept" not in other_seed.stdout
    # The scene file changed (another fog density).
    blender.ops.wm.open_mainfile(filepath=str(saved_scene))
    volume = next(node for node in blender.context.scene.world.node_tree.nodes
                  if node.type == "PRINCIPLED_VOLUME")
    volume.inputs["Density"].default_value *= 2.0
    blender.ops.wm.save_mainfile()
    changed = cli(*command, "--seed", "1")
    assert changed.returncode == 0 and ": kept" not in changed.stdout
