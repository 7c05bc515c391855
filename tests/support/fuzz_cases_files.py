"""The fuzz table's cases of issue 23, as (id, argv, words): files a command must not touch.

- data loss: an output that is an input (by its name, a symlink or a hard link), which used
  to replace the input with exit code 0; the table checks every input's bytes before and
  after (``test_fuzz_cli.snapshot``);
- hangs: a FIFO (or a device) given as an input, which an ``open`` waits on for ever;
- tracebacks: names past the file system's limits (a name over 255 bytes, a path over
  PATH_MAX), also when only a derived name (``_spp.exr``) or the temporary name is too long.

``{key}`` names a file of the workspace (``test_fuzz_cli.make_workspace``).
"""
from __future__ import annotations

from support.fuzz_cases import HOT, OUT, RG, RX, R

LONG = "a" * 300                                  # a file name no file system here takes
DEEP = "/".join(["b" * 200] * 25)                 # 5000 bytes of folders: past PATH_MAX
SAME = "name the same file"
INPUT = "(an output never replaces an input)"
FIFO = "is a FIFO (named pipe), not a regular file"

FILE_CASES = [
    # -- data loss: an output over an input ----------------------------------------------------
    ("render-stats-is-scene", R + ["--mode", "gold", "--max-spp", "1"] + OUT + ["--stats", "{blend}"],
     f"--stats and SCENE.blend {SAME}"),
    ("compare-json-is-ref", ["compare", "{exr}", "{exr}", "--json", "{exr}"], f"--json and REF {SAME}"),
    ("compare-heatmap-is-ref", ["compare", "{png}", "{other}", "--heatmap", "{png}"], f"--heatmap and REF {SAME}"),
    ("compare-heatmap-is-test", ["compare", "{png}", "{other}", "--heatmap", "{other}"], INPUT),
    ("compare-heatmap-dir-over-test", ["compare", "{png}", "{hm}/flip.png", "--heatmap-dir", "{hm}"],
     f"--heatmap-dir's flip.png and TEST {SAME}"),
    ("saliency-png-is-image", ["saliency", "{png}", "--out", "{ws}/s.exr", "--png", "{png}"], f"--png and IMAGE {SAME}"),
    ("saliency-out-is-image", ["saliency", "{exr}", "--out", "{exr}"], f"--out and IMAGE {SAME}"),
    ("hotspots-out-is-image", ["hotspots", "{png}", "{fix}", "--out", "{png}"], f"--out and IMAGE {SAME}"),
    ("hotspots-out-hard-link", ["hotspots", "{png}", "{fix}", "--out", "{hard}"], f"--out and IMAGE {SAME}"),
    ("render-out-is-map", RX + ["--map", "{exr}", "--out", "{exr}"], f"--out and --map {SAME}"),
    ("render-stats-is-map", RX + ["--map", "{exr}"] + OUT + ["--stats", "{exr}"], f"--stats and --map {SAME}"),
    ("render-stats-is-budget", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{budget_denoise}"]
     + OUT + ["--stats", "{budget_denoise}"], f"--stats and --budget-from {SAME}"),
    ("render-stats-symlink-to-scene", RG + OUT + ["--stats", "{link}"], f"--stats and SCENE.blend {SAME}"),
    ("render-spp-is-map", RX + ["--map", "{x2_spp}", "--out", "{ws}/x2.exr"], f"its samples and --map {SAME}"),
    ("render-stats-in-save-maps", RX + OUT + ["--save-maps", "{ws}/sm", "--stats", "{ws}/sm/maps.json"],
     f"--stats and --save-maps' maps.json {SAME}"),
    ("render-save-maps-over-budget", RX + ["--budget-from", "{mapsdir}/maps.json", "--save-maps", "{mapsdir}"] + OUT,
     f"--save-maps' maps.json and --budget-from {SAME}"),
    ("render-stats-over-a-frame", RX + ["--frames", "1-3", "--out", "{ws}/f_#.exr", "--stats", "{ws}/f_2_spp.exr"],
     f"--stats and frame 2's samples {SAME}"),
    ("serve-db-is-stimulus", ["experiment-serve", "{stimuli}", "--db", "{stimuli}/a.gold.png"],
     f"--db and stimulus a.gold.png {SAME}"),
    ("analyse-chart-is-db", ["experiment-analyse", "{empty_db}", "--chart", "{ws}/db_link.png"],
     f"--chart and DB {SAME}"),
    # -- hangs: FIFOs and devices as inputs ----------------------------------------------------
    ("info-fifo", ["info", "{pipe_blend}"], FIFO),
    ("compare-fifo", ["compare", "{exr}", "{pipe_exr}"], FIFO),
    ("saliency-fifo", ["saliency", "{pipe_exr}", "--out", "{ws}/s.exr"], FIFO),
    ("render-map-fifo", RX + ["--map", "{pipe_exr}"] + OUT, FIFO),
    ("render-maps-fifo", RX + ["--maps", "{pipe_maps}"] + OUT, f"xsl.exr {FIFO}"),
    ("render-budget-fifo", R + ["--mode", "uniform", "--max-spp", "4", "--budget-from", "{pipe_json}"] + OUT, FIFO),
    ("hotspots-fifo-csv", ["hotspots", "{png}", "{pipe_csv}", "--out", "{ws}/h.png"], FIFO),
    ("analyse-fifo", ["experiment-analyse", "{pipe_sqlite}"], FIFO),
    ("serve-fifo-stimulus", ["experiment-serve", "{pipe_stimuli}", "--port", "0"], FIFO),
    ("info-device", ["info", "/dev/null"], "is a character device, not a regular file"),
    # -- tracebacks: names past the system's limits --------------------------------------------
    ("render-out-name-too-long", RG + ["--out", "{ws}/" + LONG + ".exr"], "file name too long"),
    ("render-spp-name-too-long", RG + ["--out", "{spp_too_long}"], "its samples: file name too long"),
    ("render-out-temporary-too-long", RG + ["--out", "{temporary_too_long}"], "under a temporary name"),
    ("render-out-path-too-long", RG + ["--out", "{ws}/" + DEEP + "/o.exr"], "path too long"),
    ("info-name-too-long", ["info", "{ws}/" + LONG + ".blend"], "file name too long"),
    ("compare-json-name-too-long", ["compare", "{exr}", "{exr}", "--json", "{ws}/" + LONG + ".json"],
     "file name too long"),
    ("maps-out-name-too-long", ["maps", "{blend}", "--out", "{ws}/" + LONG], "file name too long"),
    ("hotspots-fixations-name-too-long", HOT[:2] + ["{ws}/" + LONG + ".csv"] + HOT[3:], "file name too long"),
]
