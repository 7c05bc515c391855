"""``xsl-render render``: every mode end to end, and one clear line with exit 2 for bad input."""
from __future__ import annotations

import hashlib
import json

import numpy as np
import OpenImageIO as oiio
import pytest
from support.fog_scene import build_fog_scene, radial_map
from test_cli_info import one_line_error

from xsl_render.core.imageio import read_image, write_exr

pytestmark = pytest.mark.blender

W, H = 64, 36


@pytest.fixture
def fog_blend(blender, tmp_path):
    """A fog scene saved with the Workbench engine (the render must switch to Cycles and warn)."""
    scene = build_fog_scene(blender, W, H)
    scene.render.engine = "BLENDER_WORKBENCH"
    path = tmp_path / "fog.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.render
def test_all_modes(cli, blender, fog_blend, tmp_path):
    before = digest(fog_blend)
    blender.context.scene.cycles.samples = own_samples = 3
    own_blend = tmp_path / "own.blend"                         # the scene with 3 samples of its own
    blender.ops.wm.save_as_mainfile(filepath=str(own_blend), copy=True)
    map_path = write_exr(tmp_path / "xsl.exr", radial_map(W, H, 0.3))
    out = tmp_path / "out"
    result = cli("render", fog_blend, "--mode", "xsl", "--max-spp", "8", "--tile-size", "16",
                 "--map", map_path, "--out", out / "xsl.exr", "--stats", out / "xsl.json")
    assert result.returncode == 0, result.stderr
    assert "warning: scene 'Scene' renders with BLENDER_WORKBENCH" in result.stderr
    assert "xsl [" in result.stderr and "ETA" in result.stderr          # progress lines (not a TTY)
    stats = json.loads((out / "xsl.json").read_text())
    assert stats["mode"] == "xsl" and stats["resolution"] == [W, H]
    # auto's choice is the default (--estimator scene: the file's own settings).
    assert set(stats["phases_s"]) == {"estimator", "maps", "plan", "renders", "composite", "denoise", "write"}
    assert stats["options"]["estimator"] == "auto"
    assert stats["wall_s"] == pytest.approx(sum(stats["phases_s"].values()))
    assert stats["renders"] == len(stats["tiles"]) == stats["plan"]["renders"] > 1
    assert stats["total_samples"] == stats["plan"]["total_samples"]
    image = read_image(out / "xsl.exr")
    spp = read_image(out / "xsl_spp.exr")[:, :, 0]
    assert image.shape == (H, W, 4) and np.isfinite(image).all()
    assert spp.sum() == stats["total_samples"] and spp.max() == 8
    assert read_image(out / "xsl_spp.png").shape == (H, W, 1)

    result = cli("render", fog_blend, "--mode", "uniform", "--max-spp", "8", "--budget-from",
                 out / "xsl.json", "--out", out / "uniform.exr", "--stats", out / "uniform.json", "--quiet")
    assert result.returncode == 0, result.stderr
    uniform = json.loads((out / "uniform.json").read_text())
    assert uniform["mean_spp"] == round(stats["mean_spp"]) and uniform["budget"] == "samples"

    result = cli("render", fog_blend, "--mode", "adaptive", "--max-spp", "8", "--budget-from",
                 out / "xsl.json", "--out", out / "adaptive.exr", "--stats", out / "adaptive.json")
    assert result.returncode == 0, result.stderr
    adaptive = json.loads((out / "adaptive.json").read_text())
    # Equal time: the xsl run's wall time less its denoising (the adaptive run denoises too).
    budget = stats["wall_s"] - stats["phases_s"]["denoise"]
    assert adaptive["time_budget_s"] == pytest.approx(budget) and adaptive["noise_threshold"] == 0.01

    result = cli("render", fog_blend, "--mode", "gold", "--max-spp", "8", "--out", out / "gold.exr",
                 "--resolution", "32x18", "--seed", "3")
    assert result.returncode == 0, result.stderr
    assert read_image(out / "gold.exr").shape == (18, 32, 4)
    assert "gold: 32x18, mean 8.00 spp in 1 render(s)" in result.stdout
    # Without --max-spp a count is the scene's own samples (uniform's too, without a budget).
    result = cli("render", own_blend, "--mode", "uniform", "--estimator", "scene", "--out", out / "own.exr",
                 "--resolution", "32x18", "--stats", out / "own.json")
    assert result.returncode == 0, result.stderr
    own = json.loads((out / "own.json").read_text())
    assert (own["max_spp"], own["mean_spp"], own["options"]["estimator"]) == (own_samples, own_samples, "scene")
    assert digest(fog_blend) == before                       # the .blend is never written
    assert not list(out.glob(".*partial*"))


