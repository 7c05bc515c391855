"""Issue 46, point 6 (the smaller ones): negative frame lists reach their parser (argparse had
taken ``-3--1`` for an option: "expected one argument"), numbers and frames are ASCII digits
only (``١-٣`` had been frames 1-3), and Blender's "Info: Read library" lines go to the log,
not to the command's stdout."""
from __future__ import annotations

import pytest
from conftest import EXAMPLES

from xsl_render.core.errors import InputError
from xsl_render.operators.cli import build_parser

SCENE = ["render", str(EXAMPLES / "road.blend"), "--mode", "gold", "--max-spp", "1", "--out", "r.exr"]


def parse(*extra):
    return build_parser().parse_args([*SCENE, *extra])


def test_a_negative_frame_list_is_a_value_not_an_option():
    assert parse("--frames", "-3--1").frames == "-3--1"
    assert parse("--frames", "-10-5:5,8").frames == "-10-5:5,8"
    assert parse("--frame", "-3").frame == -3
    with pytest.raises(InputError, match="the end frame -5 is before the start frame -3"):
        parse("--frames", "-3--5")
    with pytest.raises(InputError, match="unrecognized arguments: --nope"):    # options still are
        parse("--nope")


@pytest.mark.parametrize("option, text", [("--frames", "١-٣"), ("--frames", "1-３"), ("--frame", "٣"),
                                          ("--seed", "٣"), ("--max-spp", "１６")])
def test_only_ascii_digits_are_numbers(option, text):
    with pytest.raises(InputError, match=f"argument {option}"):
        parse(option, text)


@pytest.mark.blender
def test_blenders_library_lines_go_to_the_log(blender, cli, tmp_path):
    from support.fog_scene import build_fog_scene

    blender.data.materials.new("Fog").use_fake_user = True
    blender.ops.wm.save_as_mainfile(filepath=str(tmp_path / "library.blend"))
    build_fog_scene(blender, 16, 16)
    with blender.data.libraries.load(str(tmp_path / "library.blend"), link=True) as (_, linked):
        linked.materials = ["Fog"]
    next(ob for ob in blender.data.objects if ob.type == "MESH").data.materials.append(linked.materials[0])
    blender.ops.wm.save_as_mainfile(filepath=str(tmp_path / "scene.blend"))
    quiet = cli("info", tmp_path / "scene.blend", "--json")
    assert quiet.returncode == 0 and quiet.stdout.lstrip().startswith("{"), quiet.stdout[:300]
    assert "Read library" not in quiet.stdout + quiet.stderr
    kept = cli("--verbose", "info", tmp_path / "scene.blend")
    log = kept.stderr.strip().rsplit(" is in ", 1)[1]
    try:
        assert "Read library" in open(log, encoding="utf-8").read()
    finally:
        import os

        os.unlink(log)
