"""The fuzz table of issue 15: bad input to every subcommand, each refused as the contract says.

Every case must end with exit code 2 and one line on stderr naming the problem (no
traceback), write nothing, and never load Blender. Most cases run the command line in this
process (cheap) with ``bpy`` made unimportable, so a case that got as far as Blender fails;
a few run the real console script end to end; the permission cases run with the effective
user switched to nobody when the tests run as root (root may write anywhere).
"""
from __future__ import annotations

import hashlib
import os
import signal
import sqlite3
import subprocess
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from conftest import xsl_render_cli
from support.fuzz_cases import CASES, FARM, FT, HOT, OUT, RG, RX, R

from xsl_render.core.imageio import write_exr, write_png
from xsl_render.operators.cli import main

BLEND_HEADER = b"BLENDER-v500" + bytes(64)      # all a scene path needs before Blender opens it


def _nan_exr(path: Path) -> Path:
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(8, 6, 1, oiio.FLOAT))
    out.write_image(np.full((6, 8, 1), np.nan, np.float32))
    out.close()
    return path


def make_workspace(root: Path) -> dict[str, str]:
    """Good and bad inputs; the cases name them as {key}."""
    rng = np.random.default_rng(15)
    (root / "scene.blend").write_bytes(BLEND_HEADER)
    (root / "text.blend").write_text("not a blend file")
    (root / "file.txt").write_text("a file")
    (root / "dir").mkdir()
    write_exr(root / "ref.exr", rng.random((6, 8, 4)).astype(np.float32))
    write_exr(root / "small.exr", rng.random((3, 4, 4)).astype(np.float32))
    write_png(root / "ref.png", rng.random((6, 8, 3)).astype(np.float32))
    _nan_exr(root / "nan.exr")
    (root / "garbage.exr").write_bytes(b"\x76\x2f\x31\x01 not really an EXR")
    (root / "empty.png").write_bytes(b"")
    (root / "fix.csv").write_text("x,y,duration_ms\n2,3,400\n")
    (root / "bad.csv").write_text("2;3;400\n")
    for name, data in {"nan": '{"mean_spp": NaN, "wall_s": 1.0}', "text": '{"mean_spp": "8", "wall_s": 1.0}',
                       "negative": '{"mean_spp": 4, "wall_s": -1}', "list": "[1, 2]",
                       "garbage": "{not json", "nowall": '{"mean_spp": 4}',
                       "huge": '{"mean_spp": 1e300, "wall_s": 1}', "deep": "[" * 100000,
                       "denoise": '{"mean_spp": 4, "wall_s": 1.0, "phases_s": {"denoise": 2.0}}',
                       "phases": '{"mean_spp": 4, "wall_s": 1.0, "phases_s": [1]}'}.items():
        (root / f"budget_{name}.json").write_text(data)
    (root / "garbage.sqlite").write_bytes(b"not a database at all " * 40)
    db = sqlite3.connect(root / "empty_db.sqlite")
    db.execute("CREATE TABLE answers (participant_id TEXT, scene TEXT, condition TEXT, correct INTEGER, "
               "page_hidden INTEGER, durations_json TEXT)")
    db.commit()
    db.close()
    stimuli = root / "stimuli"
    stimuli.mkdir()
    write_png(stimuli / "a.gold.png", rng.random((4, 4, 3)).astype(np.float32))
    write_png(stimuli / "a.test.png", rng.random((4, 4, 3)).astype(np.float32))
    (root / "odd_stimuli").mkdir()
    write_png(root / "odd_stimuli" / "a.gold.png", rng.random((4, 4, 3)).astype(np.float32))
    (root / "x_spp.png").mkdir()                   # where render --out x.exr puts its samples preview
    (root / "foreign").mkdir()
    (root / "foreign" / "notes.txt").write_text("someone's files")
    add_issue_23_files(root)
    keys = {p.stem if p.is_file() else p.name: str(p) for p in root.iterdir()}
    keys.update(issue_23_keys(root))
    keys.update(ws=str(root), missing=str(root / "missing"), under=str(root / "file.txt" / "x"),
                proc="/proc/xsl-render-fuzz", png=str(root / "ref.png"), exr=str(root / "ref.exr"),
                blend=str(root / "scene.blend"))
    return keys


