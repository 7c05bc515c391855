"""The fuzz table's wrong codes of issue 23: writes that fail and cameras that place nothing.

A full disk while --stats was written used to end with exit code 1 ("internal error"), a
camera scaled to zero with 1 (LinAlgError) after Blender loaded, a camera at a NaN location
rendered with 0. Each is now exit code 2 with one line, and nothing is written: no output,
no temporary, the inputs' bytes as they were.

Write errors come two ways: the kernel's own (a file size limit, ``RLIMIT_FSIZE``, makes
every write past it fail with EFBIG, as a full disk fails with ENOSPC, in a real process),
and, in this process, ENOSPC and EACCES from the file writes themselves.
"""
from __future__ import annotations

import errno
import hashlib
import math
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import xsl_render_cli
from support.fog_scene import build_fog_scene

from xsl_render.core.errors import InputError
from xsl_render.core.imageio import write_exr, write_png
from xsl_render.core.sampling.render_files import write_render_outputs
from xsl_render.core.sampling.render_stats import RenderStats
from xsl_render.operators.cli import main

EXE = Path(sys.executable).with_name("xsl-render")


def tree(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` (hidden temporaries too) with its bytes' hash."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def assert_one_line(code: int, err: str, words: str) -> None:
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, (code, err)
    assert lines[0].startswith("xsl-render: error: ") and words in lines[0], err


@pytest.fixture
def images(tmp_path) -> Path:
    rng = np.random.default_rng(23)
    write_exr(tmp_path / "ref.exr", rng.random((48, 64, 4)).astype(np.float32))
    write_exr(tmp_path / "test.exr", rng.random((48, 64, 4)).astype(np.float32))
    write_png(tmp_path / "img.png", rng.random((48, 64, 3)).astype(np.float32))
    write_png(tmp_path / "tiny.png", rng.random((6, 8, 3)).astype(np.float32))
    (tmp_path / "fix.csv").write_text("x,y,duration_ms\n20,30,400\n")
    return tmp_path


def _file_size_limit(limit: int):
    def limited() -> None:          # in the child, before exec
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)     # the write fails instead of killing
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return limited


@pytest.mark.parametrize("case_id, argv, words", [
    # compare's JSON is a few kB: the limit stops it half-way.
    ("e2e-compare-json-file-too-large", ["compare", "ref.exr", "test.exr", "--no-vdp", "--json", "c.json"],
     "cannot write c.json: file too large"),
    # An EXR small enough to sit in OpenImageIO's buffer until close: its error was lost there
    # and the truncated file took the real name with exit code 0.
    ("e2e-saliency-exr-file-too-large", ["saliency", "tiny.png", "--out", "s.exr"],
     "cannot write s.exr: the file came out incomplete"),
    # A PNG's short writes were only a message OpenImageIO kept.
    ("e2e-hotspots-png-file-too-large", ["hotspots", "img.png", "fix.csv", "--out", "h.png"],
     "cannot write h.png: Write error"),
], ids=lambda value: value if str(value).startswith("e2e-") else "-")
def test_a_write_the_system_refuses_is_exit_2(images, case_id, argv, words):
    before = tree(images)
    limit = 300
    done = subprocess.run([str(EXE), *argv], cwd=images, capture_output=True, text=True, timeout=60,
                          preexec_fn=_file_size_limit(limit))
    assert_one_line(done.returncode, done.stderr, words)
    assert tree(images) == before and done.stdout == ""


def _failing_write_text(error_number: int):
    """``Path.write_text`` that writes half of the text, then fails as the system would."""
    real = Path.write_text

    def write_text(self, text, *args, **kwargs):
        real(self, text[:len(text) // 2], *args, **kwargs)
        raise OSError(error_number, {errno.ENOSPC: "No space left on device",
                                     errno.EACCES: "Permission denied"}[error_number], str(self))
    return write_text


@pytest.mark.parametrize("error_number, words", [(errno.ENOSPC, "no space left on device"),
                                                 (errno.EACCES, "permission denied")],
                         ids=["compare-json-disk-full", "compare-json-permission-denied"])
def test_a_failed_json_write_is_exit_2(images, capfd, monkeypatch, error_number, words):
    before = tree(images)
    monkeypatch.chdir(images)
    monkeypatch.setattr(Path, "write_text", _failing_write_text(error_number))
    capfd.readouterr()
    code = main(["compare", "ref.exr", "test.exr", "--no-vdp", "--json", "c.json"])
    assert_one_line(code, capfd.readouterr().err, f"cannot write c.json: {words}")
    assert tree(images) == before


def test_a_full_disk_while_stats_are_written_leaves_no_file_of_the_render(tmp_path, monkeypatch):
    """render-stats-disk-full: the set (image, _spp files, --stats) appears whole or not at all."""
    monkeypatch.setattr(Path, "write_text", _failing_write_text(errno.ENOSPC))
    image, samples = np.ones((8, 8, 4), np.float32), np.full((8, 8), 4.0, np.float32)
    stats = RenderStats(mode="gold", scene="Scene", resolution=(8, 8), max_spp=4, seed=0,
                        phases_s={"renders": 1.0}, total_samples=256, mean_spp=4.0, gold_samples=256,
                        renders=1, tiles=[], options={}, estimator={})
    with pytest.raises(InputError, match=r"cannot write .*s\.json: no space left on device"):
        write_render_outputs(tmp_path / "o.exr", image, samples, stats, 4, 0, tmp_path / "s.json")
    assert tree(tmp_path) == {}


@pytest.fixture
def broken_cameras(blender, tmp_path):
    """The fog scene at 64x36 saved three times: camera scaled to zero, at a NaN location, at
    an infinite one (which Blender stores as 3.4e38)."""
    build_fog_scene(blender, 64, 36)
    camera = blender.context.scene.camera
    files = {}
    for name, change in (("zero_scale", lambda: setattr(camera, "scale", (0.0, 0.0, 0.0))),
                         ("nan_location", lambda: setattr(camera, "location", (math.nan, -8.0, 2.0))),
                         ("inf_location", lambda: setattr(camera, "location", (0.0, math.inf, 2.0)))):
        scale, location = tuple(camera.scale), tuple(camera.location)
        change()
        files[name] = tmp_path / f"{name}.blend"
        blender.ops.wm.save_as_mainfile(filepath=str(files[name]), copy=True)
        camera.scale, camera.location = scale, location
    return files


@pytest.mark.blender
@pytest.mark.parametrize("case_id, mode, words", [
    ("camera-zero-scale", "gold", "is scaled to zero"),
    ("camera-nan-location", "gold", "NaN or infinite"),
    ("camera-inf-location", "xsl", "NaN or infinite"),
])
def test_a_camera_that_places_nothing_is_refused_before_rendering(broken_cameras, tmp_path, case_id, mode,
                                                                  words):
    blend = broken_cameras[{"camera-zero-scale": "zero_scale", "camera-nan-location": "nan_location",
                            "camera-inf-location": "inf_location"}[case_id]]
    before = tree(tmp_path)
    done = xsl_render_cli("render", blend, "--mode", mode, "--max-spp", "1", "--out", tmp_path / "out" / "o.exr",
                          "--stats", tmp_path / "out" / "o.json", "--quiet", cwd=tmp_path, timeout=300)
    assert_one_line(done.returncode, done.stderr, words)
    assert tree(tmp_path) == before and not (tmp_path / "out").exists()
