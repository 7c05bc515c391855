"""The farm job without Blender: task groups, the job template, bundle folders, task records
and the composite step."""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from openjd.model import (StepParameterSpaceIterator, create_job, decode_job_template,
                          preprocess_job_parameters)
from support.cli_wording import refused_in_flags

from xsl_render.core.errors import InputError
from xsl_render.core.farm.composite import composite_frame
from xsl_render.core.farm.files import (FrameFiles, maps_inputs, read_tile, tile_inputs,
                                        valid_plan, valid_tile, write_plan_record, write_tile)
from xsl_render.core.farm.job_bundle import MARKER, check_bundle_folder, write_bundle
from xsl_render.core.farm.job_template import (FarmJob, job_template, openjd_values,
                                               parameter_values, parse_frames)
from xsl_render.core.farm.task_groups import group_plan, partition, plan_group
from xsl_render.core.frames import parse_frame_list
from xsl_render.core.imageio import read_image, write_exr
from xsl_render.core.maps.options import MapOptions
from xsl_render.core.sampling.guided_plan import UNBOUNDED_SPP, GuidedOptions
from xsl_render.core.sampling.render_options import RenderOptions
from xsl_render.core.sampling.tile_plan import make_plan


def random_plan(seed: int, width=96, height=54, tile=16):
    rng = np.random.default_rng(seed)
    director = rng.random((height, width)).astype(np.float32) ** 3
    return make_plan(director, RenderOptions(max_spp=64, tile_size=tile, resolution=(width, height)))


# -- task groups ------------------------------------------------------------------------------

@pytest.mark.parametrize("groups", [1, 2, 3, 7, 40])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_groups_cover_every_rectangle_once_at_about_equal_cost(groups, seed):
    plan = random_plan(seed)
    grouping = group_plan(plan.rects, groups, render_cost=1024)
    owned = sorted(i for members in grouping.groups for i in members)
    assert owned == list(range(len(plan.rects)))
    costs = [rect.samples + 1024 for rect in plan.rects]
    assert grouping.costs == [sum(costs[i] for i in members) for members in grouping.groups]
    # LPT: no task costs more than the mean plus the largest single rectangle, and at most
    # 4/3 of the best possible split (which is at least the mean and the largest rectangle).
    lower = max(sum(costs) / groups, max(costs))
    assert max(grouping.costs) <= sum(costs) / groups + max(costs)
    assert max(grouping.costs) <= 4 / 3 * lower + 1e-9
    # Every task renders its share of the plan, and all together render the plan.
    shares = [plan_group(plan.rects, g, groups, 1024) for g in range(1, groups + 1)]
    assert sorted((r.row0, r.col0) for share in shares for r in share) == \
        sorted((r.row0, r.col0) for r in plan.rects)


def test_grouping_is_deterministic_and_empty_groups_are_no_ops():
    costs = [5, 5, 5, 1, 9, 9]
    assert partition(costs, 4) == partition(list(costs), 4) == [[4], [5], [0, 2], [1, 3]]
    assert partition([3, 2], 4) == [[0], [1], [], []]
    assert partition([], 3) == [[], [], []]
    assert group_plan([], 3, 1024).balance == 0.0


def test_balance_on_many_small_rectangles_is_close_to_perfect():
    plan = random_plan(3, width=256, height=144, tile=8)
    assert len(plan.rects) > 100
    assert group_plan(plan.rects, 4, 1024).balance < 1.05


@pytest.mark.parametrize("group,groups,message", [(0, 3, "--group"), (4, 3, "--group"),
                                                  (1, 0, "--tasks-per-frame"), (1, 10001, "--tasks-per-frame")])
def test_bad_group_numbers(group, groups, message):
    with refused_in_flags(message):
        plan_group(random_plan(0).rects, group, groups, 1024)


# -- frames and the job template ----------------------------------------------------------------

@pytest.mark.parametrize("text,expected", [("12", "12"), ("1-250", "1-250"), ("1-250:2", "1-250:2"),
                                           ("5-5", "5"), (" 3-9:1 ", "3-9"), ("-3-2", "-3-2")])
def test_parse_frames(text, expected):
    assert parse_frames(text) == expected


@pytest.mark.parametrize("text", ["", "a-b", "9-3", "1-5:0", "1-"])
def test_parse_frames_refuses(text):
    with refused_in_flags("--frames"):
        parse_frames(text)


