"""Auto Volumes: every final render of a scene with the setting on (F12, Ctrl+F12, scripts,
``blender -b -f`` / ``-a``) renders its media with auto's choice for the frame's shot, and
the artist's settings come back after every frame.

Through Blender's render handlers (their order, and what Cycles sees: docs/auto_volumes.md):
``render_init`` keeps Cycles' session between frames where the media stand still and memory
allows; ``render_pre`` applies the shot's choice (``addon.maps.shot_choice``) before Blender
builds the frame's depsgraph and records it in the frame's EXR header and the log;
``render_post`` / ``render_complete`` / ``render_cancel`` put everything back. Whatever fails
leaves the frame to render with the artist's settings and a warning; from the interface it
acts only with Render › Lock Interface on."""
from __future__ import annotations

import sys
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

from ..core.checks import available_memory, process_memory
from ..core.sampling.sample_pattern import auto_sample_pattern, needs_debug_options
from ..core.sampling.shot_plan import shot_of
from .cycles.own_renders import rendering_own
from .cycles.sample_pattern import enable_debug_patterns
from .cycles.selective_render import apply_estimator
from .cycles.volume_settings import unsupported
from .maps import shot_choice
from .scene.animation import has_media, media_move
from .scene.changes import ChangeRecord

#: Keep Cycles' session between frames only while the machine has this many times the memory
#: Blender holds free (the kept session holds about one frame's render data, which a scene's
#: evaluated copy bounds; a rule of thumb, not a measurement).
MEMORY_HEADROOM = 2.0
LOCK_INTERFACE = ("Auto Volumes needs Render › Performance › Lock Interface for a render started "
                  "from the interface (Blender lets a render change settings only then); this "
                  "render uses the file's own volume settings")


@dataclass
class _Job:
    """One render job of one scene: ``record`` what lasts it (Blender's debug preferences a
    debug sample pattern needs while Cycles creates its session, persistent data), ``frame``
    what auto sets for the frame being rendered; both restore by what they changed
    (``addon.scene.changes``)."""

    record: ChangeRecord
    kept_before: bool                       # the artist's persistent data: a session may be kept
    keeps: bool                             # this render keeps its session between frames
    shots: dict = field(default_factory=dict)       # (first, last) -> ShotChoice, or the error
    frame: ChangeRecord | None = None       # the frame's settings while auto's are applied
    synced: object = None                   # the choice the kept session last synced
    changed: list = field(default_factory=list)     # datablocks the render changed
    tagged: bool = False


_jobs: dict[int, _Job] = {}
#: Scenes (their pointers) Auto Volumes renders whatever their setting says (the command
#: line's ``render`` without --mode): ``forced``.
_forced: dict[int, bool] = {}
#: The last shot choice each scene (its pointer) rendered with, for what reports on a render.
last_plans: dict[int, object] = {}
#: The last warning printed (for scripts and tests that look at it).
last_warning = ""


def enabled(scene) -> bool:
    forced = _forced.get(scene.as_pointer())
    if forced is not None:
        return forced
    settings = getattr(scene, "xsl_render", None)
    return bool(getattr(settings, "auto_volumes", False))


@contextmanager
def forced(scene, on: bool = True):
    """A block in which Blender's renders of ``scene`` use Auto Volumes (``on``) or not,
    whatever its setting, and the handlers are registered (where the extension is not)."""
    import bpy

    key = scene.as_pointer()
    registered = _on_render_pre in bpy.app.handlers.render_pre
    if not registered:
        register()
    _forced[key] = on
    try:
        yield
    finally:
        _forced.pop(key, None)
        if not registered:
            unregister()


def current_choice(scene):
    """Auto Volumes' choice (a ``ShotChoice``) for the scene's current frame, as its render
    would make it."""
    return shot_choice.choose_for_shot(scene, shot_of(scene.frame_current, *shot_choice.shot_range(scene)))


def apply_to_scene(scene) -> tuple[object, str]:
    """Write the current frame's choice into the scene's own settings (for renders without
    this extension) and turn Auto Volumes off: the file carries the choice now, and auto on
    top of it would scale the media's own steps again. A sample pattern Cycles renders only
    with Blender's debug options is left out (a file cannot carry them). Returns the plan
    and what was left out ("" for nothing)."""
    import bpy

    plan = current_choice(scene)
    choice, left_out = plan.choice, ""
    if choice.sample_pattern is not None and needs_debug_options(choice.sample_pattern):
        choice, left_out = replace(choice, sample_pattern=None), "the sample pattern stays the file's"
    # Through a record that is never restored: what Apply to Scene writes stays (and a
    # medium linked from a library is left as it is).
    apply_estimator(scene, choice, ChangeRecord())
    for datablock in (scene, scene.world, *bpy.data.materials):
        if datablock is not None:
            datablock.update_tag()          # add-on properties do not tag: the viewport would keep the old
    scene.xsl_render.auto_volumes = False
    return replace(plan, choice=choice), left_out


def _warn(scene, message: str) -> None:
    global last_warning
    last_warning = f"{scene.name}: {message}"
    print(f"Auto Volumes: warning: {last_warning}", file=sys.stderr, flush=True)


def _may_change_data(scene) -> bool:
    return threading.current_thread() is threading.main_thread() or scene.render.use_lock_interface


def _keeps_session(scene) -> bool:
    """Whether to keep Cycles' session between frames: the file does not already, it has
    media, they stand still (moving media are rebuilt every frame anyway), memory allows."""
    if scene.render.use_persistent_data or not has_media(scene) or media_move(scene):
        return False
    free, held = available_memory(), process_memory()
    return free is not None and held is not None and free >= MEMORY_HEADROOM * held


