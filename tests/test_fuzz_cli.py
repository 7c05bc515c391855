"""The fuzz table of issue 15: bad input to every subcommand, each refused as the contract says.

Every case must end with exit code 2 and one line on stderr naming the problem (no
traceback), write nothing, and never load Blender. Most cases run the command line in this
process (cheap) with ``bpy`` made unimportable, so a case that got as far as Blender fails;
a few run the real console script end to end; the permission cases run with the effective
user switched to nobody when the tests run as root (root may write anywhere).
"""
from __future__ import annotations

import os
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
    keys = {p.stem if p.is_file() else p.name: str(p) for p in root.iterdir()}
    keys.update(ws=str(root), missing=str(root / "missing"), under=str(root / "file.txt" / "x"),
                proc="/proc/xsl-render-fuzz", png=str(root / "ref.png"), exr=str(root / "ref.exr"),
                blend=str(root / "scene.blend"))
    return keys


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    return root, make_workspace(root)


def snapshot(root: Path) -> dict:
    return {str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns) if p.is_file() else None
            for p in sorted(root.rglob("*"))}


R = ["render", "{blend}"]                        # a render with a scene that passes its checks
RX = R + ["--mode", "xsl", "--max-spp", "8"]
RG = R + ["--mode", "gold", "--max-spp", "8"]
OUT = ["--out", "{ws}/o.exr"]
M = ["maps", "{blend}", "--out", "{ws}/m"]
HOT = ["hotspots", "{png}", "{fix}", "--out", "{ws}/h.png"]
FARM = ["farm", "{blend}", "--bundle", "{ws}/bundle"]
FT = ["farm-task", "maps", "{blend}", "--scene-name", "S", "--frame", "1", "--output", "{ws}/job",
      "--mode", "xsl", "--max-spp", "8", "--resolution", "64x36"]