def add_issue_23_files(root: Path) -> None:
    """Inputs an output may meet under another name, FIFOs, and folders holding them."""
    rng = np.random.default_rng(23)
    write_png(root / "other.png", rng.random((6, 8, 3)).astype(np.float32))
    (root / "hm").mkdir()
    write_png(root / "hm" / "flip.png", rng.random((6, 8, 3)).astype(np.float32))
    os.link(root / "ref.png", root / "hard.png")
    (root / "link.json").symlink_to(root / "scene.blend")
    (root / "db_link.png").symlink_to(root / "empty_db.sqlite")
    (root / "mapsdir").mkdir()
    write_exr(root / "mapsdir" / "xsl.exr", rng.random((6, 8)).astype(np.float32))
    (root / "mapsdir" / "maps.json").write_text('{"mean_spp": 4, "wall_s": 1.0}')
    write_exr(root / "x2_spp.exr", rng.random((6, 8)).astype(np.float32))
    for suffix in ("blend", "exr", "json", "csv", "sqlite"):
        os.mkfifo(root / f"pipe_{suffix}.{suffix}")
    (root / "pipe_maps").mkdir()
    os.mkfifo(root / "pipe_maps" / "xsl.exr")
    (root / "pipe_stimuli").mkdir()
    os.mkfifo(root / "pipe_stimuli" / "a.gold.png")
    write_png(root / "pipe_stimuli" / "a.test.png", rng.random((4, 4, 3)).astype(np.float32))


def issue_23_keys(root: Path) -> dict[str, str]:
    """The FIFOs by name, and two outputs whose own names fit: one whose ``_spp.exr`` does
    not, one whose temporary name (``.NAME.<pid>-<token>.partial.exr``) does not."""
    from xsl_render.core.temporaries import temporary_name

    extra = len(temporary_name(root / "o.exr").name) - len("o.exr")     # the same in every process
    keys = {f"pipe_{suffix}": str(root / f"pipe_{suffix}.{suffix}") for suffix in ("blend", "exr", "json", "csv", "sqlite")}
    keys.update(pipe_maps=str(root / "pipe_maps"), pipe_stimuli=str(root / "pipe_stimuli"),
                spp_too_long=str(root / ("s" * (255 - extra - 2 - 4) + ".exr")),       # _spp adds 4 bytes
                temporary_too_long=str(root / ("t" * (255 - 4 - extra + 1) + ".exr")))
    return keys


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    return root, make_workspace(root)


def snapshot(root: Path) -> dict:
    """Every file of ``root`` with its size, time and bytes' hash (an input overwritten with
    the same size in the same tick still shows); FIFOs are only named, never opened."""
    return {str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns,
                                       hashlib.sha256(p.read_bytes()).hexdigest()) if p.is_file() else None
            for p in sorted(root.rglob("*"))}


def test_the_table_is_large_and_covers_every_subcommand():
    from xsl_render.operators.commands import COMMANDS

    assert len(CASES) + len(UNPRIVILEGED) + len(END_TO_END) >= 150
    assert len({case[0] for case in CASES}) == len(CASES)
    covered = {argv[0] for _, argv, _ in CASES + UNPRIVILEGED + END_TO_END if argv and argv[0] != "--verbose"}
    assert covered >= {command.NAME for command in COMMANDS}


