"""A farm bundle that runs on someone else's farm, without Blender: the executable from the
worker's PATH, the job environment that installs it, cancelation and timeouts on every
action, GPU host requirements, frame lists, the pinned requirements, the scene's files and
the progress lines."""
from __future__ import annotations

import io
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from openjd.model import StepParameterSpaceIterator, create_job, preprocess_job_parameters
from test_farm_core import decoded, farm_job, guided_job, job_tasks
from support.cli_wording import refused_in_flags

from xsl_render.core.farm.assets import ScenePath, asset_references, scene_files, sequence_paths, tile_paths
from xsl_render.core.farm.farm_job import DEFAULT_TASK_TIMEOUT, guided_timeout
from xsl_render.core.farm.job_template import job_template, openjd_values, parameter_values
from xsl_render.core.farm.task_progress import TaskProgress
from xsl_render.core.farm.worker_environment import NOTIFY_PERIOD, SCRIPT, WorkerSetup
from xsl_render.core.farm.worker_requirements import pinned_closure, requirements_text

ROOT = Path(__file__).resolve().parent.parent


def actions(template: dict) -> dict:
    return {step["name"]: step["script"]["actions"]["onRun"] for step in template["steps"]}


def test_the_executable_is_found_on_the_workers_path_and_nothing_names_this_machine(tmp_path):
    job = replace(farm_job(tmp_path), executable="xsl-render")
    values = openjd_values(parameter_values(job))
    assert values["XslRender"] == "xsl-render"
    text = repr(values) + repr(job_template(job))
    assert sys.prefix not in text and str(Path(sys.executable).parent) not in text
    assert "WorkerRequirements" not in values         # relative: resolved against the bundle


def test_every_action_is_cancelled_notify_then_terminate_with_a_timeout(tmp_path):
    selective = job_template(farm_job(tmp_path))
    guided = job_template(guided_job(tmp_path))
    environment = selective["jobEnvironments"][0]["script"]["actions"]["onEnter"]
    for action in [*actions(selective).values(), *actions(guided).values(), environment]:
        assert action["cancelation"] == {"mode": "NOTIFY_THEN_TERMINATE",
                                         "notifyPeriodInSeconds": NOTIFY_PERIOD}
        assert isinstance(action["timeout"], int) and action["timeout"] > 0
    # A task renders a chunk of FramesPerTask frames (8): its timeout is a frame's times 8.
    assert {a["timeout"] for a in actions(selective).values()} == {8 * DEFAULT_TASK_TIMEOUT}
    assert actions(guided)["Render"]["timeout"] == 8 * guided_timeout(12.5) == 8 * (25 + 900)
    single = job_template(replace(guided_job(tmp_path), frames_per_task=1))
    assert actions(single)["Render"]["timeout"] == guided_timeout(12.5)
    assert actions(job_template(replace(farm_job(tmp_path), task_timeout=600)))["Tiles"]["timeout"] == 600
    assert decoded(selective) and decoded(guided)


def test_gpu_jobs_ask_for_a_gpu_where_cycles_renders(tmp_path):
    cpu = job_template(farm_job(tmp_path))
    assert not any("hostRequirements" in step for step in cpu["steps"])
    gpu = job_template(replace(farm_job(tmp_path), device="GPU"))
    wants = {step["name"]: step.get("hostRequirements") for step in gpu["steps"]}
    assert wants["Maps"] == wants["Tiles"] == {"amounts": [{"name": "amount.worker.gpu", "min": 1}]}
    assert wants["Composite"] is None                        # denoise and assemble: no Cycles
    assert openjd_values(parameter_values(replace(farm_job(tmp_path), device="GPU")))["Device"] == "GPU"
    tiles = [str(a) for a in actions(gpu)["Tiles"]["args"]]
    assert tiles[tiles.index("--device") + 1] == "{{Param.Device}}"
    guided = job_template(replace(guided_job(tmp_path), device="GPU"))
    assert guided["steps"][0]["hostRequirements"]["amounts"][0]["name"] == "amount.worker.gpu"
    decoded(gpu)
    with refused_in_flags("--device", Exception):
        job_template(replace(farm_job(tmp_path), device="TPU"))


