"""The job environment that gives a farm worker ``xsl-render`` (Blender as ``bpy`` included).

Its ``onEnter`` runs once per session, before the first task, ``core/farm/worker_setup.py``
(embedded in the template) with the job's parameters: ``WorkerSetup`` (none: installed and on
PATH; pip or conda: an environment built with Python 3.11), ``WorkerRequirements`` (the pinned
file written into the bundle), ``XslRenderPackage`` (a pip requirement for this package) and
``WorkerCache`` (where environments are kept between sessions). The environment's folder goes
first on PATH, so the tasks' ``{{Param.XslRender}}`` is the installed one."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import SettingError
from .worker_requirements import FILE_NAME as REQUIREMENTS_FILE
from .worker_setup import SETUPS

SCRIPT = Path(__file__).with_name("worker_setup.py")
GROUP = "Worker setup"
#: Installing bpy (about 350 MB) and scipy on a slow link; a reused environment takes a second.
SETUP_TIMEOUT = 3600
#: Seconds a cancelled action gets between SIGTERM and SIGKILL: xsl-render answers SIGTERM
#: at once (operators/signals.py), after a set of renames under way; pip needs a moment.
NOTIFY_PERIOD = 30


@dataclass(frozen=True)
class WorkerSetup:
    """How a worker gets xsl-render: the job environment's parameter values."""

    setup: str = "none"
    package: str = "xsl-render==0.1.0"     # a name on the worker's index, a wheel path or URL
    python: str = "python3"
    cache: str = "auto"

    def check(self) -> "WorkerSetup":
        if self.setup not in SETUPS:
            raise SettingError(f"{{setup.name}} must be one of {', '.join(SETUPS)} "
                               "(got '{setup.value}')", setup=self.setup)
        for name in ("package", "python", "cache"):
            value = getattr(self, name)
            if not value.strip():
                raise SettingError(f"{{{name}.name}} must not be empty", **{name: value})
        return self


def cancelation() -> dict:
    return {"mode": "NOTIFY_THEN_TERMINATE", "notifyPeriodInSeconds": NOTIFY_PERIOD}


def worker_parameters(worker: WorkerSetup) -> list[dict]:
    """Parameter definitions (with ``value`` and ``flag`` None, as ``job_template`` keeps them)."""
    def ui(label: str, **more) -> dict:
        return {"userInterface": {"label": label, "groupLabel": GROUP, **more}}

    def text(name: str, value: str, description: str, label: str) -> dict:
        return {"name": name, "type": "STRING", "description": description, "default": value,
                "value": value, "minLength": 1, "flag": None, **ui(label)}

    return [
        {"name": "WorkerSetup", "type": "STRING", "description": "How a worker gets xsl-render: "
         "none (installed by its owner, on PATH), pip (a Python 3.11 virtual environment) or "
         "conda (a conda environment); pip and conda install WorkerRequirements, then "
         "XslRenderPackage, once per worker.", "default": worker.setup, "value": worker.setup,
         "allowedValues": list(SETUPS), "flag": None, **ui("Setup", control="DROPDOWN_LIST")},
        {"name": "WorkerRequirements", "type": "PATH", "objectType": "FILE", "dataFlow": "IN",
         "description": "Pinned requirements (Blender as bpy, numpy, scipy, ...): the versions "
                        "the bundle was written with.", "default": REQUIREMENTS_FILE,
         "value": REQUIREMENTS_FILE, "flag": None, **ui("Requirements", control="CHOOSE_INPUT_FILE")},
        text("XslRenderPackage", worker.package, "The xsl-render package as a pip requirement "
             "the worker can reach: a wheel's path or URL, git+https://..., or a name on its "
             "package index.", "xsl-render package"),
        text("WorkerPython", worker.python, "The Python that runs the setup (pip: must be "
             "3.11, bpy's wheels are cp311).", "Python"),
        text("WorkerCache", worker.cache, "Folder for the environments, reused between "
             "sessions; auto: ~/.cache/xsl-render/worker-envs.", "Environment cache"),
    ]


def job_environment() -> dict:
    """The ``jobEnvironments`` entry: the setup script embedded, run by ``WorkerPython``."""
    return {
        "name": "XslRenderWorker",
        "description": "Makes xsl-render (with Blender as bpy) available on the worker: "
                       "checks it (WorkerSetup none) or installs it with pip or conda.",
        "script": {
            "actions": {"onEnter": {
                "command": "{{Param.WorkerPython}}",
                "args": ["{{Env.File.Setup}}", "--setup", "{{Param.WorkerSetup}}",
                         "--executable", "{{Param.XslRender}}",
                         "--requirements", "{{Param.WorkerRequirements}}",
                         "--package", "{{Param.XslRenderPackage}}", "--cache", "{{Param.WorkerCache}}"],
                "timeout": SETUP_TIMEOUT, "cancelation": cancelation()}},
            "embeddedFiles": [{"name": "Setup", "type": "TEXT", "filename": "xsl_render_worker_setup.py",
                               "data": SCRIPT.read_text(encoding="utf-8")}],
        },
    }