def farm_job(tmp_path: Path, **changes) -> FarmJob:
    values = dict(scene=tmp_path / "scene.blend", scene_name="Scene", frames="1-3", output="output",
                  mode="xsl", map_options=MapOptions(light_n=3),
                  options=RenderOptions(max_spp=32, tile_size=16, seed=7, adaptive_threshold=0.02,
                                        resolution=(96, 54)),
                  tasks_per_frame=4, executable="/opt/xsl/bin/xsl-render")
    values.update(changes)
    return FarmJob(**values)


def decoded(template: dict):
    """The template as openjd-model reads it: its chunks need the TASK_CHUNKING extension."""
    return decode_job_template(template=template, supported_extensions=["TASK_CHUNKING"])


def job_tasks(template, values: dict, tmp_path: Path) -> dict[str, list[dict]]:
    """The tasks of each step of the job ``values`` make: {step: [{parameter: value}]}."""
    params = preprocess_job_parameters(job_template=template, job_parameter_values=values,
                                       job_template_dir=tmp_path, current_working_dir=tmp_path)
    steps = create_job(job_template=template, job_parameter_values=params).steps
    return {step.name: [{name: value.value for name, value in task.items()}
                        for task in StepParameterSpaceIterator(space=step.parameterSpace)]
            for step in steps}


def test_template_is_valid_open_job_description_and_static(tmp_path):
    job = farm_job(tmp_path)
    template = decoded(job_template(job))
    values = openjd_values(parameter_values(job))
    assert "OutputDir" not in values                  # relative: the template default applies
    params = preprocess_job_parameters(job_template=template, job_parameter_values=values,
                                       job_template_dir=tmp_path, current_working_dir=tmp_path)
    assert params["OutputDir"].value == str(tmp_path / "output")
    job_model = create_job(job_template=template, job_parameter_values=params)
    steps = {step.name: step for step in job_model.steps}
    assert list(steps) == ["Maps", "Tiles", "Composite"]
    tasks = {name: list(StepParameterSpaceIterator(space=step.parameterSpace))
             for name, step in steps.items()}
    # Every step takes chunks of FramesPerTask (8) frames: frames 1-3 are one chunk.
    assert [t["Frame"].value for t in tasks["Maps"]] == ["1-3"]
    assert [t["Frame"].value for t in tasks["Composite"]] == ["1-3"]
    assert len(tasks["Tiles"]) == 1 * 4                   # Frame chunk x Group, Group = 1..4
    assert sorted({t["Group"].value for t in tasks["Tiles"]}) == ["1", "2", "3", "4"]
    assert [d.dependsOn for d in steps["Tiles"].dependencies] == ["Maps"]
    assert sorted(d.dependsOn for d in steps["Composite"].dependencies) == ["Maps", "Tiles"]
    for step in template.steps:
        args = [str(a) for a in step.script.actions.onRun.args]
        assert args[args.index("--frames") + 1] == "{{Task.Param.Frame}}" and "--frame" not in args
    maps_args = [str(a) for a in template.steps[0].script.actions.onRun.args]
    for flag in ("--max-spp", "--seed", "--adaptive-threshold", "--light-n", "--minbound-value",
                 "--tile-size", "--resolution", "--scene-name", "--mode"):
        assert flag in maps_args
    defaults = {p.name: p.default for p in template.parameterDefinitions}
    assert defaults["XslRender"] == "/opt/xsl/bin/xsl-render" and defaults["LightN"] == "3"
    assert defaults["AdaptiveThreshold"] == "0.02" and defaults["Resolution"] == "96x54"
    assert defaults["FramesPerTask"] == 8
    assert "SceneFile" not in defaults or defaults["SceneFile"] is None


