"""Ctrl-C from the first instruction to the last (issue 15, point 2): exit 130, one line,
nothing written, whenever the signal arrives; a kill's leftovers go with the next run.

Each trial stops the command within a second of its start (or of Blender's), before anything
is rendered. "From the first instruction" is the console script's (``operators/entry.py``):
before it the process is Python starting up, which a SIGINT ends as Python does, and on a
loaded machine that start can stretch past a trial's moment, so such a trial waits for the
instruction (:func:`send_when_ours`) and counts as "late": every trial is a signal at a moment
the program answers for, whatever the load."""
from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import EXAMPLES

# The commands load Blender (when not stopped first); the Ctrl-C moments are timed from the
# process's start, which a second worker's renders would shift.
pytestmark = [pytest.mark.blender, pytest.mark.timing]

EXE = Path(sys.executable).with_name("xsl-render")
SCENE = EXAMPLES / "road.blend"
# Moments after the start: from the first instruction (0: as soon as the console script blocks
# SIGINT) through the session folder's making (within about 0.1 s) and the imports. Each
# repeat shifts the grid by SHIFT: 15 different moments, not 5 moments three times.
DELAYS = (0.0, 0.1, 0.2, 0.35, 0.5)
REPEATS = 3
SHIFT = 0.033
# Moments after Blender began to start (``import bpy``; it makes its own folder in ours some
# 0.2-0.4 s later): 0.4 s after the start on one machine, 2 s on a loaded one, so not a delay.
BLENDER_DELAYS = (0.0, 0.15, 0.3)


def render_command(folder: Path) -> list[str]:
    """Seconds of work: maps and a selective render; four files when it finishes."""
    out = folder / "out"
    return [str(EXE), "render", str(SCENE), "--mode", "xsl", "--max-spp", "64", "--resolution", "128x72",
            "--quiet", "--out", str(out / "r.exr"), "--stats", str(out / "r.json")]


