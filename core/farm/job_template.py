"""An Open Job Description job template (specification 2023-09) for a selective or guided render.

Every step's tasks take a chunk of frames (TASK_CHUNKING: ``Frame`` is a ``CHUNK[INT]``,
NONCONTIGUOUS so that ``1-250:2`` still chunks) and render them in one Blender process, the
scene synced once per chunk. A selective job has steps Maps (maps and tile plan per frame),
Tiles (``TasksPerFrame`` tasks each rendering an equal-cost share of every frame's
rectangles, ``core.farm.task_groups``) and Composite; a guided job one step, Render, a frame
never split between tasks. Every knob is a job parameter (``core.farm.job_parameters``).
Actions are cancelled NOTIFY_THEN_TERMINATE and time out after a frame's allowance times the
frames per task; rendering steps ask for a GPU when the job renders on one (both fixed when
the bundle is written)."""
from __future__ import annotations

from pathlib import Path

from ..option_table import DEVICES  # noqa: F401
from .farm_job import (DEFAULT_TASK_TIMEOUT, EXECUTABLE, MODES,  # noqa: F401
                       SELECTIVE_MODES, FarmJob, guided_timeout, parse_frames)
from .job_parameters import checked_parameters, definition, task_arguments
from .worker_environment import cancelation, job_environment

SPECIFICATION = "jobtemplate-2023-09"
#: Open Job Description extensions the template uses (a farm must support them).
EXTENSIONS = ["TASK_CHUNKING"]
#: What a step that renders with Cycles asks of a worker when the job renders on the GPU
#: (Open Job Description's standard amount capability; a farm maps it to its fleets).
GPU_HOST_REQUIREMENTS = {"amounts": [{"name": "amount.worker.gpu", "min": 1}]}


def _action(job: FarmJob, *args: str) -> dict:
    return {"onRun": {"command": "{{Param.XslRender}}", "args": ["farm-task", *args],
                      "timeout": job.timeout, "cancelation": cancelation()}}


def frame_space(**more) -> dict:
    """Chunks of ``FramesPerTask`` frames of the job's frames, times the INT ranges ``more``."""
    definitions = [{"name": "Frame", "type": "CHUNK[INT]", "range": "{{Param.Frames}}",
                    "chunks": {"defaultTaskCount": "{{Param.FramesPerTask}}",
                               "rangeConstraint": "NONCONTIGUOUS"}}]
    for name, value_range in more.items():
        definitions.append({"name": name, "type": "INT", "range": value_range})
    return {"taskParameterDefinitions": definitions}


def _step(job: FarmJob, name: str, description: str, space: dict, *args: str, renders: bool,
          after: tuple[str, ...] = ()) -> dict:
    """A step whose tasks run ``xsl-render farm-task *args``; ``renders``: with Cycles."""
    step = {"name": name, "description": description, "parameterSpace": space,
            "script": {"actions": _action(job, *args)}}
    if renders and job.device == "GPU":
        step["hostRequirements"] = GPU_HOST_REQUIREMENTS
    if after:
        step["dependencies"] = [{"dependsOn": other} for other in after]
    return step


def _job(job: FarmJob, parameters: list[dict], name: str, description: str, steps: list[dict]) -> dict:
    return {"specificationVersion": SPECIFICATION, "extensions": list(EXTENSIONS), "name": name,
            "description": description,
            "parameterDefinitions": [definition(p) for p in parameters],
            "jobEnvironments": [job_environment()], "steps": steps}


def job_template(job: FarmJob) -> dict:
    """The job template as plain data (dump it as YAML or JSON)."""
    parameters = checked_parameters(job)
    frame = ["--frames", "{{Task.Param.Frame}}", "--output", "{{Param.OutputDir}}"]
    if job.traits.time_budget:
        return _job(job, parameters, "xsl-render guided {{Param.SceneName}} frames {{Param.Frames}}",
                    "Rendering of participating media with Blender Cycles within a time budget per "
                    "frame: a pilot pass, the rest of the budget where the denoised frame keeps its "
                    "error (xsl-render render --mode guided).", [
                        _step(job, "Render", "Each task renders a chunk of frames in one Blender process, "
                              "within the time budget per frame.",
                              frame_space(), "guided", "{{Param.SceneFile}}", *frame,
                              *task_arguments(parameters), renders=True)])
    groups = "{{Param.TasksPerFrame}}"
    return _job(job, parameters, "xsl-render {{Param.SceneName}} frames {{Param.Frames}}",
                "Perceptual selective rendering of participating media (Sundstedt et al. 2007) "
                "with Blender Cycles: director maps, tile renders, composite.", [
                    _step(job, "Maps", "Director maps and the tile plan of each frame of a chunk.",
                          frame_space(), "maps", "{{Param.SceneFile}}", *frame, *task_arguments(parameters),
                          renders=True),
                    _step(job, "Tiles", "Each task renders its share of the rectangles of each frame "
                          "of a chunk, in one Cycles session.",
                          {**frame_space(Group=f"1-{groups}"), "combination": "Frame * Group"},
                          "tiles", "{{Param.SceneFile}}", *frame, "--group", "{{Task.Param.Group}}",
                          "--groups", groups, "--device", "{{Param.Device}}", renders=True,
                          after=("Maps",)),
                    _step(job, "Composite", "The final image and samples-per-pixel image of each "
                          "frame of a chunk.", frame_space(), "composite", *frame, "--groups", groups,
                          renders=False, after=("Maps", "Tiles"))])


def parameter_values(job: FarmJob) -> dict:
    """``parameter_values.yaml`` of the job bundle, in the layout AWS Deadline Cloud reads.

    A relative PATH is left out: its template default is resolved against the bundle folder
    (by Deadline Cloud and ``openjd`` alike), where a relative *value* would be resolved
    against whatever folder the job is submitted or run from.
    """
    return values_of(checked_parameters(job))


def values_of(parameters: list[dict]) -> dict:
    """``parameter_values.yaml`` of parameters with their ``value`` (see ``parameter_values``)."""
    return {"parameterValues": [{"name": p["name"], "value": p["value"]} for p in parameters
                                if not (p["type"] == "PATH" and not Path(p["value"]).is_absolute())]}


def openjd_values(values: dict) -> dict:
    """``parameter_values`` as the mapping ``openjd run --job-param`` takes (name -> value)."""
    return {entry["name"]: entry["value"] for entry in values["parameterValues"]}
