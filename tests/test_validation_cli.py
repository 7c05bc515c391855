"""``xsl-render experiment`` and ``xsl-render demo`` end to end on tiny scenes: every mode and
metric in results.json, resuming without re-rendering, continuing after a kill, and one
clear line with exit 2 for bad input."""
from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import EXAMPLES, xsl_render_cli
from support.fog_scene import saved_fog_scene
from test_cli_info import one_line_error

from xsl_render.core.sampling.render_stats import RenderStats
from xsl_render.core.validation.curves import curve_points, monotone_envelope
from xsl_render.core.validation.results import uniform_curve

pytestmark = [pytest.mark.blender, pytest.mark.render]

W, H = 64, 36
ALL = ("gold", "auto_file_samples", "auto_equal_time", "x_only", "s_only", "xs", "xsl", "xsl_no_minbound",
       "uniform_eighth", "uniform_quarter", "uniform_half", "uniform_equal_time", "adaptive_equal_time",
       "guided_equal_time")
#: A small converged reference keeps the tests quick (the default is 1024 spp).
REFERENCE = ("--reference-spp", "64")
TINY = ("--max-spp", "4", "--tile-size", "16", "--no-vdp", "--quiet") + REFERENCE


@pytest.fixture(scope="module")
def fog_blend(tmp_path_factory):
    return saved_fog_scene(tmp_path_factory.mktemp("scene"), W, H)


@pytest.fixture(scope="module")
def experiment(fog_blend, tmp_path_factory):
    """One full run over the fog scene (MinBound compared too); returns (out dir, result)."""
    out = tmp_path_factory.mktemp("experiment") / "out"
    result = xsl_render_cli("experiment", "--scenes", fog_blend, "--out", out,
                            "--minbound-scenes", "fog", *TINY)
    assert result.returncode == 0, result.stderr
    return out, result


def results(out: Path) -> dict:
    return json.loads((out / "results.json").read_text())


def test_results_hold_every_mode_and_metric(experiment):
    out, result = experiment
    data = results(out)
    runs = data["scenes"]["fog"]["runs"]
    assert tuple(runs) == ALL
    reference = data["scenes"]["fog"]["reference"]
    assert reference["inputs"]["spp"] == 64 and reference["inputs"]["seed"] == 7
    assert reference["source"] == "rendered" and Path(reference["path"]).is_file()
    # Two map sets (MinBound on, off), the renders and the converged reference.
    assert data["rendered"] == 2 + len(ALL) + 1
    gold = runs["gold"]
    assert gold["stats"]["mean_spp"] == 4 and gold["maps_s"] == 0
    for name, run in runs.items():
        assert run["time_s"] > 0 and not run["reused"]
        assert (out / run["files"]["image"]).is_file() and (out / run["files"]["spp_png"]).is_file()
        against_reference = run["reference_metrics"]
        assert against_reference["flip"]["mean_flip"] > 0 and against_reference["mse"]["skipped"] is None
        assert (out / run["reference_heatmaps"]["flip"]).is_file()
        if run["kind"] in ("gold", "uniform"):
            assert run["equal_quality"] is None                        # on the uniform curve
        else:
            assert set(run["equal_quality"]) == {"flip", "mse", "jod"}
            flip = run["equal_quality"]["flip"]
            assert flip["value"] is not None and flip["faster"] == (flip["value"] > 1)
        if name == "gold":
            continue
        assert run["speedup_over_gold"] == pytest.approx(gold["time_s"] / run["time_s"])
        for metric in ("mse", "flip"):
            summary = run["metrics"][metric]
            assert summary["skipped"] is None
            assert 0 <= summary["average_error_percent"] <= 100
            assert 0 <= summary["error_pixel_percent"] <= 100
            assert (out / run["heatmaps"][metric]).is_file()
        assert run["metrics"]["vdp"]["skipped"] == "not requested (--no-vdp)"
        assert "vdp" not in run["heatmaps"]
    for name in ("x_only", "s_only", "xs", "xsl", "xsl_no_minbound"):
        assert 0 < runs[name]["maps_s"] < runs[name]["time_s"]          # Fig. 8: maps included
        assert runs[name]["stats"]["mean_spp"] < 4                      # selective: fewer samples
    assert runs["x_only"]["maps_s"] < runs["xsl"]["maps_s"]             # X alone needs less
    assert [runs[n]["stats"]["mean_spp"] for n in ("uniform_eighth", "uniform_quarter", "uniform_half")] \
        == [1, 1, 2]                                                   # 1/8, 1/4, 1/2 of 4, at least 1
    xsl = runs["xsl"]
    assert xsl["stats"]["phases_s"]["denoise"] > 0
    for name in ("uniform_equal_time", "adaptive_equal_time"):
        # XSL's time, maps included; each pays its own denoising pass on top of the limit.
        assert runs[name]["stats"]["time_budget_s"] == pytest.approx(
            xsl["time_s"] - xsl["stats"]["phases_s"]["denoise"])
        assert runs[name]["stats"]["phases_s"]["denoise"] > 0
    # Guided's budget covers its denoising too: it gets all of XSL's time, and auto's estimator.
    guided = runs["guided_equal_time"]["stats"]
    assert guided["time_budget_s"] == pytest.approx(xsl["time_s"])
    assert guided["mode"] == "guided" and guided["estimator"]["estimator"] == "auto"
    assert runs["uniform_equal_time"]["stats"]["estimator"]["estimator"] == "scene"   # the file as it is
    assert guided["phases_s"]["denoise"] > 0 and 0 < guided["mean_spp"] <= 4      # the ceiling holds
    assert data["scenes"]["fog"]["maps"]["no_minbound"]["minbound"] is False
    lines = result.stdout.strip().splitlines()
    assert lines[0].startswith("fog (64x36, ceiling 4 spp) against a converged reference of 64 spp, seed 7")
    assert "equal quality vs uniform" in lines[1]
    assert not any("faster than gold" in line for line in lines)
    assert lines[-1] == f"report: {(out / 'report.html').resolve()}"


