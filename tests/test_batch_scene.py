"""The batch entry (``x.batch(...)`` inside ``blender -b``) leaves the open scene exactly as it
found it (issue 15, point 9), and the panel's renders write EXR as the contract says (point 11).

The dump walks every setting of the scene and of the structs inside it (render, image format
and its colour spaces, Cycles, view layers, ...), three levels deep, so a setting no one
thought of restoring shows up too.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from conftest import EXAMPLES
from support.fog_scene import build_fog_scene

from xsl_render.core.imageio import read_image

pytestmark = [pytest.mark.blender, pytest.mark.render]


@pytest.fixture(scope="module")
def addon():
    import xsl_render

    xsl_render.register()
    yield xsl_render
    xsl_render.unregister()


def deep_dump(struct, depth: int = 3) -> dict:
    """Every value of ``struct`` (names of settings too, such as a colour space's) and of the
    non-datablock structs inside it; datablocks by name. Written apart from the code under
    test (``addon.scene.state``) so that it sees what that code forgets."""
    import bpy

    values = {}
    for prop in struct.bl_rna.properties:
        name = prop.identifier
        if name == "rna_type" or prop.type in ("COLLECTION",) or getattr(prop, "is_deprecated", False):
            continue
        try:
            value = getattr(struct, name)
        except (AttributeError, RuntimeError):
            continue
        if prop.type == "POINTER":
            if isinstance(value, bpy.types.ID) or value is None:
                values[name] = getattr(value, "name", None)
            elif depth > 0:
                values[f"{name}/"] = deep_dump(value, depth - 1)
        elif hasattr(value, "__len__") and not isinstance(value, str):
            values[name] = tuple(value) if not isinstance(value, set) else frozenset(value)
        else:
            values[name] = value
    return values


def scene_dump(scene) -> dict:
    from xsl_render.addon.scene.state import settings_dump

    return {"deep": deep_dump(scene), "settings": settings_dump(scene),
            "frame": (scene.frame_current, scene.frame_subframe)}


def differences(before, after, path="") -> list[str]:
    if isinstance(before, dict) and isinstance(after, dict):
        return [d for key in before.keys() | after.keys()
                for d in differences(before.get(key), after.get(key), f"{path}{key}")]
    return [] if before == after else [f"{path}: {before!r} -> {after!r}"]


@pytest.fixture
def road(blender, addon, tmp_path):
    """The road example (its image format's linear colour space is empty, as in files of older
    Blenders), opened from a copy at a small size, at frame 2."""
    copy = tmp_path / "road.blend"
    shutil.copy(EXAMPLES / "road.blend", copy)
    blender.ops.wm.open_mainfile(filepath=str(copy))
    scene = blender.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 48, 27
    scene.frame_start, scene.frame_end = 1, 3
    scene.frame_set(2)
    assert scene.render.image_settings.linear_colorspace_settings.name == ""
    return scene


@pytest.mark.parametrize("command", [
    ["info", "--json"],
    ["xmap", "--resolution", "64x36", "--frame", "7", "--out", "{tmp}/x"],
    ["maps", "--resolution", "40x24", "--frame", "3", "--out", "{tmp}/m"],
    ["render", "--mode", "gold", "--max-spp", "2", "--frame", "3", "--out", "{tmp}/g.exr", "--quiet"],
    ["render", "--mode", "xsl", "--max-spp", "4", "--resolution", "40x24", "--out", "{tmp}/s.exr",
     "--stats", "{tmp}/s.json", "--save-maps", "{tmp}/sm", "--quiet"],
    ["render", "--mode", "uniform", "--spp", "2", "--max-spp", "4", "--frames", "1-2",
     "--out", "{tmp}/u_#.exr", "--quiet"],
    ["render", "--mode", "guided", "--time-budget", "1", "--frame", "3", "--out", "{tmp}/t.exr", "--quiet"],
], ids=["info", "xmap", "maps", "gold", "xsl", "frames", "guided"])
def test_batch_leaves_the_scene_as_it_was(addon, road, tmp_path, capfd, command):
    before = scene_dump(road)
    assert addon.batch([arg.format(tmp=tmp_path) for arg in command]) == 0
    capfd.readouterr()
    assert differences(before, scene_dump(road)) == []


def test_a_failing_batch_command_leaves_the_scene_too(addon, road, tmp_path, capfd):
    before = scene_dump(road)
    with pytest.raises(SystemExit) as done:              # a tile size larger than the frame
        addon.batch(["render", "--mode", "xsl", "--max-spp", "4", "--tile-size", "64", "--frame", "3",
                     "--out", str(tmp_path / "s.exr")])
    assert done.value.code == 2 and len(capfd.readouterr().err.strip().splitlines()) == 1
    assert differences(before, scene_dump(road)) == []
    assert list(tmp_path.glob("s*")) == []


def test_render_gold_writes_exr_and_refuses_another_extension(blender, addon, tmp_path):
    scene = build_fog_scene(blender, 32, 18, factory_reset=False)
    scene.xsl_render.max_spp = 2
    with pytest.raises(RuntimeError, match=r"must be a \.exr file"):
        blender.ops.xsl.render_gold(filepath=str(tmp_path / "g.png"))
    assert list(tmp_path.iterdir()) == []
    assert blender.ops.xsl.render_gold(filepath=str(tmp_path / "g.exr")) == {"FINISHED"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.exr", "g_spp.exr", "g_spp.png"]
    import OpenImageIO as oiio

    spec = oiio.ImageInput.open(str(tmp_path / "g.exr")).spec()
    assert spec.format.basetype == oiio.FLOAT and spec.nchannels == 4
    assert read_image(tmp_path / "g.exr").shape == (18, 32, 4)


def test_neither_the_batch_entry_nor_the_panel_writes_over_the_open_file(addon, road, tmp_path, capfd):
    """Issue 23: the open .blend is an input of every batch command and panel render: an
    output named like it, or a symlink to it, is refused before any work, the file untouched."""
    import bpy

    blend = Path(bpy.data.filepath)
    saved = blend.read_bytes()
    with pytest.raises(SystemExit) as done:
        addon.batch(["render", "--mode", "gold", "--max-spp", "1", "--out", str(tmp_path / "g.exr"),
                     "--stats", str(blend), "--quiet"])
    err = capfd.readouterr().err.strip().splitlines()
    assert done.value.code == 2 and len(err) == 1 and "--stats and the open file name the same file" in err[0]
    (tmp_path / "link.exr").symlink_to(blend)
    with pytest.raises(RuntimeError, match="the output link.exr and the open file name the same file"):
        bpy.ops.xsl.render_gold(filepath=str(tmp_path / "link.exr"))
    assert blend.read_bytes() == saved and sorted(p.name for p in tmp_path.iterdir()) == ["link.exr", "road.blend"]