#: The bad inputs issue 15 names, point by point, as cases of the table. Its other points
#: have tests of their own (test_compare_cli, test_sigint, test_temporaries, test_batch_scene,
#: test_experiment_server, test_experiment_analyse: their docstrings say which point).
ISSUE_15 = {
    1: ["compare-exposure-huge", "e2e-compare-exposure"],
    3: ["ro-maps", "maps-out-proc", "xmap-out-file", "render-out-folder", "ro-render-out",
        "ro-compare-json", "ro-compare-heatmap", "ro-compare-heatmap-dir", "ro-hotspots", "ro-analyse-chart",
        "ro-farm", "render-stats-folder"],
    4: ["render-max-spp-32bit", "render-seed-40bit", "render-frame-32bit", "maps-frame-32bit",
        "xmap-frame-32bit", "farm-max-spp-huge", "e2e-farm-max-spp", "render-spp-above-max"],
    5: ["maps-res-huge", "render-res-huge", "e2e-render-res-huge", "maps-res-1x1", "render-res-1x1"],
    6: ["render-budget-nan", "render-budget-text", "unreadable-info", "unreadable-render-scene",
        "unreadable-compare", "unreadable-budget"],
    7: ["hotspots-distance-nan", "hotspots-width-nan", "hotspots-distance-inf", "e2e-hotspots-nan",
        "analyse-tolerance-nan"],
}


#: Issue 23's lists, case by case: data loss, hangs, tracebacks, wrong codes (the write
#: errors and cameras are tests below; the server's signals are in test_experiment_server).
ISSUE_23 = {
    "data loss": ["render-stats-is-scene", "e2e-render-stats-is-scene", "compare-json-is-ref",
                  "compare-heatmap-is-ref", "compare-heatmap-is-test", "saliency-png-is-image",
                  "saliency-out-is-image", "hotspots-out-is-image", "render-out-is-map", "render-stats-is-map",
                  "render-stats-is-budget"],
    "hangs": ["info-fifo", "e2e-info-fifo", "compare-fifo", "saliency-fifo", "render-map-fifo",
              "render-budget-fifo", "hotspots-fifo-csv", "e2e-hotspots-fifo-csv"],
    "tracebacks": ["render-out-name-too-long", "render-spp-name-too-long", "e2e-render-spp-name-too-long",
                   "info-name-too-long", "compare-json-name-too-long", "maps-out-name-too-long",
                   "e2e-maps-out-name-too-long"],
}


@pytest.mark.parametrize("kind", sorted(ISSUE_23))
def test_issue_23_case_is_in_the_table(kind):
    ids = {case[0] for case in CASES + UNPRIVILEGED + END_TO_END}
    assert set(ISSUE_23[kind]) <= ids, set(ISSUE_23[kind]) - ids


@pytest.mark.parametrize("point", sorted(ISSUE_15))
def test_issue_15_point_is_in_the_table(point):
    """Every bad input of the issue's point is a case of the table (which runs it)."""
    ids = {case[0] for case in CASES + UNPRIVILEGED + END_TO_END}
    assert set(ISSUE_15[point]) <= ids, set(ISSUE_15[point]) - ids


def _timeout(signum, frame):
    raise TimeoutError("the command hung (a FIFO opened?)")


def _run_in_process(argv: list[str], cwd: Path, capfd, monkeypatch) -> tuple[int, str, str]:
    monkeypatch.chdir(cwd)
    monkeypatch.setitem(sys.modules, "bpy", None)       # `import bpy` now fails: no case may load Blender
    capfd.readouterr()
    # A case that opens a FIFO would wait for ever: the alarm ends it as a failure.
    previous = signal.signal(signal.SIGALRM, _timeout)
    signal.alarm(60)
    try:
        code = main(argv)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    out, err = capfd.readouterr()
    return code, out, err


def assert_refused(code: int, err: str, words: str) -> None:
    lines = err.strip().splitlines()
    assert code == 2, (code, err)
    assert len(lines) == 1, err
    assert lines[0].startswith("xsl-render: error: "), err
    assert words in lines[0], err
    assert "Traceback" not in err and "internal error" not in err


@pytest.mark.parametrize("case_id, argv, words", CASES, ids=[case[0] for case in CASES])
def test_bad_input_is_refused_up_front(workspace, capfd, monkeypatch, case_id, argv, words):
    root, keys = workspace
    before = snapshot(root)
    code, out, err = _run_in_process([arg.format(**keys) for arg in argv], root, capfd, monkeypatch)
    assert_refused(code, err, words)
    assert snapshot(root) == before                     # nothing written, nothing left behind


