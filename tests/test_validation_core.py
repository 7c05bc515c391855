"""The bpy-free parts of the validation: the plan, input hashes and records, the crop around
the lights, the timing chart and how scenes are named."""
from __future__ import annotations

import numpy as np
import pytest
from support.cli_wording import refused_in_flags

from xsl_render.core.errors import InputError
from xsl_render.core.maps.options import MapOptions
from xsl_render.core.validation.example_scenes import (ANIMATED_EXAMPLES, EXAMPLE_SCENES,
                                                      example_scene_path, resolve_scenes)
from xsl_render.core.validation.plan import (DEFAULT_VARIANTS, VARIANTS, map_seconds, maps_needed,
                                             parse_variants, scaled_size, scene_variants)
from xsl_render.core.validation.report_chart import Bar, timing_chart_svg
from xsl_render.core.validation.report_images import brightest_box, light_crop_box
from xsl_render.core.validation.store import inputs_hash, read_record, write_record

SECONDS = {"x": 1.0, "snapshot": 2.0, "s": 4.0, "l": 8.0, "xs": 16.0, "xsl": 32.0, "total": 63.0}


@pytest.mark.parametrize("name, expected", [
    ("x_only", 1 + 16),                 # X alone needs no snapshot, no saliency, no light map
    ("s_only", 1 + 2 + 4 + 16),         # S is computed from the snapshot and the inverted X
    ("xs", 1 + 2 + 4 + 16),
    ("xsl", 63),                        # everything
    ("xsl_no_minbound", 63),
    ("gold", 0), ("uniform_equal_time", 0),
])
def test_map_seconds_count_only_the_maps_a_run_uses(name, expected):
    assert map_seconds(VARIANTS[name], SECONDS) == expected


def test_paper_versions():
    assert VARIANTS["x_only"].map_options == MapOptions(wx=1.0, ws=0.0)
    assert VARIANTS["s_only"].map_options == MapOptions(wx=0.0, ws=1.0)
    assert VARIANTS["xsl_no_minbound"].map_options.minbound is False
    assert maps_needed(VARIANTS["gold"]) == ()


@pytest.mark.parametrize("text, expected", [
    (None, DEFAULT_VARIANTS),
    ("xs", ("gold", "xs")),                                       # gold always comes along
    ("adaptive_equal_time", ("gold", "xsl", "adaptive_equal_time")),  # and the run it times by
    ("guided_equal_time", ("gold", "xsl", "guided_equal_time")),
    ("auto_equal_time", ("gold", "auto_equal_time")),              # Auto Volumes takes gold's time
    ("xsl, gold ,xs", ("gold", "xs", "xsl")),                     # plan order, spaces ignored
])
def test_parse_variants(text, expected):
    assert parse_variants(text) == expected


@pytest.mark.parametrize("text", ["", "xs,nope", ","])
def test_parse_variants_refuses_unknown(text):
    with refused_in_flags("--variants"):
        parse_variants(text)


def test_minbound_comparison_only_with_xsl():
    names = [v.name for v in scene_variants(DEFAULT_VARIANTS, compare_minbound=True)]
    assert names.index("xsl_no_minbound") == names.index("xsl") + 1
    assert names[:3] == ["gold", "auto_file_samples", "auto_equal_time"]
    assert names[-3:] == ["uniform_equal_time", "adaptive_equal_time", "guided_equal_time"]
    assert "xsl_no_minbound" not in [v.name for v in scene_variants(DEFAULT_VARIANTS)]
    assert [v.name for v in scene_variants(("gold", "xs"), compare_minbound=True)] == ["gold", "xs"]


@pytest.mark.parametrize("size, side, expected", [
    ((512, 288), 256, (256, 144)), ((384, 512), 256, (192, 256)), ((100, 100), None, (100, 100)),
    ((512, 289), 64, (64, 36)),
])
def test_scaled_size(size, side, expected):
    assert scaled_size(size, side) == expected