def start(command: list[str], folder: Path) -> subprocess.Popen:
    """The command with a temporary folder of its own (Blender's session folder goes there too)."""
    (folder / "tmp").mkdir(parents=True)
    env = {**os.environ, "TMPDIR": str(folder / "tmp")}
    return subprocess.Popen(command, cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def ours(pid: int) -> bool | None:
    """Whether the console script's first instruction has run in process ``pid``: its main
    thread blocks SIGINT from then on. None where ``/proc`` does not say (not Linux)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None
    for line in status.splitlines():
        if line.startswith("SigBlk:"):
            return bool(int(line.split()[1], 16) >> (signal.SIGINT - 1) & 1)
    return None


def send_when_ours(process: subprocess.Popen, signum: int, at: float) -> bool:
    """Send ``signum`` ``at`` seconds (monotonic) or, if the interpreter is still starting up
    then, as soon as the console script blocks it; True if the signal came late."""
    time.sleep(max(0.0, at - time.monotonic()))
    late = False
    while ours(process.pid) is False and process.poll() is None:
        late = True
        time.sleep(0.001)
    process.send_signal(signum)
    return late


def blender_started(pid: int) -> bool | None:
    """Whether ``import bpy`` began in process ``pid`` (Blender's library is mapped); None
    where ``/proc`` does not say."""
    try:
        return "/bpy/__init__" in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return None


def send_after_blender_starts(process: subprocess.Popen, signum: int, delay: float) -> None:
    """Send ``signum`` ``delay`` seconds after Blender began to start in ``process`` (where
    that cannot be seen: ``delay`` seconds after the start)."""
    while blender_started(process.pid) is False and process.poll() is None:
        time.sleep(0.002)
    time.sleep(delay)
    process.send_signal(signum)


def left_behind(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.name != "tmp")


def test_ctrl_c_at_any_moment_exits_130_and_writes_nothing(tmp_path):
    digest = hashlib.sha256(SCENE.read_bytes()).hexdigest()
    results, late = [], []
    moments = [(f"{base + repeat * SHIFT:.3f}", base + repeat * SHIFT) for repeat in range(REPEATS)
               for base in DELAYS] + [(f"bpy+{delay}", delay) for delay in BLENDER_DELAYS]
    for name, delay in moments:
        folder = tmp_path / name
        started = time.monotonic()
        process = start(render_command(folder), folder)
        if name.startswith("bpy+"):
            send_after_blender_starts(process, signal.SIGINT, delay)
        elif send_when_ours(process, signal.SIGINT, started + delay):
            late.append(name)
        out, err = process.communicate(timeout=60)
        results.append((name, process.returncode, err, out, left_behind(folder),
                        list((folder / "tmp").iterdir())))
    failures = [r for r in results if r[1:] != (130, "xsl-render: cancelled\n", "", [], [])]
    assert failures == [], failures
    assert len(results) == len(DELAYS) * REPEATS + len(BLENDER_DELAYS)
    print(f"{len(results)} trials, {len(late)} waited for the interpreter's start-up: {late}")
    assert hashlib.sha256(SCENE.read_bytes()).hexdigest() == digest       # never written


def test_sigterm_is_a_cancel_too(tmp_path):
    process = start(render_command(tmp_path), tmp_path)
    send_when_ours(process, signal.SIGTERM, time.monotonic() + 0.5)
    out, err = process.communicate(timeout=60)
    assert (process.returncode, err, left_behind(tmp_path)) == (143, "xsl-render: cancelled\n", [])


@pytest.mark.parametrize("command", ["render", "saliency"])
def test_ctrl_c_as_the_outputs_go_in_place_leaves_all_of_them_or_none(tmp_path, command):
    """The riskiest moment: the work is done and the files are being renamed into place. The
    signal comes right after the summary line; either it came before the set was in place
    (130, nothing) or after (0, every file): never a part of the set."""
    if command == "render":
        argv = render_command(tmp_path)
        argv[argv.index("64")] = "4"
        expected = ["out", "out/r.exr", "out/r.json", "out/r_spp.exr", "out/r_spp.png"]
    else:
        from xsl_render.core.imageio import write_png

        import numpy as np

        write_png(tmp_path / "in.png", np.random.default_rng(1).random((64, 96, 3)).astype(np.float32))
        argv = [str(EXE), "saliency", str(tmp_path / "in.png"), "--out", str(tmp_path / "out" / "s.exr"),
                "--png", str(tmp_path / "out" / "s.png")]
        expected = ["in.png", "out", "out/s.exr", "out/s.png"]
    process = start(argv, tmp_path)
    line = process.stdout.readline()
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert line, err
    if process.returncode == 130:
        assert err == "xsl-render: cancelled\n"
        assert left_behind(tmp_path) == [p for p in expected if p == "in.png"]
    else:
        assert (process.returncode, err) == (0, "")
        assert left_behind(tmp_path) == expected
    assert list((tmp_path / "tmp").iterdir()) == []


def test_a_killed_run_leaves_what_the_next_run_removes(tmp_path):
    """SIGKILL cannot be answered: the temporaries stay, with the dead process's id in their
    names, and the next command (here one that needs no Blender) removes them."""
    process = start(render_command(tmp_path), tmp_path)
    deadline = time.monotonic() + 60            # its session folder made, however loaded the machine
    while not list((tmp_path / "tmp").iterdir()) and time.monotonic() < deadline:
        time.sleep(0.005)
    time.sleep(0.3)
    process.kill()
    process.communicate(timeout=60)
    assert process.returncode == -signal.SIGKILL
    leftovers = list((tmp_path / "tmp").iterdir())
    assert [p.name.startswith(f"xsl-render-{process.pid}-") for p in leftovers] == [True]
    # A partial output of the killed run, as a kill during a write leaves it.
    (tmp_path / "out").mkdir(exist_ok=True)
    partial = tmp_path / "out" / f".r.{process.pid}-0123abcd.partial.exr"
    partial.write_bytes(b"half")
    from xsl_render.core.imageio import write_png

    import numpy as np

    write_png(tmp_path / "in.png", np.zeros((8, 8, 3), np.float32))
    done = subprocess.run([str(EXE), "saliency", str(tmp_path / "in.png"), "--out", str(tmp_path / "out" / "s.exr")],
                          env={**os.environ, "TMPDIR": str(tmp_path / "tmp")}, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    assert list((tmp_path / "tmp").iterdir()) == []
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["s.exr"]


def test_ctrl_c_once_the_outputs_are_written_changes_nothing(tmp_path):
    """Issue 15, point 2: a Ctrl-C while the finished command shuts Blender down used to end
    it with -2 and no word. The outputs are in place: it ends as it would have."""
    argv = render_command(tmp_path)
    argv[argv.index("64")] = "2"
    process = start(argv, tmp_path)
    deadline = time.monotonic() + 60
    while not (tmp_path / "out" / "r.json").exists() and time.monotonic() < deadline:
        time.sleep(0.002)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert (process.returncode, err) == (0, ""), err
    assert out.startswith("xsl: ") and len(left_behind(tmp_path)) == 5
