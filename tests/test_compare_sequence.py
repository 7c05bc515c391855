"""``xsl-render compare`` on frame sequences: the per-frame figures against single-image
compare, the JSON, the flicker of real files, heatmaps and the report (also in headless
Chromium), the video JOD (where ColorVideoVDP is installed) and one-line errors."""
from __future__ import annotations

import importlib.util
import json
import shutil

import numpy as np
import pytest
from test_frame_sequence import H, W, write_sequence

from xsl_render.core.imageio import write_exr
from xsl_render.core.validation.report_sequence import strip_frames

HAS_VDP = importlib.util.find_spec("pycvvdp") is not None


def test_the_strip_shows_every_frame_or_evenly_spaced_ones_with_the_worst():
    assert strip_frames([1, 2, 3], 2) == [1, 2, 3]
    shown = strip_frames(list(range(1, 101)), 37, limit=10)
    assert len(shown) <= 10 and 37 in shown and shown[0] == 1 and shown[-1] == 100


def compare_main(capfd, *argv) -> tuple[int, str, str]:
    from xsl_render.operators.cli import main

    capfd.readouterr()
    code = main([str(a) for a in argv])
    printed = capfd.readouterr()
    return code, printed.out, printed.err


@pytest.fixture
def sequences(tmp_path):
    """A reference of frames 1-5, a test with per-frame noise and one with the same noise
    in every frame (same amplitude)."""
    from xsl_render.core.imageio import read_image

    reference = write_sequence(tmp_path / "ref", range(1, 6))
    write_sequence(tmp_path / "dynamic", range(1, 6), seed=3, sigma=0.03)
    static = tmp_path / "static"
    static.mkdir()
    rng = np.random.default_rng(3)
    noise = rng.normal(0, 0.03, (H, W, 3)).astype(np.float32)
    for frame in range(1, 6):
        write_exr(static / f"frame_{frame:04d}.exr",
                  np.maximum(read_image(reference / f"frame_{frame:04d}.exr") + noise, 0.0))
    return tmp_path


def test_sequence_json_holds_every_frame_and_the_sequence(capfd, sequences):
    out = sequences / "c.json"
    code, printed, err = compare_main(capfd, "compare", sequences / "ref" / "frame_####.exr",
                                      sequences / "dynamic", "--json", out, "--no-vdp", "--fps", "30")
    assert (code, err) == (0, "")
    data = json.loads(out.read_text())
    assert [record["frame"] for record in data["frames"]] == [1, 2, 3, 4, 5]
    assert data["dynamic_range"] == "HDR" and (data["width"], data["height"]) == (W, H)
    sequence = data["sequence"]
    assert sequence["count"] == 5 and sequence["fps"] == 30.0
    for metric in ("flip", "flip_tile95", "flip_share", "mse"):
        values = [record[metric] for record in data["frames"]]
        assert sequence["mean"][metric] == pytest.approx(np.mean(values))
        assert sequence["worst"][metric]["value"] == max(values)
        assert data["frames"][[r["frame"] for r in data["frames"]].index(
            sequence["worst"][metric]["frame"])][metric] == max(values)
    assert data["frames"][0]["flicker"] is None and all(r["flicker"] > 0 for r in data["frames"][1:])
    assert sequence["flicker"]["flicker"] == pytest.approx(np.mean([r["flicker"] for r in data["frames"][1:]]))
    assert sequence["vdp"] == {"jod": None, "skipped": "not requested (--no-vdp)"}
    assert printed.splitlines()[0].split()[:3] == ["frame", "mean", "FLIP"]
    assert "flicker" in printed and f"{sequence['mean']['flip']:.4f}" in printed


