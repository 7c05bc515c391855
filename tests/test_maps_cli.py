"""``xsl-render maps``: the files, maps.json, the degenerate XSL cases, warnings, bad options."""
from __future__ import annotations

import json

import numpy as np
import pytest

from test_cli_info import one_line_error, save_scene
from xsl_render.core.imageio import read_image

pytestmark = [pytest.mark.blender, pytest.mark.render]
MAPS = ("z", "x", "snapshot", "s", "l", "xs", "xsl")


@pytest.fixture(scope="module")
def fog_scene(tmp_path_factory):
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.engine = "CYCLES"
    return save_scene(bpy, tmp_path_factory.mktemp("scene") / "fog.blend")


def read(folder, name):
    return read_image(folder / f"{name}.exr")


def test_maps_writes_every_map_and_its_parameters(cli, fog_scene, tmp_path):
    out = tmp_path / "maps"
    result = cli("maps", fog_scene, "--out", out, "--resolution", "96x54", "--light-n", "6",
                 "--light-sigma-base", "3")
    assert result.returncode == 0, result.stderr
    for name in MAPS:
        image = read(out, name)
        assert image.shape[:2] == (54, 96) and np.isfinite(image).all()
        assert (out / "preview" / f"{name}.png").exists()
    for name in ("x", "s", "l", "xs", "xsl"):
        values = read(out, name)
        assert values.min() >= 0 and values.max() <= 1, name
    info = json.loads((out / "maps.json").read_text())
    assert info["options"]["light_n"] == 6 and info["options"]["light_sigma_base"] == 3.0
    assert set(info["seconds"]) >= {"x", "snapshot", "s", "l", "xs", "xsl", "total"}
    assert info["l"]["drawn"][0]["name"] == "Lamp"
    # XS(0.5, 0.5, +) of the written X and S
    np.testing.assert_allclose(read(out, "xs"), 0.5 * read(out, "x") + 0.5 * read(out, "s"), atol=1e-6)


@pytest.mark.parametrize("weights, equals", [(("1", "0"), "xs"), (("0", "1"), "l")])
def test_xsl_degenerate_weights_give_their_input_bit_for_bit(cli, fog_scene, tmp_path, weights, equals):
    out = tmp_path / "maps"
    result = cli("maps", fog_scene, "--out", out, "--resolution", "64x36",
                 "--wxs", weights[0], "--wl", weights[1])
    assert result.returncode == 0, result.stderr
    assert np.array_equal(read(out, "xsl"), read(out, equals))


def test_no_lights_gives_zero_l_and_says_so(blender, cli, tmp_path):
    path = save_scene(blender, tmp_path / "dark.blend")
    import bpy

    bpy.ops.wm.open_mainfile(filepath=str(path))
    for name in ("Lamp", "Behind"):
        bpy.data.objects.remove(bpy.data.objects[name])
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    result = cli("maps", path, "--out", tmp_path / "maps", "--resolution", "64x36")
    assert result.returncode == 0, result.stderr
    assert not read(tmp_path / "maps", "l").any()
    assert "no light source shows in the frame" in result.stderr


@pytest.mark.parametrize("option, value, named", [
    ("--wx", "-0.5", "--wx"), ("--wl", "-1", "--wl"), ("--xs-op", "max", "--xs-op"),
    ("--xsl-op", "divide", "--xsl-op"), ("--light-n", "-2", "--light-n"),
    ("--light-sigma-base", "0", "--light-sigma-base"), ("--light-sigma-base", "-3", "--light-sigma-base"),
    ("--resolution", "12by5", "--resolution")])
def test_bad_options_name_the_option(cli, fog_scene, tmp_path, option, value, named):
    line = one_line_error(cli("maps", fog_scene, "--out", tmp_path / "maps", option, value))
    assert named in line
    assert not (tmp_path / "maps" / "xsl.exr").exists()


def test_render_computes_the_maps_on_the_fly(cli, fog_scene, tmp_path):
    out = tmp_path / "xsl.exr"
    result = cli("render", fog_scene, "--mode", "xsl", "--max-spp", "8", "--out", out,
                 "--resolution", "64x36", "--stats", tmp_path / "stats.json",
                 "--save-maps", tmp_path / "maps", "--quiet")
    assert result.returncode == 0, result.stderr
    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["phases_s"]["maps"] > 0
    xsl = read(tmp_path / "maps", "xsl")[..., 0]
    assert stats["director_map_mean"] == pytest.approx(float(xsl.mean()), rel=1e-5)
    samples = read_image(tmp_path / "xsl_spp.exr")[..., 0]
    # Tiles render with the largest target of their pixels: nothing gets less than asked.
    assert (samples >= np.maximum(1, np.round(8 * xsl)) - 1e-6).all()