def test_inputs_hash_is_stable_and_sensitive():
    inputs = {"scene_sha256": "ab", "options": {"max_spp": 16, "seed": 0}, "mode": "gold"}
    same = {"mode": "gold", "options": {"seed": 0, "max_spp": 16}, "scene_sha256": "ab"}
    assert inputs_hash(inputs) == inputs_hash(same)                 # key order does not matter
    for changed in ({**inputs, "scene_sha256": "ac"}, {**inputs, "mode": "xsl"},
                    {**inputs, "options": {"max_spp": 64, "seed": 0}}):
        assert inputs_hash(changed) != inputs_hash(inputs)


def test_read_record_reuses_only_matching_finished_work(tmp_path):
    image = tmp_path / "gold.exr"
    record_path = tmp_path / "gold.json"
    assert read_record(record_path, "h1") is None                   # nothing yet
    write_record(record_path, {"input_hash": "h1", "stats": {"wall_s": 1.0}})
    assert read_record(record_path, "h2") is None                   # other inputs: stale
    assert read_record(record_path, "h1", (image,)) is None         # its image is gone
    image.write_bytes(b"exr")
    assert read_record(record_path, "h1", (image,))["stats"]["wall_s"] == 1.0
    record_path.write_text("{half a reco")                          # unreadable: redo, no crash
    assert read_record(record_path, "h1") is None


@pytest.mark.parametrize("row, col", [(10, 20), (0, 0), (35, 63), (18, 2)])
def test_brightest_box_centres_on_the_glow_inside_the_frame(row, col):
    values = np.zeros((36, 64), np.float32)
    values[row, col] = 1.0
    values[5, 60] = 0.2                                             # a dimmer light elsewhere
    row0, row1, col0, col1 = brightest_box(values, 0.25)
    assert (row1 - row0, col1 - col0) == (9, 16)
    assert 0 <= row0 and row1 <= 36 and 0 <= col0 and col1 <= 64
    assert row0 <= row < row1 and col0 <= col < col1


def test_crop_box_falls_back_to_the_brightest_part_of_the_gold_standard():
    gold = np.zeros((36, 64, 3), np.float32)
    gold[30, 50] = 1.0
    box, where = light_crop_box(np.zeros((36, 64), np.float32), gold)
    assert "gold standard" in where and box[0] <= 30 < box[1] and box[2] <= 50 < box[3]
    box, where = light_crop_box(None, np.zeros((36, 64, 3), np.float32))
    assert "middle" in where
    assert brightest_box(np.zeros((4, 4))) is None


def test_timing_chart_bars_scale_with_time():
    svg = timing_chart_svg([Bar("gold", 0.0, 10.0, "gold"), Bar("xsl <&>", 1.0, 4.0, "render", "2x")], "t")
    assert svg.startswith("<svg") and svg.endswith("</svg>")
    assert 'width="420.00"' in svg                       # the longest bar fills the axis
    assert 'width="42.00"' in svg and 'width="168.00"' in svg   # maps 1 s, render 4 s
    assert "xsl &lt;&amp;&gt;" in svg                    # labels are escaped
    assert "guided render" not in svg                   # its legend entry only with a guided bar
    guided = timing_chart_svg([Bar("gold", 0.0, 10.0, "gold"), Bar("guided", 0.0, 8.0, "guided")], "t")
    assert "guided render" in guided and 'fill="#2a9d8f"' in guided


def test_resolve_scenes(tmp_path):
    blend = tmp_path / "my-scene.blend"
    blend.write_bytes(b"BLENDER")
    assert resolve_scenes(str(blend)) == [("my-scene", blend)]
    for text, message in (("nope", "unknown scene 'nope'"), (str(tmp_path / "gone.blend"), "no such scene file"),
                          (f"{blend},{blend}", "given twice"), (" , ", "empty")):
        with pytest.raises(InputError, match=message):
            resolve_scenes(text)
    assert EXAMPLE_SCENES == ("balls_a", "balls_b", "statue", "road")
    # The animation is taken by name, never by default.
    assert ANIMATED_EXAMPLES == ("street",)
    assert resolve_scenes("street,road") == [("street", example_scene_path("street")),
                                             ("road", example_scene_path("road"))]
    assert example_scene_path("street").name == "street.blend"
    assert [name for name, _ in resolve_scenes(None)] == list(EXAMPLE_SCENES)