def test_frames_per_task_chunks_every_step_and_a_chunk_expands_to_a_frame_list(tmp_path):
    """FramesPerTask, chosen at submission, cuts the frames into chunks of at most that
    many (Open Job Description spreads them evenly); a chunk's text is a frame list that
    core.frames reads back to exactly the chunk's frames, across gaps and steps."""
    job = farm_job(tmp_path, frames="1-3,8,10-20:3")
    template = decoded(job_template(job))
    values = openjd_values(parameter_values(job))
    assert values["FramesPerTask"] == 8
    everything = parse_frame_list(values["Frames"])
    assert everything == (1, 2, 3, 8, 10, 13, 16, 19)
    for per_task, count in ((8, 1), (3, 3), (2, 4), (1, 8), (1000, 1)):
        tasks = job_tasks(template, {**values, "FramesPerTask": per_task}, tmp_path)
        chunks = [parse_frame_list(t["Frame"]) for t in tasks["Maps"]]
        assert len(chunks) == count and max(map(len, chunks)) <= per_task, (per_task, chunks)
        assert [f for chunk in chunks for f in chunk] == list(everything)
        assert [t["Frame"] for t in tasks["Composite"]] == [t["Frame"] for t in tasks["Maps"]]
        assert [(t["Frame"], t["Group"]) for t in tasks["Tiles"]] == \
            [(t["Frame"], str(g)) for t in tasks["Maps"] for g in range(1, 5)]
    one_each = job_tasks(template, {**values, "FramesPerTask": 1}, tmp_path)["Maps"]
    assert [t["Frame"] for t in one_each] == [str(f) for f in everything]     # as before chunks
    for bad in (0, 1001):                             # the form refuses what no task can take
        with pytest.raises(ValueError):
            job_tasks(template, {**values, "FramesPerTask": bad}, tmp_path)
    guided = replace(guided_job(tmp_path), frames="1-250:2", frames_per_task=16)
    renders = job_tasks(decoded(job_template(guided)), openjd_values(parameter_values(guided)),
                        tmp_path)["Render"]
    assert len(renders) == 8 and renders[0]["Frame"] == "1-31:2"     # 125 frames in 8 chunks
    with refused_in_flags("--frames-per-task must be a whole number from 1 to 1000"):
        job_template(replace(job, frames_per_task=0))


def test_parameter_values_override_and_an_absolute_output_has_no_default(tmp_path):
    job = farm_job(tmp_path, output=str(tmp_path / "renders"), frames="10")
    data = job_template(job)
    output = next(p for p in data["parameterDefinitions"] if p["name"] == "OutputDir")
    assert "default" not in output
    values = openjd_values(parameter_values(job))
    assert values["OutputDir"] == str(tmp_path / "renders") and values["Frames"] == "10"
    template = decoded(data)
    params = preprocess_job_parameters(job_template=template, job_parameter_values={**values, "MaxSpp": 8},
                                       job_template_dir=tmp_path, current_working_dir=tmp_path)
    assert params["MaxSpp"].value == "8"


@pytest.mark.parametrize("changes,message", [
    ({"mode": "gold"}, "--mode"), ({"tasks_per_frame": 0}, "--tasks-per-frame"),
    ({"frames": "4-1"}, "--frames"), ({"map_options": MapOptions(wx=-1)}, "--wx"),
])
def test_bad_farm_jobs(tmp_path, changes, message):
    with refused_in_flags(message):
        job_template(farm_job(tmp_path, **changes))


def guided_job(tmp_path: Path, max_spp: int = UNBOUNDED_SPP, tile_size: int = 16, **guided_changes) -> FarmJob:
    guided = GuidedOptions(**{"time_budget": 12.5, "importance": "xs", **guided_changes})
    return farm_job(tmp_path, mode="guided", guided=guided, tasks_per_frame=1,
                    options=RenderOptions(max_spp=max_spp, tile_size=tile_size, seed=7, resolution=(96, 54)))


