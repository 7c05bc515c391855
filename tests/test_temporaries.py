"""Temporary files and output sets: whatever stops the work, no half-written output, no
mixed set, nothing left behind (``core.temporaries``, ``core.files``)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from xsl_render.core import files, temporaries
from xsl_render.core.errors import Cancelled, InputError
from xsl_render.core.files import atomic_path, output_set, write_json, write_text
from xsl_render.core.maps.files import MapSet, write_map_set


def tree(folder) -> dict:
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None)
            for p in sorted(folder.rglob("*"))}


def test_a_set_appears_whole_when_its_block_ends(tmp_path):
    with output_set():
        write_text(tmp_path / "a.txt", "a")
        write_json(tmp_path / "sub" / "b.json", {"b": 1})
        assert not (tmp_path / "a.txt").exists() and not (tmp_path / "sub" / "b.json").exists()
        with output_set():                               # an inner set joins the outer one
            write_text(tmp_path / "c.txt", "c")
        assert not (tmp_path / "c.txt").exists()
    assert sorted(tree(tmp_path)) == ["a.txt", "c.txt", "sub", "sub/b.json"]


def test_a_failing_set_leaves_nothing_not_even_the_folders_it_made(tmp_path):
    with pytest.raises(RuntimeError):
        with output_set():
            write_text(tmp_path / "new" / "deeper" / "a.txt", "a")
            write_text(tmp_path / "b.txt", "b")
            raise RuntimeError("the render failed")
    assert tree(tmp_path) == {}


def test_a_file_written_twice_in_a_set_keeps_the_last(tmp_path):
    with output_set():
        write_text(tmp_path / "a.txt", "first")
        write_text(tmp_path / "a.txt", "second")
    assert tree(tmp_path) == {"a.txt": b"second"}


def _maps(value: float) -> MapSet:
    plane = np.full((6, 8), value, np.float32)
    return MapSet(z=np.where(plane > 0, 5.0, np.inf).astype(np.float32), x=plane, snapshot=np.zeros((6, 8, 4)),
                  s=plane, l=plane, xs=plane, xsl=plane, info={"value": value})


def test_a_map_set_interrupted_while_written_leaves_the_earlier_set_whole(tmp_path, monkeypatch):
    """Issue 15, point 8: an earlier set in the folder must not mix with a new one."""
    write_map_set(tmp_path, _maps(0.25))
    earlier = tree(tmp_path)
    assert "preview/z.png" in earlier and "xsl.exr" in earlier
    real = files.os.replace
    calls = []

    def interrupted(source, target):
        calls.append(target)
        raise KeyboardInterrupt         # Ctrl-C reaching Python while the set goes in place

    monkeypatch.setattr(files.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_map_set(tmp_path, _maps(0.75))
    monkeypatch.setattr(files.os, "replace", real)
    assert len(calls) == 1 and tree(tmp_path) == earlier
    # And one that fails while writing (the last map, say) leaves it whole too.
    original = files.temporaries.new_file

    def full_disk(path):
        if str(path).endswith("xsl.exr"):
            raise OSError(28, "No space left on device")
        return original(path)

    monkeypatch.setattr(files.temporaries, "new_file", full_disk)
    with pytest.raises(InputError, match=r"cannot write .*xsl\.exr: no space left on device"):
        write_map_set(tmp_path, _maps(0.75))
    assert tree(tmp_path) == earlier


def test_every_map_set_has_the_same_files(tmp_path):
    write_map_set(tmp_path / "lit", _maps(0.5))
    write_map_set(tmp_path / "sky", _maps(0.0))         # no surface at all: z is inf everywhere
    assert sorted(tree(tmp_path / "lit")) == sorted(tree(tmp_path / "sky"))


@pytest.mark.parametrize("pid", [7, 300, 32767, 4194304])
def test_a_temporary_name_is_as_long_in_every_process(tmp_path, monkeypatch, pid):
    # The up-front checks ask whether an output's name leaves room for its temporary: the
    # answer must not change with the pid (a pid counter that wrapped gave 3 digits for 5).
    expected = len(temporaries.temporary_name(tmp_path / "render.exr").name)
    monkeypatch.setattr(temporaries.os, "getpid", lambda: pid)
    assert len(temporaries.temporary_name(tmp_path / "render.exr").name) == expected


def test_temporaries_say_whose_they_are(tmp_path):
    name = temporaries.temporary_name(tmp_path / "render.exr").name
    pid = f"{os.getpid():0{temporaries.PID_DIGITS}d}"
    assert name.startswith(f".render.{pid}-") and name.endswith(".partial.exr")
    with atomic_path(tmp_path / "render.exr") as tmp:
        assert tmp.name.startswith(f".render.{pid}-") and tmp.exists()
        tmp.write_bytes(b"x")
    assert tree(tmp_path) == {"render.exr": b"x"}


def _dead_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_temporaries_of_killed_runs_are_swept_when_a_folder_is_written(tmp_path):
    """Issue 15, point 8: a kill leaves .*.partial files; the next write into the folder
    removes those of processes that are gone, and only those."""
    dead, alive = _dead_pid(), os.getppid()
    stale = [tmp_path / f".render.{dead}-0123abcd.partial.exr", tmp_path / f".render_spp.{dead}-89abcdef.partial.png"]
    stale_folder = tmp_path / f".maps.{dead}-00aa11bb.partial"
    keep = [tmp_path / f".render.{alive}-0123abcd.partial.exr", tmp_path / ".hidden.partial.exr",
            tmp_path / "render.exr"]
    for path in stale + keep:
        path.write_bytes(b"x")
    stale_folder.mkdir()
    (stale_folder / "z.exr").write_bytes(b"x")
    write_text(tmp_path / "new.txt", "n")
    assert sorted(tree(tmp_path)) == sorted([p.name for p in keep] + ["new.txt"])


def _run(code: str, **env) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=60, env={**os.environ, **env})


def test_abort_removes_every_temporary_and_refuses_what_follows(tmp_path):
    """What the signal watcher does, from another thread, while the main thread writes."""
    done = _run(f"""
        import os, threading
        from pathlib import Path
        from xsl_render.core import temporaries
        from xsl_render.core.files import atomic_path, output_set, write_text

        root = Path({str(tmp_path)!r})
        with output_set():
            write_text(root / "made" / "deeper" / "staged.txt", "s")
            with atomic_path(root / "open.exr") as tmp:
                tmp.write_bytes(b"half")
                aborted = threading.Event()

                def watch():                    # as the signal watcher: abort, then never return
                    print(temporaries.abort(), flush=True)
                    aborted.set()
                    threading.Event().wait()

                threading.Thread(target=watch, daemon=True).start()
                aborted.wait()
                # The abort keeps the gate: whatever the main thread writes next waits forever
                # (the process ends first).
                writer = threading.Thread(target=write_text, args=(root / "after.txt", "a"), daemon=True)
                writer.start()
                writer.join(0.5)
                print("waiting" if writer.is_alive() else "written", flush=True)
                print(sorted(str(p) for p in root.rglob("*")), flush=True)
                os._exit(0)
        """)
    assert done.stdout.split("\n")[:3] == ["True", "waiting", "[]"], done.stderr
    assert tree(tmp_path) == {}


def test_after_seal_a_cancel_is_too_late(tmp_path):
    done = _run(f"""
        from pathlib import Path
        from xsl_render.core import temporaries
        from xsl_render.core.files import output_set, write_text

        with output_set(seal=True):
            write_text(Path({str(tmp_path)!r}) / "out.txt", "o")
        print(temporaries.abort())
        """)
    assert done.stdout.split() == ["False"], done.stderr
    assert tree(tmp_path) == {"out.txt": b"o"}


def test_the_session_folder_takes_every_temporary_and_sweeps_dead_ones(tmp_path):
    dead = _dead_pid()
    (tmp_path / f"xsl-render-{dead}-abcd1234" / "blender_x").mkdir(parents=True)
    (tmp_path / f"xsl-render-{os.getpid()}-abcd1234").mkdir()          # alive: kept
    (tmp_path / "xsl-render-abcd1234.log").write_text("a --verbose log")  # not a session: kept
    done = _run("""
        import os, tempfile
        from xsl_render.core import temporaries

        folder = temporaries.open_session()
        assert tempfile.gettempdir() == str(folder) == os.environ["TMPDIR"]
        print(temporaries.system_tempdir())
        tempfile.mkstemp(prefix="xsl-tiles-")
        temporaries.close_session()
        """, TMPDIR=str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([
        "xsl-render-abcd1234.log", f"xsl-render-{os.getpid()}-abcd1234"])


def test_the_gate_refuses_once_cancelled(monkeypatch):
    monkeypatch.setitem(temporaries._state, "aborted", True)
    with pytest.raises(Cancelled):
        with temporaries.gate():
            pass