def test_a_frame_list_makes_one_task_per_listed_frame_or_chunk_of_them(tmp_path):
    job = replace(farm_job(tmp_path), frames="1-3,8", frames_per_task=1)
    template = decoded(job_template(job))
    params = preprocess_job_parameters(job_template=template,
                                       job_parameter_values=openjd_values(parameter_values(job)),
                                       job_template_dir=tmp_path, current_working_dir=tmp_path)
    steps = create_job(job_template=template, job_parameter_values=params).steps
    frames = [t["Frame"].value for t in StepParameterSpaceIterator(space=steps[0].parameterSpace)]
    assert frames == ["1", "2", "3", "8"]
    assert len(list(StepParameterSpaceIterator(space=steps[1].parameterSpace))) == 4 * 4
    chunked = job_tasks(decoded(job_template(replace(job, frames_per_task=2))),
                        openjd_values(parameter_values(replace(job, frames_per_task=2))), tmp_path)
    assert [t["Frame"] for t in chunked["Maps"]] == ["1,2", "3,8"] and len(chunked["Tiles"]) == 2 * 4


def test_the_job_environment_embeds_the_setup_script_and_passes_every_parameter(tmp_path):
    job = replace(farm_job(tmp_path), worker=WorkerSetup(setup="pip", package="/wheels/x.whl"))
    template = job_template(job)
    environment = template["jobEnvironments"][0]
    assert environment["script"]["embeddedFiles"][0]["data"] == SCRIPT.read_text()
    args = environment["script"]["actions"]["onEnter"]["args"]
    for flag, name in (("--setup", "WorkerSetup"), ("--executable", "XslRender"),
                       ("--requirements", "WorkerRequirements"), ("--package", "XslRenderPackage"),
                       ("--cache", "WorkerCache")):
        assert args[args.index(flag) + 1] == f"{{{{Param.{name}}}}}"
    values = openjd_values(parameter_values(job))
    assert values["WorkerSetup"] == "pip" and values["XslRenderPackage"] == "/wheels/x.whl"
    with pytest.raises(ValueError):
        preprocess_job_parameters(job_template=decoded(template),
                                  job_parameter_values={**values, "WorkerSetup": "apt"},
                                  job_template_dir=tmp_path, current_working_dir=tmp_path)
    with refused_in_flags("--worker-setup", Exception):
        job_template(replace(job, worker=WorkerSetup(setup="apt")))


def test_the_workers_requirements_are_the_lock_files_pins():
    lock = {}
    for line in (ROOT / "requirements.lock").read_text().splitlines():
        requirement = line.partition("#")[0].strip()
        if "==" in requirement:
            name, version = requirement.split("==")
            lock[name.lower().replace("_", "-")] = version
    pins = pinned_closure()
    assert {"bpy", "numpy", "scipy", "scikit-image", "OpenImageIO"} <= set(pins)
    for name, version in pins.items():
        assert lock[name.lower().replace("_", "-")] == version, name
    text = requirements_text(pins)
    assert "bpy==5.0.1" in text.splitlines() and "pytest" not in text and "openjd" not in text
    with pytest.raises(LookupError, match="no-such-distribution"):
        pinned_closure(("no-such-distribution",))


# -- the setup script, as a worker runs it ----------------------------------------------------

def setup_script(*args: str, env: dict, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True,
                          env=env, timeout=timeout)


def test_setup_none_finds_xsl_render_on_path_or_fails_before_any_task(tmp_path):
    bin_folder = str(Path(sys.executable).parent)
    found = setup_script("--setup", "none", "--executable", "xsl-render",
                         env={**os.environ, "PATH": bin_folder + os.pathsep + "/usr/bin:/bin"})
    assert found.returncode == 0, found.stderr
    assert f"openjd_status: xsl-render is {bin_folder}/xsl-render" in found.stdout
    assert "openjd_env:" not in found.stdout                          # PATH left as it is
    missing = setup_script("--setup", "none", "--executable", "xsl-render", env={**os.environ, "PATH": "/usr/bin:/bin"})
    assert missing.returncode == 1 and missing.stderr.count("\n") == 1
    assert "'xsl-render' is not on this worker's PATH" in missing.stderr
    assert "WorkerSetup to pip or conda" in missing.stderr