#: (id, argv, words the one line must hold)
CASES = [
    # -- info ------------------------------------------------------------------------------
    ("info-missing", ["info", "{missing}"], "no such file"),
    ("info-folder", ["info", "{dir}"], "is a folder, not a file"),
    ("info-not-blend", ["info", "{text}"], "not a .blend file"),
    ("info-empty", ["info", "{empty}"], "not a .blend file"),
    ("info-extra", ["info", "{blend}", "--bogus"], "unrecognized arguments: --bogus"),
    ("info-none", ["info"], "required: SCENE.blend"),
    ("no-command", [], "required: COMMAND"),
    ("unknown-command", ["rendr"], "invalid choice: 'rendr'"),
    # -- maps ------------------------------------------------------------------------------
    ("maps-scene-missing", ["maps", "{missing}", "--out", "{ws}/m"], "no such file"),
    ("maps-scene-not-blend", ["maps", "{file}", "--out", "{ws}/m"], "not a .blend file"),
    ("maps-out-file", ["maps", "{blend}", "--out", "{file}"], "is a file, not a folder"),
    ("maps-out-proc", ["maps", "{blend}", "--out", "{proc}"], "cannot write /proc/xsl-render-fuzz"),
    ("maps-out-under-file", ["maps", "{blend}", "--out", "{under}"], "is not a folder"),
    ("maps-res-1x1", M + ["--resolution", "1x1"], "each side must be 4 to 65536"),
    ("maps-res-huge", M + ["--resolution", "65536x65536"], "of memory"),
    ("maps-res-0x0", M + ["--resolution", "0x0"], "each side must be 4 to 65536"),
    ("maps-res-negative", M + ["--resolution=-64x36"], "each side must be 4 to 65536"),
    ("maps-res-word", M + ["--resolution", "big"], "must look like 512x288"),
    ("maps-res-3d", M + ["--resolution", "4x4x4"], "must look like 512x288"),
    ("maps-res-float", M + ["--resolution", "64.5x36"], "must look like 512x288"),
    ("maps-res-wide", M + ["--resolution", "70000x4"], "each side must be 4 to 65536"),
    ("maps-frame-32bit", M + ["--frame", "3000000000"], "from -1048574 to 1048574"),
    ("maps-frame-past-blender", M + ["--frame", "1048575"], "from -1048574 to 1048574"),
    ("maps-frame-nan", M + ["--frame", "nan"], "whole number, not 'nan'"),
    ("maps-frame-float", M + ["--frame", "1.5"], "whole number, not '1.5'"),
    ("maps-wx-nan", M + ["--wx", "nan"], "finite number, not nan"),
    ("maps-wx-inf", M + ["--wx", "inf"], "finite number, not inf"),
    ("maps-wx-negative", M + ["--wx", "-1"], "--wx must be a number >= 0"),
    ("maps-ws-nan", M + ["--ws", "NaN"], "finite number, not nan"),
    ("maps-wxs-inf", M + ["--wxs=-inf"], "finite number, not -inf"),
    ("maps-wl-word", M + ["--wl", "heavy"], "must be a number, not 'heavy'"),
    ("maps-weights-zero", M + ["--wx", "0", "--ws", "0"], "cannot both be 0"),
    ("maps-xs-op", M + ["--xs-op", "max"], "--xs-op must be 'add' or 'multiply'"),
    ("maps-xsl-op", M + ["--xsl-op", ""], "--xsl-op must be 'add' or 'multiply'"),
    ("maps-light-n-negative", M + ["--light-n", "-1"], "from 0 to 100, not -1"),
    ("maps-light-n-huge", M + ["--light-n", "2147483648"], "from 0 to 100"),
    ("maps-light-n-word", M + ["--light-n", "many"], "whole number, not 'many'"),
    ("maps-sigma-zero", M + ["--light-sigma-base", "0"], "greater than 0"),
    ("maps-sigma-nan", M + ["--light-sigma-base", "nan"], "finite number, not nan"),
    ("maps-sigma-huge", M + ["--light-sigma-base", "1e9"], "at most 100"),
    # -- xmap ------------------------------------------------------------------------------
    ("xmap-out-file", ["xmap", "{blend}", "--out", "{file}"], "is a file, not a folder"),
    ("xmap-out-proc", ["xmap", "{blend}", "--out", "{proc}"], "cannot write"),
    ("xmap-tolerance-zero", ["xmap", "{blend}", "--out", "{ws}/x", "--tolerance", "0"], "greater than 0"),
    ("xmap-tolerance-one", ["xmap", "{blend}", "--out", "{ws}/x", "--tolerance", "1"], "less than 1"),
    ("xmap-tolerance-nan", ["xmap", "{blend}", "--out", "{ws}/x", "--tolerance", "nan"], "finite"),
    ("xmap-samples-zero", ["xmap", "{blend}", "--out", "{ws}/x", "--samples", "0"], "from 1 to 4096"),
    ("xmap-samples-huge", ["xmap", "{blend}", "--out", "{ws}/x", "--samples", "1000000"], "from 1 to 4096"),
    ("xmap-samples-and-tolerance", ["xmap", "{blend}", "--out", "{ws}/x", "--samples", "4", "--tolerance",
                                    "0.1"], "exclude each other"),
    ("xmap-frame-32bit", ["xmap", "{blend}", "--out", "{ws}/x", "--frame", "3000000000"], "1048574"),
    ("xmap-res-1x1", ["xmap", "{blend}", "--out", "{ws}/x", "--resolution", "1x1"], "4 to 65536"),
    # -- saliency --------------------------------------------------------------------------
    ("saliency-missing", ["saliency", "{missing}", "--out", "{ws}/s.exr"], "no such image file"),
    ("saliency-folder", ["saliency", "{dir}", "--out", "{ws}/s.exr"], "is a folder, not a file"),
    ("saliency-garbage", ["saliency", "{garbage}", "--out", "{ws}/s.exr"], "cannot read image"),
    ("saliency-empty", ["saliency", "{empty}", "--out", "{ws}/s.exr"], "cannot read image"),
    ("saliency-text", ["saliency", "{file}", "--out", "{ws}/s.exr"], "cannot read image"),
    ("saliency-out-png", ["saliency", "{png}", "--out", "{ws}/s.png"], "must be a .exr file"),
    ("saliency-out-folder", ["saliency", "{png}", "--out", "{dir}"], "is a folder, not a file"),
    ("saliency-out-under-file", ["saliency", "{png}", "--out", "{under}.exr"], "is not a folder"),
    ("saliency-out-proc", ["saliency", "{png}", "--out", "{proc}/s.exr"], "cannot write"),
    ("saliency-png-exr", ["saliency", "{png}", "--out", "{ws}/s.exr", "--png", "{ws}/p.exr"],
     "must be a .png file"),
    ("saliency-nan-image", ["saliency", "{nan}", "--out", "{ws}/s.exr"], "NaN"),
    # -- render: numbers ---------------------------------------------------------------------
    ("render-max-spp-zero", R + ["--mode", "gold", "--max-spp", "0"] + OUT, "from 1 to 16777216"),
    ("render-max-spp-negative", R + ["--mode", "gold", "--max-spp", "-1"] + OUT, "from 1 to 16777216"),
    ("render-max-spp-32bit", R + ["--mode", "gold", "--max-spp", "2147483648"] + OUT, "from 1 to 16777216"),
    ("render-max-spp-past-cycles", R + ["--mode", "gold", "--max-spp", "16777217"] + OUT, "Cycles' limit"),
    ("render-max-spp-nan", R + ["--mode", "gold", "--max-spp", "nan"] + OUT, "whole number, not 'nan'"),
    ("render-max-spp-float", R + ["--mode", "gold", "--max-spp", "8.5"] + OUT, "whole number, not '8.5'"),
    ("render-min-above-max", RX + ["--min-spp", "9", "--map", "{exr}"] + OUT, "larger than --max-spp"),
    ("render-min-zero", RX + ["--min-spp", "0"] + OUT, "from 1 to 16777216"),
    ("render-spp-above-max", R + ["--mode", "uniform", "--max-spp", "4", "--spp", "100000"] + OUT,
     "--spp 100000 is above --max-spp 4"),
    ("render-spp-zero", R + ["--mode", "uniform", "--max-spp", "4", "--spp", "0"] + OUT, "from 1"),
    ("render-seed-negative", RG + ["--seed", "-1"] + OUT, "from 0 to 2147483647"),
    ("render-seed-40bit", RG + ["--seed", "1099511627776"] + OUT, "from 0 to 2147483647"),
    ("render-tile-small", RX + ["--tile-size", "4"] + OUT, "from 8 to 65536"),
    ("render-tile-huge", RX + ["--tile-size", "1000000"] + OUT, "from 8 to 65536"),
    ("render-quantile-zero", RX + ["--tile-quantile", "0"] + OUT, "greater than 0"),
    ("render-quantile-big", RX + ["--tile-quantile", "1.5"] + OUT, "at most 1"),
    ("render-quantile-nan", RX + ["--tile-quantile", "nan"] + OUT, "finite"),
    ("render-levels-one", RX + ["--spp-levels", "1", "--map", "{exr}"] + OUT, "--spp-levels must be 0"),
    ("render-levels-negative", RX + ["--spp-levels", "-1"] + OUT, "from 0 to 1024"),
    ("render-margin", RX + ["--margin", "65"] + OUT, "from 0 to 64"),
    ("render-cost-negative", RX + ["--render-cost", "-1"] + OUT, "from 0"),
    ("render-adaptive-zero", RX + ["--adaptive-threshold", "0"] + OUT, "greater than 0"),
    ("render-adaptive-nan", RX + ["--adaptive-threshold", "nan"] + OUT, "finite"),
    ("render-adaptive-big", RX + ["--adaptive-threshold", "2"] + OUT, "at most 1"),
    ("render-res-1x1", RG + ["--resolution", "1x1"] + OUT, "4 to 65536"),
    ("render-res-huge", RG + ["--resolution", "65536x65536"] + OUT, "of memory"),
    ("render-frame-32bit", RG + ["--frame", "3000000000"] + OUT, "1048574"),
    ("render-frames-32bit", RX + ["--frames", "1-3000000000"] + ["--out", "{ws}/f_#.exr"], "Blender's limits"),
    ("render-frames-backwards", RX + ["--frames", "5-1"] + OUT, "before the start frame"),
    ("render-frames-word", RX + ["--frames", "all"] + OUT, "must look like START-END"),
    ("render-frames-step", RX + ["--frames", "1-5:0"] + OUT, "step must be at least 1"),
    ("render-frame-and-frames", RX + ["--frame", "1", "--frames", "1-2"] + OUT, "cannot be combined"),
    ("render-frames-and-map", RX + ["--frames", "1-2", "--map", "{exr}"] + OUT, "every frame's own maps"),
    ("render-noise-zero", R + ["--mode", "adaptive", "--max-spp", "4", "--equal-time", "1",
                               "--noise-threshold", "0"] + OUT, "greater than 0"),
    ("render-noise-inf", R + ["--mode", "adaptive", "--max-spp", "4", "--equal-time", "1",
                              "--noise-threshold", "inf"] + OUT, "finite"),
    ("render-equal-time-zero", R + ["--mode", "uniform", "--max-spp", "4", "--equal-time", "0"] + OUT,
     "--equal-time must be positive"),
    ("render-equal-time-nan", R + ["--mode", "uniform", "--max-spp", "4", "--equal-time", "nan"] + OUT,
     "finite"),
    ("render-equal-time-inf", R + ["--mode", "adaptive", "--max-spp", "4", "--equal-time", "inf"] + OUT,
     "finite"),
    ("render-mode-bogus", R + ["--mode", "bogus", "--max-spp", "4"] + OUT, "invalid choice: 'bogus'"),
    ("render-mode-missing", R + ["--max-spp", "4"] + OUT, "required: --mode"),
    ("render-uniform-no-budget", R + ["--mode", "uniform", "--max-spp", "4"] + OUT, "needs --spp N"),
    ("render-adaptive-no-budget", R + ["--mode", "adaptive", "--max-spp", "4"] + OUT, "needs --budget-from"),
    ("render-equal-time-no-stats", R + ["--mode", "uniform", "--max-spp", "4", "--equal-time"] + OUT,
     "needs --budget-from"),
    # -- render: files -----------------------------------------------------------------------
    ("render-scene-missing", ["render", "{missing}", "--mode", "gold", "--max-spp", "4"] + OUT, "no such file"),
    ("render-scene-folder", ["render", "{dir}", "--mode", "gold", "--max-spp", "4"] + OUT, "is a folder"),
    ("render-scene-text", ["render", "{text}", "--mode", "gold", "--max-spp", "4"] + OUT, "not a .blend"),
    ("render-out-png", RG + ["--out", "{ws}/o.png"], "must be a .exr file"),
    ("render-out-folder", RG + ["--out", "{dir}"], "is a folder, not a file"),
    ("render-out-under-file", RG + ["--out", "{under}.exr"], "is not a folder"),
    ("render-out-proc", RG + ["--out", "{proc}/o.exr"], "cannot write"),
    ("render-out-no-suffix", RG + ["--out", "{ws}/o"], "must be a .exr file"),
    ("render-stats-folder", RG + OUT + ["--stats", "{dir}"], "is a folder, not a file"),
    ("render-stats-is-out", RG + OUT + ["--stats", "{ws}/o.exr"], "name the same file"),
    ("render-stats-is-spp", RG + OUT + ["--stats", "{ws}/o_spp.png"], "name the same file"),
    ("render-stats-under-file", RG + OUT + ["--stats", "{under}"], "is not a folder"),
    ("render-spp-sibling-folder", RG + ["--out", "{ws}/x.exr"], "its samples preview"),
    ("render-map-missing", RX + ["--map", "{missing}.exr"] + OUT, "no such director map"),
    ("render-map-folder", RX + ["--map", "{dir}"] + OUT, "is a folder, not a file"),
    ("render-map-nan", RX + ["--map", "{nan}"] + OUT, "NaN"),
    ("render-map-garbage", RX + ["--map", "{garbage}"] + OUT, "cannot read image"),
    ("render-maps-missing", RX + ["--maps", "{missing}"] + OUT, "no such maps folder"),
    ("render-maps-file", RX + ["--maps", "{file}"] + OUT, "is a file, not a folder"),
    ("render-maps-empty", RX + ["--maps", "{dir}"] + OUT, "no such director map"),
    ("render-save-maps-file", RX + ["--save-maps", "{file}"] + OUT, "is a file, not a folder"),
    ("render-budget-missing", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{missing}"] + OUT,
     "no such stats file"),
    ("render-budget-nan", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{budget_nan}"] + OUT,
     "mean_spp must be a finite number"),
    ("render-budget-text", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{budget_text}"] + OUT,
     "mean_spp must be a number, not '8'"),
    ("render-budget-negative", R + ["--mode", "adaptive", "--max-spp", "4", "--budget-from",
                                    "{budget_negative}"] + OUT, "wall_s must be at least 0"),
    ("render-budget-list", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{budget_list}"] + OUT,
     "is not the --stats JSON"),
    ("render-budget-garbage", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from",
                                   "{budget_garbage}"] + OUT, "cannot read stats file"),
    ("render-budget-deep", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{budget_deep}"] + OUT,
     "cannot read stats file"),
    ("render-budget-no-wall", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from",
                                   "{budget_nowall}"] + OUT, "is not the --stats JSON"),
    ("render-budget-huge", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{budget_huge}"] + OUT,
     "mean_spp must be at most 1.67772e+07"),
    ("render-budget-no-time", R + ["--mode", "adaptive", "--max-spp", "4", "--budget-from",
                                   "{budget_denoise}"] + OUT, "leaves no time to render"),
    ("render-budget-phases", R + ["--mode", "adaptive", "--max-spp", "4", "--budget-from",
                                  "{budget_phases}"] + OUT, "phases_s must be an object"),
    ("render-budget-folder", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{dir}"] + OUT,
     "is a folder"),
    # -- compare ---------------------------------------------------------------------------
    ("compare-ref-missing", ["compare", "{missing}.exr", "{exr}"], "no such image file"),
    ("compare-test-folder", ["compare", "{exr}", "{dir}"], "is a folder, not a file"),
    ("compare-garbage", ["compare", "{garbage}", "{exr}"], "cannot read image"),
    ("compare-hdr-ldr", ["compare", "{exr}", "{png}"], "same kind"),
    ("compare-sizes", ["compare", "{exr}", "{small}"], "differ in size"),
    ("compare-nan", ["compare", "{nan}", "{nan}"], "NaN or Inf"),
    ("compare-exposure-huge", ["compare", "{exr}", "{exr}", "--exposure", "1000"], "at most 64"),
    ("compare-exposure-nan", ["compare", "{exr}", "{exr}", "--exposure", "nan"], "finite"),
    ("compare-exposure-inf", ["compare", "{exr}", "{exr}", "--exposure=-inf"], "finite"),
    ("compare-json-folder", ["compare", "{exr}", "{exr}", "--json", "{dir}"], "is a folder, not a file"),
    ("compare-json-under-file", ["compare", "{exr}", "{exr}", "--json", "{under}"], "is not a folder"),
    ("compare-json-proc", ["compare", "{exr}", "{exr}", "--json", "{proc}/c.json"], "cannot write"),
    ("compare-heatmap-exr", ["compare", "{exr}", "{exr}", "--heatmap", "{ws}/h.exr"], "must be a .png file"),
    ("compare-heatmap-folder", ["compare", "{exr}", "{exr}", "--heatmap", "{dir}"], "is a folder"),
    ("compare-heatmap-dir-file", ["compare", "{exr}", "{exr}", "--heatmap-dir", "{file}"], "is a file"),
    ("compare-heatmap-dir-proc", ["compare", "{exr}", "{exr}", "--heatmap-dir", "{proc}"], "cannot write"),
    ("compare-json-is-heatmap", ["compare", "{exr}", "{exr}", "--json", "{ws}/h.png", "--heatmap",
                                 "{ws}/h.png"], "name the same file"),
    ("compare-heatmap-in-dir", ["compare", "{exr}", "{exr}", "--heatmap", "{ws}/hm/flip.png",
                                "--heatmap-dir", "{ws}/hm"], "name the same file"),
    ("compare-one-image", ["compare", "{exr}"], "required: TEST"),
    # -- experiment and demo ----------------------------------------------------------------
    ("experiment-out-file", ["experiment", "--out", "{file}"], "is a file, not a folder"),
    ("experiment-out-proc", ["experiment", "--out", "{proc}"], "cannot write"),
    ("experiment-max-spp-zero", ["experiment", "--max-spp", "0"], "from 1 to 16777216"),
    ("experiment-max-spp-32bit", ["experiment", "--max-spp", "4294967296"], "from 1 to 16777216"),
    ("experiment-size-small", ["experiment", "--size", "2"], "from 8 to 16384"),
    ("experiment-size-nan", ["experiment", "--size", "nan"], "whole number"),
    ("experiment-res-1x1", ["experiment", "--resolution", "1x1"], "4 to 65536"),
    ("experiment-res-and-size", ["experiment", "--resolution", "64x36", "--size", "64"], "not both"),
    ("experiment-seed", ["experiment", "--seed", "-5"], "from 0 to 2147483647"),
    ("experiment-tile", ["experiment", "--tile-size", "2"], "from 8 to 65536"),
    ("experiment-min-above-max", ["experiment", "--max-spp", "4", "--min-spp", "8"], "larger than --max-spp"),
    ("experiment-scene-unknown", ["experiment", "--scenes", "nowhere"], "unknown scene 'nowhere'"),
    ("experiment-scene-missing", ["experiment", "--scenes", "{missing}.blend"], "no such scene file"),
    ("experiment-scene-text", ["experiment", "--scenes", "{text}"], "not a .blend file"),
    ("experiment-scene-twice", ["experiment", "--scenes", "{blend},{blend}"], "given twice"),
    ("experiment-scenes-empty", ["experiment", "--scenes", ","], "--scenes is empty"),
    ("experiment-variants", ["experiment", "--variants", "gold,bogus"], "unknown variant 'bogus'"),
    ("demo-out-file", ["demo", "--out", "{file}"], "is a file, not a folder"),
    ("demo-max-spp", ["demo", "--max-spp", "0"], "from 1 to 16777216"),
    ("demo-res", ["demo", "--resolution", "2x2"], "4 to 65536"),
    ("demo-scene-missing", ["demo", "--scene", "{missing}"], "no such file"),
    ("demo-scene-text", ["demo", "--scene", "{text}"], "not a .blend file"),
    # -- farm and farm-task -----------------------------------------------------------------
    ("farm-max-spp-huge", FARM + ["--max-spp", "99999999999"], "from 1 to 16777216"),
    ("farm-max-spp-zero", FARM + ["--max-spp", "0"], "from 1 to 16777216"),
    ("farm-bundle-file", ["farm", "{blend}", "--bundle", "{file}"], "is a file, not a folder"),
    ("farm-bundle-foreign", ["farm", "{blend}", "--bundle", "{foreign}"], "refusing to overwrite"),
    ("farm-bundle-proc", ["farm", "{blend}", "--bundle", "{proc}"], "cannot write"),
    ("farm-tasks-zero", FARM + ["--tasks-per-frame", "0"], "--tasks-per-frame must be between 1"),
    ("farm-tasks-huge", FARM + ["--tasks-per-frame", "99999999999"], "whole number from -2147483648"),
    ("farm-frames", FARM + ["--frames", "9-1"], "before the start frame"),
    ("farm-frames-32bit", FARM + ["--frames", "1-4000000000"], "Blender's limits"),
    ("farm-res", FARM + ["--resolution", "1x1"], "4 to 65536"),
    ("farm-mode", FARM + ["--mode", "gold"], "invalid choice: 'gold'"),
    ("farm-scene-missing", ["farm", "{missing}", "--bundle", "{ws}/b"], "no such file"),
    ("farm-light-n", FARM + ["--light-n", "1000"], "from 0 to 100"),
    ("farm-min-above-max", FARM + ["--max-spp", "4", "--min-spp", "8"], "larger than --max-spp"),
    ("farm-task-frame-32bit", FT[:6] + ["3000000000"] + FT[7:], "from -1048574 to 1048574"),
    ("farm-task-max-spp", FT[:-3] + ["0", "--resolution", "64x36"], "from 1 to 16777216"),
    ("farm-task-res", FT[:-1] + ["1x1"], "4 to 65536"),
    ("farm-task-output-file", FT[:7] + ["--output", "{file}"] + FT[9:], "is a file, not a folder"),
    ("farm-task-no-step", ["farm-task"], "required: STEP"),
    ("farm-task-tiles-group", ["farm-task", "tiles", "{blend}", "--frame", "1", "--output", "{ws}/job",
                               "--group", "abc", "--groups", "4"], "whole number, not 'abc'"),
    ("farm-task-composite-groups", ["farm-task", "composite", "--frame", "1", "--output", "{ws}/job",
                                    "--groups", "0"], "--tasks-per-frame must be between 1"),
    # -- the experiment --------------------------------------------------------------------
    ("serve-missing", ["experiment-serve", "{missing}"], "no such stimuli folder"),
    ("serve-file", ["experiment-serve", "{file}"], "is a file, not a folder"),
    ("serve-port-high", ["experiment-serve", "{stimuli}", "--port", "70000"], "from 0 to 65535"),
    ("serve-port-negative", ["experiment-serve", "{stimuli}", "--port", "-1"], "from 0 to 65535"),
    ("serve-port-word", ["experiment-serve", "{stimuli}", "--port", "http"], "whole number, not 'http'"),
    ("serve-db-folder", ["experiment-serve", "{stimuli}", "--db", "{dir}"], "is a folder, not a file"),
    ("serve-db-garbage", ["experiment-serve", "{stimuli}", "--db", "{garbage}", "--port", "0"],
     "as the answers database"),
    ("serve-condition", ["experiment-serve", "{stimuli}", "--condition", "both"], "invalid choice"),
    ("serve-unpaired", ["experiment-serve", "{odd_stimuli}", "--port", "0"], "to pair with"),
    ("serve-empty", ["experiment-serve", "{dir}", "--port", "0"], "no stimuli in"),
    ("analyse-missing", ["experiment-analyse", "{missing}"], "no such answers database"),
    ("analyse-folder", ["experiment-analyse", "{dir}"], "is a folder, not a file"),
    ("analyse-garbage", ["experiment-analyse", "{garbage}"], "is not an experiment database"),
    ("analyse-no-answers", ["experiment-analyse", "{empty_db}"], "holds no answers yet"),
    ("analyse-tolerance-nan", ["experiment-analyse", "{empty_db}", "--timing-tolerance-ms", "nan"], "finite"),
    ("analyse-tolerance-inf", ["experiment-analyse", "{empty_db}", "--timing-tolerance-ms", "inf"], "finite"),
    ("analyse-tolerance-negative", ["experiment-analyse", "{empty_db}", "--timing-tolerance-ms", "-1"],
     "at least 0"),
    ("analyse-chart-svg", ["experiment-analyse", "{empty_db}", "--chart", "{ws}/c.svg"], "must be a .png file"),
    ("analyse-chart-folder", ["experiment-analyse", "{empty_db}", "--chart", "{dir}"], "is a folder"),
    ("analyse-chart-proc", ["experiment-analyse", "{empty_db}", "--chart", "{proc}/c.png"], "cannot write"),
    # -- hotspots --------------------------------------------------------------------------
    ("hotspots-image-missing", ["hotspots", "{missing}.png", "{fix}", "--out", "{ws}/h.png"],
     "no such image file"),
    ("hotspots-fixations-missing", ["hotspots", "{png}", "{missing}.csv", "--out", "{ws}/h.png"],
     "no such fixations file"),
    ("hotspots-fixations-malformed", ["hotspots", "{png}", "{bad}", "--out", "{ws}/h.png"], "3 columns"),
    ("hotspots-out-jpg", ["hotspots", "{png}", "{fix}", "--out", "{ws}/h.jpg"], "must be a .png file"),
    ("hotspots-out-folder", ["hotspots", "{png}", "{fix}", "--out", "{dir}"], "is a folder"),
    ("hotspots-out-proc", ["hotspots", "{png}", "{fix}", "--out", "{proc}/h.png"], "cannot write"),
    ("hotspots-distance-nan", HOT + ["--distance-cm", "nan"], "finite number, not nan"),
    ("hotspots-distance-inf", HOT + ["--distance-cm", "inf"], "finite number, not inf"),
    ("hotspots-distance-zero", HOT + ["--distance-cm", "0"], "greater than 0"),
    ("hotspots-width-nan", HOT + ["--screen-width-cm", "nan"], "finite number, not nan"),
    ("hotspots-width-negative", HOT + ["--screen-width-cm", "-30"], "greater than 0"),
    ("hotspots-width-px-zero", HOT + ["--screen-width-px", "0"], "from 1 to 65536"),
    ("hotspots-width-px-float", HOT + ["--screen-width-px", "1280.5"], "whole number"),
    ("hotspots-max-ms-zero", HOT + ["--max-ms", "0"], "greater than 0"),
    ("hotspots-max-ms-nan", HOT + ["--max-ms", "nan"], "finite"),
    ("hotspots-sigma-inf", HOT + ["--sigma-deg", "inf"], "finite"),
    ("hotspots-sigma-negative", HOT + ["--sigma-deg", "-1"], "greater than 0"),
    ("hotspots-image-garbage", ["hotspots", "{garbage}", "{fix}", "--out", "{ws}/h.png"], "cannot read image"),
    # -- the batch entry's own rule, and --verbose with bad input ---------------------------
    ("verbose-bad-input", ["--verbose", "render", "{blend}", "--mode", "gold", "--max-spp", "0"] + OUT,
     "from 1 to 16777216"),
]


def test_the_table_is_large_and_covers_every_subcommand():
    from xsl_render.operators.commands import COMMANDS

    assert len(CASES) + len(UNPRIVILEGED) + len(END_TO_END) >= 150
    assert len({case[0] for case in CASES}) == len(CASES)
    covered = {argv[0] for _, argv, _ in CASES + UNPRIVILEGED + END_TO_END if argv and argv[0] != "--verbose"}
    assert covered >= {command.NAME for command in COMMANDS}


def _run_in_process(argv: list[str], cwd: Path, capfd, monkeypatch) -> tuple[int, str, str]:
    monkeypatch.chdir(cwd)
    monkeypatch.setitem(sys.modules, "bpy", None)       # `import bpy` now fails: no case may load Blender
    capfd.readouterr()
    code = main(argv)
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
    ("e2e-compare-exposure", ["compare", "{exr}", "{exr}", "--exposure", "1000"], "at most 64"),
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
