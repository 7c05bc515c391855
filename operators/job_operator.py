"""Running a job (``jobs.py``) from an operator: modally in the interface, in one go otherwise.

Clicked in the panel, a window timer advances the job one step per tick (a map, a tile, a band
of the gold render), so Blender redraws, shows the progress and reads ESC, which closes the job
and puts every setting back; navigation passes through, edits wait. From a script or ``blender
-b`` the whole job runs before the call returns. Bad input is one ERROR report naming settings
by their panel labels, a cancel one WARNING; only a bug of ours prints a traceback (with
``XSL_DEBUG=1``)."""
from __future__ import annotations

import os
import traceback
import warnings

import bpy

from ..addon.panel.setting_labels import in_panel_words
from ..core.errors import Cancelled, InputError
from ..core.progress import StepRunner, run_steps
from .jobs import Job, JobResult

#: Events that reach the rest of Blender while a job runs: looking around, not editing.
# (Blender itself postpones autosave while a modal operator runs, so the borrowed settings
# never reach an autosave file.)
_PASS_THROUGH = {"MOUSEMOVE", "INBETWEEN_MOUSEMOVE", "WHEELUPMOUSE", "WHEELDOWNMOUSE", "MIDDLEMOUSE",
                 "TRACKPADPAN", "TRACKPADZOOM", "NDOF_MOTION", "WINDOW_DEACTIVATE", "TIMER",
                 "TIMER0", "TIMER1", "TIMER2", "TIMER_JOBS", "TIMER_AUTOSAVE", "TIMER_REPORT",
                 "TIMERREGION"}
_TICK_SECONDS = 0.02

#: The one job running (XSL jobs borrow the scene's render settings, so one at a time).
_running: dict = {"label": None}


def running_label() -> str | None:
    return _running["label"]


def render_job_running() -> bool:
    """Blender's own render (F12) or bake is running: Cycles is busy, our renders must wait."""
    is_running = getattr(bpy.app, "is_job_running", None)
    return bool(is_running is not None and (is_running("RENDER") or is_running("OBJECT_BAKE")))


def busy_reason() -> str | None:
    if _running["label"]:
        return f"XSL Render is busy ({_running['label']}): wait, or press ESC to cancel it"
    if render_job_running():
        return "A render is running: wait for it to finish"
    return None


def scene_problem(context, need_camera: bool = True) -> str | None:
    """Why the scene cannot be rendered by XSL Render (None if it can)."""
    scene = getattr(context, "scene", None)
    if scene is None:
        return "There is no scene"
    if scene.render.engine != "CYCLES":
        return (f"The render engine is {scene.render.engine.replace('BLENDER_', '').title()}: "
                "XSL Render drives Cycles (set Render Engine to Cycles)")
    if need_camera and scene.camera is None:
        return "The scene has no active camera"
    if need_camera and scene.camera.type != "CAMERA":
        return f"The active camera '{scene.camera.name}' is not a camera object"
    return busy_reason()


def _status(context):
    return getattr(context.window_manager, "xsl_render_status", None)


