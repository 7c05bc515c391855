"""Issue 46, point 5: a farm task fails when a file its scene reads is missing, and the digest
that tells finished work from stale work covers those files, not the .blend alone.

A bundle of balls_b whose fog material is linked from a library: with the library moved
away, ``openjd run`` had exited 0 with a fog-less frame (Blender only says "Unable to open"),
and with the library back a rerun kept that frame. Also: statue's bundle warned "the scene
reads /, which does not exist" for the path ``//../../../../`` its volume keeps.
"""
from __future__ import annotations

import hashlib
import shutil

import pytest
from conftest import EXAMPLES
from test_cli_info import one_line_error
from test_farm_cli import job_values, openjd, private_tmp

from xsl_render.core.farm.files import FrameFiles

pytestmark = [pytest.mark.blender, pytest.mark.render]

GUIDED = ["--mode", "guided", "--time-budget", "1", "--importance", "none", "--seed", "3",
          "--resolution", "48x36", "--frames", "1"]


def write_library(bpy, path, peak_density: float) -> None:
    """A library holding balls_b's fog material ``Fog``, at ``peak_density``."""
    bpy.ops.wm.open_mainfile(filepath=str(EXAMPLES / "balls_b.blend"))
    material = bpy.data.materials["Fog"]
    material.node_tree.nodes["Fog Peak Density"].inputs[1].default_value = peak_density
    bpy.data.libraries.write(str(path), {material}, fake_user=True)


@pytest.fixture
def linked_scene(blender, tmp_path):
    """balls_b whose fog box renders the material ``Fog`` linked from fog_library.blend (by a
    relative path), saved as scene.blend; returns (scene path, library path)."""
    library = tmp_path / "fog_library.blend"
    write_library(blender, library, 0.6)
    blender.ops.wm.open_mainfile(filepath=str(EXAMPLES / "balls_b.blend"))
    fog = blender.data.objects["Fog"]
    own = fog.material_slots[0].material
    scene = tmp_path / "scene.blend"
    blender.ops.wm.save_as_mainfile(filepath=str(scene))       # (so the library's path is relative)
    with blender.data.libraries.load(str(library), link=True, relative=True) as (_, linked):
        linked.materials = ["Fog"]
    fog.material_slots[0].material = linked.materials[0]
    blender.data.materials.remove(own)
    blender.ops.wm.save_mainfile()
    return scene, library


def digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_missing_library_fails_the_task_and_a_changed_one_redoes_the_frame(cli, blender, linked_scene,
                                                                            tmp_path):
    scene, library = linked_scene
    bundle = tmp_path / "bundle"
    assert cli("farm", scene, "--bundle", bundle, *GUIDED).returncode == 0
    files = FrameFiles(bundle / "output", 1)
    run = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert run.returncode == 0 and "1 rendered now" in run.stdout, run.stdout[-3000:]
    first = digest(files.image)

    # The library moved away: the task fails with one line, the frame is not kept as done.
    library.rename(tmp_path / "elsewhere.blend")
    run = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert run.returncode != 0, run.stdout[-3000:]
    assert f"xsl-render: error: the scene reads {library}, which does not exist" in run.stdout, \
        run.stdout[-3000:]
    # Moved back as it was: the frame made from it is still current.
    (tmp_path / "elsewhere.blend").rename(library)
    run = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert run.returncode == 0 and "0 rendered now, 1 already done" in run.stdout, run.stdout[-3000:]
    assert digest(files.image) == first

    # Another library in its place (thicker fog): the frame is made again, from it.
    write_library(blender, library, 1.2)
    run = openjd("run", bundle / "template.yaml", "-p", job_values(bundle), env=private_tmp(tmp_path))
    assert run.returncode == 0 and "1 rendered now" in run.stdout, run.stdout[-3000:]
    assert digest(files.image) != first


def test_a_tile_job_task_fails_too_with_one_line(cli, linked_scene, tmp_path):
    scene, library = linked_scene
    library.unlink()
    result = cli("farm-task", "maps", scene, "--scene-name", "balls_b", "--frame", "1", "--output",
                 tmp_path / "out", "--mode", "xs", "--max-spp", "2", "--resolution", "32x24")
    assert f"the scene reads {library}, which does not exist" in one_line_error(result)
    assert not list((tmp_path / "out").rglob("*.exr"))


def test_a_volume_path_that_names_no_file_is_not_a_missing_file(cli, tmp_path):
    """statue's volume keeps "//../../../../" (its grids come from Geometry Nodes)."""
    copy = tmp_path / "a" / "b" / "statue.blend"
    copy.parent.mkdir(parents=True)
    shutil.copy(EXAMPLES / "statue.blend", copy)
    result = cli("farm", copy, "--bundle", tmp_path / "bundle", "--frames", "1", "--resolution", "32x24")
    assert result.returncode == 0 and "which does not exist" not in result.stderr, result.stderr
