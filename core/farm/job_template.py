"""An Open Job Description job template (specification 2023-09) for a selective or guided render.

Every step's tasks take a *chunk* of frames (the TASK_CHUNKING extension: ``Frame`` is a
``CHUNK[INT]`` task parameter, ``{{Task.Param.Frame}}`` a frame list such as ``1-8`` or
``9,11,15-17``) and render them in one Blender process: the scene is opened once and Cycles
syncs it once per chunk (heterogeneous fog's volume octree, 3.5 s on balls_b), not once per
frame. The chunk size is the job parameter ``FramesPerTask``; the chunks are NONCONTIGUOUS (the
next frames of the list whatever their gaps: a CONTIGUOUS chunk never spans a gap, so every
chunk of ``1-250:2`` would hold one frame). A task keeps each frame as soon as it is done and
skips the frames a rerun finds done.

A selective job (``xs``, ``xsl``: the paper) has three steps, each a command of the
``xsl-render`` executable:

1. ``Maps`` — one task per chunk: the director maps of each frame and its tile plan
   (``xsl-render farm-task maps``);
2. ``Tiles`` — Frame chunk x Group tasks, ``Group`` = 1..TasksPerFrame: each task renders its
   share of the rectangles of every frame of its chunk, in one Cycles session, split so that
   the tasks of a frame cost about the same (``core.farm.task_groups``; the plan only exists
   once the maps are computed, so the template fixes the number of tasks, not the
   rectangles). A group's share of one frame is independent of its share of the next, so a
   task renders them one frame after the other, and every tile task of a chunk pays the
   scene sync once instead of once per frame. Depends on Maps;
3. ``Composite`` — one task per chunk: the final EXR and samples-per-pixel image of each
   frame. It renders nothing, but each task is a process that loads Blender (for its
   denoiser) and a task for the farm to schedule. Depends on Maps and Tiles.

A guided job (``xsl-render render --mode guided``) has one step, ``Render``: one task per
chunk renders its frames one after another within the time budget per frame, sharing the
chunk's time as ``render --frames`` does (``xsl-render farm-task guided``). A frame's passes
follow the clock of one process, so a frame is not split between tasks; frames are.

Every knob is a job parameter (a farm's submitter shows them as a form; the values chosen
are recorded with the job): the scene file (a PATH, so the farm can map it between machines),
the scene in it, the frames (an Open Job Description range expression such as ``1-250``,
``1-99:2`` or ``1-3,8``; ``core.frames`` reads the same text) and how many a task renders,
the output folder, the paper's map options, the tile options of ``xsl-render render`` and
the number of tile tasks per frame (selective) or the time budget and the guided sampler's
options (guided), the Cycles device, the ``xsl-render`` command (found on the worker's PATH
unless the bundle names one) and how a worker gets it (``core.farm.worker_environment``, the
job environment).

Every action is cancelled NOTIFY_THEN_TERMINATE (xsl-render removes its temporaries on
SIGTERM and exits 143; a kill follows after ``NOTIFY_PERIOD``) and has a timeout: a frame's
allowance (derived from the time budget for a guided frame, ``DEFAULT_TASK_TIMEOUT``
otherwise) times the bundle's frames per task, or ``task_timeout``. The steps that render
with Cycles (Maps: its snapshot; Tiles; Render) ask for a GPU in ``hostRequirements`` when
the job renders on one. The timeout and the requirement are fixed when the bundle is
written, so FramesPerTask (far up) and Device should be changed by writing the bundle again.
"""
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
