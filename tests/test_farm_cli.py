"""``xsl-render farm``: a job bundle that ``openjd`` validates and runs to the image of
``xsl-render render``, resumes after a tile task is killed, and never overwrites a folder
that is not ours."""
from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import EXAMPLES
from test_cli_info import one_line_error

from xsl_render.core.farm.files import FrameFiles, read_record, valid_plan, valid_tile
from xsl_render.core.farm.job_template import openjd_values
from xsl_render.core.farm.task_groups import plan_group
from xsl_render.core.imageio import read_image

pytestmark = pytest.mark.blender

ROAD = EXAMPLES / "road.blend"
W, H = 96, 54
# High enough a ceiling that a tile task takes a few tenths of a second: time to kill it.
OPTIONS = ["--max-spp", "64", "--tile-size", "16", "--seed", "3", "--resolution", f"{W}x{H}"]
OPENJD = Path(sys.executable).with_name("openjd")


def openjd(*args, env: dict | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([str(OPENJD), *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=timeout)


def private_tmp(tmp_path: Path) -> dict:
    """An environment whose temporary folder is the test's own: a killed task's leftovers
    (its Cycles scratch folder, the openjd session folder) go with the test's files. Its PATH
    finds xsl-render, as a prepared worker's does (the bundle names no executable)."""
    folder = tmp_path / "tmp"
    folder.mkdir(exist_ok=True)
    path = os.pathsep.join([str(OPENJD.parent), os.environ.get("PATH", "/usr/bin:/bin")])
    return {**os.environ, "TMPDIR": str(folder), "PATH": path}


def job_values(bundle: Path) -> str:
    """The bundle's parameter_values.yaml as ``openjd run --job-param`` JSON."""
    return json.dumps(openjd_values(yaml.safe_load((bundle / "parameter_values.yaml").read_text())))


def tile_records(files: FrameFiles) -> list[Path]:
    """The rectangles' records (not the temporaries of a write in progress: .name.*.partial.json)."""
    return sorted(files.tiles.glob("[!.]*.json")) if files.tiles.is_dir() else []


def render_ids(files: FrameFiles) -> dict[str, str]:
    return {path.stem: read_record(path)["render_id"] for path in tile_records(files)}


def kill_first_task_of_group(process: subprocess.Popen, files: FrameFiles, group: int) -> None:
    """Wait until tile task ``group`` has written its first rectangle, then kill that task's
    process (the xsl-render process the job started, by the id it recorded)."""
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        for path in tile_records(files):
            record = read_record(path)
            if record is not None and record.get("group") == group:
                os.kill(record["pid"], signal.SIGKILL)
                return
        assert process.poll() is None, "the job ended before tile task 2 started"
        time.sleep(0.005)
    pytest.fail("tile task 2 never wrote a rectangle")


@pytest.mark.render
def test_bundle_runs_with_openjd_resumes_after_a_killed_task_and_equals_render(cli, tmp_path):
    scene_digest = hashlib.sha256(ROAD.read_bytes()).hexdigest()
    bundle = tmp_path / "bundle"
    result = cli("farm", ROAD, "--bundle", bundle, "--frames", "1", "--tasks-per-frame", "2", *OPTIONS)
    assert result.returncode == 0, result.stderr
    assert f"openjd run {bundle}/template.yaml -p SceneFile={ROAD}" in result.stdout
    check = openjd("check", bundle / "template.yaml")
    assert check.returncode == 0 and "passes validation" in check.stdout, check.stdout + check.stderr

    # The whole job, with tile task 2 of 2 killed after its first rectangle.
    files = FrameFiles(bundle / "output", 1)
    log_path = tmp_path / "killed.log"
    with open(log_path, "w") as log:
        process = subprocess.Popen([str(OPENJD), "run", str(bundle / "template.yaml"), "-p", job_values(bundle)],
                                   stdout=log, stderr=subprocess.STDOUT, env=private_tmp(tmp_path))
        try:
            kill_first_task_of_group(process, files, group=2)
            assert process.wait(timeout=120) != 0           # the job failed with its task
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
    plan = valid_plan(files)
    groups = [plan_group(plan.plan.rects, g, 2, plan.options.render_cost) for g in (1, 2)]
    finished = [[rect for rect in group if valid_tile(files, plan, rect)] for group in groups]
    assert finished[0] == groups[0]                           # task 1 completed before
    assert 1 <= len(finished[1]) < len(groups[1]), log_path.read_text()   # task 2 died midway
    assert not files.image.exists()
    before = render_ids(files)

    # Rerun the job: only the rectangles task 2 never finished are rendered.
    rerun = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert rerun.returncode == 0, rerun.stdout[-3000:]
    out = rerun.stdout
    missing = len(groups[1]) - len(finished[1])
    assert "frame 1: maps and tile plan already done" in out
    assert f"task 1/2: {len(groups[0])} rectangles, 0 rendered now, {len(groups[0])} already done" in out
    assert f"task 2/2: {len(groups[1])} rectangles, {missing} rendered now, {len(finished[1])} already done" in out
    after = render_ids(files)
    rerendered = {name for name in after if before.get(name) != after[name]}
    assert rerendered == {files.rect_name(rect) for rect in groups[1] if rect not in finished[1]}
    assert out.count(" rendered r") == missing

    # The same image as one `xsl-render render` process with the same options and seed.
    reference = tmp_path / "render" / "xsl.exr"
    result = cli("render", ROAD, "--mode", "xsl", "--frame", "1", "--out", reference, "--quiet",
                 "--estimator", "scene", *OPTIONS)
    assert result.returncode == 0, result.stderr
    np.testing.assert_array_equal(read_image(files.image), read_image(reference))
    np.testing.assert_array_equal(read_image(files.spp_image), read_image(reference.with_name("xsl_spp.exr")))
    stats = json.loads(files.stats.read_text())
    assert stats["renders"] == len(plan.plan.rects) and stats["grouping"]["groups"] == 2

    # A damaged rectangle is rendered again (to the same pixels), and nothing else.
    damaged = groups[0][0]
    files.tile_image(damaged).write_bytes(files.tile_image(damaged).read_bytes()[:-64])
    result = cli("farm-task", "tiles", ROAD, "--frame", "1", "--output", files.output,
                 "--group", "1", "--groups", "2")
    assert result.returncode == 0, result.stderr
    assert f"{len(groups[0])} rectangles, 1 rendered now" in result.stdout
    result = cli("farm-task", "composite", "--frame", "1", "--output", files.output)
    assert result.returncode == 0 and "already done" in result.stdout, result.stdout + result.stderr
    assert hashlib.sha256(ROAD.read_bytes()).hexdigest() == scene_digest     # never written


def moving_camera(bpy, source: Path, path: Path) -> Path:
    """``source`` with its camera keyframed to slide sideways from frame 1 to frame 8, saved
    as ``path`` (every frame then differs, and Cycles syncs only the camera between them)."""
    bpy.ops.wm.open_mainfile(filepath=str(source))
    scene = bpy.context.scene
    for frame in (1, 8):
        scene.camera.location.x += 0.05 * frame
        scene.camera.keyframe_insert("location", frame=frame)
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


CHUNK = ["--max-spp", "4", "--tile-size", "8", "--seed", "3", "--resolution", "32x18"]


@pytest.mark.render
def test_a_chunk_of_frames_is_one_process_per_task_and_equals_render(cli, blender, tmp_path):
    """Frames 1-3 with FramesPerTask 8: one Maps task, two Tiles tasks (the chunk x Group 1, 2)
    and one Composite task, each rendering the three frames in one process, to the images
    of one `xsl-render render --frames 1-3`."""
    scene = moving_camera(blender, ROAD, tmp_path / "road_moving.blend")
    bundle = tmp_path / "bundle"
    result = cli("farm", scene, "--bundle", bundle, "--frames", "1-3", "--mode", "xsl", "--tasks-per-frame", "2",
                 *CHUNK)
    assert result.returncode == 0 and "up to 8 frame(s) a task" in result.stdout, result.stderr
    check = openjd("check", bundle / "template.yaml")
    assert check.returncode == 0 and "passes validation" in check.stdout, check.stdout + check.stderr
    run = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert run.returncode == 0, run.stdout[-3000:]
    out = run.stdout
    for status in ("frames 1-3: director maps and tile plans", "frames 1-3, task 1/2: reading the plans",
                   "frames 1-3, task 2/2: reading the plans"):
        assert out.count(f"openjd_status: {status}") == 1, out[-3000:]
    frames = [FrameFiles(bundle / "output", frame) for frame in (1, 2, 3)]
    plans = [valid_plan(files) for files in frames]
    assert len({plan.data["task"]["pid"] for plan in plans}) == 1
    assert plans[0].data["task"]["frames"] == [1, 2, 3]
    for group in (1, 2):              # each tile task rendered its share of all three frames
        records = [read_record(path) for files in frames for path in tile_records(files)]
        mine = [record for record in records if record["group"] == group]
        assert {record["inputs_detail"]["frame"] for record in mine} == {1, 2, 3}
        assert len({record["pid"] for record in mine}) == 1
        assert f"frame 3, task {group}/2: " in out
    for files in frames:
        assert f"frame {files.frame}: {files.image} written: 32x18" in out

    reference = tmp_path / "render" / "f_####.exr"
    result = cli("render", scene, "--mode", "xsl", "--frames", "1-3", "--out", reference, "--quiet",
                 "--estimator", "scene", *CHUNK)
    assert result.returncode == 0, result.stderr
    images = []
    for files in frames:
        rendered = tmp_path / "render" / f"f_{files.frame:04d}.exr"
        images.append(read_image(files.image))
        np.testing.assert_array_equal(images[-1], read_image(rendered))
        np.testing.assert_array_equal(read_image(files.spp_image),
                                      read_image(rendered.with_name(f"f_{files.frame:04d}_spp.exr")))
    assert not np.array_equal(images[0], images[2])                 # the camera moved


@pytest.mark.render
def test_later_frames_of_a_tile_chunk_skip_the_fogs_scene_sync(cli, blender, tmp_path):
    """balls_b's noise fog makes Cycles build its volume octree at a full sync (seconds);
    a tile task renders a chunk in one session, so frames 2 and 3 sync only the moved camera.
    Each frame's record says what Cycles reported."""
    scene = moving_camera(blender, EXAMPLES / "balls_b.blend", tmp_path / "balls_moving.blend")
    output = tmp_path / "job"
    options = ["--max-spp", "4", "--tile-size", "16", "--resolution", "32x24"]
    for step in (["maps", scene, "--scene-name", "balls_b", "--mode", "xsl", *options],
                 ["tiles", scene, "--group", "1", "--groups", "1"], ["composite"]):
        result = cli("farm-task", *step, "--frames", "1-3", "--output", output)
        assert result.returncode == 0, result.stdout[-2000:] + result.stderr
    synced = [json.loads(FrameFiles(output, frame).stats.read_text())["cycles_sync_s"] for frame in (1, 2, 3)]
    assert synced[0] > 0.3 and synced[1] + synced[2] < 0.1 * synced[0], synced


@pytest.mark.render
def test_a_maps_chunk_of_a_still_shot_casts_the_camera_rays_once(cli, tmp_path):
    output = tmp_path / "job"
    result = cli("farm-task", "maps", ROAD, "--scene-name", "road", "--frames", "1-2", "--output", output,
                 "--mode", "xs", *CHUNK)
    assert result.returncode == 0, result.stderr
    plans = [valid_plan(FrameFiles(output, frame)) for frame in (1, 2)]
    assert [plan.data["ray_cache_hit"] for plan in plans] == [False, True]
    assert all((FrameFiles(output, frame).maps / "zcache.npz").is_file() for frame in (1, 2))
    np.testing.assert_array_equal(read_image(FrameFiles(output, 1).maps / "x.exr"),
                                  read_image(FrameFiles(output, 2).maps / "x.exr"))


def test_refuses_a_folder_that_is_not_ours_and_rewrites_our_own(cli, tmp_path):
    foreign = tmp_path / "thesis"
    foreign.mkdir()
    (foreign / "chapter1.tex").write_text("precious")
    result = cli("farm", ROAD, "--bundle", foreign)
    assert result.returncode == 2
    assert "is not an xsl-render job bundle" in one_line_error(result)
    assert [p.name for p in foreign.iterdir()] == ["chapter1.tex"]

    ours = tmp_path / "bundle"
    for frames, tasks in (("1-3", "2"), ("2-4:2", "5")):
        result = cli("farm", ROAD, "--bundle", ours, "--frames", frames, "--tasks-per-frame", tasks,
                     "--mode", "xs", "--wl", "0.8", "--adaptive-threshold", "0.05")
        assert result.returncode == 0, result.stderr
    values = openjd_values(yaml.safe_load((ours / "parameter_values.yaml").read_text()))
    assert values["Frames"] == "2-4:2" and values["TasksPerFrame"] == 5 and values["Mode"] == "xs"
    assert values["MaxSpp"] == 64                     # the scene's own Cycles samples
    assert values["Resolution"] == "512x288" and values["AdaptiveThreshold"] == "0.05"
    assert values["SceneFile"] == str(ROAD) and "OutputDir" not in values
    assert Path(values["XslRender"]).name.startswith("xsl-render")


@pytest.mark.parametrize("args,message", [
    (["--tasks-per-frame", "0"], "--tasks-per-frame"),
    (["--frames", "9-1"], "--frames"),
    (["--max-spp", "0"], "--max-spp"),
    (["--tile-size", "4"], "--tile-size"),
    (["--wx", "0", "--ws", "0"], "cannot both be 0"),
])
def test_bad_options_exit_2_before_anything_is_written(cli, tmp_path, args, message):
    result = cli("farm", ROAD, "--bundle", tmp_path / "bundle", *args)
    assert result.returncode == 2
    assert message in one_line_error(result)
    assert not (tmp_path / "bundle").exists()


def test_scene_without_camera_is_refused(cli, blender, tmp_path):
    blender.ops.wm.read_factory_settings(use_empty=True)
    path = tmp_path / "empty.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    result = cli("farm", path, "--bundle", tmp_path / "bundle")
    assert result.returncode == 2 and "no active camera" in one_line_error(result)
    assert not (tmp_path / "bundle").exists()


GUIDED_BUDGET = 1.5
GUIDED = ["--mode", "guided", "--time-budget", str(GUIDED_BUDGET), "--importance", "x",
          "--tile-size", "16", "--seed", "3", "--resolution", "64x36"]


def digests(files: FrameFiles) -> list[str]:
    return [hashlib.sha256(path.read_bytes()).hexdigest()
            for path in (files.image, files.spp_image, files.stats)]


@pytest.mark.render
def test_guided_bundle_renders_a_chunk_in_one_process_and_a_rerun_renders_only_missing_frames(cli, tmp_path):
    bundle = tmp_path / "bundle"
    result = cli("farm", ROAD, "--bundle", bundle, "--frames", "1-3", *GUIDED)
    assert result.returncode == 0, result.stderr
    assert ("guided within 1.5 s per frame without a ceiling, importance x, up to 8 frame(s) a task"
            in result.stdout)
    check = openjd("check", bundle / "template.yaml")
    assert check.returncode == 0 and "passes validation" in check.stdout, check.stdout + check.stderr

    run = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert run.returncode == 0, run.stdout[-3000:]
    # One task, one process for the chunk 1-3 (FramesPerTask 8), each frame within its budget.
    assert run.stdout.count("openjd_status: frames 1-3: guided render") == 1, run.stdout[-3000:]
    assert "frames 1-3: 3 rendered now, 0 already done" in run.stdout
    before, tasks = {}, set()
    for frame in (1, 2, 3):
        files = FrameFiles(bundle / "output", frame)
        assert f"frame {frame}: {files.image} written: 64x36" in run.stdout
        stats = json.loads(files.stats.read_text())
        assert stats["mode"] == "guided" and stats["inputs_detail"]["guided"]["time_budget"] == GUIDED_BUDGET
        # The chunk's frames share its time as `render --frames` does: 1.5 s a frame in all.
        assert stats["sequence_budget"]["per_frame"] == GUIDED_BUDGET
        assert stats["sequence_budget"]["frames"] == 3 and stats["sequence_budget"]["done"] == frame
        assert stats["time_budget_s"] >= GUIDED_BUDGET / 2
        assert stats["inputs_detail"]["guided"]["importance"] == "x" and stats["seed"] == 3
        assert stats["inputs_detail"]["map_options"]["minbound"] is True
        assert stats["phases_s"]["maps"] > 0.0 and stats["mean_spp"] > stats["pilot_spp"] >= 1
        assert stats["cycles_sync_s"] >= 0.0 and stats["task"]["frames"] == [1, 2, 3]
        tasks.add(stats["task"]["pid"])
        image = read_image(files.image)
        assert image.shape == (36, 64, 4) and np.isfinite(image).all() and image[..., :3].max() > 0.0
        assert read_image(files.spp_image).shape[:2] == (36, 64) and files.spp_preview.is_file()
        before[frame] = digests(files)
    assert len(tasks) == 1
    assert not (bundle / "output" / "work").exists()

    rerun = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert rerun.returncode == 0, rerun.stdout[-3000:]
    assert "frames 1-3: 0 rendered now, 3 already done" in rerun.stdout
    for frame in (1, 2, 3):
        files = FrameFiles(bundle / "output", frame)
        assert f"frame {frame}: {files.image} already done" in rerun.stdout
        assert digests(files) == before[frame]

    # As if the task had been killed after frame 1: frames 2 and 3 are missing (frame 3's set
    # whole, frame 2's record only). The task renders those two and keeps frame 1.
    for path in (FrameFiles(bundle / "output", 3).image, FrameFiles(bundle / "output", 3).spp_image,
                 FrameFiles(bundle / "output", 3).spp_preview, FrameFiles(bundle / "output", 3).stats,
                 FrameFiles(bundle / "output", 2).stats):
        path.unlink()
    resumed = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert resumed.returncode == 0, resumed.stdout[-3000:]
    assert "frames 1-3: 2 rendered now, 1 already done" in resumed.stdout
    assert f"frame 1: {FrameFiles(bundle / 'output', 1).image} already done" in resumed.stdout
    assert digests(FrameFiles(bundle / "output", 1)) == before[1]
    for frame in (2, 3):
        files = FrameFiles(bundle / "output", frame)
        assert f"frame {frame}: {files.image} written" in resumed.stdout
        stats = json.loads(files.stats.read_text())
        assert stats["task"]["frames"] == [1, 2, 3] and stats["task"]["pid"] not in tasks
        assert stats["sequence_budget"]["frames"] == 2             # the two it rendered share time


@pytest.mark.parametrize("command,args,message", [
    ("farm", ["--mode", "guided"], "--mode guided needs --time-budget SECONDS"),
    ("farm", ["--mode", "guided", "--time-budget", "0"], "--time-budget: must be greater than 0, not 0"),
    ("farm", ["--mode", "guided", "--time-budget", "-3"], "--time-budget: must be greater than 0, not -3"),
    ("farm", ["--mode", "guided", "--time-budget", "nan"], "--time-budget: must be a finite number, not nan"),
    ("farm", ["--mode", "guided", "--time-budget", "1e9"], "--time-budget: must be at most 604800"),
    ("farm", ["--mode", "guided", "--time-budget", "5", "--tasks-per-frame", "2"], "a guided frame is one task"),
    ("farm", ["--mode", "xsl", "--time-budget", "5"], "--time-budget is for --mode guided"),
    ("farm-task", ["guided", "--frame", "1", "--scene-name", "road", "--resolution", "64x36",
                   "--time-budget", "0"], "--time-budget: must be greater than 0, not 0"),
    ("farm-task", ["guided", "--frame", "1", "--scene-name", "road", "--resolution", "64x36",
                   "--time-budget", "5", "--max-spp", "-1"], "--max-spp: must be a whole number from 0 to"),
])
def test_bad_guided_options_exit_2_before_any_work(cli, tmp_path, command, args, message):
    where = ["--bundle", tmp_path / "bundle"] if command == "farm" else ["--output", tmp_path / "bundle"]
    step, rest = ([], args) if command == "farm" else (args[:1], args[1:])
    result = cli(command, *step, ROAD, *where, *rest)
    assert result.returncode == 2
    assert message in one_line_error(result)
    assert not (tmp_path / "bundle").exists()


def test_an_animations_default_job_is_blenders_own_with_auto_volumes_and_a_stills_is_xsl(cli, tmp_path):
    from xsl_render.core.farm.blender_job import TASK_SCRIPT

    result = cli("farm", ROAD, "--bundle", tmp_path / "animation", "--frames", "1-9:2", "--frames-per-task", "3")
    assert result.returncode == 0 and "a Blender job, frames 1-9:2" in result.stdout, result.stderr
    template = yaml.safe_load((tmp_path / "animation" / "template.yaml").read_text())
    step, = template["steps"]
    assert step["script"]["actions"]["onRun"]["command"] == "{{Param.BlenderExecutable}}"
    assert step["script"]["embeddedFiles"][0]["data"] == TASK_SCRIPT
    values = openjd_values(yaml.safe_load((tmp_path / "animation" / "parameter_values.yaml").read_text()))
    assert values["AutoVolumes"] == "true" and values["BlenderExecutable"] == "blender"
    assert values["FramesPerTask"] == 3 and values["Frames"] == "1-9:2"
    check = openjd("check", tmp_path / "animation" / "template.yaml")
    assert check.returncode == 0, check.stdout + check.stderr
    # The options of the paper's jobs are refused by a Blender job, and the other way round.
    for args, flag in ((["--max-spp", "8"], "--max-spp"), (["--resolution", "64x36"], "--resolution"),
                       (["--worker-setup", "pip"], "--worker-setup")):
        refused = cli("farm", ROAD, "--bundle", tmp_path / "refused", "--frames", "1-3", *args)
        assert refused.returncode == 2 and f"{flag} is for --mode xs, xsl or guided" in one_line_error(refused)
    refused = cli("farm", ROAD, "--bundle", tmp_path / "refused", "--frames", "1", "--blender", "b")
    assert refused.returncode == 2 and "--blender is for --mode blender" in one_line_error(refused)
    assert not (tmp_path / "refused").exists()
    still = cli("farm", ROAD, "--bundle", tmp_path / "still", "--frames", "7", "--max-spp", "4")
    assert still.returncode == 0 and "xsl up to 4 spp" in still.stdout, still.stderr