def test_guided_template_is_one_task_per_chunk_with_every_knob_a_parameter(tmp_path):
    job = guided_job(tmp_path, pilot_fraction=0.3, exponent=0.5, level_ratio=2.0)
    template = decoded(job_template(job))
    values = openjd_values(parameter_values(job))
    assert values["TimeBudget"] == 12.5 and values["Importance"] == "xs" and values["MaxSpp"] == 0
    assert (values["PilotFraction"], values["GuidedExponent"], values["LevelRatio"]) == (0.3, 0.5, 2.0)
    assert values["Seed"] == 7 and values["Resolution"] == "96x54" and values["TileSize"] == 16
    assert not {"Mode", "TasksPerFrame", "MinSpp", "TileQuantile", "Margin"} & values.keys()
    params = preprocess_job_parameters(job_template=template, job_parameter_values=values,
                                       job_template_dir=tmp_path, current_working_dir=tmp_path)
    job_model = create_job(job_template=template, job_parameter_values=params)
    assert [step.name for step in job_model.steps] == ["Render"]
    tasks = list(StepParameterSpaceIterator(space=job_model.steps[0].parameterSpace))
    assert [t["Frame"].value for t in tasks] == ["1-3"]            # one chunk of up to 8 frames
    args = [str(a) for a in template.steps[0].script.actions.onRun.args]
    assert args[:3] == ["farm-task", "guided", "{{Param.SceneFile}}"]
    assert args[args.index("--frames") + 1] == "{{Task.Param.Frame}}" and values["FramesPerTask"] == 8
    for flag, name in (("--time-budget", "TimeBudget"), ("--importance", "Importance"),
                       ("--max-spp", "MaxSpp"), ("--pilot-fraction", "PilotFraction"),
                       ("--guided-exponent", "GuidedExponent"), ("--level-ratio", "LevelRatio"),
                       ("--seed", "Seed"), ("--resolution", "Resolution"), ("--tile-size", "TileSize"),
                       ("--wx", "Wx"), ("--light-n", "LightN"), ("--minbound-value", "MinBound")):
        assert args[args.index(flag) + 1] == f"{{{{Param.{name}}}}}", flag
    # The farm's form refuses what the task would: no budget of 0, no unknown map. (Not a
    # MaxSpp of -1: openjd-model 0.13 skips a minValue of 0; the task refuses it.)
    for bad in ({"TimeBudget": 0.0}, {"Importance": "xyz"}, {"GuidedExponent": 3.0},
                {"MaxSpp": UNBOUNDED_SPP + 1}):
        with pytest.raises(ValueError):
            preprocess_job_parameters(job_template=template, job_parameter_values={**values, **bad},
                                      job_template_dir=tmp_path, current_working_dir=tmp_path)
    assert openjd_values(parameter_values(guided_job(tmp_path, max_spp=48)))["MaxSpp"] == 48


@pytest.mark.parametrize("changes,message", [
    ({"guided": None}, "--mode guided needs --time-budget"),
    ({"guided": GuidedOptions(time_budget=0.0005)}, "--time-budget must be between 0.001 and"),
    ({"guided": GuidedOptions(time_budget=float("nan"))}, "--time-budget must be a finite number"),
    ({"mode": "xsl"}, "--time-budget is for --mode guided"),
])
def test_bad_guided_farm_jobs(tmp_path, changes, message):
    with refused_in_flags(message):
        job_template(replace(guided_job(tmp_path), **changes))


def test_a_guided_farm_jobs_tiles_fit_its_frame(tmp_path):
    with refused_in_flags("--tile-size 128 is larger"):
        job_template(guided_job(tmp_path, tile_size=128))


# -- the bundle folder --------------------------------------------------------------------------

def test_bundle_folder_must_be_new_empty_or_ours(tmp_path):
    assert check_bundle_folder(tmp_path / "new") == tmp_path / "new"
    (tmp_path / "empty").mkdir()
    check_bundle_folder(tmp_path / "empty")
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("precious")
    with pytest.raises(InputError, match="not an xsl-render job bundle"):
        check_bundle_folder(foreign)
    with pytest.raises(InputError, match="not an xsl-render job bundle"):
        write_bundle(foreign, {}, {}, {})
    assert sorted(p.name for p in foreign.iterdir()) == ["thesis.tex"]
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a folder"):
        check_bundle_folder(tmp_path / "file")
    job = farm_job(tmp_path)
    written = write_bundle(tmp_path / "ours", job_template(job), parameter_values(job), {"frames": "1-3"})
    assert sorted(p.name for p in written) == sorted([MARKER, "template.yaml", "parameter_values.yaml"])
    (tmp_path / "ours" / "output").mkdir()
    write_bundle(tmp_path / "ours", job_template(job), parameter_values(job), {})      # ours: rewritten
    loaded = yaml.safe_load((tmp_path / "ours" / "parameter_values.yaml").read_text())
    assert {"name": "TasksPerFrame", "value": 4} in loaded["parameterValues"]
    assert yaml.safe_load((tmp_path / "ours" / "template.yaml").read_text()) == job_template(job)


# -- task records and the composite -------------------------------------------------------------