# -- permissions: as a user they apply to ------------------------------------------------------
@contextmanager
def unprivileged():
    """Root may write anywhere: switch the effective user to nobody for the block."""
    if os.name != "posix" or os.geteuid() != 0:
        yield
        return
    os.setegid(65534)
    os.seteuid(65534)
    try:
        yield
    finally:
        os.seteuid(0)
        os.setegid(0)


@pytest.fixture(scope="module")
def locked(tmp_path_factory):
    """A world-readable folder (nobody can reach it) with a read-only folder and unreadable files."""
    if os.name != "posix":
        pytest.skip("POSIX permissions")
    root = Path(tempfile.mkdtemp(prefix="xsl-fuzz-locked-"))
    root.chmod(0o755)
    keys = make_workspace(root)
    for path in root.rglob("*"):
        path.chmod(0o755 if path.is_dir() else 0o644)
    (root / "ro").mkdir()
    for name in ("secret.exr", "secret.blend", "secret.json", "secret.csv", "secret.sqlite"):
        (root / name).write_bytes((root / {"exr": "ref.exr", "blend": "scene.blend", "json": "budget_nan.json",
                                           "csv": "fix.csv", "sqlite": "empty_db.sqlite"}[name.split(".")[1]]).read_bytes())
        (root / name).chmod(0)
    (root / "ro").chmod(0o555)
    keys.update(ro=str(root / "ro"), **{f"secret_{p.suffix[1:]}": str(p) for p in root.glob("secret.*")})
    yield root, keys
    for path in root.rglob("*"):
        path.chmod(0o755 if path.is_dir() else 0o644)
    subprocess.run(["rm", "-rf", str(root)], check=False)


UNPRIVILEGED = [
    ("ro-maps", ["maps", "{blend}", "--out", "{ro}/m"], "permission denied"),
    ("ro-xmap", ["xmap", "{blend}", "--out", "{ro}"], "permission denied"),
    ("ro-render-out", RG + ["--out", "{ro}/o.exr"], "permission denied"),
    ("ro-render-stats", RG + OUT + ["--stats", "{ro}/s.json"], "permission denied"),
    ("ro-render-save-maps", RX + OUT + ["--save-maps", "{ro}/maps"], "permission denied"),
    ("ro-saliency", ["saliency", "{png}", "--out", "{ro}/s.exr"], "permission denied"),
    ("ro-compare-json", ["compare", "{exr}", "{exr}", "--json", "{ro}/c.json"], "permission denied"),
    ("ro-compare-heatmap", ["compare", "{exr}", "{exr}", "--heatmap", "{ro}/h.png"], "permission denied"),
    ("ro-compare-heatmap-dir", ["compare", "{exr}", "{exr}", "--heatmap-dir", "{ro}/h"], "permission denied"),
    ("ro-hotspots", ["hotspots", "{png}", "{fix}", "--out", "{ro}/h.png"], "permission denied"),
    ("ro-analyse-chart", ["experiment-analyse", "{empty_db}", "--chart", "{ro}/c.png"], "permission denied"),
    ("ro-farm", ["farm", "{blend}", "--bundle", "{ro}/bundle"], "permission denied"),
    ("ro-experiment", ["experiment", "--out", "{ro}/e"], "permission denied"),
    ("ro-demo", ["demo", "--out", "{ro}/d"], "permission denied"),
    ("ro-serve-db", ["experiment-serve", "{stimuli}", "--db", "{ro}/a.sqlite"], "permission denied"),
    ("ro-farm-task", FT[:7] + ["--output", "{ro}/job"] + FT[9:], "permission denied"),
    ("ro-reference", ["reference", "{blend}", "--out", "{ro}/r.exr"], "permission denied"),
    ("ro-curves", ["curves", "{blend}", "--out", "{ro}/c"], "permission denied"),
    ("unreadable-info", ["info", "{secret_blend}"], "cannot read"),
    ("unreadable-render-scene", ["render", "{secret_blend}", "--mode", "gold", "--max-spp", "4"] + OUT,
     "cannot read"),
    ("unreadable-compare", ["compare", "{secret_exr}", "{exr}"], "cannot read"),
    ("unreadable-saliency", ["saliency", "{secret_exr}", "--out", "{ws}/s.exr"], "cannot read"),
    ("unreadable-budget", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{secret_json}"] + OUT,
     "cannot read"),
    ("unreadable-map", RX + ["--map", "{secret_exr}"] + OUT, "cannot read"),
    ("unreadable-fixations", ["hotspots", "{png}", "{secret_csv}", "--out", "{ws}/h.png"], "cannot read"),
    ("unreadable-analyse", ["experiment-analyse", "{secret_sqlite}"], "cannot read"),
]