def _start(scene) -> None:
    key = scene.as_pointer()
    if key in _jobs:                # a job whose end never came (Blender stopped in between)
        _finish(scene)
    if rendering_own() or not enabled(scene):
        return
    reason = unsupported()
    if reason:
        _warn(scene, f"{reason}; the render uses the file's own volume settings")
        return
    if not _may_change_data(scene):
        _warn(scene, LOCK_INTERFACE)
        return
    job = _Job(ChangeRecord(), kept_before=scene.render.use_persistent_data, keeps=False)
    _jobs[key] = job
    if needs_debug_options(auto_sample_pattern(scene.cycles.sampling_pattern)):
        # Cycles reads them as it creates its session, which may last the whole render.
        enable_debug_patterns(scene, job.record)
    if _keeps_session(scene):
        job.record.set(scene.render, "use_persistent_data", True)
        job.keeps = True


def _frame_choice(scene, job: _Job):
    shot = shot_of(scene.frame_current, *shot_choice.shot_range(scene))
    if shot not in job.shots:
        try:
            job.shots[shot] = shot_choice.choose_for_shot(scene, shot)
        except Exception as error:          # noqa: BLE001 - any failure: the artist's settings
            job.shots[shot] = error
            raise
    found = job.shots[shot]
    if isinstance(found, Exception):
        raise found
    return found


def _apply(scene, job: _Job) -> None:
    plan = _frame_choice(scene, job)
    job.frame = ChangeRecord()
    apply_estimator(scene, plan.choice, job.frame)
    _note(scene, plan, job.frame)
    changed = job.frame.datablocks()
    before, job.changed = job.changed, _union(job.changed, changed)
    if (job.kept_before or job.keeps) and plan.choice != job.synced:
        # A session kept from before (or from the frame before) holds other settings:
        # add-on properties do not tag, so the datablocks auto changes now or changed
        # before are tagged, and the session syncs them again.
        job.tagged = True
        _tag(_union(changed, before))
    job.synced = plan.choice
    last_plans[scene.as_pointer()] = plan
    print(f"Auto Volumes: {scene.name} frame {scene.frame_current}: {plan.describe()}", flush=True)


def _note(scene, plan, changes: ChangeRecord) -> None:
    """The choice in the frame's EXR header: Blender's stamp note, as metadata only."""
    render = scene.render
    if render.use_stamp:
        return                  # burnt into the image: the artist's stamp stays as it is
    text = f"Auto Volumes: {shot_choice.applied(plan.choice)} (decided at frame {plan.frame})"
    if render.use_stamp_note and render.stamp_note_text:
        text = f"{render.stamp_note_text} | {text}"
    changes.set(render, "use_stamp_note", True)
    changes.set(render, "stamp_note_text", text)


def _restore_frame(job: _Job) -> None:
    if job.frame is not None:
        frame, job.frame = job.frame, None
        frame.restore()


def _finish(scene) -> None:
    job = _jobs.pop(scene.as_pointer(), None)
    if job is None:
        return
    try:
        _restore_frame(job)
    finally:
        job.record.restore()
        if job.changed and (job.tagged or scene.render.use_persistent_data):
            # What a depsgraph re-evaluated while auto's settings were on (the viewport's,
            # a session the artist keeps) takes the artist's settings again.
            _tag(job.changed)


def _tag(datablocks) -> None:
    for datablock in datablocks:
        datablock.update_tag()


def _union(first: list, second: list) -> list:
    return first + [item for item in second if all(item is not seen for seen in first)]


def _guarded(action, scene, what: str) -> None:
    """Run a handler's work; a failure puts the frame's settings back and warns."""
    try:
        action(scene)
    except Exception as error:                  # noqa: BLE001 - never break the artist's render
        job = _jobs.get(scene.as_pointer())
        if job is not None:
            try:
                _restore_frame(job)
            except Exception:                   # noqa: BLE001
                pass
            job.synced = None
        _warn(scene, f"{what} failed ({type(error).__name__}: {error}); frame {scene.frame_current} "
                     "renders with the file's own volume settings")


def _on_render_init(scene, *_):
    _guarded(_start, scene, "starting")


def _on_render_pre(scene, *_):
    job = _jobs.get(scene.as_pointer())
    if job is not None:
        _guarded(lambda s: _apply(s, job), scene, "choosing the volume settings")


def _on_render_post(scene, *_):
    job = _jobs.get(scene.as_pointer())
    if job is not None:
        _guarded(lambda s: _restore_frame(job), scene, "putting the frame's settings back")


def _on_render_end(scene, *_):
    if scene.as_pointer() in _jobs:
        _guarded(_finish, scene, "putting the settings back")


def _on_save_pre(*_):
    """The file is written with the artist's settings, even mid-render."""
    for job in _jobs.values():
        _restore_frame(job)


def _on_load(*_):
    _jobs.clear()
    shot_choice.remember_ranges()


_HANDLERS = (("render_init", _on_render_init), ("render_pre", _on_render_pre),
             ("render_post", _on_render_post), ("render_complete", _on_render_end),
             ("render_cancel", _on_render_end), ("save_pre", _on_save_pre),
             ("save_post", lambda *_: shot_choice.remember_ranges()), ("load_post", _on_load))


def register() -> None:
    import bpy

    for name, function in _HANDLERS:
        function = bpy.app.handlers.persistent(function)
        handlers = getattr(bpy.app.handlers, name)
        if function not in handlers:
            handlers.append(function)
    shot_choice.remember_ranges()


def unregister() -> None:
    import bpy

    for name, function in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        while function in handlers:
            handlers.remove(function)
