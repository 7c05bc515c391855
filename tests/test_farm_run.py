"""A farm bundle as another machine would run it: ``openjd run`` from a clean folder with
``xsl-render`` taken from PATH, a task cancelled the way a farm cancels it (SIGTERM, then a
kill after the notify period) leaving nothing half-written, the files a fog scene reads
(an OpenVDB sequence, UDIM tiles, a linked library) attached, the printed command quoted,
and the Cycles device taken from the scene or the command line."""
from __future__ import annotations

import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from conftest import EXAMPLES
from test_cli_info import one_line_error
from test_farm_cli import OPENJD, job_values, openjd, tile_records

from xsl_render.core.farm.files import FrameFiles, read_record, valid_plan, valid_tile
from xsl_render.core.temporaries import SESSION_PREFIX

pytestmark = pytest.mark.blender

ROAD = EXAMPLES / "road.blend"
VENV_BIN = Path(sys.executable).parent


def worker_env(tmp_path: Path) -> dict:
    """A worker's environment: xsl-render only through PATH, a temporary folder of its own."""
    folder = tmp_path / "tmp"
    folder.mkdir(exist_ok=True)
    env = {key: value for key, value in os.environ.items() if not key.startswith(("VIRTUAL_ENV", "PYTHON"))}
    return {**env, "PATH": f"{VENV_BIN}{os.pathsep}/usr/bin:/bin", "TMPDIR": str(folder)}


def partial_files(folder: Path) -> list[Path]:
    return [path for path in folder.rglob("*") if ".partial" in path.name]


def wait_for_first_tile(process: subprocess.Popen, files: FrameFiles) -> dict:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        for path in tile_records(files):
            record = read_record(path)
            if record is not None:
                return record
        assert process.poll() is None, "the job ended before its tile task rendered"
        time.sleep(0.005)
    pytest.fail("the tile task never wrote a rectangle")


@pytest.mark.render
def test_a_bundle_runs_from_path_in_a_clean_folder_and_a_cancelled_task_leaves_no_partial_file(cli, tmp_path):
    bundle = tmp_path / "bundle"
    result = cli("farm", ROAD, "--bundle", bundle, "--frames", "1", "--tasks-per-frame", "1",
                 "--max-spp", "4", "--tile-size", "8", "--resolution", "64x36", "--seed", "3")
    assert result.returncode == 0, result.stderr
    values = yaml.safe_load((bundle / "parameter_values.yaml").read_text())["parameterValues"]
    assert {"name": "XslRender", "value": "xsl-render"} in values
    assert str(VENV_BIN) not in (bundle / "parameter_values.yaml").read_text()
    check = openjd("check", bundle / "template.yaml")
    assert check.returncode == 0 and "passes validation" in check.stdout, check.stdout + check.stderr

    clean = tmp_path / "elsewhere"
    clean.mkdir()
    env = worker_env(tmp_path)
    files = FrameFiles(bundle / "output", 1)
    log_path = tmp_path / "cancelled.log"
    with open(log_path, "w") as log:
        process = subprocess.Popen([str(OPENJD), "run", str(bundle / "template.yaml"), "-p", job_values(bundle)],
                                   stdout=log, stderr=subprocess.STDOUT, env=env, cwd=clean)
        try:
            record = wait_for_first_tile(process, files)
            process.send_signal(signal.SIGTERM)           # the farm cancels the job
            assert process.wait(timeout=120) != 0
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
    log = log_path.read_text()
    # The task heard SIGTERM, cleaned up and ended with 143 before any kill was needed.
    assert f'Sending signal "term" to process {record["pid"]}' in log, log[-3000:]
    assert "xsl-render: cancelled" in log and "exited with code: 143" in log, log[-3000:]
    assert 'Sending signal "kill"' not in log
    assert "openjd_status: xsl-render is " + str(VENV_BIN / "xsl-render") in log
    assert "openjd_progress: " in log and "openjd_status: frame 1: " in log
    assert not partial_files(bundle) and not files.image.exists()
    plan = valid_plan(files)
    finished = [rect for rect in plan.plan.rects if valid_tile(files, plan, rect)]
    assert 1 <= len(finished) < len(plan.plan.rects), log[-3000:]
    assert len(tile_records(files)) == len(finished)           # every record is whole
    assert list(clean.iterdir()) == []                          # nothing lands where it ran from

    rerun = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=env)
    assert rerun.returncode == 0, rerun.stdout[-3000:]
    assert f"{len(finished)} already done" in rerun.stdout and files.image.is_file()
    assert "openjd_progress: 100" in rerun.stdout and not partial_files(bundle)
    # The cancelled task's scratch folder is gone: removed as it ended, or (when a Cycles
    # thread wrote into it while it was being removed) swept by the next xsl-render.
    assert not [p for p in Path(env["TMPDIR"]).iterdir() if p.name.startswith(SESSION_PREFIX)]


