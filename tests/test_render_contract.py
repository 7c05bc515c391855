"""The render command's outputs as a contract: for every mode (and a frame range), the files a
run writes and the shape of its ``--stats`` JSON (every key, nested, and the JSON type of each
value) match ``tests/data/render_contract.json``, recorded before the stats became typed.

A change that drops, renames or retypes a stats field, or writes another file, fails here. To
record a deliberate change: ``XSL_RECORD_CONTRACT=1 pytest tests/test_render_contract.py``
and say why in the commit.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from support.fog_scene import build_fog_scene, radial_map

from xsl_render.core.imageio import write_exr

pytestmark = [pytest.mark.blender, pytest.mark.render]

W, H = 32, 18
CONTRACT = Path(__file__).parent / "data" / "render_contract.json"
#: Keys a run writes only when something happened (a guided run that overran, a scene sync
#: measured outside the budget): present or not, they are not part of the shape compared.
CONDITIONAL = {"sync_outside_budget_s"}

RUNS = {
    "gold": ["--mode", "gold", "--max-spp", "4"],
    "uniform": ["--mode", "uniform", "--max-spp", "4", "--spp", "3"],
    "uniform_equal_time": ["--mode", "uniform", "--max-spp", "4", "--equal-time", "0.5"],
    "adaptive": ["--mode", "adaptive", "--max-spp", "4", "--budget-from", "{out}/xsl/stats.json"],
    "xs": ["--mode", "xs", "--max-spp", "4", "--tile-size", "16", "--save-maps", "{out}/xs/maps"],
    "xsl": ["--mode", "xsl", "--max-spp", "4", "--tile-size", "16", "--map", "{out}/map.exr"],
    "guided": ["--mode", "guided", "--time-budget", "2", "--max-spp", "8"],
    "frames": ["--mode", "uniform", "--max-spp", "4", "--spp", "2", "--frames", "1-2"],
}


def shape(value):
    """The JSON type tree of ``value``: dicts by key, a list of records by its first record."""
    if isinstance(value, dict):
        return {key: shape(item) for key, item in sorted(value.items()) if key not in CONDITIONAL}
    if isinstance(value, list):
        records = [item for item in value if isinstance(item, dict)]
        return ["list", shape(records[0])] if records else "list"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, (int, float)):
        return "number"
    return "null" if value is None else "string"


@pytest.fixture(scope="module")
def addon():
    import xsl_render

    xsl_render.register()
    yield xsl_render
    xsl_render.unregister()


def run_all(blender, addon, tmp_path) -> dict:
    scene = build_fog_scene(blender, W, H)
    scene.frame_start, scene.frame_end = 1, 2
    write_exr(tmp_path / "map.exr", radial_map(W, H, 0.3))
    found = {}
    for name in ("xsl", *[n for n in RUNS if n != "xsl"]):     # adaptive takes its budget from xsl
        folder = tmp_path / name
        image = folder / ("f_#.exr" if name == "frames" else "image.exr")
        args = [arg.format(out=tmp_path) for arg in RUNS[name]]
        assert addon.batch(["render", *args, "--out", str(image), "--stats", str(folder / "stats.json"),
                            "--quiet"]) == 0, name
        stats = json.loads((folder / "stats.json").read_text())
        files = sorted(str(path.relative_to(folder)) for path in folder.rglob("*") if path.is_file())
        found[name] = {"files": files, "stats": shape(stats)}
    return found


def test_every_mode_writes_the_recorded_files_and_stats(blender, addon, tmp_path):
    found = run_all(blender, addon, tmp_path)
    if os.environ.get("XSL_RECORD_CONTRACT"):
        CONTRACT.parent.mkdir(exist_ok=True)
        CONTRACT.write_text(json.dumps(found, indent=1, sort_keys=True) + "\n")
    expected = json.loads(CONTRACT.read_text())
    for name in RUNS:
        assert found[name]["files"] == expected[name]["files"], name
        assert found[name]["stats"] == expected[name]["stats"], name