def test_rerun_reuses_every_finished_step(experiment, fog_blend):
    out, _ = experiment
    before = {p: p.stat().st_mtime_ns for p in out.glob("fog/*.exr")}
    result = xsl_render_cli("experiment", "--scenes", fog_blend, "--out", out,
                            "--minbound-scenes", "fog", *TINY)
    assert result.returncode == 0, result.stderr
    data = results(out)
    assert data["rendered"] == 0 and data["reused"] == 2 + len(ALL) + 1     # the reference too
    assert all(run["reused"] for run in data["scenes"]["fog"]["runs"].values())
    assert {p: p.stat().st_mtime_ns for p in out.glob("fog/*.exr")} == before
    assert "0 step(s) computed" in result.stdout

    # Only what is missing or made from other inputs is done again.
    (out / "fog" / "adaptive_equal_time.json").unlink()
    result = xsl_render_cli("experiment", "--scenes", fog_blend, "--out", out,
                            "--minbound-scenes", "fog", *TINY)
    assert result.returncode == 0, result.stderr
    assert results(out)["rendered"] == 1
    assert not results(out)["scenes"]["fog"]["runs"]["adaptive_equal_time"]["reused"]


def test_other_ceiling_renders_again_but_keeps_the_maps(experiment, fog_blend, tmp_path):
    out, _ = experiment
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    result = xsl_render_cli("experiment", "--scenes", fog_blend, "--out", copy, "--variants", "xs",
                            "--max-spp", "5", "--tile-size", "16", "--no-vdp", "--quiet", *REFERENCE)
    assert result.returncode == 0, result.stderr
    data = results(copy)
    assert (data["rendered"], data["reused"]) == (2, 2)        # gold and xs again; maps, reference reused
    assert data["scenes"]["fog"]["runs"]["gold"]["stats"]["mean_spp"] == 5


def test_a_killed_run_continues(fog_blend, tmp_path):
    """SIGKILL as soon as the gold standard is on disk; the rerun keeps it and does the rest."""
    out = tmp_path / "out"
    exe = Path(sys.executable).with_name("xsl-render")
    args = [str(exe), "experiment", "--scenes", str(fog_blend), "--out", str(out), "--max-spp", "64",
            "--tile-size", "16", "--no-vdp", "--quiet", "--variants", "xs,xsl", *REFERENCE]
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while not (out / "fog" / "gold.json").exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    process.send_signal(signal.SIGKILL)
    process.wait()
    assert process.returncode == -signal.SIGKILL, "the run ended before it could be killed"
    assert not (out / "results.json").exists()
    result = xsl_render_cli(*args[1:])
    assert result.returncode == 0, result.stderr
    data = results(out)
    assert data["scenes"]["fog"]["runs"]["gold"]["reused"]
    assert not data["scenes"]["fog"]["runs"]["xsl"]["reused"]
    assert not list(out.rglob(".*partial*"))                  # nothing half-written left behind