@pytest.mark.parametrize("case_id, argv, words", UNPRIVILEGED, ids=[case[0] for case in UNPRIVILEGED])
def test_what_the_user_may_not_touch_is_refused_up_front(locked, capfd, monkeypatch, case_id, argv, words):
    root, keys = locked
    before = snapshot(root)
    monkeypatch.chdir(root)
    with unprivileged():
        code, out, err = _run_in_process([arg.format(**keys) for arg in argv], root, capfd, monkeypatch)
    assert_refused(code, err, words)
    assert snapshot(root) == before


# -- end to end: the console script ------------------------------------------------------------
END_TO_END = [
    ("e2e-render-res-huge", RG + OUT + ["--resolution", "65536x65536"], "of memory"),
    ("e2e-farm-max-spp", FARM + ["--max-spp", "99999999999"], "from 1 to 16777216"),
    ("e2e-hotspots-nan", HOT + ["--distance-cm", "nan"], "finite number, not nan"),
    ("e2e-render-out-folder", RG + ["--out", "{dir}"], "is a folder, not a file"),
    ("e2e-render-guided-budget-zero", R + ["--mode", "guided", "--time-budget", "0"] + OUT, "greater than 0"),
    ("e2e-render-guided-budget-nan", R + ["--mode", "guided", "--time-budget", "nan"] + OUT, "not nan"),
    ("e2e-compare-exposure", ["compare", "{exr}", "{exr}", "--exposure", "1000"], "at most 64"),
    ("e2e-render-stats-is-scene", RG + OUT + ["--stats", "{blend}"], "--stats and SCENE.blend name the same file"),
    ("e2e-info-fifo", ["info", "{pipe_blend}"], "is a FIFO"),
    ("e2e-hotspots-fifo-csv", ["hotspots", "{png}", "{pipe_csv}", "--out", "{ws}/h.png"], "is a FIFO"),
    ("e2e-maps-out-name-too-long", ["maps", "{blend}", "--out", "{ws}/" + "d" * 300], "file name too long"),
    ("e2e-render-spp-name-too-long", RG + ["--out", "{spp_too_long}"], "its samples: file name too long"),
]


@pytest.mark.parametrize("case_id, argv, words", END_TO_END, ids=[case[0] for case in END_TO_END])
def test_the_console_script_refuses_up_front(workspace, case_id, argv, words):
    root, keys = workspace
    before = snapshot(root)
    done = xsl_render_cli(*[arg.format(**keys) for arg in argv], cwd=root, timeout=60)
    assert_refused(done.returncode, done.stderr, words)
    assert done.stdout == "" and snapshot(root) == before


@pytest.mark.blender
def test_a_scene_that_cannot_be_used_is_refused_after_loading_it(blender, tmp_path):
    """What only Blender can tell (no camera) still ends with exit 2, one line, nothing written."""
    blender.ops.wm.read_factory_settings(use_empty=True)
    blend = tmp_path / "no_camera.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(blend))
    saved = blend.read_bytes()
    done = xsl_render_cli("render", blend, "--mode", "gold", "--max-spp", "2", "--out", tmp_path / "o.exr",
                          "--stats", tmp_path / "o.json", "--quiet", cwd=tmp_path, timeout=120)
    assert_refused(done.returncode, done.stderr, "has no active camera")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["no_camera.blend"]
    assert blend.read_bytes() == saved                               # the .blend is never written
