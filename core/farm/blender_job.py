"""A plain Blender job: an Open Job Description template whose tasks run ``blender -b`` on a
chunk of frames with the xsl_render extension from the worker's Blender and Auto Volumes on.

The default job for an animation (``xsl-render farm``): the file renders as it is set up (its
samples, denoiser, compositor, outputs), every frame with Auto Volumes' choice for its shot,
the same however the frames are chunked (``core.sampling.shot_plan``). One step, ``Render``:
one task per chunk of ``FramesPerTask`` frames (TASK_CHUNKING, as ``job_template``), each a
Blender process that keeps Cycles' session from frame to frame where Auto Volumes finds it
pays. The task runs ``TASK_SCRIPT`` (embedded in the template), which enables the extension
installed in the worker's Blender and hands the chunk to it (``render_chunk`` of the
extension's ``__init__``); a worker without the extension fails the task, saying so.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import SettingError
from ..option_table import DEFAULT_FRAMES_PER_TASK, OPTIONS
from .farm_job import DEFAULT_TASK_TIMEOUT, check_frames_per_task, parse_frames
from .job_parameters import definition, setting_parameter
from .job_template import EXTENSIONS, GPU_HOST_REQUIREMENTS, SPECIFICATION, frame_space, values_of
from .worker_environment import cancelation

#: The Blender command on the farm's machines unless the bundle names one.
BLENDER = "blender"
#: Run by the worker's Blender after it loads the scene: enables the extension and hands it the
#: task's arguments. (Blender exits with the code of ``sys.exit``.)
TASK_SCRIPT = '''\
"""xsl-render farm task of a Blender job: the chunk rendered by the xsl_render extension."""
import sys

import addon_utils

found = [module.__name__ for module in addon_utils.modules()
         if module.__name__.rsplit(".", 1)[-1] == "xsl_render"]
if not found:
    print("xsl-render: error: this Blender has no xsl_render extension installed", file=sys.stderr)
    sys.exit(1)
module = addon_utils.enable(found[0], default_set=False)
if module is None:
    print(f"xsl-render: error: Blender could not enable {found[0]}", file=sys.stderr)
    sys.exit(1)
sys.exit(module.render_chunk(sys.argv[sys.argv.index("--") + 1:]))
'''
_SCENE, _FARM = "Scene", "Farm"


@dataclass(frozen=True)
class BlenderJob:
    """A plain Blender job of one scene, as the bundle's parameter values."""

    scene: Path                     # absolute path of the .blend
    scene_name: str
    frames: str                     # canonical range (parse_frames)
    output: str                     # folder; relative paths are relative to the bundle
    executable: str = BLENDER
    device: str = "CPU"
    auto_volumes: bool = True
    frames_per_task: int = DEFAULT_FRAMES_PER_TASK
    task_timeout: int | None = None

    @property
    def timeout(self) -> int:
        return self.task_timeout if self.task_timeout is not None else DEFAULT_TASK_TIMEOUT * self.frames_per_task

    def check(self) -> "BlenderJob":
        parse_frames(self.frames)
        check_frames_per_task(self.frames_per_task)
        OPTIONS["device"].check(self.device)
        if not self.executable.strip():
            raise SettingError("{executable.name} must not be empty", executable=self.executable)
        return self


def _ui(group: str, label: str, **more) -> dict:
    return {"userInterface": {"label": label, "groupLabel": group, **more}}


def parameters(job: BlenderJob) -> list[dict]:
    """The job's parameter definitions, each with its ``value``."""
    job.check()
    text = {"type": "STRING", "minLength": 1}
    return [
        {"name": "SceneFile", "type": "PATH", "objectType": "FILE", "dataFlow": "IN",
         "description": "The .blend file to render (never written).", "value": str(job.scene),
         **_ui(_SCENE, "Scene file", control="CHOOSE_INPUT_FILE",
               fileFilters=[{"label": "Blender files", "patterns": ["*.blend"]}])},
        {"name": "SceneName", **text, "description": "Which scene of the file to render.",
         "default": job.scene_name, "value": job.scene_name, **_ui(_SCENE, "Scene")},
        {"name": "Frames", **text, "description": "Frames to render: 12, 1-250, 1-250:2 or a list "
         "such as 1-3,8.", "default": job.frames, "value": job.frames, **_ui(_SCENE, "Frames")},
        {"name": "OutputDir", "type": "PATH", "objectType": "DIRECTORY", "dataFlow": "OUT",
         "description": "Folder for frame_NNNN in the file's own output format (its compositor's "
                        "File Output nodes write where the file says).",
         **({} if Path(job.output).is_absolute() else {"default": job.output}), "value": job.output,
         **_ui(_SCENE, "Output folder", control="CHOOSE_DIRECTORY")},
        {"name": "AutoVolumes", "type": "STRING", "description": "Render with Auto Volumes' choice "
         "(true), or with the file's own volume settings (false).", "default": _flag(job.auto_volumes),
         "value": _flag(job.auto_volumes), "allowedValues": ["true", "false"],
         **_ui(_SCENE, "Auto Volumes", control="CHECK_BOX")},
        setting_parameter("frames_per_task", job.frames_per_task, _FARM),
        setting_parameter("device", job.device, _FARM,
                          description=f"{OPTIONS['device'].help}. The step's host requirements were "
                          "fixed with the bundle: write it again to change device."),
        {"name": "BlenderExecutable", **text, "description": "The Blender command on the farm's "
         "machines, with the xsl_render extension installed.", "default": job.executable,
         "value": job.executable, **_ui(_FARM, "Blender executable")},
    ]


def _flag(value: bool) -> str:
    return "true" if value else "false"


def blender_job_template(job: BlenderJob) -> dict:
    """The job template as plain data (dump it as YAML or JSON)."""
    definitions = [definition(p) for p in parameters(job)]
    step = {"name": "Render", "description": "Each task renders a chunk of frames with Blender, "
            "Auto Volumes choosing each shot's volume settings.", "parameterSpace": frame_space(),
            "script": {"actions": {"onRun": {
                "command": "{{Param.BlenderExecutable}}",
                "args": ["-b", "{{Param.SceneFile}}", "--python", "{{Task.File.Render}}", "--",
                         "--scene-name", "{{Param.SceneName}}", "--frames", "{{Task.Param.Frame}}",
                         "--output", "{{Param.OutputDir}}", "--device", "{{Param.Device}}",
                         "--auto-volumes", "{{Param.AutoVolumes}}"],
                "timeout": job.timeout, "cancelation": cancelation()}},
                "embeddedFiles": [{"name": "Render", "type": "TEXT", "filename": "xsl_render_chunk.py",
                                   "data": TASK_SCRIPT}]}}
    if job.device == "GPU":
        step["hostRequirements"] = GPU_HOST_REQUIREMENTS
    return {"specificationVersion": SPECIFICATION, "extensions": list(EXTENSIONS),
            "name": "Blender {{Param.SceneName}} frames {{Param.Frames}}",
            "description": "The file rendered by Blender as it is set up, with the xsl_render "
                           "extension's Auto Volumes.",
            "parameterDefinitions": definitions, "steps": [step]}


def blender_parameter_values(job: BlenderJob) -> dict:
    """``parameter_values.yaml``, as ``job_template.parameter_values``."""
    return values_of(parameters(job))