def planned_frame(tmp_path: Path, options=None, scene_digest="a" * 64):
    """A frame whose maps step is done: a director map file and plan.json."""
    options = options or RenderOptions(max_spp=16, tile_size=16, resolution=(48, 32), denoise=False)
    files = FrameFiles(tmp_path / "output", 3)
    rng = np.random.default_rng(5)
    director = rng.random((32, 48)).astype(np.float32)
    write_exr(files.maps / "xsl.exr", director, ["Y"])
    inputs = maps_inputs(scene_digest, "Scene", 3, "xsl", MapOptions().to_dict(), options)
    write_plan_record(files, inputs, make_plan(director, options), files.maps / "xsl.exr",
                      {"seconds": {"total": 0.5}})
    return files, inputs


def fake_render(files, record, rect, value):
    pixels = np.full((rect.height, rect.width, 4), value, np.float32)
    return write_tile(files, record, rect, pixels, rect.spp, {"seconds": 0.01, "group": 1})


def test_plan_record_is_valid_only_for_its_inputs_and_intact_map(tmp_path):
    files, inputs = planned_frame(tmp_path)
    assert valid_plan(files, inputs) is not None
    assert valid_plan(files, {**inputs, "frame": 4}) is None
    with open(files.maps / "xsl.exr", "r+b") as stream:          # a damaged map
        stream.seek(-8, 2)
        stream.write(b"\0" * 8)
    assert valid_plan(files, inputs) is None
    with pytest.raises(InputError, match="run the maps step first"):
        composite_frame(files)


def test_tile_records_reject_missing_stale_and_damaged_images(tmp_path):
    files, inputs = planned_frame(tmp_path)
    record = valid_plan(files, inputs)
    rect = record.plan.rects[0]
    assert valid_tile(files, record, rect) is None                         # never rendered
    fake_render(files, record, rect, 0.25)
    assert valid_tile(files, record, rect)["group"] == 1
    pixels, samples, guides = read_tile(files, rect)
    assert guides is None
    assert (pixels == 0.25).all() and (samples == rect.spp).all()
    other = planned_frame(tmp_path / "other", RenderOptions(max_spp=16, tile_size=16, seed=1,
                                                            resolution=(48, 32)))[0]
    other_record = valid_plan(other)
    assert tile_inputs(other_record, rect) != tile_inputs(record, rect)    # the seed decides pixels
    files.tile_image(rect).write_bytes(files.tile_image(rect).read_bytes()[:-10])   # truncated
    assert valid_tile(files, record, rect) is None
    fake_render(files, record, rect, 0.25)
    files.tile_record(rect).unlink()                                      # killed before its record
    assert valid_tile(files, record, rect) is None


def test_composite_assembles_checks_and_skips_when_current(tmp_path):
    files, inputs = planned_frame(tmp_path)
    record = valid_plan(files, inputs)
    rects = record.plan.rects
    for index, rect in enumerate(rects[:-1]):
        fake_render(files, record, rect, float(index))
    with pytest.raises(InputError, match=f"1 of {len(rects)} rectangles have no finished render"):
        composite_frame(files, groups=2)
    assert not files.image.exists()
    fake_render(files, record, rects[-1], float(len(rects) - 1))
    result = composite_frame(files, groups=2)
    assert not result.skipped
    image = read_image(files.image)
    spp = read_image(files.spp_image)[:, :, 0]
    for index, rect in enumerate(rects):
        assert (image[rect.row0:rect.row1, rect.col0:rect.col1] == float(index)).all()
        assert (spp[rect.row0:rect.row1, rect.col0:rect.col1] == rect.spp).all()
    stats = json.loads(files.stats.read_text())
    assert stats["total_samples"] == record.plan.total_samples and stats["renders"] == len(rects)
    assert stats["grouping"]["groups"] == 2 and stats["phases_s"]["maps"] == 0.5
    assert stats["wall_s"] == pytest.approx(sum(stats["phases_s"].values()))
    assert composite_frame(files, groups=2).skipped
    fake_render(files, record, rects[0], 9.0)                              # a rectangle changed
    result = composite_frame(files)
    assert not result.skipped and (read_image(files.image)[rects[0].row0, rects[0].col0] == 9.0).all()


