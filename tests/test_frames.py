"""Frame ranges and numbered output names (core.frames) and the steps machinery
(core.progress): plain Python, plus one check against Blender's own frame naming."""
from __future__ import annotations

import pytest

from xsl_render.core.errors import Cancelled, InputError
from xsl_render.core.frames import (frame_expression, frame_path, has_frame_marker, parse_frame_list,
                                    parse_frame_range)
from xsl_render.core.progress import StepRunner, run_steps, scaled_steps, timed_steps


@pytest.mark.parametrize("text, frames", [
    ("1-3", [1, 2, 3]), ("1..3", [1, 2, 3]), ("7", [7]), ("0-10:5", [0, 5, 10]),
    ("-2-1", [-2, -1, 0, 1]), (" 4 - 5 ", [4, 5]),
])
def test_frame_ranges(text, frames):
    assert list(parse_frame_range(text)) == frames


@pytest.mark.parametrize("text, message", [
    ("3-1", "the end frame 1 is before the start frame 3"), ("1-5:0", "the step must be at least 1"),
    ("a-b", "must look like START-END"), ("", "must look like START-END"), ("1-2-3", "must look like"),
])
def test_bad_frame_ranges(text, message):
    with pytest.raises(InputError, match=message):
        parse_frame_range(text)


@pytest.mark.parametrize("text, frames, canonical", [
    ("1-3,8", [1, 2, 3, 8], "1-3,8"), ("8, 1-3:1", [1, 2, 3, 8], "1-3,8"),
    ("1-250:2", list(range(1, 251, 2)), "1-250:2"), ("7", [7], "7"), ("5-5", [5], "5"),
    ("4,3", [3, 4], "3,4"), ("-3-2,10-20:5", [-3, -2, -1, 0, 1, 2, 10, 15, 20], "-3-2,10-20:5"),
])
def test_frame_lists(text, frames, canonical):
    from openjd.model import IntRangeExpr

    assert list(parse_frame_list(text)) == frames
    assert frame_expression(text) == canonical
    assert list(IntRangeExpr.from_str(canonical)) == frames       # the farm's template agrees


@pytest.mark.parametrize("text, message", [
    ("1-3,2", "1-3 and 2 overlap"), ("1-9:2,2-8:2", "overlap"), ("1,,2", "an empty item"),
    ("1-3,", "an empty item"), ("1-3,x", "must look like START-END"), ("3-1,5", "is before"),
])
def test_bad_frame_lists(text, message):
    from openjd.model import IntRangeExpr

    with pytest.raises(InputError, match=message):
        parse_frame_list(text)
    with pytest.raises(InputError, match=message):
        frame_expression(text)
    with pytest.raises(ValueError):
        IntRangeExpr.from_str(text.replace(" ", ""))        # nor does the template take it


@pytest.mark.parametrize("pattern, frame, path", [
    ("out/frame_####.exr", 7, "out/frame_0007.exr"),
    ("out/frame_##", 123, "out/frame_123.exr"),
    ("out/f_#_x_###", 5, "out/f_#_x_005.exr"),          # the last run of # counts
    ("out/render.exr", 12, "out/render0012.exr"),        # no #: four digits before .exr
    ("out/render", 12, "out/render0012.exr"),
    ("out/", 3, "out/0003.exr"),                         # a folder: the number is the name
    ("sh#ots/take.exr", 2, "sh#ots/take0002.exr"),       # # in a folder is not a marker
    ("out\\win_###.exr", 4, "out\\win_004.exr"),
    ("f_####.exr", -3, "f_-003.exr"),                    # as Blender's %0*d prints it
])
def test_frame_paths(pattern, frame, path):
    assert frame_path(pattern, frame) == path


def test_frame_markers():
    assert has_frame_marker("a/b_##.exr") and not has_frame_marker("a#/b.exr")


@pytest.mark.blender
@pytest.mark.parametrize("pattern", ["/tmp/out/frame_####.exr", "/tmp/out/f_##_x", "/tmp/out/",
                                     "/tmp/a#b/c_###", "/tmp/out/render"])
def test_frame_paths_match_blender(blender, pattern):
    render = blender.context.scene.render
    render.image_settings.file_format = "OPEN_EXR"
    render.use_file_extension = True
    render.filepath = pattern
    assert frame_path(pattern, 42) == render.frame_path(frame=42)


def counting_steps(log: list, steps: int = 3, result="done"):
    try:
        for index in range(steps):
            yield index / steps, f"step {index}"
        return result
    finally:
        log.append("closed")


def test_run_steps_returns_and_cancels_after_cleanup():
    log = []
    assert run_steps(counting_steps(log), lambda f, m: log.append(m)) == "done"
    assert log == ["step 0", "step 1", "step 2", "closed"]
    log.clear()
    with pytest.raises(Cancelled):
        run_steps(counting_steps(log), lambda f, m: m == "step 1")
    assert log == ["closed"]


def test_scaled_steps_and_the_step_runner():
    log = []

    def outer():
        first = yield from scaled_steps(counting_steps(log, 2, "a"), 0.0, 0.5, "one: ")
        second = yield from scaled_steps(counting_steps(log, 2, "b"), 0.5, 1.0, "two: ")
        return first + second

    runner = StepRunner(outer())
    seen = []
    while not runner.advance():
        seen.append((runner.fraction, runner.message))
    assert seen == [(0.0, "one: step 0"), (0.25, "one: step 1"), (0.5, "two: step 0"), (0.75, "two: step 1")]
    assert runner.result == "ab" and runner.fraction == 1.0 and log == ["closed", "closed"]

    log.clear()
    runner = StepRunner(outer())
    runner.advance()
    runner.cancel()                       # ESC: the inner generator's clean-up runs now
    assert log == ["closed"] and runner.done


@pytest.mark.timing
def test_timed_steps_count_the_work_not_the_wait_between_steps():
    import time

    log = []

    def working(seconds: float):
        try:
            for index in range(3):
                time.sleep(seconds)
                yield index / 3, f"step {index}"
            time.sleep(seconds)
            return "done"
        finally:
            log.append("closed")

    runner = StepRunner(timed_steps(working(0.02)))
    while not runner.advance():
        time.sleep(0.05)                   # a modal operator waiting for its next tick
    result, seconds = runner.result
    assert result == "done" and 0.08 <= seconds < 0.08 + 0.1 and log == ["closed"]
    runner = StepRunner(timed_steps(working(0.0)))
    runner.advance()
    runner.cancel()
    assert log == ["closed", "closed"]