def fog_scene_with_files(bpy, folder: Path) -> Path:
    """A scene that reads an OpenVDB sequence (three frames), a UDIM texture of two tiles, a
    plain image, a linked library, and one image that does not exist. The .vdb files are
    placeholders: the list is made from Blender's data, no grid is read."""
    (folder / "cache").mkdir(parents=True)
    (folder / "tex").mkdir()
    (folder / "lib").mkdir()
    bpy.ops.mesh.primitive_cube_add()
    bpy.context.object.name = "Prop"
    bpy.ops.wm.save_as_mainfile(filepath=str(folder / "lib" / "props.blend"))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    for frame in (1, 2, 3):
        (folder / "cache" / f"fog_{frame:04d}.vdb").write_bytes(b"placeholder")
    volume = bpy.data.volumes.new("fog")
    volume.filepath = str(folder / "cache" / "fog_0001.vdb")
    volume.is_sequence = True
    scene.collection.objects.link(bpy.data.objects.new("fog", volume))
    plain = bpy.data.images.new("plain", 4, 4)
    plain.filepath_raw = str(folder / "tex" / "plain.png")
    plain.file_format = "PNG"
    plain.save()
    plain.use_fake_user = True
    for tile in (1001, 1002):
        (folder / "tex" / f"wood.{tile}.png").write_bytes((folder / "tex" / "plain.png").read_bytes())
    wood = bpy.data.images.load(str(folder / "tex" / "wood.1001.png"))
    wood.source = "TILED"
    wood.tiles.new(1002)
    wood.use_fake_user = True
    gone = bpy.data.images.load(str(folder / "tex" / "plain.png"), check_existing=False)
    gone.filepath = str(folder / "tex" / "gone.png")
    gone.use_fake_user = True
    with bpy.data.libraries.load(str(folder / "lib" / "props.blend"), link=True) as (_, linked):
        linked.objects = ["Prop"]
    scene.collection.objects.link(linked.objects[0])
    path = folder / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path), relative_remap=True)
    return path


def test_asset_references_list_the_vdb_sequence_udim_tiles_and_library(cli, blender, tmp_path):
    folder = tmp_path / "shot $(touch pwned) 'q'"
    scene = fog_scene_with_files(blender, folder)
    bundle = tmp_path / "bundle"
    result = cli("farm", scene, "--bundle", bundle, "--frames", "1-3,8", "--mode", "xsl", "--resolution", "32x18",
                 "--max-spp", "2", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    inputs = yaml.safe_load((bundle / "asset_references.yaml").read_text())["assetReferences"]["inputs"]
    assert sorted(inputs["filenames"]) == sorted(str(folder / name) for name in (
        "cache/fog_0001.vdb", "cache/fog_0002.vdb", "cache/fog_0003.vdb", "tex/plain.png",
        "tex/wood.1001.png", "tex/wood.1002.png", "lib/props.blend", "scene.blend"))
    assert f"the scene reads {folder / 'tex' / 'gone.png'}, which does not exist" in result.stderr
    assert "7 file(s) the scene reads" in result.stdout          # the .blend besides
    # The printed command is quoted: pasted into a shell it names the file, runs nothing.
    hint = result.stdout.split("run here with: ")[1].strip()
    assert shlex.split(hint)[-1] == f"SceneFile={scene}"
    echoed = subprocess.run(["sh", "-c", "printf '%s\\n' " + hint.removeprefix("openjd run ")],
                            capture_output=True, text=True, cwd=tmp_path)
    assert echoed.stdout.splitlines()[-1] == f"SceneFile={scene}" and not (tmp_path / "pwned").exists()
    check = openjd("check", bundle / "template.yaml")
    assert check.returncode == 0, check.stdout + check.stderr


def test_the_device_follows_the_scene_or_the_command_line(cli, blender, tmp_path):
    from xsl_render.addon.cycles.device import gpu_backend
    from xsl_render.addon.cycles.render import ensure_cycles
    from xsl_render.addon.scene.state import preserved_scene

    scene = blender.context.scene
    scene.camera = blender.data.objects.new("Camera", blender.data.cameras.new("Camera"))
    scene.collection.objects.link(scene.camera)
    scene.cycles.device = "GPU"
    path = tmp_path / "gpu.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    with preserved_scene(scene):                # what every render does, the panel's too
        ensure_cycles(scene)
        assert scene.cycles.device == ("GPU" if gpu_backend() else "CPU")
    assert scene.cycles.device == "GPU"         # the user's setting is back

    result = cli("farm", path, "--bundle", tmp_path / "gpu", "--resolution", "32x18", "--frames", "1")
    assert result.returncode == 0 and "on the GPU" in result.stdout, result.stderr
    template = yaml.safe_load((tmp_path / "gpu" / "template.yaml").read_text())
    assert template["steps"][1]["hostRequirements"]["amounts"][0]["name"] == "amount.worker.gpu"
    result = cli("farm", path, "--bundle", tmp_path / "cpu", "--resolution", "32x18", "--frames", "1",
                 "--device", "CPU")
    template = yaml.safe_load((tmp_path / "cpu" / "template.yaml").read_text())
    assert result.returncode == 0 and not any("hostRequirements" in s for s in template["steps"])
    if gpu_backend() is None:                   # a task promised a GPU refuses to crawl on the CPU
        result = cli("farm-task", "maps", path, "--scene-name", "Scene", "--frame", "1",
                     "--output", tmp_path / "out", "--mode", "xs", "--max-spp", "2",
                     "--resolution", "32x18", "--device", "GPU")
        assert result.returncode == 2 and "Cycles finds no GPU" in one_line_error(result)
        assert not list((tmp_path / "out").rglob("*.exr"))
