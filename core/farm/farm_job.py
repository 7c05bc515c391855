"""A farm job of one scene as plain data: what the bundle renders and how (``FarmJob``).

``core.farm.job_parameters`` turns it into the job's parameters, ``core.farm.job_template``
into the Open Job Description template; both check it first (``FarmJob.check``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError, SettingError
from ..frames import frame_expression
from ..maps.options import MapOptions
from ..option_table import DEFAULT_FRAMES_PER_TASK, MAX_TIME_BUDGET, OPTIONS
from ..sampling.guided_plan import GuidedOptions
from ..sampling.render_options import RenderOptions
from ..sampling.render_request import MODE_TRAITS, SELECTIVE_MODES, ModeTraits, RenderRequest  # noqa: F401
from .task_groups import check_groups
from .worker_environment import WorkerSetup

#: The modes a farm renders: those that plan their frame themselves (a selective one's tiles
#: are tasks of their own; a time budget's frame is one task).
MODES = tuple(mode for mode, traits in MODE_TRAITS.items() if traits.director_map or traits.time_budget)
#: MaxSpp of a guided job without a per-pixel ceiling. An INT parameter cannot be empty, and
#: 0 samples per pixel means nothing else, so the farm's form can still check the number.
NO_CEILING = 0
#: The shortest time budget a guided job takes: a job parameter's minimum is inclusive, and
#: the budget must be more than 0 (nothing renders in a millisecond; the bound only keeps the
#: form's check honest).
MIN_FARM_TIME_BUDGET = 0.001
#: The task command when the bundle names none: whatever the worker's PATH finds.
EXECUTABLE = "xsl-render"
#: A selective task's timeout per frame of its chunk unless --task-timeout says otherwise: a
#: frame's maps or a share of its tiles at film resolution take minutes; twelve hours catches
#: only a hang.
DEFAULT_TASK_TIMEOUT = 12 * 3600
#: A guided frame's timeout is its budget plus this (Blender starting, the .blend loading,
#: the volumes' octree, the files written) plus the budget again, in case the machine is slow.
GUIDED_OVERHEAD = 900


def parse_frames(text: str) -> str:
    """'12', '1-250', '1-250:2' or a list '1-3,8' -> its canonical form; InputError otherwise."""
    return frame_expression(text)


def guided_timeout(time_budget: float) -> int:
    """Seconds a guided frame may take: twice its budget and a fixed allowance."""
    return int(math.ceil(2 * time_budget)) + GUIDED_OVERHEAD


def check_frames_per_task(count: int) -> int:
    """``count`` if it is a sensible number of frames per task, else InputError."""
    return OPTIONS["frames_per_task"].check(count)


@dataclass(frozen=True)
class FarmJob:
    """Everything a farm job of one scene renders, as the bundle's parameter values."""

    scene: Path                     # absolute path of the .blend
    scene_name: str
    frames: str                     # canonical range (parse_frames)
    output: str                     # folder; relative paths are relative to the bundle
    mode: str
    map_options: MapOptions
    options: RenderOptions          # its resolution must be set (the farm never guesses)
    tasks_per_frame: int            # tile tasks per frame (selective; a guided frame is one task)
    executable: str = EXECUTABLE    # the xsl-render command on the farm's machines
    guided: GuidedOptions | None = None     # the time budget and its options (guided only)
    device: str = "CPU"             # the Cycles device of every render
    task_timeout: int | None = None     # seconds a task; None: a frame's allowance x frames_per_task
    worker: WorkerSetup = field(default_factory=WorkerSetup)
    frames_per_task: int = DEFAULT_FRAMES_PER_TASK     # frames a task renders in one process

    @property
    def timeout(self) -> int:
        """Seconds each task may run before the farm cancels it: ``task_timeout``, else a
        frame's allowance times ``frames_per_task`` (a chunk of that many frames)."""
        if self.task_timeout is not None:
            return self.task_timeout
        if self.traits.time_budget and self.guided is not None:
            return guided_timeout(self.guided.time_budget) * self.frames_per_task
        return DEFAULT_TASK_TIMEOUT * self.frames_per_task

    @property
    def traits(self) -> ModeTraits:
        return MODE_TRAITS.get(self.mode, ModeTraits())

    def check(self) -> "FarmJob":
        if self.mode not in MODES:
            raise SettingError(f"{{mode.name}} must be one of {', '.join(MODES)} for a farm job "
                               "(got '{mode.value}')", mode=self.mode)
        if self.options.resolution is None:
            raise InputError("a farm job needs its resolution fixed")
        width, height = self.options.resolution
        # The render each task makes, checked as every front end's is.
        RenderRequest(self.mode, self.options, guided=self.guided, map_options=self.map_options).check()
        self.options.check_frame(width, height)
        self.map_options.validate()
        check_groups(self.tasks_per_frame)
        check_frames_per_task(self.frames_per_task)
        parse_frames(self.frames)
        OPTIONS["device"].check(self.device)
        if self.task_timeout is not None and not 1 <= self.task_timeout <= MAX_TIME_BUDGET:
            raise SettingError(f"{{task_timeout.name}} must be between 1 and {MAX_TIME_BUDGET} "
                               "seconds (got {task_timeout.value})", task_timeout=self.task_timeout)
        if not self.executable.strip():
            raise SettingError("{executable.name} must not be empty", executable=self.executable)
        self.worker.check()
        return self