def test_a_guided_frame_is_finished_only_as_a_whole_set_for_its_inputs(tmp_path, monkeypatch):
    from xsl_render.core.farm import frame_outputs
    from xsl_render.core.farm.files import guided_inputs, json_digest
    from xsl_render.core.farm.frame_outputs import (guided_frame_record, valid_frame_outputs,
                                                     write_frame_outputs)

    files = FrameFiles(tmp_path / "output", 7)
    options = RenderOptions(max_spp=64, tile_size=16, resolution=(8, 4))
    inputs = guided_inputs("a" * 64, "Scene", 7, GuidedOptions(time_budget=3.0).to_dict(), None, options)
    samples = np.arange(32, dtype=np.float32).reshape(4, 8)

    def write(inputs, value: float):
        stats = guided_frame_record(inputs, {"mode": "guided", "mean_spp": 15.5, "phases_s": {"final": 1.0}})
        return write_frame_outputs(files, np.full((4, 8, 4), value, np.float32), samples, 31,
                                   {"xsl_render:mode": "guided"}, stats)

    assert valid_frame_outputs(files, json_digest(inputs)) is None            # nothing yet
    stats = write(inputs, 0.5)
    assert stats["wall_s"] == pytest.approx(1.0 + stats["phases_s"]["write"])
    assert valid_frame_outputs(files, json_digest(inputs))["inputs_detail"] == inputs
    assert (read_image(files.image) == 0.5).all() and read_image(files.spp_preview).max() == 1.0
    other = {**inputs, "guided": GuidedOptions(time_budget=4.0).to_dict()}
    assert valid_frame_outputs(files, json_digest(other)) is None              # another budget

    # A task killed while writing its set leaves the finished one as it was, and no debris.
    def killed(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(frame_outputs, "write_png", killed)
    with pytest.raises(KeyboardInterrupt):
        write(other, 0.75)
    monkeypatch.undo()
    assert valid_frame_outputs(files, json_digest(inputs)) is not None
    assert (read_image(files.image) == 0.5).all()
    assert sorted(p.name for p in files.output.iterdir()) == \
        ["frame_0007.exr", "frame_0007.json", "frame_0007_spp.exr", "frame_0007_spp.png"]
    files.image.write_bytes(files.image.read_bytes()[:-16])                      # damaged
    assert valid_frame_outputs(files, json_digest(inputs)) is None


def test_a_chunk_renders_as_runs_of_evenly_spaced_frames():
    from xsl_render.core.frames import frame_runs

    runs = frame_runs((1, 2, 3, 5, 7, 8, 20))
    assert [(r.start, r[-1], r.step) for r in runs] == [(1, 3, 1), (5, 7, 2), (8, 20, 12)]
    assert [list(r) for r in frame_runs((9, 11, 15, 16, 17))] == [[9, 11], [15, 16, 17]]
    assert frame_runs(()) == [] and [list(r) for r in frame_runs((4,))] == [[4]]


def test_a_blender_jobs_task_runs_the_worker_blender_on_its_chunk_with_auto_volumes(tmp_path):
    from xsl_render.core.errors import InputError
    from xsl_render.core.farm.blender_job import BlenderJob, blender_job_template, blender_parameter_values

    job = BlenderJob(scene=tmp_path / "shot.blend", scene_name="Shot", frames="1-250", output="output",
                     device="GPU", frames_per_task=10)
    template = blender_job_template(job)
    step, = template["steps"]
    action = step["script"]["actions"]["onRun"]
    assert action["args"][:4] == ["-b", "{{Param.SceneFile}}", "--python", "{{Task.File.Render}}"]
    assert "{{Task.Param.Frame}}" in action["args"] and "{{Param.AutoVolumes}}" in action["args"]
    assert action["timeout"] == 10 * 12 * 3600 and step["hostRequirements"]
    assert step["parameterSpace"]["taskParameterDefinitions"][0]["type"] == "CHUNK[INT]"
    values = {v["name"]: v["value"] for v in blender_parameter_values(job)["parameterValues"]}
    assert values == {"SceneFile": str(tmp_path / "shot.blend"), "SceneName": "Shot", "Frames": "1-250",
                      "AutoVolumes": "true", "FramesPerTask": 10, "Device": "GPU",
                      "BlenderExecutable": "blender"}                  # OutputDir: the default
    assert not any("value" in p for p in template["parameterDefinitions"])
    for bad in ({"frames": "9-1"}, {"frames_per_task": 0}, {"device": "TPU"}, {"executable": " "}):
        with pytest.raises(InputError):
            BlenderJob(**{**job.__dict__, **bad}).check()