def test_demo_end_to_end(tmp_path):
    assert (EXAMPLES / "road.blend").is_file()              # committed with its build script
    out = tmp_path / "demo"
    result = xsl_render_cli("demo", "--out", out, "--resolution", "64x36", "--max-spp", "4", "--no-vdp",
                            *REFERENCE)
    assert result.returncode == 0, result.stderr
    assert "demo [" in result.stderr and "ETA" in result.stderr          # the progress bar
    last = result.stdout.strip().splitlines()[-1]
    assert last == f"report: {(out / 'report.html').resolve()}"
    assert (out / "report.html").stat().st_size > 10_000
    runs = results(out)["scenes"]["road"]["runs"]
    assert tuple(runs) == ("gold", "auto_file_samples", "auto_equal_time", "xs", "xsl", "uniform_eighth",
                           "uniform_quarter", "uniform_half", "uniform_equal_time", "adaptive_equal_time",
                           "guided_equal_time")
    # The main job: the file (gold, its own settings) against Auto Volumes in its time, placed
    # on the file's curve, shown first in the report.
    auto, gold = runs["auto_equal_time"], runs["gold"]
    assert auto["stats"]["estimator"]["estimator"] == "auto" and gold["stats"]["estimator"]["estimator"] == "scene"
    gold_stats = RenderStats.from_json(json.loads((out / "road" / "gold.json").read_text())["stats"])
    assert auto["stats"]["time_budget_s"] == pytest.approx(gold_stats.render_seconds)
    assert runs["auto_file_samples"]["mean_spp"] == gold["mean_spp"] == 4
    report = (out / "report.html").read_text()
    assert report.index("The file and Auto Volumes in the same time") < report.index("Director maps")
    assert runs["xsl"]["metrics"]["flip"]["mean_flip"] > 0
    assert runs["xsl"]["reference_metrics"]["flip"]["mean_flip"] > 0
    # xsl is placed on the uniform curve (gold and the uniform runs). Its renders of a few
    # tens of milliseconds at this size may time out of order on a loaded machine, leaving
    # one point on the curve's monotone envelope: then the speedup says why it has no value.
    flip = runs["xsl"]["equal_quality"]["flip"]
    envelope = monotone_envelope(curve_points(uniform_curve(runs), "flip"))
    if len(envelope) >= 2:
        assert flip["value"] == pytest.approx(flip["time_to_reach_s"] / runs["xsl"]["time_s"])
    else:
        assert flip["value"] is None and "one point" in flip["reason"]
    # The demo prints equal-quality speedups over uniform, never a time ratio to gold.
    assert "equal quality vs uniform" in result.stdout and "faster than gold" not in result.stdout
    assert results(out)["scenes"]["road"]["maps"]["minbound"]["lights"]["drawn"]   # lamps in the L map


@pytest.mark.parametrize("args, message", [
    (("experiment", "--scenes", "nowhere"), "unknown scene 'nowhere'"),
    (("experiment", "--scenes", "missing.blend"), "no such scene file"),
    (("experiment", "--max-spp", "0"), "argument --max-spp: must be a whole number from 1 to"),
    (("experiment", "--variants", "gold,bogus"), "unknown variant 'bogus'"),
    (("experiment", "--size", "2"), "argument --size: must be a whole number from 8 to 16384"),
    (("experiment", "--resolution", "12by4"), "argument --resolution: must look like"),
    (("experiment", "--resolution", "64x36", "--size", "64"), "not both"),
    (("experiment", "--seed", "7"), "contestant seed 7 is the converged reference's seed"),
    (("experiment", "--reference-spp", "0"), "--reference-spp: must be a whole number from 1 to 16777216"),
    (("demo", "--scene", "README.md"), "not a .blend file"),
])
def test_bad_input_is_one_line(args, message):
    assert message in one_line_error(xsl_render_cli(*args))


def test_output_folder_that_is_a_file(tmp_path, fog_blend):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert "is a file, not a folder" in one_line_error(
        xsl_render_cli("experiment", "--scenes", fog_blend, "--out", blocker))


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--no-first-run"]


@pytest.mark.browser
@pytest.mark.skipif(CHROMIUM is None, reason="no chromium on this machine (apt-get install chromium; "
                                             "python3 run.py test installs it when it can)")
def test_report_renders_in_headless_chromium(experiment, tmp_path):
    """The report opens without console errors, every image decodes, and the page is not blank."""
    import numpy as np

    from xsl_render.core.imageio import read_image

    sync_api = pytest.importorskip("playwright.sync_api")
    out, _ = experiment
    report = out / "report.html"
    html = report.read_text()
    assert "src='data:image/png;base64," in html and "<script" not in html
    assert "<svg" in html and "Table I" in html and "Table II" in html
    errors = []
    with sync_api.sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(tmp_path / "profile"), executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS,
            viewport={"width": 1280, "height": 900}, offline=True)
        try:
            page = context.new_page()
            page.on("console", lambda message: errors.append(message.text) if message.type == "error" else None)
            page.on("pageerror", lambda error: errors.append(str(error)))
            page.on("requestfailed", lambda request: errors.append(f"failed: {request.url[:80]}"))
            page.goto(report.resolve().as_uri(), wait_until="load")
            images = page.eval_on_selector_all(
                "img", "els => els.map(e => [e.complete, e.naturalWidth, e.alt])")
            page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
        finally:
            context.close()
    assert errors == []
    assert len(images) > 30
    assert all(complete and width > 0 for complete, width, _ in images), images
    shot = read_image(tmp_path / "report.png")[..., :3]
    assert shot.shape[0] > 2000                                   # tables, charts and image grids
    assert shot.std() > 0.1                                       # not a blank page
    dark = (shot.mean(axis=2) < 0.5).mean()
    assert 0.05 < dark < 0.9                                      # pictures and text on a light page