def test_each_frame_scores_as_single_image_compare_scores_it(capfd, sequences):
    """The per-frame figures come from the single-image comparison itself."""
    seq_json, one_json = sequences / "s.json", sequences / "one.json"
    assert compare_main(capfd, "compare", sequences / "ref", sequences / "dynamic", "--json", seq_json,
                        "--no-vdp", "--exposure", "1")[0] == 0
    assert compare_main(capfd, "compare", sequences / "ref" / "frame_0003.exr",
                        sequences / "dynamic" / "frame_0003.exr", "--json", one_json,
                        "--no-vdp", "--exposure", "1")[0] == 0
    frame = json.loads(seq_json.read_text())["frames"][2]
    single = json.loads(one_json.read_text())["metrics"]
    assert frame["frame"] == 3
    for name in ("mse", "flip"):
        for key, value in single[name].items():
            if key != "seconds":
                assert frame["metrics"][name][key] == value, (name, key)
    assert frame["flip"] == single["flip"]["mean_flip"] and frame["mse"] == single["mse"]["mse"]
    assert frame["flip_tile95"] == single["flip"]["tile95_flip"]
    assert frame["flip_share"] == single["flip"]["error_pixel_percent"]


def test_per_frame_noise_flickers_more_than_the_same_noise_standing_still(capfd, sequences):
    results = {}
    for kind in ("static", "dynamic", "ref"):
        out = sequences / f"{kind}.json"
        assert compare_main(capfd, "compare", sequences / "ref", sequences / kind, "--json", out, "--no-vdp")[0] == 0
        results[kind] = json.loads(out.read_text())["sequence"]
    assert results["ref"]["flicker"]["flicker"] == 0.0 and results["ref"]["mean"]["flip"] == 0.0
    # about the same error in every frame, but only one of them flickers (the static noise is
    # added to scene-linear frames, so where the scene changes its display-encoded error does too)
    assert results["static"]["mean"]["flip"] == pytest.approx(results["dynamic"]["mean"]["flip"], rel=0.25)
    assert results["static"]["flicker"]["flicker"] < 0.2 * results["dynamic"]["flicker"]["flicker"]


def test_heatmaps_and_report_of_a_sequence(capfd, sequences):
    maps, report, out = sequences / "maps", sequences / "report.html", sequences / "c.json"
    code, printed, err = compare_main(capfd, "compare", sequences / "ref", sequences / "dynamic", "--no-vdp",
                                      "--heatmap-dir", maps, "--report", report, "--json", out,
                                      "--frames", "2-4")
    assert (code, err) == (0, ""), err
    assert sorted(p.name for p in maps.iterdir()) == [f"{m}_{f:04d}.png" for m in ("flip", "mse") for f in (2, 3, 4)]
    data = json.loads(out.read_text())
    assert [r["frame"] for r in data["frames"]] == [2, 3, 4] and len(data["heatmaps"]) == 6
    html = report.read_text()
    assert "<script" not in html and html.count("<svg") == 1 and "<polyline" in html
    assert html.count("src='data:image/png;base64,") == 9          # 3 frames x test, reference, FLIP
    assert "frame 4" in html and f"{data['sequence']['mean']['flip']:.4f}" in html
    assert not list(sequences.glob("**/.*partial*"))


@pytest.mark.parametrize("argv, words", [
    (["{ref}", "{ref}/frame_0001.exr"], "REF is a sequence of frames and TEST one image"),
    (["{ref}", "{short}"], "frame 5 is in REF but not in TEST"),
    (["{ref}", "{short}", "--frames", "1-6"], "TEST has no frame 5 of --frames"),
    (["{ref}", "{odd}"], "every frame must have one size"),
    (["{ref}", "{dynamic}", "--heatmap", "{ws}/h.png"], "for sequences give --heatmap-dir"),
    (["{ref}/frame_0001.exr", "{ref}/frame_0002.exr", "--report", "{ws}/r.html"], "--report is for sequences"),
    (["{ref}/frame_0001.exr", "{ref}/frame_0002.exr", "--fps", "30"], "--fps is for sequences"),
    (["{ref}", "{dynamic}", "--json", "{dynamic}/frame_0003.exr"], "--json and frame 3 of TEST name the same file"),
    (["{ref}", "{dynamic}", "--fps", "0"], "must be greater than 0"),
    (["{ref}", "{dynamic}", "--frames", "3-1"], "is before the start frame"),
])
def test_bad_sequence_input_exits_2_with_one_line_and_writes_nothing(capfd, sequences, argv, words):
    short = sequences / "short"
    shutil.copytree(sequences / "dynamic", short)
    (short / "frame_0005.exr").unlink()
    write_sequence(sequences / "odd", range(1, 6), size=(H + 2, W))
    keys = {"ref": sequences / "ref", "short": short, "odd": sequences / "odd",
            "dynamic": sequences / "dynamic", "ws": sequences}
    before = sorted(p.relative_to(sequences) for p in sequences.rglob("*"))
    code, printed, err = compare_main(capfd, "compare", *[a.format(**keys) for a in argv],
                                      *(["--no-vdp"] if "--json" not in argv else []))
    assert code == 2 and printed == ""
    assert len(err.splitlines()) == 1 and words in err and "Traceback" not in err, err
    assert sorted(p.relative_to(sequences) for p in sequences.rglob("*")) == before