class JobOperator:
    """Mixin for ``bpy.types.Operator`` subclasses: define ``make_job(context) -> Job``."""

    bl_options = {"REGISTER"}
    #: Set by the operator class: does poll() need a camera and Cycles.
    needs_scene = True

    @classmethod
    def problem(cls, context) -> str | None:
        return scene_problem(context) if cls.needs_scene else busy_reason()

    @classmethod
    def poll(cls, context):
        problem = cls.problem(context)
        if problem:
            cls.poll_message_set(problem)
            return False
        return True

    def make_job(self, context, modal: bool) -> Job:
        """The job this operator runs; every concrete operator defines it (bpy's operator
        metaclass does not combine with abc's, hence no @abstractmethod)."""
        raise NotImplementedError(f"{type(self).__name__} defines no job")

    # -- in one go ---------------------------------------------------------------------------
    def execute(self, context):
        job = self._start(context, modal=False)
        if job is None:
            return {"CANCELLED"}
        bar = None
        if bpy.app.background:
            from .progress_bar import ProgressBar

            bar = ProgressBar(job.label)
        notes: list[str] = []
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                result = run_steps(job.steps, bar)
            notes = [str(w.message) for w in caught]
            return self._finish(context, job, result, notes)
        except BaseException as error:          # noqa: B036 - Cancelled is a KeyboardInterrupt
            return self._failed(context, job, error)
        finally:
            if bar is not None:
                bar.close()
            _running["label"] = None

    # -- modal -------------------------------------------------------------------------------
    def in_one_go(self, context) -> bool:
        """No window to keep responsive (``blender -b``): run as ``execute`` does."""
        return bpy.app.background or context.window is None

    def invoke(self, context, event):
        if self.in_one_go(context):
            return self.execute(context)
        job = self._start(context, modal=True)
        if job is None:
            return {"CANCELLED"}
        self._job, self._runner, self._notes = job, StepRunner(job.steps), []
        wm = context.window_manager
        self._timer = wm.event_timer_add(_TICK_SECONDS, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0.0, 1.0)
        self._show_progress(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self._runner.cancel()
            self._end_modal(context)
            message = f"{self._job.label} cancelled; the scene is as it was"
            self.report({"WARNING"}, message)
            self._set_status(context, message)
            return {"CANCELLED"}
        if event.type == "TIMER":
            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    done = self._runner.advance()
                self._notes += [str(w.message) for w in caught]
            except BaseException as error:      # noqa: B036
                self._end_modal(context)
                self._failed(context, self._job, error)
                return {"CANCELLED"}
            if done:
                result = self._runner.result
                self._end_modal(context)
                return self._finish(context, self._job, result, self._notes)
            self._show_progress(context)
            return {"PASS_THROUGH"}
        return {"PASS_THROUGH"} if event.type in _PASS_THROUGH else {"RUNNING_MODAL"}

    def cancel(self, context):
        # Blender ends the operator (window closed, file loaded): close the job cleanly.
        runner = getattr(self, "_runner", None)
        if runner is not None:
            runner.cancel()
            self._end_modal(context)

    # -- shared ------------------------------------------------------------------------------
    def _start(self, context, modal: bool) -> Job | None:
        problem = self.problem(context)
        if problem:                                 # poll() passed but the state changed
            self.report({"ERROR"}, problem)
            return None
        try:
            job = self.make_job(context, modal)
        except InputError as error:
            self.report({"ERROR"}, in_panel_words(error))
            return None
        _running["label"] = job.label
        status = _status(context)
        if status is not None:
            status.running, status.label, status.fraction, status.message = True, job.label, 0.0, "starting"
        return job

    def _show_progress(self, context) -> None:
        runner = self._runner
        context.window_manager.progress_update(runner.fraction)
        text = f"{self._job.label}: {runner.message} ({100 * runner.fraction:.0f}%), ESC to cancel"
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        status = _status(context)
        if status is not None:
            status.fraction, status.message = runner.fraction, runner.message
        _redraw(context)

    def _end_modal(self, context) -> None:
        wm = context.window_manager
        if getattr(self, "_timer", None) is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        _running["label"] = None
        self._runner = None

    def _finish(self, context, job: Job, result, notes: list[str]):
        try:
            outcome: JobResult = job.finish(result)
        except BaseException as error:          # noqa: B036
            return self._failed(context, job, error)
        for note in dict.fromkeys(notes + outcome.warnings):
            self.report({"WARNING"}, note)
        self.report({"INFO"}, outcome.report)
        self._set_status(context, outcome.report)
        if outcome.image is not None and context.screen is not None:
            from ..addon.panel.image_display import show_in_image_editors

            show_in_image_editors(context.screen, outcome.image)
        return {"FINISHED"}

    def _failed(self, context, job: Job, error: BaseException):
        if isinstance(error, InputError):
            message = in_panel_words(error)
        elif isinstance(error, (Cancelled, KeyboardInterrupt)):
            message = f"{job.label} cancelled; the scene is as it was"
            self.report({"WARNING"}, message)
            self._set_status(context, message)
            return {"CANCELLED"}
        else:
            if os.environ.get("XSL_DEBUG"):
                traceback.print_exception(error)
            first = str(error).strip().splitlines()[0] if str(error).strip() else ""
            message = f"{job.label} failed: {type(error).__name__}: {first} (set XSL_DEBUG=1 for details)"
        self.report({"ERROR"}, message)
        self._set_status(context, message)
        return {"CANCELLED"}

    @staticmethod
    def _set_status(context, text: str) -> None:
        status = _status(context)
        if status is not None:
            status.running, status.fraction, status.message, status.last_report = False, 0.0, "", text
        _redraw(context)


def _redraw(context) -> None:
    screen = getattr(context, "screen", None)
    if screen is None:
        return
    for area in screen.areas:
        if area.type in ("PROPERTIES", "IMAGE_EDITOR"):
            area.tag_redraw()