def nan_map(path):
    spec = oiio.ImageSpec(W, H, 1, oiio.FLOAT)
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(np.full((H, W, 1), np.nan, np.float32))
    out.close()
    return path


@pytest.mark.parametrize("args,message", [
    (["--mode", "gold", "--max-spp", "0"], "argument --max-spp: must be a whole number from 1 to"),
    (["--mode", "xsl", "--max-spp", "4", "--min-spp", "5", "--map", "nan.exr"], "larger than --max-spp"),
    (["--mode", "xsl", "--max-spp", "4", "--tile-size", "4", "--map", "nan.exr"],
     "argument --tile-size: must be a whole number from 8 to"),
    (["--mode", "xsl", "--max-spp", "4", "--wl", "-1"], "--wl: must be at least 0, not -1"),
    (["--mode", "xsl", "--max-spp", "4", "--map", "missing.exr"], "no such director map"),
    (["--mode", "xsl", "--max-spp", "4", "--map", "nan.exr"], "NaN"),
    (["--mode", "uniform", "--spp", "4", "--equal-time", "2"], "needs either --spp or --equal-time"),
    (["--mode", "adaptive", "--spp", "4"], "--spp is for --mode uniform"),
    (["--mode", "uniform", "--max-spp", "4", "--budget-from", "missing.json"], "no such stats file"),
    (["--mode", "gold", "--max-spp", "4", "--resolution", "big"], "--resolution"),
    (["--mode", "bogus", "--max-spp", "4"], "invalid choice"),
])
def test_bad_options_fail_before_the_scene_is_opened(cli, tmp_path, args, message):
    nan_map(tmp_path / "nan.exr")
    (tmp_path / "unused.blend").write_bytes(b"BLENDER-v500")       # a header is all it needs
    result = cli("render", tmp_path / "unused.blend", *args, "--out", tmp_path / "o.exr", cwd=tmp_path)
    assert message in one_line_error(result)
    assert not (tmp_path / "o.exr").exists()


@pytest.mark.parametrize("extra,message", [
    (["--mode", "xsl", "--tile-size", "72", "--map", "map.exr"], "--tile-size 72 is larger than the 64x36 frame"),
    (["--mode", "xsl", "--map", "map.exr", "--resolution", "32x18"], "the director map is 64x36 but the render is 32x18"),
    (["--mode", "gold", "--scene-name", "NoCamera"], "has no active camera"),
])
def test_bad_input_found_in_the_scene(cli, blender, fog_blend, tmp_path, extra, message):
    if "NoCamera" in extra:
        blender.ops.wm.open_mainfile(filepath=str(fog_blend))
        blender.data.scenes.new("NoCamera")
        blender.ops.wm.save_mainfile()
    write_exr(tmp_path / "map.exr", radial_map(W, H, 0.3))
    result = cli("render", fog_blend, "--max-spp", "4", *extra, "--out", tmp_path / "o.exr", cwd=tmp_path)
    assert message in one_line_error(result)
    assert not list(tmp_path.glob("o*"))


def test_not_an_exr_output(cli, tmp_path):
    (tmp_path / "x.blend").write_bytes(b"BLENDER-v500")
    result = cli("render", tmp_path / "x.blend", "--mode", "gold", "--max-spp", "4", "--out", tmp_path / "o.png")
    assert "argument --out:" in one_line_error(result) and "must be a .exr file" in one_line_error(result)


@pytest.mark.render
def test_ctrl_c_cancels_between_tiles_and_writes_nothing(fog_blend, tmp_path):
    import signal
    import subprocess
    import sys
    from pathlib import Path

    map_path = write_exr(tmp_path / "xsl.exr", radial_map(W, H, 0.5))
    exe = Path(sys.executable).with_name("xsl-render")
    process = subprocess.Popen(
        [str(exe), "render", str(fog_blend), "--mode", "xsl", "--max-spp", "256", "--tile-size", "8",
         "--map", str(map_path), "--estimator", "scene",      # the tiles from the first line on
         "--out", str(tmp_path / "o.exr"), "--stats", str(tmp_path / "o.json")],
        stderr=subprocess.PIPE, text=True)
    first = process.stderr.readline()             # the progress bar's first line: rendering began
    assert "tile 1/" in first, first
    process.send_signal(signal.SIGINT)
    rest = process.communicate(timeout=60)[1]
    assert process.returncode == 130, rest
    assert "xsl-render: cancelled" in rest
    assert not list(tmp_path.glob("o*"))