@pytest.mark.skipif(not HAS_VDP, reason="ColorVideoVDP (optional) is not installed")
def test_video_jod_of_a_sequence(capfd, sequences):
    jods = {}
    for kind in ("ref", "dynamic"):
        out = sequences / f"{kind}.json"
        assert compare_main(capfd, "compare", sequences / "ref", sequences / kind, "--json", out)[0] == 0
        jods[kind] = json.loads(out.read_text())["sequence"]["vdp"]
    assert jods["ref"]["jod"] == pytest.approx(10.0, abs=1e-3)
    assert jods["dynamic"]["jod"] < 9.9 and jods["dynamic"]["as_video"] and jods["dynamic"]["fps"] == 24.0
    assert jods["dynamic"]["frames"] == 5 and jods["dynamic"]["skipped"] is None


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.browser
@pytest.mark.skipif(CHROMIUM is None, reason="no chromium on this machine (apt-get install chromium)")
def test_sequence_report_renders_in_headless_chromium(capfd, sequences, tmp_path):
    """The report opens without errors, every thumbnail decodes, and it is not a blank page."""
    from xsl_render.core.imageio import read_image

    sync_api = pytest.importorskip("playwright.sync_api")
    report = sequences / "report.html"
    assert compare_main(capfd, "compare", sequences / "ref", sequences / "dynamic", "--no-vdp",
                        "--report", report)[0] == 0
    errors = []
    with sync_api.sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(tmp_path / "profile"), executable_path=CHROMIUM, headless=True,
            args=["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"],
            viewport={"width": 1280, "height": 900}, offline=True)
        try:
            page = context.new_page()
            page.on("console", lambda message: errors.append(message.text) if message.type == "error" else None)
            page.on("pageerror", lambda error: errors.append(str(error)))
            page.goto(report.resolve().as_uri(), wait_until="load")
            images = page.eval_on_selector_all("img", "els => els.map(e => [e.complete, e.naturalWidth])")
            points = page.eval_on_selector_all("svg circle", "els => els.length")
            page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
        finally:
            context.close()
    assert errors == []
    assert len(images) == 15 and all(done and width == W for done, width in images), images
    assert points == 10                                          # 5 frames x 2 curves
    shot = read_image(tmp_path / "report.png")[..., :3]
    assert shot.std() > 0.1 and 0.02 < (shot.mean(axis=2) < 0.5).mean() < 0.9


def test_the_video_jod_is_skipped_with_a_reason_when_its_frames_would_not_fit(monkeypatch):
    from xsl_render.core.validation import sequence
    from xsl_render.core.validation.frame_sequence import FrameSize

    size = FrameSize(1920, 1080, True)
    assert sequence.video_skip_reason(48, size, vdp=False) == "not requested (--no-vdp)"
    monkeypatch.setattr(sequence, "vdp_unavailable_reason", lambda: None)
    monkeypatch.setattr(sequence, "physical_memory", lambda: 4 * 10 ** 9)
    assert sequence.video_bytes(48, size) == 2 * 48 * 1080 * 1920 * 3 * 2
    assert sequence.video_skip_reason(4, size, vdp=True) is None
    reason = sequence.video_skip_reason(48, size, vdp=True)
    assert "1.2 GB" in reason and "--frames" in reason