def test_setup_pip_builds_one_environment_per_inputs_and_reuses_it(tmp_path):
    """A real virtual environment and pip, offline: the package is a wheel of a small project
    built here (bpy from the internet is what a real worker installs; not in a test)."""
    project = tmp_path / "project"
    (project / "tool").mkdir(parents=True)
    (project / "tool" / "__init__.py").write_text("def main():\n    print('hello from the worker')\n")
    (project / "pyproject.toml").write_text(
        '[build-system]\nrequires = ["setuptools"]\nbuild-backend = "setuptools.build_meta"\n'
        '[project]\nname = "tool"\nversion = "1.0"\n[project.scripts]\nxsl-render = "tool:main"\n')
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                    "-w", str(wheels), str(project)], check=True, capture_output=True, timeout=300)
    wheel = next(wheels.glob("tool-1.0-*.whl"))
    requirements = tmp_path / "worker_requirements.txt"
    requirements.write_text("# nothing pinned: offline\n")
    cache = tmp_path / "cache"
    env = {**os.environ, "PATH": "/usr/bin:/bin", "PIP_NO_INDEX": "1"}
    args = ("--setup", "pip", "--executable", "xsl-render", "--requirements", str(requirements),
            "--package", str(wheel), "--cache", str(cache))
    first = setup_script(*args, env=env)
    assert first.returncode == 0, first.stdout + first.stderr
    (prefix,) = [p for p in cache.iterdir() if p.is_dir()]
    assert prefix.name.startswith("pip-") and (prefix / ".xsl-render-complete").is_file()
    exported = [line for line in first.stdout.splitlines() if line.startswith("openjd_env: PATH=")]
    assert exported == [f"openjd_env: PATH={prefix / 'bin'}{os.pathsep}/usr/bin:/bin"]
    assert f"openjd_status: xsl-render is {prefix / 'bin' / 'xsl-render'}" in first.stdout
    hello = subprocess.run([str(prefix / "bin" / "xsl-render")], capture_output=True, text=True)
    assert hello.stdout == "hello from the worker\n"

    again = setup_script(*args, env=env)                    # the next session on the worker
    assert again.returncode == 0 and f"reusing the environment {prefix}" in again.stdout
    (prefix / ".xsl-render-complete").unlink()              # as if cancelled mid-install
    rebuilt = setup_script(*args, env=env)
    assert rebuilt.returncode == 0 and "creating a virtual environment" in rebuilt.stdout
    assert (prefix / ".xsl-render-complete").is_file()
    requirements.write_text("# other pins\n")              # other inputs: another environment
    assert setup_script(*args, env=env).returncode == 0
    assert len([p for p in cache.iterdir() if p.is_dir()]) == 2


# -- the scene's files --------------------------------------------------------------------------

def test_tiles_and_sequences_expand_into_the_files_on_disk(tmp_path):
    assert tile_paths("/t/wood.<UDIM>.png", (1001, 1012)) == ["/t/wood.1001.png", "/t/wood.1012.png"]
    assert tile_paths("/t/w_<UVTILE>.png", (1001, 1012)) == ["/t/w_u1_v1.png", "/t/w_u2_v2.png"]
    cache = tmp_path / "cache"
    cache.mkdir()
    for name in ("fog_0001.vdb", "fog_0002.vdb", "fog_0010.vdb", "fog_0001.vdb.bak", "smoke_0001.vdb",
                 "fog_a.vdb"):
        (cache / name).write_bytes(b"")
    assert [Path(p).name for p in sequence_paths(str(cache / "fog_0002.vdb"))] == \
        ["fog_0001.vdb", "fog_0002.vdb", "fog_0010.vdb"]
    assert sequence_paths(str(cache / "fog_a.vdb")) == [str(cache / "fog_a.vdb")]
    (tmp_path / "a.1001.png").write_bytes(b"")
    files = scene_files([ScenePath(str(cache / "fog_0001.vdb"), sequence=True),
                         ScenePath(str(tmp_path / "a.<UDIM>.png"), tiles=(1001, 1002)),
                         ScenePath(str(cache / "smoke_0001.vdb"))],
                        ["//cache/fog_0001.vdb", "/abs/a.<UDIM>.png", "//cache/smoke_0001.vdb"])
    assert [p.name for p in files.found] == ["a.1001.png", "fog_0001.vdb", "fog_0002.vdb",
                                             "fog_0010.vdb", "smoke_0001.vdb"]
    assert files.missing == [str(tmp_path / "a.1002.png")]
    assert files.absolute_in_blend == ["/abs/a.<UDIM>.png"]
    references = asset_references(tmp_path / "s.blend", files, tmp_path / "out")["assetReferences"]
    assert references["inputs"]["filenames"][-1] == str(tmp_path / "s.blend")
    assert references["outputs"]["directories"] == [str(tmp_path / "out")]


def test_progress_lines_are_whole_percents_and_changed_statuses():
    stream = io.StringIO()
    report = TaskProgress(stream)
    callback = report.callback("frame 1: ")
    for fraction, message in ((0.0, "X map"), (0.001, "X map"), (0.3, "snapshot\nof it"), (1.5, "done")):
        assert callback(fraction, message) is False
    assert stream.getvalue().splitlines() == [
        "openjd_progress: 0", "openjd_status: frame 1: X map", "openjd_progress: 30",
        "openjd_status: frame 1: snapshot of it", "openjd_progress: 100", "openjd_status: frame 1: done"]
